// Grid indexing, parameters, plane fit, classification, region growing and reflections below the
// ground in isolation.
#include <gseg/below_ground.hpp>
#include <gseg/cell_classifier.hpp>
#include <gseg/grid.hpp>
#include <gseg/params.hpp>
#include <gseg/plane_fit.hpp>
#include <gseg/region_growing.hpp>
#include <gseg/sensor_height.hpp>
#include <gseg/text.hpp>
#include <support/lidar_sim.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <optional>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <random>

// --- text helpers (gseg/text.hpp) --------------------------------------------------------------

TEST(Text, TrimStartsEndsLowercaseTable) {
    EXPECT_EQ(gseg::trim("  a b \t\r\n"), "a b");
    EXPECT_EQ(gseg::trim(" \t "), "");
    EXPECT_EQ(gseg::trim(""), "");
    EXPECT_EQ(gseg::trim("\ra\r", " \t"), "\ra\r");  // only the blanks asked for
    EXPECT_TRUE(gseg::endsWith("scan.rawlog", ".rawlog"));
    EXPECT_FALSE(gseg::endsWith("log", ".rawlog"));
    EXPECT_TRUE(gseg::endsWith("x", ""));
    EXPECT_TRUE(gseg::startsWith("Message: x", "Message:"));
    EXPECT_FALSE(gseg::startsWith("Mess", "Message:"));
    EXPECT_EQ(gseg::lowercase("Scan.RAWLOG.Gz"), "scan.rawlog.gz");
}

TEST(Text, ParseNumberReadsAllOfTheTextOrNothing) {
    struct Row {
        const char* text;
        bool ok;
        double value;
    };
    for (const Row& r : {Row{"1.5", true, 1.5}, Row{" -2e3 \t", true, -2000}, Row{"0", true, 0}, Row{"", false, 0},
                         Row{" ", false, 0}, Row{"1.5x", false, 0}, Row{"x1", false, 0}, Row{"1 2", false, 0},
                         Row{"1e999", false, 0}, Row{"0x10", false, 0}}) {
        const std::optional<double> v = gseg::parseNumber<double>(r.text);
        EXPECT_EQ(v.has_value(), r.ok) << "'" << r.text << "'";
        if (r.ok && v) {
            EXPECT_EQ(*v, r.value) << "'" << r.text << "'";
        }
    }
    EXPECT_TRUE(std::isinf(*gseg::parseNumber<double>("inf")));
    EXPECT_EQ(gseg::parseNumber<int>("42"), 42);
    EXPECT_FALSE(gseg::parseNumber<int>("4.2"));
    EXPECT_FALSE(gseg::parseNumber<unsigned>("-1"));
    EXPECT_FALSE(gseg::parseNumber<int>("99999999999"));  // out of range
}

TEST(Text, SecondsSinceIsNotNegativeAndGrows) {
    const auto t0 = std::chrono::steady_clock::now();
    const double a = gseg::secondsSince(t0), b = gseg::secondsSince(t0);
    EXPECT_GE(a, 0.0);
    EXPECT_GE(b, a);
    EXPECT_LT(b, 60.0);
}

// --- grid --------------------------------------------------------------------------------------

TEST(CellCoord, FloorNotTruncationTable) {
    struct Row {
        float v;
        double size;
        int expected;
    } rows[] = {{0.f, 1.5, 0},   {1.49f, 1.5, 0},   {1.5f, 1.5, 1},     {-0.f, 1.5, 0},  {-1e-6f, 1.5, -1},
                {-1.5f, 1.5, -1}, {-1.51f, 1.5, -2}, {-0.1f, 0.2, -1},  {0.2f, 0.2, 1},  {-3.f, 1.0, -3},
                {1e12f, 0.2, 1 << 30}, {-1e12f, 0.2, -(1 << 30)}};
    for (const Row& r : rows) EXPECT_EQ(gseg::cellCoord(r.v, r.size), r.expected) << r.v << " / " << r.size;
    EXPECT_EQ(gseg::cellCoord(-1.8f, 0.2, -1.9), 0);  // origin shifts the borders
    EXPECT_EQ(gseg::cellCoord(-1.95f, 0.2, -1.9), -1);
}

// cellCoord is branch-free so that grid.cpp's loops vectorise (#21): the floor of the quotient,
// clamped, for values near cell borders, of every magnitude, negative, NaN and infinite; and the
// vectorised loops of ColumnIndex::build give each point the column of cellCoord.
TEST(CellCoord, BranchFreeFormIsTheClampedFloorAndColumnIndexAgrees) {
    const auto reference = [](float v, double size, double origin) {
        const double q = (double(v) - origin) / size;
        if (std::isnan(q) || q <= -1073741824.0) return -(1 << 30);
        if (q >= 1073741824.0) return 1 << 30;
        return int(std::floor(q));
    };
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1, 1);
    std::vector<float> xyz;
    for (int i = 0; i < 30000; ++i) {
        const float scale = std::pow(10.f, float(i % 12) - 3.f);
        const float border = std::round(u(rng) * 100.f) * 1.5f;  // on and next to cell borders
        const float v = i % 3 == 0 ? std::nextafter(border, u(rng) > 0 ? 1e30f : -1e30f) : u(rng) * scale;
        for (const double size : {1.5, 1.0, 0.2})
            for (const double origin : {0.0, -1.9})
                ASSERT_EQ(gseg::cellCoord(v, size, origin), reference(v, size, origin)) << v << " " << size << " " << origin;
        xyz.insert(xyz.end(), {v, -v * 0.7f, 0.f});
    }
    for (const float v : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                          -std::numeric_limits<float>::infinity(), 3e38f, -3e38f})
        EXPECT_EQ(gseg::cellCoord(v, 0.2), reference(v, 0.2, 0.0)) << v;
    const gseg::PointCloudView cloud(xyz.data(), xyz.size() / 3);
    std::vector<std::uint32_t> idx(cloud.size()), columnOf;
    for (std::uint32_t i = 0; i < idx.size(); ++i) idx[i] = i;
    gseg::ColumnIndex columns;
    columns.build(cloud, idx, 1.5, 1.0, columnOf);
    for (std::uint32_t i = 0; i < idx.size(); ++i) {
        ASSERT_EQ(columns.ix(columnOf[i]), gseg::cellCoord(cloud.x(i), 1.5)) << cloud.x(i);
        ASSERT_EQ(columns.iy(columnOf[i]), gseg::cellCoord(cloud.y(i), 1.0)) << cloud.y(i);
    }
}

