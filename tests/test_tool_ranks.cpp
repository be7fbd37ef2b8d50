// What the tools share for MPI (#12), in one process: the split of work over ranks, the bytes of
// the messages, and the ranks of a tool started without a launcher (one process, MPI untouched).
#include "common/bytes.hpp"
#include "common/ranks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>

using gseg::tools::splitByWork;

namespace {

std::vector<std::uint64_t> loads(const std::vector<std::uint64_t>& work, const std::vector<int>& owner, int ranks) {
    std::vector<std::uint64_t> l(std::size_t(ranks), 0);
    for (std::size_t i = 0; i < work.size(); ++i) l[std::size_t(owner[i])] += work[i];
    return l;
}

/// The ranks of this test process, started without a launcher (one object per process, as MPI
/// can only be initialised once).
gseg::tools::Ranks& alone() {
    for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"}) ::unsetenv(v);
    static int argc = 1;
    static char name[] = "test", *args[] = {name, nullptr};
    static char** argv = args;
    static gseg::tools::Ranks ranks(argc, argv);
    return ranks;
}

}  // namespace

TEST(SplitByWork, LargestFirstToTheLeastLoadedRank) {
    // Largest first: 9 -> 0, 8 -> 1, 7 -> 1 (8 < 9), 6 -> 0 (9 < 15), 5 -> 0 (15 = 15: the lower rank), 4 -> 1.
    const std::vector<std::uint64_t> work = {5, 9, 4, 7, 8, 6};
    const std::vector<int> owner = splitByWork(work, 2);
    EXPECT_EQ(owner, (std::vector<int>{0, 0, 1, 1, 1, 0}));
    EXPECT_EQ(loads(work, owner, 2), (std::vector<std::uint64_t>{20, 19}));
    EXPECT_EQ(splitByWork(work, 2), owner) << "deterministic";
}

TEST(SplitByWork, TiesGoToTheLowestRankAndEveryItemHasOne) {
    EXPECT_EQ(splitByWork({3, 3, 3, 3}, 3), (std::vector<int>{0, 1, 2, 0}));
    EXPECT_EQ(splitByWork({0, 0, 0}, 2), (std::vector<int>{0, 1, 0})) << "unknown sizes still spread";
    EXPECT_EQ(splitByWork({7}, 1), (std::vector<int>{0}));
    EXPECT_TRUE(splitByWork({}, 2).empty());
    EXPECT_THROW(splitByWork({1}, 0), std::invalid_argument);
}

TEST(SplitByWork, OneHugeItemDoesNotDragOthersAlong) {
    std::vector<std::uint64_t> work(20, 1);
    work[7] = 100;
    const std::vector<int> owner = splitByWork(work, 3);
    for (std::size_t i = 0; i < work.size(); ++i) {
        if (i != 7) {
            EXPECT_NE(owner[i], owner[7]) << "item " << i << " shares the rank of the huge one";
        }
    }
    EXPECT_EQ(loads(work, owner, 3)[1] + loads(work, owner, 3)[2], 19u);
}

TEST(ShareItems, OneProcessDoesEveryItemAndGetsThemBackByIndex) {
    gseg::tools::Ranks& ranks = alone();
    std::vector<int> owner;
    std::vector<std::size_t> asked;
    const auto all = gseg::tools::shareItems(ranks, {5, 9, 1}, [&](const std::vector<std::size_t>& mine) {
        asked = mine;
        std::vector<std::string> out;
        for (std::size_t i : mine) out.push_back("item " + std::to_string(i));
        return out;
    }, &owner);
    EXPECT_EQ(asked, (std::vector<std::size_t>{0, 1, 2})) << "ascending";
    EXPECT_EQ(all, (std::vector<std::string>{"item 0", "item 1", "item 2"}));
    EXPECT_EQ(owner, (std::vector<int>{0, 0, 0}));
    auto throws = [](const std::vector<std::size_t>&) -> std::vector<std::string> { throw std::runtime_error("disk gone"); };
    EXPECT_THROW(gseg::tools::shareItems(ranks, {1, 2}, throws), std::runtime_error);
    auto short_ = [](const std::vector<std::size_t>&) { return std::vector<std::string>{"only one"}; };
    EXPECT_THROW(gseg::tools::shareItems(ranks, {1, 2}, short_), std::runtime_error) << "one result per item";
}

TEST(Bytes, ValuesRoundTripBitForBit) {
    gseg::tools::ByteWriter out;
    const double values[] = {0.1 + 0.2, -0.0, std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::infinity()};
    out.u64(0).u64(std::numeric_limits<std::uint64_t>::max()).str(std::string("a\0b", 3)).str("");
    for (double v : values) out.f64(v);
    out.f64(std::nan(""));
    EXPECT_EQ(out.bytes().size(), 8u * 2 + (8 + 3) + 8 + 8 * 5);
    EXPECT_EQ(out.bytes()[8], '\xff') << "little-endian";
    gseg::tools::ByteReader in(out.bytes());
    EXPECT_EQ(in.u64(), 0u);
    EXPECT_EQ(in.u64(), std::numeric_limits<std::uint64_t>::max());
    EXPECT_EQ(in.str(), std::string("a\0b", 3));
    EXPECT_EQ(in.str(), "");
    for (double v : values) {
        const double back = in.f64();
        EXPECT_EQ(std::signbit(back), std::signbit(v));
        EXPECT_EQ(back, v);
    }
    EXPECT_TRUE(std::isnan(in.f64()));
    EXPECT_TRUE(in.done());
    EXPECT_THROW(in.u64(), std::runtime_error);
}

TEST(Bytes, AShortOrLyingMessageThrows) {
    gseg::tools::ByteWriter out;
    out.u64(1000);  // a string length with no string after it
    gseg::tools::ByteReader in(out.bytes());
    EXPECT_THROW(in.str(), std::runtime_error);
    const std::string three = "abc";
    gseg::tools::ByteReader shortOne(three);
    EXPECT_THROW(shortOne.u64(), std::runtime_error);
}

TEST(Ranks, WithoutALauncherTheToolIsOneProcess) {
    gseg::tools::Ranks& ranks = alone();
    EXPECT_EQ(ranks.rank(), 0);
    EXPECT_EQ(ranks.size(), 1);
    EXPECT_TRUE(ranks.root());
    EXPECT_EQ(ranks.gather("mine"), (std::vector<std::string>{"mine"}));
    EXPECT_EQ(ranks.broadcast("value"), "value");
    EXPECT_EQ(ranks.firstError(""), "");
    EXPECT_EQ(ranks.firstError("bad file"), "bad file") << "rank 0's message has no prefix";
    EXPECT_EQ(ranks.exitCode(0), 0);
    EXPECT_EQ(ranks.exitCode(3), 3);
}
