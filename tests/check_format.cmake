# Fails when any C++ source of the tree is not clang-format clean (.clang-format at the root).
# Run by ctest as style.clang_format: -DCLANG_FORMAT=<binary> -DSOURCE_DIR=<tree>.
file(GLOB_RECURSE sources RELATIVE ${SOURCE_DIR}
     ${SOURCE_DIR}/core/*.cpp ${SOURCE_DIR}/core/*.h ${SOURCE_DIR}/ui/*.cpp ${SOURCE_DIR}/ui/*.h
     ${SOURCE_DIR}/app/*.cpp ${SOURCE_DIR}/app/*.h ${SOURCE_DIR}/tests/*.cpp ${SOURCE_DIR}/tests/*.h)
execute_process(COMMAND ${CLANG_FORMAT} --dry-run -Werror ${sources}
                WORKING_DIRECTORY ${SOURCE_DIR} RESULT_VARIABLE rc ERROR_VARIABLE err)
list(LENGTH sources n)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "clang-format: not clean (run clang-format -i on these):\n${err}")
endif()
message(STATUS "clang-format: ${n} files clean")