// detail::cellCoords (the vectorised form; on AVX2 a product with the reciprocal of the size,
// the division only near a border) gives cellCoord's value for every input: on the borders of
// every size and origin the segmenter uses and the floats next to them, far values, NaN and
// infinities.
TEST(CellCoord, ValueRangeIsTheMinimumAndMaximumOfEveryLength) {
    std::mt19937 rng(3);
    std::uniform_int_distribution<std::int32_t> any(std::numeric_limits<std::int32_t>::min(),
                                                    std::numeric_limits<std::int32_t>::max());
    for (std::size_t n = 0; n <= 70; ++n) {
        std::vector<std::int32_t> v(n);
        for (auto& x : v) x = n % 2 ? any(rng) : std::int32_t(any(rng) % 100);
        if (n > 5) v[n - 1] = std::numeric_limits<std::int32_t>::min(), v[n / 2] = std::numeric_limits<std::int32_t>::max();
        std::int32_t lo = 7, hi = 7;  // starting values take part
        gseg::detail::valueRange(v.data(), n, lo, hi);
        std::int32_t wantLo = 7, wantHi = 7;
        for (std::int32_t x : v) wantLo = std::min(wantLo, x), wantHi = std::max(wantHi, x);
        EXPECT_EQ(lo, wantLo) << n;
        EXPECT_EQ(hi, wantHi) << n;
    }
}

TEST(CellCoord, VectorisedFormEqualsCellCoordOnAndNextToBorders) {
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> cell(-700, 700);
    for (const double size : {1.5, 1.0, 0.2, 0.1, 0.3})
        for (const double origin : {0.0, -1.9, -1.723 - 0.8 * 1.5, -1.723 - 0.8 * 0.2}) {
            std::vector<float> v;
            for (int i = 0; i < 4000; ++i) {
                const float border = float(origin + double(cell(rng)) * size);
                v.insert(v.end(), {border, std::nextafter(border, 1e30f), std::nextafter(border, -1e30f),
                                   std::nextafter(std::nextafter(border, 1e30f), 1e30f)});
            }
            v.insert(v.end(), {0.f, -0.f, 1e12f, -1e12f, 3e38f, -3e38f, std::numeric_limits<float>::quiet_NaN(),
                               std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(), 1e-30f});
            for (std::size_t n : {v.size(), v.size() - 3}) {  // with and without a remainder of the groups of four
                std::vector<std::int32_t> out(n, 12345);
                gseg::detail::cellCoords(v.data(), n, size, origin, out.data());
                for (std::size_t k = 0; k < n; ++k)
                    ASSERT_EQ(out[k], gseg::cellCoord(v[k], size, origin)) << v[k] << " " << size << " " << origin;
            }
        }
}

TEST(Grid, GroupsPointsByCellSortedByColumnThenHeight) {
    const std::vector<float> xyz = {0.1f, 0.1f, 0.1f,  -0.1f, 0.1f, 0.1f,  0.2f, 0.3f, 0.15f,
                                    0.1f, 0.1f, -0.1f, -0.1f, -0.1f, -0.1f};
    gseg::Grid g;
    g.build(gseg::PointCloudView(xyz.data(), 5), {0, 1, 2, 3, 4}, 1.0, 1.0, 1.0);
    ASSERT_EQ(g.cells().size(), 4u);
    // (-1,-1,-1) (-1,0,0) (0,0,-1) (0,0,0): lexicographic, z fastest
    EXPECT_EQ(g.cells()[0].ix, -1);
    EXPECT_EQ(g.cells()[0].iy, -1);
    EXPECT_EQ(g.cells()[2].iz, -1);
    EXPECT_EQ(g.cells()[3].iz, 0);
    EXPECT_EQ(g.cells()[3].size(), 2u);  // points 0 and 2
    std::size_t total = 0;
    for (const auto& c : g.cells()) total += c.size();
    EXPECT_EQ(total, 5u);
}

TEST(Grid, SparseFallbackMatchesDensePath) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-20, 20);
    std::vector<float> xyz;
    for (int i = 0; i < 2000; ++i) xyz.insert(xyz.end(), {u(rng), u(rng), u(rng) * 0.1f});
    std::vector<std::uint32_t> idx(2000);
    for (std::uint32_t i = 0; i < 2000; ++i) idx[i] = i;
    gseg::Grid dense;
    dense.build(gseg::PointCloudView(xyz.data(), 2000), idx, 1.5, 1.0, 0.2);
    xyz.insert(xyz.end(), {1e7f, -1e7f, 1e6f});  // forces the sparse path
    idx.push_back(2000);
    gseg::Grid sparse;
    sparse.build(gseg::PointCloudView(xyz.data(), 2001), idx, 1.5, 1.0, 0.2);
    ASSERT_EQ(sparse.cells().size(), dense.cells().size() + 1);
    for (std::size_t c = 0; c < dense.cells().size(); ++c) {
        const auto &a = dense.cells()[c], &b = sparse.cells()[c];
        EXPECT_EQ(std::tie(a.ix, a.iy, a.iz, a.begin, a.end), std::tie(b.ix, b.iy, b.iz, b.begin, b.end));
    }
}

