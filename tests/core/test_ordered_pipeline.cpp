// The map pipeline's structure (runOrdered: parallel per-scan work, results consumed in order,
// bounded memory, deterministic errors). The progress lines of every tool: test_tool_common.cpp.
#include <gseg/ordered_pipeline.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using gseg::PipelineOptions;
using gseg::runOrdered;

/// Deterministic, uneven work: later items are not always slower.
std::uint64_t busyWork(int item) {
    std::uint64_t x = std::uint64_t(item) + 1;
    const int rounds = 2000 * ((item * 7919) % 13);
    for (int i = 0; i < rounds; ++i) x = x * 6364136223846793005ULL + 1442695040888963407ULL;
    return x;
}

struct Outcome {
    std::vector<std::size_t> indices;
    std::vector<long> values;
    std::string error;
    std::size_t maxInFlight = 0;
};

/// Items 0..n-1; work gives item * item; optional failures at given items.
Outcome run(unsigned workers, int n, int workFailsAt = -1, int produceFailsAt = -1, int consumeFailsAt = -1,
        std::size_t capacity = 4) {
    Outcome r;
    int next = 0;
    std::atomic<std::size_t> produced{0}, consumed{0};
    auto produce = [&](int& item) {
        if (next == produceFailsAt) throw std::runtime_error("produce " + std::to_string(next));
        if (next == n) return false;
        item = next++;
        const std::size_t inFlight = ++produced - consumed;
        r.maxInFlight = std::max(r.maxInFlight, inFlight);
        return true;
    };
    auto work = [&](unsigned, int& item) -> long {
        volatile std::uint64_t sink = busyWork(item);
        (void)sink;
        if (item == workFailsAt) throw std::runtime_error("work " + std::to_string(item));
        return long(item) * item;
    };
    auto consume = [&](std::size_t index, long& value) {
        if (int(index) == consumeFailsAt) throw std::runtime_error("consume " + std::to_string(index));
        r.indices.push_back(index);
        r.values.push_back(value);
        ++consumed;
    };
    try {
        runOrdered<int, long>(produce, work, consume, PipelineOptions{workers, capacity});
    } catch (const std::runtime_error& e) {
        r.error = e.what();
    }
    return r;
}

/// The number of worker threads (0: everything on the calling thread).
class OrderedPipelineWorkers : public ::testing::TestWithParam<unsigned> {};

TEST_P(OrderedPipelineWorkers, ResultsAreConsumedInItemOrder) {
    const unsigned workers = GetParam();
    const Outcome r = run(workers, 200);
    ASSERT_EQ(r.indices.size(), 200u) << workers;
    for (std::size_t i = 0; i < 200; ++i) {
        EXPECT_EQ(r.indices[i], i) << workers;
        EXPECT_EQ(r.values[i], long(i * i)) << workers;
    }
    EXPECT_TRUE(r.error.empty()) << r.error;
}

INSTANTIATE_TEST_SUITE_P(AnyNumber, OrderedPipelineWorkers, ::testing::Values(0u, 1u, 2u, 5u));

TEST(OrderedPipeline, NoMoreThanCapacityItemsAreInFlight) {
    for (std::size_t capacity : {1u, 3u, 8u}) {
        const Outcome r = run(3, 100, -1, -1, -1, capacity);
        EXPECT_EQ(r.indices.size(), 100u);
        EXPECT_LE(r.maxInFlight, capacity);
        EXPECT_GE(r.maxInFlight, 1u);
    }
}

TEST_P(OrderedPipelineWorkers, TheErrorOfTheEarliestItemWinsAndEverythingBeforeItIsConsumed) {
    struct Case {
        int work, produce, consume;
        const char* error;
        std::size_t consumed;
    };
    const Case cases[] = {{5, -1, -1, "work 5", 5},  {9, 7, -1, "produce 7", 7}, {5, 30, -1, "work 5", 5},
                          {-1, 12, -1, "produce 12", 12}, {-1, -1, 3, "consume 3", 3}, {8, -1, 3, "consume 3", 3}};
    const unsigned workers = GetParam();
    for (const auto& c : cases) {
        const Outcome r = run(workers, 50, c.work, c.produce, c.consume);
        EXPECT_EQ(r.error, c.error) << workers << " workers";
        EXPECT_EQ(r.indices.size(), c.consumed) << c.error << ", " << workers << " workers";
    }
}

}  // namespace
