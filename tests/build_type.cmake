# The top-level CMakeLists gives Release where no build type is given and never overrides one that
# is given (an empty one included). Configures the core alone (no MRPT, apps or tests: seconds) in
# three fresh folders and reads each cache. -D: SRC (the project), WORK (scratch dir).
function(configured_type out)
  file(REMOVE_RECURSE "${WORK}")
  execute_process(COMMAND ${CMAKE_COMMAND} -E env --unset=CMAKE_BUILD_TYPE
                          ${CMAKE_COMMAND} -S ${SRC} -B ${WORK} -DGSEG_WITH_MRPT=OFF -DGSEG_BUILD_TESTS=OFF ${ARGN}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE log ERROR_VARIABLE log)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "configuring failed (${rc}) with '${ARGN}':\n${log}")
  endif()
  file(STRINGS ${WORK}/CMakeCache.txt line REGEX "^CMAKE_BUILD_TYPE:")
  string(REGEX REPLACE "^[^=]*=" "" type "${line}")
  set(${out} "${type}" PARENT_SCOPE)
endfunction()
configured_type(none)
configured_type(debug -DCMAKE_BUILD_TYPE=Debug)
configured_type(empty -DCMAKE_BUILD_TYPE=)
file(REMOVE_RECURSE "${WORK}")
message(STATUS "none given: '${none}', Debug given: '${debug}', empty given: '${empty}'")
if(NOT none STREQUAL "Release" OR NOT debug STREQUAL "Debug" OR NOT empty STREQUAL "")
  message(FATAL_ERROR "build type: expected 'Release', 'Debug', '' and got '${none}', '${debug}', '${empty}'")
endif()