// The ColumnIndex form of Grid::build (#21: columns numbered once per scan) gives the cells and the
// point order of the plain form, on a shuffled subset with negative coordinates, tall columns
// (z-cell ranges beyond the counting sort's), a column with one z cell, and the sparse column ids
// of points spread absurdly far; columnCells() and find() agree with the cells.
TEST(Grid, ColumnIndexFormMatchesThePlainFormDenseAndSparse) {
    for (const bool far : {false, true}) {
        std::mt19937 rng(11);
        std::uniform_real_distribution<float> u(-20, 20);
        std::vector<float> xyz;
        for (int i = 0; i < 20000; ++i) xyz.insert(xyz.end(), {u(rng), u(rng), u(rng) * 0.1f});  // several chunks of the pool
        for (int i = 0; i < 50; ++i) xyz.insert(xyz.end(), {3.2f, -4.1f, u(rng) * 40.f});  // a tall column
        for (int i = 0; i < 5; ++i) xyz.insert(xyz.end(), {-7.3f, 8.6f, 0.05f});          // one z cell
        if (far) xyz.insert(xyz.end(), {1e7f, -1e7f, 1e6f});
        const std::uint32_t n = std::uint32_t(xyz.size() / 3);
        const gseg::PointCloudView cloud(xyz.data(), n);
        std::vector<std::uint32_t> idx;
        for (std::uint32_t i = 0; i < n; ++i)
            if (i % 7 != 3) idx.push_back(i);
        std::shuffle(idx.begin(), idx.end(), rng);
        gseg::ColumnIndex columns;
        std::vector<std::uint32_t> columnOf;
        columns.build(cloud, idx, 1.5, 1.0, columnOf);
        // `g` (a ColumnIndex form) has the cells and point order of `plain` (the plain form on the
        // same input); its columns agree with the index, and its points are those of the cloud.
        const auto expectSameAsPlain = [&](const gseg::Grid& plain, const gseg::Grid& g) {
            ASSERT_EQ(plain.cells().size(), g.cells().size()) << far;
            EXPECT_EQ(plain.order(), g.order()) << far;
            for (std::size_t c = 0; c < g.cells().size(); ++c) {
                const auto &a = plain.cells()[c], &b = g.cells()[c];
                ASSERT_EQ(std::tie(a.ix, a.iy, a.iz, a.begin, a.end), std::tie(b.ix, b.iy, b.iz, b.begin, b.end)) << c;
                const std::int64_t col = columns.find(a.ix, a.iy);
                ASSERT_GE(col, 0);
                EXPECT_EQ(columns.ix(std::uint32_t(col)), a.ix);
                EXPECT_EQ(columns.iy(std::uint32_t(col)), a.iy);
                EXPECT_EQ(g.cellColumns()[c], std::uint32_t(col));
                EXPECT_GE(c, g.columnCells()[std::size_t(col)]);
                EXPECT_LT(c, g.columnCells()[std::size_t(col) + 1]);
            }
            for (std::size_t k = 0; k < g.order().size(); ++k) {
                const float* p = cloud.point(g.order()[k]);
                EXPECT_EQ(g.points()[k], Eigen::Vector3f(p[0], p[1], p[2]));
            }
        };
        gseg::Grid plain, byColumn, byColumnZ;
        plain.build(cloud, idx, 1.5, 1.0, 0.2, -1.9);
        byColumn.build(cloud, idx, columns, columnOf.data(), 0.2, -1.9);
        expectSameAsPlain(plain, byColumn);
        // The z the columns' numbering gathered (ColumnIndex::z(), in idx's order) instead of the cloud's.
        ASSERT_EQ(columns.z().size(), idx.size());
        for (std::size_t k = 0; k < idx.size(); ++k) ASSERT_EQ(columns.z()[k], cloud.z(idx[k])) << k;
        byColumnZ.build(cloud, idx, columns, columnOf.data(), 0.2, -1.9, nullptr, columns.z().data());
        expectSameAsPlain(plain, byColumnZ);
        EXPECT_EQ(columns.find(1 << 29, 1 << 29), -1);

        // Few (column, z cell) keys (Phase I's tall cells; no tall column): the single counting
        // sort by both, the same cells and order.
        std::vector<std::uint32_t> low, lowColumns;
        for (std::size_t k = 0; k < idx.size(); ++k)
            if (std::abs(cloud.z(idx[k])) < 5.f) low.push_back(idx[k]), lowColumns.push_back(columnOf[k]);
        gseg::Grid plainLow, byKeyLow, byKeyLowZ;
        plainLow.build(cloud, low, 1.5, 1.0, 1.5, -2.5);
        byKeyLow.build(cloud, low, columns, lowColumns.data(), 1.5, -2.5);
        expectSameAsPlain(plainLow, byKeyLow);
        std::vector<float> lowZ;
        for (std::uint32_t i : low) lowZ.push_back(cloud.z(i));
        byKeyLowZ.build(cloud, low, columns, lowColumns.data(), 1.5, -2.5, nullptr, lowZ.data());
        expectSameAsPlain(plainLow, byKeyLowZ);

        // Input already grouped by column (Phase II's: Phase I's cells in order) takes the path
        // without the scatter by column: the same cells and order as the plain form on that input,
        // with the points handed over or read from the cloud, and z cells of another height.
        const std::vector<std::uint32_t> grouped = byColumn.order();
        std::vector<std::uint32_t> groupedColumns(grouped.size());
        for (std::size_t c = 0; c < byColumn.cells().size(); ++c)
            for (std::uint32_t k = byColumn.cells()[c].begin; k < byColumn.cells()[c].end; ++k)
                groupedColumns[k] = byColumn.cellColumns()[c];
        gseg::Grid plainGrouped, fromCloud, fromPoints;
        plainGrouped.build(cloud, grouped, 1.5, 1.0, 0.05, -0.7);
        fromCloud.build(cloud, grouped, columns, groupedColumns.data(), 0.05, -0.7);
        fromPoints.build(cloud, grouped, columns, groupedColumns.data(), 0.05, -0.7, byColumn.points().data());
        ASSERT_GT(plainGrouped.cells().size(), byColumn.cells().size()) << far;  // the thin cells reorder points
        EXPECT_NE(plainGrouped.order(), grouped) << far;
        for (const gseg::Grid* g : {&fromCloud, &fromPoints}) expectSameAsPlain(plainGrouped, *g);
    }
}

// --- params ------------------------------------------------------------------------------------

TEST(Params, DefaultsAreValidAndRoundTripThroughText) {
    gseg::Params p;
    EXPECT_NO_THROW(p.validate());
    gseg::Params q;
    q.cellSizeX = 9;
    for (const auto& k : gseg::Params::keys()) q.set(k, p.get(k));
    for (const auto& k : gseg::Params::keys()) EXPECT_EQ(q.get(k), p.get(k)) << k;
    EXPECT_EQ(q.cellSizeX, 1.5);
}

TEST(Params, RejectsUnknownKeysAndBadText) {
    gseg::Params p;
    EXPECT_THROW(p.set("cellSize", "1"), std::invalid_argument);
    EXPECT_THROW(p.set("cellSizeX", "1.5m"), std::invalid_argument);
    EXPECT_THROW(p.set("cellSizeX", ""), std::invalid_argument);
    EXPECT_THROW(p.set("minPointsPerCell", "3.5"), std::invalid_argument);
    EXPECT_THROW(p.set("ransacSeed", "-1"), std::invalid_argument);
    p.set("cellSizeX", " 2.25 ");
    EXPECT_EQ(p.cellSizeX, 2.25);
    // Switches take true/false (or 1/0), nothing else.
    p.set("checkPlaneNormal", "false");
    EXPECT_FALSE(p.checkPlaneNormal);
    p.set("recoverNearGround", " 1 ");
    EXPECT_TRUE(p.recoverNearGround);
    EXPECT_EQ(p.get("checkPlaneNormal"), "false");
    EXPECT_THROW(p.set("checkPlaneNormal", "yes"), std::invalid_argument);
}

