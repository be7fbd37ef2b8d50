// The map layer's voxel keys (Morton codes, grid column keys, brick sets), built with UBSan that
// halts on the first error (#9 item 5: a left shift of a negative column index went unnoticed).
#include "voxel_keys.hpp"

#include <gtest/gtest.h>

#include <climits>

namespace {

using namespace gseg::map::detail;

TEST(MapKeys, MortonCodesRoundTripAndFollowOctomapsChildOrder) {
    const std::uint16_t values[] = {0, 1, 2, 7, 8, 255, 256, 32767, 32768, 32769, 65534, 65535};
    for (std::uint16_t x : values)
        for (std::uint16_t y : values)
            for (std::uint16_t z : values) {
                const octomap::OcTreeKey k(x, y, z);
                const std::uint64_t c = mortonCode(k);
                ASSERT_TRUE(keyOfCode(c) == k) << x << " " << y << " " << z;
                for (int depth = 0; depth < kTreeDepth; ++depth)
                    ASSERT_EQ(childIndex(c, depth), octomap::computeChildIdx(k, kTreeDepth - 1 - depth));
            }
}

TEST(MapKeys, SharedDepthIsWhereTwoPathsSplit) {
    const octomap::OcTreeKey a(32768, 32768, 32768);
    EXPECT_EQ(sharedDepth(mortonCode(a), mortonCode(a)), 16);
    EXPECT_EQ(sharedDepth(mortonCode(a), mortonCode(octomap::OcTreeKey(32769, 32768, 32768))), 15);
    EXPECT_EQ(sharedDepth(mortonCode(a), mortonCode(octomap::OcTreeKey(32768, 32768, 32776))), 12);
    EXPECT_EQ(sharedDepth(mortonCode(a), mortonCode(octomap::OcTreeKey(32767, 32768, 32768))), 0);
    EXPECT_EQ(lastCodeBelow(mortonCode(a), 15), mortonCode(a) | 7);
    EXPECT_EQ(lastCodeBelow(0, 0), (1ULL << 48) - 1);
}

TEST(MapKeys, GridColumnKeysTakeNegativeIndices) {
    struct Case {
        std::int64_t a, b;
    };
    const Case cases[] = {{0, 0}, {-1, 0}, {0, -1}, {-1, -1}, {-32768, 32767}, {INT32_MIN, INT32_MAX}, {12345, -54321}};
    for (const auto& c : cases) {
        const auto [a, b] = splitPairKey(pairKey(c.a, c.b));
        EXPECT_EQ(a, c.a);
        EXPECT_EQ(b, c.b);
    }
    EXPECT_NE(pairKey(-1, 0), pairKey(0, -1));
    EXPECT_NE(pairKey(-1, -1), pairKey(0, 0));
}

TEST(MapKeys, BrickSetsSortAndSubtract) {
    BrickSet all, minus;
    std::vector<std::uint64_t> codes;
    for (std::uint16_t x = 32760; x < 32780; x += 3)
        for (std::uint16_t z = 32700; z < 32900; z += 37) codes.push_back(mortonCode(octomap::OcTreeKey(x, 32768, z)));
    for (auto it = codes.rbegin(); it != codes.rend(); ++it) EXPECT_TRUE(all.insert(*it));
    EXPECT_FALSE(all.insert(codes[0]));
    for (std::size_t i = 0; i < codes.size(); i += 2) minus.insert(codes[i]);
    std::sort(codes.begin(), codes.end());
    EXPECT_EQ(all.sortedCodes(), codes);
    const auto rest = all.sortedCodes({&minus});
    EXPECT_EQ(rest.size(), codes.size() - (codes.size() + 1) / 2);
    for (std::uint64_t c : rest) EXPECT_FALSE(minus.contains(c));
    all.clear();
    EXPECT_TRUE(all.sortedCodes().empty());
    EXPECT_FALSE(all.contains(codes[0]));
}

}  // namespace
