# Fails unless FILE contains the literal TEXT (used on stats.json written by the CLI).
file(READ "${FILE}" content)
string(FIND "${content}" "${TEXT}" at)
if(at EQUAL -1)
  message(FATAL_ERROR "${FILE} does not contain: ${TEXT}")
endif()