TEST(Params, ValidateNamesTheOffendingKey) {
    const struct {
        const char* key;
        const char* value;
    } bad[] = {{"cellSizeX", "-1"},          {"cellSizeZPhase2", "0"},      {"slopeThresholdDegrees", "95"},
               {"groundInlierThreshold", "0"}, {"minPointsPerCell", "2"},     {"ransacConfidence", "1"},
               {"centroidSearchRadius", "nan"}, {"heightGate", "-0.1"},       {"gridGroundLevel", "1"},
               {"sparsityMedium", "0.0001"},  {"minGroundInlierRatio", "1"}, {"distToGround", "inf"},
               {"seedHeightTolerance", "0"},  {"recoveryThreshold", "-1"},   {"stripMinSpread", "nan"},
               {"belowGroundMargin", "-0.5"}, {"sparseRecoveryThreshold", "-0.1"}, {"floatingMinHeight", "inf"},
               {"floatingMaxDepth", "-1"},    {"bridgeRadius", "-5"},       {"bridgeGate", "nan"},
               {"bridgeMaxAngleDegrees", "91"}, {"bridgeMaxDrop", "-0.3"},
               {"bridgeGapGate", "inf"}};
    for (const auto& b : bad) {
        gseg::Params p;
        p.set(b.key, b.value);
        try {
            p.validate();
            ADD_FAILURE() << b.key << " = " << b.value << " accepted";
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find(b.key), std::string::npos) << e.what();
        }
    }
}

// --- plane fit ---------------------------------------------------------------------------------

namespace {
std::vector<Eigen::Vector3f> tiltedPlane(double deg, int n, int outliers, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0, 1.5);
    std::normal_distribution<float> noise(0, 0.01f);
    const float t = float(std::tan(deg * M_PI / 180));
    std::vector<Eigen::Vector3f> pts;
    for (int i = 0; i < n; ++i) {
        const float x = u(rng), y = u(rng);
        pts.emplace_back(x, y, -1.7f + t * x + noise(rng));
    }
    for (int i = 0; i < outliers; ++i) pts.emplace_back(u(rng), u(rng), -1.0f + u(rng));
    return pts;
}
}  // namespace

TEST(PlaneFit, RecoversPlaneAndInliersDeterministically) {
    const auto pts = tiltedPlane(10, 200, 40, 1);
    gseg::Params p;
    std::vector<std::uint8_t> in1, in2;
    const auto a = gseg::fitPlane(pts.data(), pts.size(), p, 123, in1);
    const auto b = gseg::fitPlane(pts.data(), pts.size(), p, 123, in2);
    ASSERT_TRUE(a.valid);
    EXPECT_NEAR(gseg::planeSlopeDegrees(a.normal), 10.0, 0.5);
    EXPECT_GE(a.numInliers, 199u);
    EXPECT_LE(a.numInliers, 200u + 5u);  // a few outliers may fall within 0.125 m
    EXPECT_EQ(in1, in2);
    EXPECT_EQ(a.numInliers, b.numInliers);
    EXPECT_LT(a.iterations, 100);  // adaptive: far from the 1000 bound
}

TEST(PlaneFit, SlopeLimitRejectsSteepPlanes) {
    const auto pts = tiltedPlane(50, 100, 0, 2);
    gseg::Params p;
    std::vector<std::uint8_t> in;
    EXPECT_TRUE(gseg::fitPlane(pts.data(), pts.size(), p, 1, in).valid);
    const auto limited = gseg::fitPlane(pts.data(), pts.size(), p, 1, in, 30.0, 0.5);
    EXPECT_TRUE(!limited.valid || limited.numInliers <= 50u);
}

TEST(PlaneFit, SingleRingIsALineNotATiltedPlane) {
    // 20 points on one horizontal line plus one stray point above and aside: the least tilted plane
    // through the line keeps the line, instead of tilting towards the stray point.
    std::vector<Eigen::Vector3f> pts;
    for (int i = 0; i < 20; ++i) pts.emplace_back(0.07f * i, 0.f, -1.7f);
    pts.emplace_back(0.7f, 0.45f, -1.33f);
    gseg::Params p;
    std::vector<std::uint8_t> in;
    const auto fit = gseg::fitPlane(pts.data(), pts.size(), p, 5, in, 30.0, 0.5);
    ASSERT_TRUE(fit.valid);
    EXPECT_EQ(fit.numInliers, 20u);
    EXPECT_EQ(in.back(), 0);
    EXPECT_LT(gseg::planeSlopeDegrees(fit.normal), 5.0);
}

// The classification's moments (PointMoments) spare the least-squares refit its sums where RANSAC's
// plane holds every point: the fit must be the same bit for bit, with and without outliers.
/// The seed of a tilted plane (every third with outliers).
class PlaneFitMoments : public ::testing::TestWithParam<std::uint32_t> {
public:
    static std::vector<Eigen::Vector3f> plane(std::uint32_t seed) {
        return tiltedPlane(double(seed % 20), 20 + int(seed) * 7, seed % 3 == 0 ? int(seed) : 0, seed);
    }
};

TEST_P(PlaneFitMoments, ClassificationMomentsGiveTheSameFitBitForBit) {
    const std::uint32_t seed = GetParam();
    gseg::Params p;
    const gseg::SlopeLimit slope(p);
    const auto pts = plane(seed);
    gseg::PointMoments m;
    gseg::classifyCell(pts.data(), pts.size(), p, slope, &m);
    ASSERT_EQ(m.count, pts.size());
    std::vector<std::uint8_t> in1, in2;
    gseg::PlaneFitScratch s1, s2;
    const auto a = gseg::fitPlane(pts.data(), pts.size(), p, seed, in1, s1, 30.0, 0.5);
    const auto b = gseg::fitPlane(pts.data(), pts.size(), p, seed, in2, s2, 30.0, 0.5, &m);
    ASSERT_EQ(a.valid, b.valid);
    EXPECT_EQ(std::memcmp(a.normal.data(), b.normal.data(), sizeof(float) * 3), 0);
    EXPECT_EQ(std::memcmp(&a.d, &b.d, sizeof(float)), 0);
    EXPECT_EQ(a.numInliers, b.numInliers);
    EXPECT_EQ(in1, in2);
}

