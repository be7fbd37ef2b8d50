// Failure breakdown (gseg/eval/breakdown.hpp): where false and missed ground come from, by hand.
#include <gseg/eval/breakdown.hpp>

#include <gtest/gtest.h>

TEST(Breakdown, HandComputedClassesHeightsAndRanges) {
    // Labelled road at z = -1.7 in the cells around x = 1 m and x = 25 m; errors placed on purpose.
    const std::vector<float> xyz = {
        1.0f,  0.0f, -1.7f,   // 0 road, predicted ground          -> true ground
        1.2f,  0.0f, -1.7f,   // 1 road, not predicted             -> missed, road, 0..10 m
        1.4f,  0.0f, -0.4f,   // 2 car roof 1.3 m up, predicted    -> false, car, 1..2 m, 0..10 m
        1.1f,  0.0f, -1.6f,   // 3 fence foot 0.1 m up, predicted  -> false, fence, -0.3..0.25 m
        1.3f,  0.0f, -2.5f,   // 4 building 0.8 m below, predicted -> false, below -0.3 m
        25.0f, 0.0f, -1.7f,   // 5 terrain at 25 m, predicted      -> true ground
        25.3f, 0.0f, -1.1f,   // 6 trunk 0.6 m up at 25 m, pred.   -> false, trunk, 0.5..1 m, 20..30 m
        60.0f, 0.0f, -1.7f,   // 7 sidewalk at 60 m, not predicted -> missed, sidewalk, beyond 50 m
        90.0f, 0.0f, 3.0f,    // 8 pole far from any ground, pred. -> false, no ground near
        1.0f,  0.5f, -1.7f,   // 9 unlabelled, predicted           -> true ground (protocol)
        1.0f,  0.6f, -1.0f,   // 10 car, not predicted             -> correct
    };
    const std::vector<std::uint32_t> labels = {40, 40, 10 | (3u << 16), 51, 50, 72, 71, 48, 80, 0, 10};
    const std::vector<std::uint8_t> pred = {1, 0, 1, 1, 1, 1, 1, 0, 1, 1, 0};
    std::vector<gseg::PointOutcome> out;
    const gseg::Breakdown b = gseg::breakdownFrame(gseg::PointCloudView(xyz.data(), 11), labels, pred,
                                                   gseg::BreakdownOptions(), &out);
    using O = gseg::PointOutcome;
    EXPECT_EQ(out, (std::vector<O>{O::TrueGround, O::MissedGround, O::FalseGround, O::FalseGround, O::FalseGround,
                                   O::TrueGround, O::FalseGround, O::MissedGround, O::FalseGround, O::TrueGround,
                                   O::TrueNonGround}));
    EXPECT_EQ(b.trueGround, 3u);
    EXPECT_EQ(b.falseGround, 5u);
    EXPECT_EQ(b.missedGround, 2u);
    EXPECT_EQ(b.falseByClass, (std::map<std::uint32_t, std::uint64_t>{{10, 1}, {50, 1}, {51, 1}, {71, 1}, {80, 1}}));
    EXPECT_EQ(b.missedByClass, (std::map<std::uint32_t, std::uint64_t>{{40, 1}, {48, 1}}));
    // Height bins: below -0.3, -0.3..0.25, 0.25..0.5, 0.5..1, 1..2, above 2, no ground near.
    EXPECT_EQ(b.falseByHeight, (std::array<std::uint64_t, 7>{1, 1, 0, 1, 1, 0, 1}));
    // Range bins: 0..10, 10..20, 20..30, 30..50, beyond 50.
    EXPECT_EQ(b.falseByRange, (std::array<std::uint64_t, 5>{3, 0, 1, 0, 1}));
    EXPECT_EQ(b.missedByRange, (std::array<std::uint64_t, 5>{1, 0, 0, 0, 1}));
    // Sums add up and merge.
    gseg::Breakdown twice = b;
    twice += b;
    EXPECT_EQ(twice.falseGround, 10u);
    EXPECT_EQ(twice.falseByClass.at(10), 2u);
    EXPECT_EQ(gseg::semanticClassName(10), "car");
    EXPECT_EQ(gseg::semanticClassName(4242), "class 4242");
    EXPECT_STREQ(gseg::HeightBins::name(4), "1..2 m");
    EXPECT_THROW(gseg::breakdownFrame(gseg::PointCloudView(xyz.data(), 11), labels, {1, 0}), std::invalid_argument);
}
