#pragma once
// The map's .3Dscene (MRPT opengl objects), in a file of its own: MRPT 2.5.8's opengl classes
// that derive virtually from CRenderizableShaderPoints (COctoMapVoxels, CSetOfLines) fail UBSan's
// alignment check in their inline destructors when built in our code ("member call on misaligned
// address ... requires 32 byte alignment"), so sanitized builds turn that one check off here only.

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace gseg::io {
class AtomicFile;
}
namespace gseg::map {
class LayerGrid;
}
namespace mrpt::opengl {
class CSetOfTriangles;
}

namespace gseg::map::detail {

/// Writes the .3Dscene into `file` (gzip; not committed here): voxel centres `xyz` (3 floats each) with `labels` (1 ground, 0 obstacle) as coloured
/// boxes of edge `resolution`, the path as a blue line with a box at each sensor position, axes at
/// its start, and, given `layers` with an `elevation` layer, its elevationMesh(). The scene is
/// serialised straight into the compressor: no copy of it in memory. `groundUnderObstacles`: the
/// occupied ground voxels also occupied as obstacles (shown red), so that the legend's ground
/// count is the console's (every occupied ground voxel, as `_ground.bt` holds them). Lit from
/// above and mostly ambient: every face shows 80 to 100 % of the legend's colour. The sensor positions are
/// boxes of 1 % of the map's extent (at least two voxels), so the path shows on a whole drive.
void writeMapScene(gseg::io::AtomicFile& file, const std::vector<float>& xyz,
                   const std::vector<std::uint8_t>& labels, double resolution, const std::vector<Eigen::Vector3d>& path,
                   const LayerGrid* layers = nullptr, std::size_t groundUnderObstacles = 0);

/// [m] The edge of the boxes at the sensor positions for a map whose box spans `extent` metres on
/// its longest side: 1 % of it, at least 2 voxels, at most 5 m.
double pathMarkSize(double extent, double resolution);

/// The 2.5D map for MRPT's viewers (SceneViewer3D): every cell of `layers` with a finite
/// `elevation` a square tile of the cell's size at that height (map frame, metres), two triangles
/// counter-clockwise seen from above (6 vertices a cell), coloured by the cell's `class` in the
/// colours of the map's pictures (colourOf(): 1 traversable green, 2 not traversable red, no class
/// grey) and shaded by the local slope (normals from the elevation of the neighbouring cells).
/// Cells without an elevation are left out (no tile at height 0). The object's name says so.
/// Throws std::out_of_range if `layers` has no `elevation` layer, std::invalid_argument if a
/// layer's values are not one per cell.
std::shared_ptr<::mrpt::opengl::CSetOfTriangles> elevationMesh(const LayerGrid& layers);

}  // namespace gseg::map::detail