INSTANTIATE_TEST_SUITE_P(Seeds, PlaneFitMoments, ::testing::Range(std::uint32_t(1), std::uint32_t(41)));

TEST(PlaneFit, TheSeedsOfPlaneFitMomentsMeetThePlaneThatHoldsEveryPoint) {
    gseg::Params p;
    int allInliers = 0;
    for (std::uint32_t seed = 1; seed <= 40; ++seed) {
        const auto pts = PlaneFitMoments::plane(seed);
        std::vector<std::uint8_t> in;
        gseg::PlaneFitScratch s;
        const auto a = gseg::fitPlane(pts.data(), pts.size(), p, seed, in, s, 30.0, 0.5);
        allInliers += a.valid && a.numInliers == pts.size();
    }
    EXPECT_GE(allInliers, 10);  // the case the moments serve was met
}

TEST(PlaneFit, MomentsOfAnotherPointCountAreNotTaken) {
    gseg::Params p;
    const gseg::SlopeLimit slope(p);
    // Moments of another point count are not taken; moments of these points are (zeroed, the refit
    // finds no plane through them and RANSAC's plane stays).
    const auto pts = tiltedPlane(5, 100, 0, 7);
    gseg::PointMoments m;
    gseg::classifyCell(pts.data(), pts.size(), p, slope, &m);
    std::vector<std::uint8_t> in;
    gseg::PlaneFitScratch s;
    const auto ref = gseg::fitPlane(pts.data(), pts.size(), p, 7, in, s, 30.0, 0.5);
    ASSERT_EQ(ref.numInliers, pts.size());
    gseg::PointMoments other = m;
    other.count = pts.size() - 1;
    other.scatter.setZero();
    const auto ignored = gseg::fitPlane(pts.data(), pts.size(), p, 7, in, s, 30.0, 0.5, &other);
    EXPECT_EQ(std::memcmp(ref.normal.data(), ignored.normal.data(), sizeof(float) * 3), 0);
    other.count = pts.size();
    const auto taken = gseg::fitPlane(pts.data(), pts.size(), p, 7, in, s, 30.0, 0.5, &other);
    EXPECT_NE(std::memcmp(ref.normal.data(), taken.normal.data(), sizeof(float) * 3), 0);
}

TEST(PlaneFit, DegenerateInputIsInvalid) {
    gseg::Params p;
    std::vector<std::uint8_t> in;
    const std::vector<Eigen::Vector3f> two = {{0, 0, 0}, {1, 0, 0}};
    EXPECT_FALSE(gseg::fitPlane(two.data(), two.size(), p, 1, in).valid);
    std::vector<Eigen::Vector3f> vertical;
    for (int i = 0; i < 10; ++i) vertical.emplace_back(0.f, 0.f, 0.1f * i);
    EXPECT_FALSE(gseg::fitPlane(vertical.data(), vertical.size(), p, 1, in, 30.0).valid);
}

// --- classification ----------------------------------------------------------------------------

// detail::pointSum and detail::scatterMatrix (SSE2, or AVX2 where the CPU has it) against Eigen's
// plain double sums in the points' order, bit for bit: every point, masked, one point, none, and
// far from the origin (where a different order of the sums would show).
TEST(CellClassifier, PointSumAndScatterMatrixEqualEigensSumsBitForBit) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    std::uniform_int_distribution<int> coin(0, 3);
    for (std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(2), std::size_t(3), std::size_t(17), std::size_t(250)}) {
        for (float offset : {0.f, 70.f, -3000.f}) {
            // The points end where the buffer ends: nothing past the last point may be read.
            auto buffer = std::make_unique<Eigen::Vector3f[]>(std::max<std::size_t>(n, 1));
            std::vector<std::uint8_t> mask(n);
            for (std::size_t i = 0; i < n; ++i) {
                buffer[i] = Eigen::Vector3f(offset + 10 * u(rng), offset * 0.5f + u(rng), u(rng) * 0.1f);
                mask[i] = coin(rng) != 0;
            }
            const Eigen::Vector3f* pts = buffer.get();
            for (const std::uint8_t* m : {static_cast<const std::uint8_t*>(nullptr), static_cast<const std::uint8_t*>(mask.data())}) {
                Eigen::Vector3d sum = Eigen::Vector3d::Zero();
                std::size_t count = 0;
                for (std::size_t i = 0; i < n; ++i)
                    if (!m || m[i]) sum += pts[i].cast<double>(), ++count;
                const Eigen::Vector3d mean = count ? Eigen::Vector3d(sum / double(count)) : Eigen::Vector3d::Zero();
                Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
                for (std::size_t i = 0; i < n; ++i) {
                    if (m && !m[i]) continue;
                    const Eigen::Vector3d d = pts[i].cast<double>() - mean;
                    cov.noalias() += d * d.transpose();
                }
                std::size_t gotCount = 99;
                const Eigen::Vector3d gotSum = gseg::detail::pointSum(pts, n, m, &gotCount);
                const Eigen::Matrix3d gotCov = gseg::detail::scatterMatrix(pts, n, mean, m);
                EXPECT_EQ(gotCount, count) << n;
                EXPECT_EQ(std::memcmp(gotSum.data(), sum.data(), sizeof(double) * 3), 0) << n << " " << offset;
                EXPECT_EQ(std::memcmp(gotCov.data(), cov.data(), sizeof(double) * 9), 0) << n << " " << offset << "\n"
                                                                                        << gotCov - cov;
            }
        }
    }
}

