# The short fuzz run of the test suite in a build made with another compiler: builds the fuzz
# targets with clang (GSEG_FUZZ) in BUILD (kept between runs, so only the first one compiles), then
# runs each for SECONDS. -D: SRC, BUILD, CLANGXX, SECONDS, BUILD_TYPE.
execute_process(
  COMMAND ${CMAKE_COMMAND} -S "${SRC}" -B "${BUILD}" -DCMAKE_CXX_COMPILER=${CLANGXX} -DGSEG_FUZZ=ON
          -DGSEG_BUILD_TESTS=OFF -DGSEG_BUILD_APPS=OFF -DGSEG_FUZZ_SECONDS=${SECONDS}
          -DCMAKE_BUILD_TYPE=${BUILD_TYPE}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the clang fuzz build failed:\n${out}\n${err}")
endif()
set(targets)
foreach(t kitti ply config segmenter rawlog map)
  list(APPEND targets --target fuzz_${t})
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} --build "${BUILD}" -j2 ${targets}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the fuzz targets with clang failed:\n${out}\n${err}")
endif()
execute_process(COMMAND ${CMAKE_CTEST_COMMAND} --test-dir "${BUILD}" -R "^fuzz_.*_short$" --output-on-failure
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "a fuzz target failed:\n${out}\n${err}")
endif()
