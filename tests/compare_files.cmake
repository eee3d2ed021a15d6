# Fails unless each of FILES is byte-identical in directories A and B.
foreach(f ${FILES})
  execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${A}/${f} ${B}/${f} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${f} differs between ${A} and ${B}")
  endif()
endforeach()
message(STATUS "identical: ${FILES}")