TEST(CellClassifier, LinePlaneClutterAndSmallCells) {
    gseg::Params p;
    std::vector<Eigen::Vector3f> line, steepLine, plane, blob, smallUpright, smallFlat;
    for (int i = 0; i < 20; ++i) {
        line.emplace_back(0.07f * i, 0.001f * (i % 2), -1.7f);
        steepLine.emplace_back(0.f, 0.001f * (i % 2), 0.07f * i);
    }
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j) plane.emplace_back(0.15f * i, 0.1f * j, -1.7f + 0.002f * ((i + j) % 3));
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(0, 1);
    for (int i = 0; i < 100; ++i) blob.emplace_back(u(rng), u(rng), u(rng));
    smallUpright = {{0, 0, 0}, {0.01f, 0, 0.5f}, {0, 0.01f, 1.0f}};
    smallFlat = {{0, 0, 0}, {0.5f, 0, 0.01f}, {0, 0.5f, 0}, {0.5f, 0.5f, 0}};
    EXPECT_EQ(gseg::classifyCell(line.data(), line.size(), p).cellClass, gseg::CellClass::Line);
    EXPECT_TRUE(gseg::classifyCell(line.data(), line.size(), p).groundCandidate);
    EXPECT_FALSE(gseg::classifyCell(steepLine.data(), steepLine.size(), p).groundCandidate);
    EXPECT_EQ(gseg::classifyCell(plane.data(), plane.size(), p).cellClass, gseg::CellClass::Plane);
    EXPECT_EQ(gseg::classifyCell(blob.data(), blob.size(), p).cellClass, gseg::CellClass::NonPlanar);
    EXPECT_EQ(gseg::classifyCell(smallUpright.data(), 3, p).cellClass, gseg::CellClass::Small);
    EXPECT_FALSE(gseg::classifyCell(smallUpright.data(), 3, p).groundCandidate);
    EXPECT_TRUE(gseg::classifyCell(smallFlat.data(), 4, p).groundCandidate);
    EXPECT_EQ(gseg::classifyCell(smallFlat.data(), 2, p).cellClass, gseg::CellClass::TooFewPoints);
}

TEST(CellClassifier, UprightSurfacesAreSteepWhateverAPlaneFitWouldFind) {
    gseg::Params p;
    // A 0.2 m tall band of a car side (a thin Phase II cell): every point lies within the inlier
    // distance of a horizontal plane through the band, but its normal is horizontal.
    std::vector<Eigen::Vector3f> band, strip, ring, flatPatch;
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 4; ++j) band.emplace_back(0.05f * i, 2.0f + 0.002f * (i % 3), -1.2f + 0.06f * j);
    // Two rings 0.12 m apart on a wall: a "line" 1.5 m long with a clear vertical second extent.
    for (int i = 0; i < 30; ++i)
        for (int j = 0; j < 2; ++j) strip.emplace_back(0.05f * i, 3.0f, -1.6f + 0.12f * j);
    // One ring on the ground, slightly curved: a line without a second extent.
    for (int i = 0; i < 30; ++i) ring.emplace_back(0.05f * i, 0.0004f * float(i * i) / 30.f, -1.73f);
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j) flatPatch.emplace_back(0.15f * i, 0.1f * j, -1.7f + 0.01f * i);
    const auto b = gseg::classifyCell(band.data(), band.size(), p);
    EXPECT_EQ(b.cellClass, gseg::CellClass::Plane);
    EXPECT_TRUE(b.steepNormal);
    const auto st = gseg::classifyCell(strip.data(), strip.size(), p);
    EXPECT_EQ(st.cellClass, gseg::CellClass::Line);
    EXPECT_FALSE(st.groundCandidate);
    const auto r = gseg::classifyCell(ring.data(), ring.size(), p);
    EXPECT_EQ(r.cellClass, gseg::CellClass::Line);
    EXPECT_TRUE(r.groundCandidate);
    EXPECT_NEAR(r.normal.z(), 1.0f, 1e-3f);  // the least tilted plane containing a level ring
    const auto f = gseg::classifyCell(flatPatch.data(), flatPatch.size(), p);
    EXPECT_EQ(f.cellClass, gseg::CellClass::Plane);
    EXPECT_FALSE(f.steepNormal);
    // The switch turns both rules off (only the plane fit decides, as before).
    p.checkPlaneNormal = false;
    EXPECT_FALSE(gseg::classifyCell(band.data(), band.size(), p).steepNormal);
    EXPECT_TRUE(gseg::classifyCell(strip.data(), strip.size(), p).groundCandidate);
}

TEST(Sparsity, Buckets) {
    gseg::Params p;
    EXPECT_EQ(gseg::sparsityBucket(0.0005, p), gseg::Sparsity::Low);
    EXPECT_EQ(gseg::sparsityBucket(0.001, p), gseg::Sparsity::Medium);
    EXPECT_EQ(gseg::sparsityBucket(0.0099, p), gseg::Sparsity::Medium);
    EXPECT_EQ(gseg::sparsityBucket(0.01, p), gseg::Sparsity::High);
}

// --- region growing ----------------------------------------------------------------------------

TEST(RegionGrowing, ChainReachedGapNotGateBlocksRejectedDoNotPropagate) {
    // A chain along x every 3 m from the seed, a gap of 8 m, then more; a step up of 1 m at x = 9.
    std::vector<Eigen::Vector3f> c;
    for (float x : {3.f, 6.f}) c.emplace_back(x, 0.f, -1.7f);
    c.emplace_back(9.f, 0.f, -0.7f);   // 2: 1 m higher
    c.emplace_back(20.f, 0.f, -1.7f);  // 3: beyond a gap
    gseg::ExpansionSettings s;
    s.seed = {0, 0, -1.7f};
    s.seedRadius = 5;
    s.radius = 5;
    std::vector<int> calls(c.size(), 0);
    auto acceptAll = [&](std::uint32_t i, const std::vector<std::uint32_t>&) { return ++calls[i] > 0; };
    auto state = gseg::expandRegion(c, s, acceptAll);
    EXPECT_EQ(state, (std::vector<std::uint8_t>{2, 2, 2, 0}));
    for (int n : {calls[0], calls[1], calls[2]}) EXPECT_EQ(n, 1);

    s.heightGate = 0.5;  // Phase II gate stops the 1 m step
    state = gseg::expandRegion(c, s, acceptAll);
    EXPECT_EQ(state, (std::vector<std::uint8_t>{2, 2, 0, 0}));

    s.heightGate = 10;  // a rejected cell does not propagate
    state = gseg::expandRegion(c, s, [](std::uint32_t i, const std::vector<std::uint32_t>&) { return i != 1; });
    EXPECT_EQ(state, (std::vector<std::uint8_t>{2, 1, 0, 0}));
}

