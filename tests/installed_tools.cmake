# Installs the build into a prefix, moves the prefix elsewhere (any prefix must work: the tools
# find their libraries through RPATH $ORIGIN/../lib), and runs the installed tools there with no
# library path set. -D: BUILD (the gseg build dir), WORK (scratch dir).
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
function(step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()
step(${CMAKE_COMMAND} --install "${BUILD}" --prefix "${WORK}/installed")
file(RENAME "${WORK}/installed" "${WORK}/moved")
set(bin "${WORK}/moved/bin")
# A small scan: flat ground in a 20 m square around the sensor.
set(ply "ply\nformat ascii 1.0\nelement vertex 400\nproperty float x\nproperty float y\nproperty float z\nend_header\n")
foreach(i RANGE 0 399)
  math(EXPR x "${i} % 20 - 10")
  math(EXPR y "${i} / 20 - 10")
  string(APPEND ply "${x} ${y} -1.7\n")
endforeach()
file(WRITE "${WORK}/scan.ply" "${ply}")
set(clean ${CMAKE_COMMAND} -E env --unset=LD_LIBRARY_PATH)
step(${clean} "${bin}/gseg" segment "${WORK}/scan.ply" -c "${WORK}/moved/share/gseg/config/kitti_hdl64.yaml"
     --labels-out "${WORK}/scan.labels")
file(SIZE "${WORK}/scan.labels" n)
if(NOT n EQUAL 400)
  message(FATAL_ERROR "installed gseg segment wrote ${n} labels for 400 points")
endif()
step(${clean} "${bin}/rawlog-gseg" --version)
step(${clean} "${bin}/kitti2rawlog" --help)
step(${clean} "${bin}/rawlog-octomap" --help)
# The Python package (where built): importable from the moved prefix with only PYTHONPATH set, and
# segmenting with the installed libraries (RPATH $ORIGIN/../../..).
if(PYTHON AND PYTHON_DIR)
  file(WRITE "${WORK}/installed.py" "import gseg, numpy as n\np = n.zeros((400, 3), n.float32)\n"
       "p[:, 0] = n.arange(400) % 20 - 10\np[:, 1] = n.arange(400) // 20 - 10\np[:, 2] = -1.7\n"
       "r = gseg.segment(p, distToGround=1.7)\nassert r.labels.shape == (400,), r\n"
       "print(gseg.__file__)\n")
  step(${clean} PYTHONPATH=${WORK}/moved/${PYTHON_DIR} ${PYTHON} "${WORK}/installed.py")
  if(NOT last_output MATCHES "^${WORK}/moved/${PYTHON_DIR}/gseg/")
    message(FATAL_ERROR "the installed gseg module was not the one imported: ${last_output}")
  endif()
endif()
message(STATUS "installed tools run from a moved prefix")
