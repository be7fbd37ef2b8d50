#pragma once
/// \file map_stats.hpp
/// The figures of a traversability map (TraversabilityMap::stats()), as the tools report them.

#include <cstddef>

namespace gseg::map {

/// Figures of a map, voxels counted at the finest resolution.
struct MapStats {
    std::size_t scans = 0;             ///< scans inserted
    std::size_t groundPoints = 0;      ///< ground points given (all scans)
    std::size_t obstaclePoints = 0;    ///< obstacle points given (all scans)
    std::size_t pointsSkipped = 0;     ///< points not used: NaN/infinite or outside the map's extent
    std::size_t rays = 0;              ///< rays cast (one per endpoint voxel and scan)
    std::size_t groundVoxels = 0;      ///< occupied voxels of the ground tree
    std::size_t obstacleVoxels = 0;    ///< occupied voxels of the obstacle tree
    std::size_t freeVoxels = 0;        ///< voxels known free in the obstacle tree
    std::size_t clearedObstacleVoxels = 0;  ///< voxels once occupied as obstacle, free by the end (seen through)
    std::size_t groundUnderObstacle = 0;    ///< occupied in both trees: shown as obstacle
    std::size_t cellsTraversable = 0, cellsObstacle = 0;  ///< top-down grid of the voxel columns (`_traversability.png`)
    std::size_t cellsUnknown = 0;      ///< cells without data inside the picture's frame
    /// The costmap (`<prefix>_costmap.pgm`, the `class` layer as map_server loads it; the map a
    /// planner uses): its free, occupied and unknown cells, every pixel of the PGM counted once.
    std::size_t costmapFree = 0, costmapOccupied = 0, costmapUnknown = 0;
    double pathLength = 0;             ///< [m] length of the sensor path
    std::size_t bricks = 0;            ///< 8 x 8 x 8 voxel bricks holding the maps while integrating
    std::size_t brickValueBlocks = 0;  ///< words of 4 x 4 x 4 voxels with a value each (the others hold one)
    std::size_t mapBytes = 0;          ///< [bytes] memory of the bricks, their index and values
};

}  // namespace gseg::map
