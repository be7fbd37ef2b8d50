// The map pipeline's structure (runOrdered: parallel per-scan work, results consumed in order,
// bounded memory, deterministic errors) and the progress lines of the map tools.
#include <gseg/map/ordered_pipeline.hpp>
#include <gseg/map/progress.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using gseg::map::PipelineOptions;
using gseg::map::runOrdered;

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

TEST(OrderedPipeline, ResultsAreConsumedInItemOrderWithAnyNumberOfWorkers) {
    for (unsigned workers : {0u, 1u, 2u, 5u}) {
        const Outcome r = run(workers, 200);
        ASSERT_EQ(r.indices.size(), 200u) << workers;
        for (std::size_t i = 0; i < 200; ++i) {
            EXPECT_EQ(r.indices[i], i) << workers;
            EXPECT_EQ(r.values[i], long(i * i)) << workers;
        }
        EXPECT_TRUE(r.error.empty()) << r.error;
    }
}

TEST(OrderedPipeline, NoMoreThanCapacityItemsAreInFlight) {
    for (std::size_t capacity : {1u, 3u, 8u}) {
        const Outcome r = run(3, 100, -1, -1, -1, capacity);
        EXPECT_EQ(r.indices.size(), 100u);
        EXPECT_LE(r.maxInFlight, capacity);
        EXPECT_GE(r.maxInFlight, 1u);
    }
}

TEST(OrderedPipeline, TheErrorOfTheEarliestItemWinsAndEverythingBeforeItIsConsumed) {
    struct Case {
        int work, produce, consume;
        const char* error;
        std::size_t consumed;
    };
    const Case cases[] = {{5, -1, -1, "work 5", 5},  {9, 7, -1, "produce 7", 7}, {5, 30, -1, "work 5", 5},
                          {-1, 12, -1, "produce 12", 12}, {-1, -1, 3, "consume 3", 3}, {8, -1, 3, "consume 3", 3}};
    for (unsigned workers : {0u, 2u, 4u})
        for (const auto& c : cases) {
            const Outcome r = run(workers, 50, c.work, c.produce, c.consume);
            EXPECT_EQ(r.error, c.error) << workers << " workers";
            EXPECT_EQ(r.indices.size(), c.consumed) << c.error << ", " << workers << " workers";
        }
}

/// Progress lines written to memory with a clock the test moves.
struct Captured {
    char* buf = nullptr;
    std::size_t size = 0;
    std::FILE* f = open_memstream(&buf, &size);
    double now = 0;
    ~Captured() {
        if (f) std::fclose(f);
        std::free(buf);
    }
    std::string text() {
        std::fflush(f);
        return std::string(buf, size);
    }
};

TEST(Progress, PlainLinesAtASteadyRateWhenNotATerminal) {
    Captured out;
    gseg::map::Progress p(out.f, "tool", "scans", 0, 10.0, [&] { return out.now; });
    for (int k = 1; k <= 40; ++k) {
        out.now = k;  // one scan per second, a quarter of the input every 10 scans
        p.update(std::size_t(k), k / 40.0);
    }
    p.finish(40);
    const std::string t = out.text();
    EXPECT_EQ(t,
              "tool: 1 scans, 1.0 scans/s, 2 %, 39 s left\n"
              "tool: 11 scans, 1.0 scans/s, 28 %, 29 s left\n"
              "tool: 21 scans, 1.0 scans/s, 52 %, 19 s left\n"
              "tool: 31 scans, 1.0 scans/s, 78 %, 9 s left\n"
              "tool: 40 scans, 1.0 scans/s, 40 s in all\n");
}

TEST(Progress, OneLiveLineOnATerminal) {
    Captured out;
    gseg::map::Progress p(out.f, "tool", "scans", 1, 10.0, [&] { return out.now; });
    for (int k = 1; k <= 10; ++k) {
        out.now = 0.1 * k;
        p.update(std::size_t(k), -1);  // unknown fraction: no time left
    }
    p.message("tool: skipped scan 3");
    p.finish(10);
    const std::string t = out.text();
    EXPECT_EQ(std::count(t.begin(), t.end(), '\n'), 2) << t;
    EXPECT_EQ(t.find("left"), std::string::npos) << t;
    EXPECT_NE(t.find("\rtool: 1 scans, 10.0 scans/s\033[K"), std::string::npos) << t;
    EXPECT_EQ(t.find("\rtool: 2 scans"), std::string::npos) << "redrawn at most every 0.2 s: " << t;
    EXPECT_NE(t.find("\rtool: skipped scan 3\033[K\n"), std::string::npos) << t;
    EXPECT_NE(t.find("\rtool: 10 scans, 10.0 scans/s, 1 s in all\033[K\n"), std::string::npos) << t;
}

TEST(Progress, DurationsReadLikeClocks) {
    EXPECT_EQ(gseg::map::formatDuration(0), "0 s");
    EXPECT_EQ(gseg::map::formatDuration(59.4), "59 s");
    EXPECT_EQ(gseg::map::formatDuration(61), "1 min 01 s");
    EXPECT_EQ(gseg::map::formatDuration(3725), "1 h 02 min");
    EXPECT_EQ(gseg::map::formatDuration(-5), "0 s");
}

}  // namespace
