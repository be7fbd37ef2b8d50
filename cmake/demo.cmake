# The main job, run by `cmake --build build --target demo` (README Quick start, first command):
# segment the real VLP-16 scan that Debian's mrpt-common ships and, where ../shared/data is present,
# the SemanticKITTI scans; write a coloured PLY (with labels), a top-down PNG and an MRPT 3D scene
# of each into OUT.
# Then build traversability OctoMaps: of the VLP-16 scan (a stationary sensor: one identity pose),
# and of the SemanticKITTI sequence-00 drive (six scans with their poses) where present.
# Inputs (-D): GSEG (the gseg executable), BIN (folder of the tools), SRC (source dir), OUT (output dir).
# Every tool is given -w (replace the outputs of a previous run), so the demo can be run again.
file(MAKE_DIRECTORY "${OUT}")

function(run_tool)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (exit ${rc}): ${ARGN}")
  endif()
endfunction()

function(run_segment scan config name)
  message(STATUS "gseg segment ${scan}")
  execute_process(COMMAND "${GSEG}" segment -w -i "${scan}" --config "${config}"
                          --ply-out "${OUT}/${name}.ply" --png-out "${OUT}/${name}.png"
                          --scene-out "${OUT}/${name}.3Dscene" --labels-out "${OUT}/${name}.labels"
                  RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "gseg segment failed on ${scan} (exit ${rc})")
  endif()
endfunction()

set(vlp16 /usr/share/mrpt/datasets/test_velodyne_VLP16.rawlog)
if(NOT EXISTS "${vlp16}")
  message(FATAL_ERROR "${vlp16} is missing: apt-get install mrpt-common")
endif()
run_segment("${vlp16}" "${SRC}/config/vlp16.yaml" vlp16)

set(kitti "${SRC}/../shared/data/semantickitti/sequences")
file(GLOB scans "${kitti}/*/velodyne/*.bin")
if(scans)
  foreach(scan IN LISTS scans)
    get_filename_component(frame "${scan}" NAME_WE)
    get_filename_component(seqdir "${scan}" DIRECTORY)
    get_filename_component(seqdir "${seqdir}" DIRECTORY)
    get_filename_component(seq "${seqdir}" NAME)
    run_segment("${scan}" "${SRC}/config/kitti_hdl64.yaml" "kitti_${seq}_${frame}")
  endforeach()
else()
  message(STATUS "No SemanticKITTI scans at ${kitti}: segmented the VLP-16 scan only")
endif()
# Traversability maps. The VLP-16 scan has no pose: a TUM file with one identity pose, matched
# whatever the scan's time stamp, stands for a sensor that did not move.
file(WRITE "${OUT}/stationary.tum" "0 0 0 0 0 0 0 1\n")
message(STATUS "rawlog-octomap ${vlp16}")
run_tool("${BIN}/rawlog-octomap" -w -i "${vlp16}" -o "${OUT}/vlp16" --poses "${OUT}/stationary.tum"
         --pose-tolerance 1e12 -c "${SRC}/config/vlp16.yaml")
if(EXISTS "${kitti}/00/poses.txt")
  message(STATUS "kitti2rawlog + rawlog-octomap: SemanticKITTI sequence 00")
  run_tool("${BIN}/kitti2rawlog" -w -i "${kitti}/00" -o "${OUT}/seq00.rawlog")
  run_tool("${BIN}/rawlog-octomap" -w -i "${OUT}/seq00.rawlog" -o "${OUT}/seq00" -c "${SRC}/config/kitti_hdl64.yaml")
endif()
# The closing line names every kind of file written, the planner's maps first.
set(maps "vlp16")
if(EXISTS "${kitti}/00/poses.txt")
  set(maps "seq00 (SemanticKITTI 00) and vlp16")
endif()
message(STATUS "Outputs in ${OUT}: maps of ${maps}, 17 files each: *_costmap.pgm + *_costmap.yaml (the costmap a planner "
               "loads: ROS map_server / Nav2), *_layers.tif (the 2.5D layers as a GeoTIFF: gdalinfo, QGIS), "
               "*_layer_<name>.png (a picture per layer; *_layer_class.png is the costmap, x right and y up as the PGM), "
               "*_traversability.png (the voxel columns from above), *_ground.bt / *_obstacles.bt / *_traversability.ot "
               "(OctoMaps: liboctomap tools), *_traversability.ply (CloudCompare), *_traversability.3Dscene "
               "(SceneViewer3D of mrpt-apps); of each scan *.png, *.ply, *.3Dscene and *.labels")
