// Segments a flat 20 x 20 m grid of points 1.7 m below the sensor plus a post: all ground but the post.
#include <gseg/ground_segmenter.hpp>

#include <cstdio>
#include <vector>

int main() {
    std::vector<float> xyz;
    for (int i = -40; i <= 40; ++i)
        for (int j = -40; j <= 40; ++j) xyz.insert(xyz.end(), {0.25f * i, 0.25f * j, -1.7f});
    const std::size_t ground = xyz.size() / 3;
    for (int k = 0; k < 30; ++k) xyz.insert(xyz.end(), {5.f, 5.f, -1.6f + 0.05f * k});
    gseg::Params params;
    params.distToGround = 1.7;
    gseg::GroundSegmenter segmenter(params);
    const gseg::Result r = segmenter.segment(gseg::PointCloudView(xyz.data(), xyz.size() / 3));
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < r.labels.size(); ++i) wrong += r.labels[i] != (i < ground ? 1 : 0);
    std::printf("%zu points, %zu ground, %zu wrong\n", r.labels.size(), r.numGround, wrong);
    return wrong * 100 < r.labels.size() ? 0 : 1;  // fewer than 1 % wrong
}
