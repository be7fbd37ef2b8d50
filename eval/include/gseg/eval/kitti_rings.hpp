#pragma once
/// \file kitti_rings.hpp
/// A sparser sensor's scan taken out of a KITTI HDL-64E scan: the laser ring of each point, found
/// from the order KITTI stores its points in, and every n-th ring or point kept (gseg eval
/// --ring-step, --point-step).

#include <cstddef>
#include <cstdint>
#include <vector>

namespace gseg::eval {

/// The laser ring of each point of a KITTI velodyne scan, numbered from 0 in file order, found from
/// the order the points are stored in: ring by ring, each ring sweeping once round in azimuth
/// (counter-clockwise, atan2(y, x) rising). A new ring begins where the azimuth falls back by more
/// than half a turn, if the ring before holds more than `minRingPoints` points (the few points right
/// behind the sensor jitter across the wrap; an HDL-64E ring holds 1,000-2,200 points). A point
/// with a non-finite x or y, and the point after it, never begin a ring. `xyzi`: 4 floats per point (x, y, z, intensity).
std::vector<std::uint32_t> kittiRings(const float* xyzi, std::size_t points, std::size_t minRingPoints = 600);

/// The points of a sparser sensor's scan taken out of a KITTI scan: the indices, in file order, of
/// the points of every `ringStep`-th ring (rings 0, ringStep, 2 ringStep, ... of kittiRings()) whose
/// index in the file is a multiple of `pointStep` (every pointStep-th point along the rings).
/// 1 and 1 keep every point. Throws std::invalid_argument if a step is 0.
std::vector<std::size_t> kittiThinned(const float* xyzi, std::size_t points, unsigned ringStep, unsigned pointStep);

/// Thins a scan and its labels in place to the points kittiThinned() keeps (their order kept).
/// Throws std::invalid_argument if a step is 0 or there is not one label per point.
void thinKittiScan(std::vector<float>& xyzi, std::vector<std::uint32_t>& labels, unsigned ringStep, unsigned pointStep);

}  // namespace gseg::eval
