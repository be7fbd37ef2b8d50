// gseg::map from an installed prefix: one scan of a floor 1.7 m below the sensor, through the map
// builder (segmented, moved into the world, ray cast, integrated): the floor under the sensor is
// ground in the map, and its top-down grid and picture (headers of their own) show it.
#include <gseg/map/map_builder.hpp>
#include <gseg/map/top_down_picture.hpp>

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservationPointCloud.h>

#include <cstdio>
#include <string>

int main() {
    gseg::mrpt::LoadedConfig cfg;
    cfg.params.distToGround = 1.7;
    gseg::map::MapBuilder builder(cfg, gseg::map::TraversabilityOptions());
    auto cloud = mrpt::maps::CSimplePointsMap::Create();
    for (int i = -40; i <= 40; ++i)
        for (int j = -40; j <= 40; ++j) cloud->insertPoint(0.25f * i, 0.25f * j, -1.7f);
    mrpt::obs::CObservationPointCloud obs;
    obs.pointcloud = cloud;
    obs.sensorLabel = "LIDAR";
    const bool used = builder.insert(obs, mrpt::poses::CPose3D(0, 0, 1.7, 0, 0, 0));
    const gseg::map::MapStats s = builder.map().stats();
    const gseg::map::TopDownGrid grid = builder.map().topDown();
    const std::string png = gseg::map::encodeTopDownPng(grid, builder.map().path());
    const std::size_t traversable = grid.count(gseg::map::ColumnClass::Traversable);
    std::printf("gseg::map: scan used %d, %zu ground voxels, %zu obstacle voxels, %zu traversable cells, %zu PNG bytes\n",
                int(used), s.groundVoxels, s.obstacleVoxels, traversable, png.size());
    return used && s.groundVoxels > 100 && s.obstacleVoxels == 0 && traversable > 100 && png.compare(1, 3, "PNG") == 0 ? 0 : 1;
}