TEST(RegionGrowing, GateMeasuresStepsAlongTheGroundPlanesSoSlopesStayConnected) {
    // Centroids 1.5 m apart up a 15 deg slope (0.40 m higher each), and the same rise as a
    // staircase of level cells (normals vertical): with a 0.1 m gate the slope is connected
    // because each step lies in both cells' planes; the staircase is not.
    const float t = float(std::tan(15 * M_PI / 180));
    std::vector<Eigen::Vector3f> c, slopeNormals, levelNormals;
    const Eigen::Vector3f n = Eigen::Vector3f(-t, 0, 1).normalized();
    for (int i = 1; i <= 6; ++i) {
        c.emplace_back(1.5f * i, 0.f, -1.7f + t * 1.5f * float(i - 1));
        slopeNormals.push_back(n);
        levelNormals.push_back(Eigen::Vector3f::UnitZ());
    }
    gseg::ExpansionSettings s;
    s.seed = {0, 0, -1.7f};
    s.seedRadius = 2;
    s.radius = 2;
    s.heightGate = 0.1;
    auto acceptAll = [](std::uint32_t, const std::vector<std::uint32_t>&) { return true; };
    s.normals = &slopeNormals;
    EXPECT_EQ(gseg::expandRegion(c, s, acceptAll), std::vector<std::uint8_t>(6, 2));
    s.normals = &levelNormals;
    EXPECT_EQ(gseg::expandRegion(c, s, acceptAll), (std::vector<std::uint8_t>{2, 0, 0, 0, 0, 0}));
    // The step must lie in both planes: a level cell next to a sloped one is not joined.
    std::vector<Eigen::Vector3f> mixed = slopeNormals;
    mixed[3] = Eigen::Vector3f::UnitZ();
    s.normals = &mixed;
    EXPECT_EQ(gseg::expandRegion(c, s, acceptAll), (std::vector<std::uint8_t>{2, 2, 2, 0, 0, 0}));
    // parents: who reached whom (the seed is -1, unreached -2).
    std::vector<std::int32_t> parents;
    gseg::expandRegion(c, s, acceptAll, &parents);
    EXPECT_EQ(parents, (std::vector<std::int32_t>{-1, 0, 1, -2, -2, -2}));
}

TEST(RegionGrowing, FewSeedsNearTheRobotReachBeyondTheBlindZone) {
    // A wheel of a parked car 3 m out is the only candidate in the seed disc (7.7 m) at ground
    // level; the ground starts 9 m out, beyond the neighbour radius from the wheel.
    std::vector<Eigen::Vector3f> c = {{3.f, 2.f, -1.6f}};
    for (int i = 0; i < 5; ++i) c.emplace_back(9.f + 1.5f * float(i), 0.f, -1.7f);
    c.emplace_back(10.f, 1.f, 0.f);  // a car roof, 1.7 m up: never a seed
    gseg::ExpansionSettings s;
    s.seed = {0, 0, -1.7f};
    s.seedRadius = 7.7;
    s.radius = 5;
    s.heightGate = 0.1;
    s.seedGate = 0.3;
    auto acceptAll = [](std::uint32_t, const std::vector<std::uint32_t>&) { return true; };
    EXPECT_EQ(gseg::expandRegion(c, s, acceptAll), (std::vector<std::uint8_t>{2, 0, 0, 0, 0, 0, 0}))
        << "the seed disc alone: the wheel, and nothing within 5 m of it";
    s.fewSeeds = 4;
    std::vector<std::int32_t> parents;
    EXPECT_EQ(gseg::expandRegion(c, s, acceptAll, &parents), (std::vector<std::uint8_t>{2, 2, 2, 2, 2, 2, 0}));
    // The second disc reaches 7.7 m beyond the wheel (3.6 m out): the ground up to 11.3 m seeds.
    EXPECT_EQ(parents[1], -1);
    EXPECT_EQ(parents[2], -1);
    EXPECT_GE(parents[5], 0) << "reached by the expansion, not seeded";
    // Enough seeds in the disc: no second disc.
    s.fewSeeds = 1;
    EXPECT_EQ(gseg::expandRegion(c, s, acceptAll), (std::vector<std::uint8_t>{2, 0, 0, 0, 0, 0, 0}));
}

// --- reflections below the ground ----------------------------------------------------------------

TEST(BelowGround, FlagsNonGroundFarBelowTheGroundOfItsColumnOrOfColumnsUpToTwoAway) {
    gseg::Params p;  // columns 1.5 m x 1.0 m, margin 0.5 m
    std::vector<float> xyz;
    std::vector<std::uint8_t> labels;
    auto add = [&](float x, float y, float z, bool ground) {
        xyz.insert(xyz.end(), {x, y, z});
        labels.push_back(ground);
    };
    for (int ix = 0; ix < 4; ++ix)  // ground at z = -1.7 over x in [0, 6), y in [0, 4)
        for (int iy = 0; iy < 4; ++iy) add(0.75f + 1.5f * float(ix), 0.5f + float(iy), -1.7f, true);
    add(2.0f, 1.5f, -2.5f, false);    // 16: 0.8 m below its column's ground: flagged
    add(2.0f, 1.5f, -2.0f, false);    // 17: 0.3 m below: kept
    add(8.0f, 1.5f, -2.5f, false);    // 18: column (5, 1), two away from the ground of (3, 1): flagged
    add(2.0f, 7.5f, -2.5f, false);    // 19: column (1, 7), four away: no reference, kept
    add(2.0f, 1.5f, std::nanf(""), false);  // 20: not finite: never flagged
    add(0.75f, 3.5f, -2.5f, true);    // 21: ground, the lowest of its column (0, 3), and never flagged
    add(0.75f, 3.2f, -2.9f, false);   // 22: 0.4 m below the lowest ground of its column: kept
    add(6.5f, 0.5f, -2.3f, false);    // 23: column (4, 0), one away, 0.6 m below: flagged
    add(12.5f, 0.5f, -1.7f, true);    // 24: ground of column (8, 0)
    const gseg::PointCloudView cloud(xyz.data(), labels.size());
    gseg::BelowGroundScratch scratch;
    const std::vector<std::uint32_t> want = {16, 18, 23};
    EXPECT_EQ(gseg::flagBelowGround(cloud, labels, p, scratch), want);
    p.belowGroundMargin = 0;  // 0: never
    EXPECT_TRUE(gseg::flagBelowGround(cloud, labels, p, scratch).empty());
    p.belowGroundMargin = 0.5;
    std::fill(labels.begin(), labels.end(), std::uint8_t(0));  // no ground: nothing to compare with
    EXPECT_TRUE(gseg::flagBelowGround(cloud, labels, p, scratch).empty());
}

// --- sensor height (distToGround: auto) ---------------------------------------------------------

