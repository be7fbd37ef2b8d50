#pragma once
// The map's .3Dscene (MRPT opengl objects), in a file of its own: MRPT 2.5.8's opengl classes
// that derive virtually from CRenderizableShaderPoints (COctoMapVoxels, CSetOfLines) fail UBSan's
// alignment check in their inline destructors when built in our code ("member call on misaligned
// address ... requires 32 byte alignment"), so sanitized builds turn that one check off here only.

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace gseg::io {
class AtomicFile;
}

namespace gseg::map::detail {

/// Writes the .3Dscene into `file` (gzip; not committed here): voxel centres `xyz` (3 floats each) with `labels` (1 ground, 0 obstacle) as coloured
/// boxes of edge `resolution`, the path as a blue line with a box at each sensor position, axes at
/// its start. The scene is serialised straight into the compressor: no copy of it in memory.
void writeMapScene(gseg::io::AtomicFile& file, const std::vector<float>& xyz,
                   const std::vector<std::uint8_t>& labels, double resolution, const std::vector<Eigen::Vector3d>& path);

}  // namespace gseg::map::detail
