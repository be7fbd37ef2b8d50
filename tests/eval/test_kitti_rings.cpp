// Ring thinning (gseg/eval/kitti_rings.hpp): a sparser sensor's scan taken out of a KITTI scan.
#include <gseg/eval/kitti_rings.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

// Rings found from the order KITTI stores its points in: each ring one sweep from -180 to +180 deg
// (the scan's first ring only its last part), a few points right behind the sensor jittering across
// the wrap just after a ring began.
TEST(KittiRings, SweepsAreRingsAndJitterAtTheWrapIsNot) {
    std::vector<float> xyzi;
    const auto add = [&](double az) { xyzi.insert(xyzi.end(), {float(10 * std::cos(az)), float(10 * std::sin(az)), -1.7f, 0.f}); };
    for (int k = 0; k < 700; ++k) add(M_PI * (k + 0.5) / 700);  // ring 0: from 0 deg on
    for (int ring = 1; ring <= 2; ++ring)
        for (int k = 0; k < 1000; ++k)
            add(ring == 1 && (k == 1 || k == 3) ? M_PI - 0.0005 : -M_PI + 2 * M_PI * (k + 0.5) / 1000);
    const std::size_t n = xyzi.size() / 4;
    const std::vector<std::uint32_t> rings = gseg::eval::kittiRings(xyzi.data(), n);
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(rings[i], i < 700 ? 0u : i < 1700 ? 1u : 2u) << "point " << i;
    const auto everySecondRing = gseg::eval::kittiThinned(xyzi.data(), n, 2, 1);
    ASSERT_EQ(everySecondRing.size(), 1700u);
    EXPECT_EQ(everySecondRing[699], 699u);
    EXPECT_EQ(everySecondRing[700], 1700u);
    const auto everyThirdPoint = gseg::eval::kittiThinned(xyzi.data(), n, 1, 3);
    ASSERT_EQ(everyThirdPoint.size(), 900u);
    EXPECT_EQ(everyThirdPoint[1], 3u);
    EXPECT_EQ(gseg::eval::kittiThinned(xyzi.data(), n, 1, 1).size(), n);
    EXPECT_THROW(gseg::eval::kittiThinned(xyzi.data(), n, 0, 1), std::invalid_argument);
    std::vector<std::uint32_t> labels(n);
    for (std::size_t i = 0; i < n; ++i) labels[i] = std::uint32_t(i);
    std::vector<float> scan = xyzi;
    gseg::eval::thinKittiScan(scan, labels, 2, 1);
    ASSERT_EQ(labels.size(), 1700u);
    ASSERT_EQ(scan.size(), 4 * labels.size());
    EXPECT_EQ(labels[700], 1700u);
    EXPECT_EQ(scan[4 * 700], xyzi[4 * 1700]);
    labels.pop_back();
    EXPECT_THROW(gseg::eval::thinKittiScan(scan, labels, 1, 1), std::invalid_argument);
}
