// gseg::mrpt from an installed prefix: a configuration from YAML text, and the filter on an MRPT
// point cloud of a flat floor 1.7 m below the sensor with a post: the floor is ground, the post not.
#include <gseg/mrpt/config.hpp>
#include <gseg/mrpt/ground_filter.hpp>

#include <mrpt/maps/CSimplePointsMap.h>

#include <cstdio>

int main() {
    const gseg::mrpt::LoadedConfig cfg = gseg::mrpt::loadConfigFromText("distToGround: 1.7\n", gseg::mrpt::ConfigFormat::Yaml, "text");
    mrpt::maps::CSimplePointsMap cloud;
    for (int i = -40; i <= 40; ++i)
        for (int j = -40; j <= 40; ++j) cloud.insertPoint(0.25f * i, 0.25f * j, -1.7f);
    const std::size_t floor = cloud.size();
    for (int k = 0; k < 30; ++k) cloud.insertPoint(5.f, 5.f, -1.6f + 0.05f * k);
    gseg_filters::GroundFilter filter(cfg);
    const auto out = filter.filter(cloud, "LIDAR");
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < out.result.labels.size(); ++i) wrong += out.result.labels[i] != (i < floor ? 1 : 0);
    std::printf("gseg::mrpt: distToGround %.2f m, %zu points, %zu wrong\n", cfg.params.distToGround, out.result.labels.size(), wrong);
    return cfg.params.distToGround == 1.7 && wrong * 100 < out.result.labels.size() ? 0 : 1;
}
