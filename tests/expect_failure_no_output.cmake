# A bad scene must fail with a message naming the field and leave no output directory.
file(REMOVE_RECURSE ${OUT})
execute_process(COMMAND ${FL} render ${SCENE} --quiet --out ${OUT}
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0)
  message(FATAL_ERROR "expected a failure, got exit 0")
endif()
if(NOT err MATCHES "objects\\[1\\]\\.material\\.roughness: expected a number in \\(0, 1\\]")
  message(FATAL_ERROR "message does not name the field: ${err}")
endif()
if(EXISTS ${OUT})
  message(FATAL_ERROR "output directory ${OUT} was created despite the error")
endif()