TEST(SensorHeight, EstimatedFromTheLowestDenseSurface) {
    for (const double h : {0.8, 1.73, 2.5}) {
        gseg::test::Scene s;
        s.addFlatGround(h);
        s.addBox(6, -3, -h, 9, 3, -h + 2.0);         // a van
        s.addBox(-20, -25, -h, 20, -24, -h + 4.0);   // a wall
        s.addBox(-8, 5, -h + 2.5, -4, 9, -h + 3.0);  // an overhang
        const auto scan = gseg::test::simulate(s, gseg::test::Lidar::hdl64());
        const auto e = gseg::estimateSensorHeight(gseg::PointCloudView(scan.xyz.data(), scan.size()));
        ASSERT_TRUE(e.valid) << h;
        EXPECT_NEAR(e.height, h, 0.05) << h;
    }
    const std::vector<float> few = {5, 0, -1, 6, 0, -1};
    EXPECT_FALSE(gseg::estimateSensorHeight(gseg::PointCloudView(few.data(), 2)).valid);
}

TEST(SensorHeight, ReflectionsBelowTheGroundDoNotMoveIt) {
    gseg::test::Scene s;
    s.addFlatGround(1.73);
    auto scan = gseg::test::simulate(s, gseg::test::Lidar::hdl64());
    // Sparse points 1 to 3 m below the road in every direction (mirror reflections).
    for (int i = 0; i < 1500; ++i) {
        const double a = 0.0042 * i * 2 * M_PI, r = 3 + (i % 27);
        scan.xyz.insert(scan.xyz.end(), {float(r * std::cos(a)), float(r * std::sin(a)), float(-2.73 - (i % 20) * 0.1)});
        scan.truth.push_back(gseg::test::Truth::NonGround);
    }
    const auto e = gseg::estimateSensorHeight(gseg::PointCloudView(scan.xyz.data(), scan.size()));
    ASSERT_TRUE(e.valid) << e.reason;
    EXPECT_NEAR(e.height, 1.73, 0.03);
    EXPECT_LT(e.tiltDegrees, 0.5);
}

TEST(SensorHeight, TiltOfTheMountIsEstimated) {
    gseg::test::Scene s;
    s.addFlatGround(1.2);
    gseg::test::Lidar l;
    l.pitchDeg = 4, l.rollDeg = -3;
    const auto scan = gseg::test::simulate(s, l);
    const auto e = gseg::estimateSensorHeight(gseg::PointCloudView(scan.xyz.data(), scan.size()));
    ASSERT_TRUE(e.valid) << e.reason;
    EXPECT_NEAR(e.height, 1.2, 0.05);
    EXPECT_NEAR(e.tiltDegrees, 5.0, 0.3);
    EXPECT_TRUE(e.reason.empty());
}

TEST(AutoHeight, NeverRefusesAScanFallsBackToThePreviousThenTheDefault) {
    gseg::Params p;
    p.distToGround = 1.5;  // the fallback
    gseg::AutoHeightSegmenter seg(p);
    const std::vector<float> few = {5, 0, -1, 6, 0, -1, 7, 0, -1};  // no ground level to be found
    auto r = seg.segment(gseg::PointCloudView(few.data(), 3));
    EXPECT_EQ(r.result.labels.size(), 3u);
    EXPECT_EQ(r.decision.source, gseg::HeightDecision::Source::Fallback);
    EXPECT_EQ(r.decision.height, 1.5);
    EXPECT_NE(r.decision.describe().find("no estimate"), std::string::npos) << r.decision.describe();

    gseg::test::Scene s;
    s.addFlatGround(0.9);
    const auto scan = gseg::test::simulate(s, gseg::test::Lidar::vlp16());
    r = seg.segment(gseg::PointCloudView(scan.xyz.data(), scan.size()));
    EXPECT_EQ(r.decision.source, gseg::HeightDecision::Source::Estimated);
    EXPECT_NEAR(r.decision.height, 0.9, 0.05);
    EXPECT_GT(r.result.numGround, scan.size() / 2);
    const gseg::SensorHeightEstimate previous = r.decision.estimate;

    r = seg.segment(gseg::PointCloudView(few.data(), 3), true, &previous);
    EXPECT_EQ(r.decision.source, gseg::HeightDecision::Source::PreviousScan);
    EXPECT_NEAR(r.decision.height, 0.9, 0.05);
    // No state between scans: without a previous estimate, the fallback again.
    r = seg.segment(gseg::PointCloudView(few.data(), 3));
    EXPECT_EQ(r.decision.source, gseg::HeightDecision::Source::Fallback);
    EXPECT_EQ(r.decision.height, 1.5);
}

// The segmenter's route (ground per column from its grid, the finite points given) and the
// convenience one (both from the labels) flag the same points, on a seeded scene with reflections.
TEST(BelowGround, TheGridRouteAndTheLabelRouteFlagTheSamePoints) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(-20.f, 20.f), noise(-0.03f, 0.03f);
    std::vector<float> xyz;
    std::vector<std::uint8_t> labels;
    for (int i = 0; i < 4000; ++i) {
        const float x = u(rng), y = u(rng);
        const int kind = i % 10;  // 0: a reflection 1-3 m down, 1: an obstacle, 2: no return, else ground
        const float z = kind == 0 ? -1.73f - 1.f - std::fabs(noise(rng)) * 60 : kind == 1 ? 0.5f : -1.73f + noise(rng);
        xyz.insert(xyz.end(), {x, y, kind == 2 ? NAN : z});
        labels.push_back(kind >= 3);
    }
    const gseg::PointCloudView cloud(xyz.data(), labels.size());
    gseg::Params p;
    gseg::BelowGroundScratch scratch;
    std::vector<std::uint32_t> finite;
    std::vector<gseg::GroundColumn> columns;
    for (std::uint32_t i = 0; i < labels.size(); ++i) {
        if (std::isnan(cloud.z(i))) continue;
        finite.push_back(i);
        if (labels[i]) columns.push_back({gseg::cellCoord(cloud.x(i), p.cellSizeX), gseg::cellCoord(cloud.y(i), p.cellSizeY), cloud.z(i)});
    }
    std::reverse(columns.begin(), columns.end());  // any order
    const auto fromLabels = gseg::flagBelowGround(cloud, labels, p, scratch);
    EXPECT_EQ(gseg::flagBelowGround(cloud, finite, labels, columns, p, scratch), fromLabels);
    EXPECT_EQ(fromLabels.size(), 400u);  // every reflection, nothing else
}
