// BrickMap: the voxel store of the two maps while a drive is integrated (brick_map.hpp); its
// OctoMap byte encoders are in brick_map_octomap_bytes.cpp.
#include "brick_map.hpp"

#include <gseg/io/bytes.hpp>

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <exception>
#include <system_error>
#include <thread>
#include <numeric>
#include <string>

namespace gseg::map::detail {

inline BrickMap::Brick& BrickMap::brickOf(std::uint64_t brickCode) {
    bool inserted = false;
    const std::uint32_t i = index_.insert(brickCode, inserted);
    if (inserted) codes_.push_back(brickCode), bricks_.emplace_back();
    return bricks_[i];
}

inline std::int32_t BrickMap::takeBlock(Pool& pool, std::int32_t poolBits) {
    if (pool.free.empty()) {
        if (pool.count % kBlocksPerChunk == 0) pool.chunks.emplace_back(new float[kBlocksPerChunk * 64]);
        pool.free.push_back(poolBits | std::int32_t(pool.count++));
    }
    const std::int32_t b = pool.free.back();
    pool.free.pop_back();
    return b;
}

inline void BrickMap::collapseIfUniform(Words& t, Pool& pool) {
    for (unsigned w = 0; w < 8; ++w) {
        if (t.block[w] < 0) continue;
        const int n = __builtin_popcountll(t.exists[w]);
        if (t.atMin[w] != n && t.atMax[w] != n) continue;
        t.uniform[w] = t.atMin[w] == n ? l_.clampMin : l_.clampMax;
        pool.free.push_back(t.block[w]);
        t.block[w] = -1;
    }
}

namespace {

/// `old + delta` clamped as OcTreeNode::addValue() and updateNodeLogOdds() do.
inline float clamped(float old, float delta, const LogOdds& l) {
    float value = old + delta;
    if (value < l.clampMin) value = l.clampMin;
    else if (value > l.clampMax) value = l.clampMax;
    return value;
}

/// One voxel's update: OccupancyOcTreeBase::updateNode(key, delta) (OctoMap 1.9.7 semantics) on
/// voxel v of a word whose values are `values` (a block of 64), `exists` and its counts of values
/// at each bound.
inline void updateVoxel(float* values, std::uint64_t& exists, std::uint8_t& atMin, std::uint8_t& atMax, unsigned v, float delta,
                        bool skipOccupied, const LogOdds& l) {
    const std::uint64_t bit = 1ULL << v;
    const bool had = exists & bit;
    const float old = had ? values[v] : 0.f;
    if (skipOccupied && had && old >= l.occupied) return;  // ground does not move
    const float value = clamped(old, delta, l);
    if (had && value == old) return;  // at the bound already
    if (had) {
        atMin -= old == l.clampMin;
        atMax -= old == l.clampMax;
    }
    exists |= bit;
    values[v] = value;
    atMin += value == l.clampMin;
    atMax += value == l.clampMax;
}

#if defined(__GNUC__) && defined(__x86_64__)
/// updateVoxel() for every voxel of `bits`, eight at a time: each lane does updateVoxel()'s
/// addition, clamping and comparisons (IEEE single precision, the same values).
__attribute__((target("avx2,popcnt"))) void updateWordAvx2(float* values, std::uint64_t bits, std::uint64_t& exists, std::uint8_t& atMin,
                                                           std::uint8_t& atMax, float delta, bool skipOccupied, const LogOdds& l) {
    const __m256 vDelta = _mm256_set1_ps(delta), vMin = _mm256_set1_ps(l.clampMin), vMax = _mm256_set1_ps(l.clampMax),
                 vOccupied = _mm256_set1_ps(l.occupied);
    const __m256i laneBits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    std::uint64_t had = exists;
    int dMin = 0, dMax = 0;
    for (unsigned j = 0; j < 8; ++j) {
        const unsigned todo = unsigned(bits >> (8 * j)) & 0xffu;
        if (!todo) continue;
        const unsigned e = unsigned(had >> (8 * j)) & 0xffu;
        const __m256i eLanes = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(int(e)), laneBits), laneBits);
        const __m256 old = _mm256_and_ps(_mm256_loadu_ps(values + 8 * j), _mm256_castsi256_ps(eLanes));  // a new voxel: 0
        const __m256 value = _mm256_min_ps(_mm256_max_ps(_mm256_add_ps(old, vDelta), vMin), vMax);
        unsigned act = todo;
        if (skipOccupied) act &= ~(e & unsigned(_mm256_movemask_ps(_mm256_cmp_ps(old, vOccupied, _CMP_GE_OQ))));
        const unsigned changed = act & ~(e & unsigned(_mm256_movemask_ps(_mm256_cmp_ps(value, old, _CMP_EQ_OQ))));
        if (!changed) continue;
        const __m256i store = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(int(changed)), laneBits), laneBits);
        _mm256_maskstore_ps(values + 8 * j, store, value);
        const unsigned wasMin = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(old, vMin, _CMP_EQ_OQ)));
        const unsigned wasMax = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(old, vMax, _CMP_EQ_OQ)));
        const unsigned isMin = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(value, vMin, _CMP_EQ_OQ)));
        const unsigned isMax = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(value, vMax, _CMP_EQ_OQ)));
        dMin += __builtin_popcount(changed & isMin) - __builtin_popcount(changed & e & wasMin);
        dMax += __builtin_popcount(changed & isMax) - __builtin_popcount(changed & e & wasMax);
        exists |= std::uint64_t(changed) << (8 * j);
    }
    atMin = std::uint8_t(atMin + dMin), atMax = std::uint8_t(atMax + dMax);
}
#endif

}  // namespace

inline void BrickMap::updateWord(Words& t, unsigned w, std::uint64_t bits, float delta, bool skipOccupied, Pool& pool, std::int32_t poolBits) {
    if (t.block[w] < 0) {  // one value for the word so far: a block of 64 only where a voxel changes
        const float u = t.uniform[w];
        const bool existingStay = (skipOccupied && u >= l_.occupied) || clamped(u, delta, l_) == u;
        if (!(bits & ~t.exists[w]) && existingStay) return;  // most of a long drive's free space, seen again and again
        t.block[w] = takeBlock(pool, poolBits);
        std::fill(block(t.block[w]), block(t.block[w]) + 64, u);
    }
    float* values = block(t.block[w]);
#if defined(__GNUC__) && defined(__x86_64__)
    if (avx2_) return updateWordAvx2(values, bits, t.exists[w], t.atMin[w], t.atMax[w], delta, skipOccupied, l_);
#endif
    for (; bits; bits &= bits - 1) updateVoxel(values, t.exists[w], t.atMin[w], t.atMax[w], unsigned(__builtin_ctzll(bits)), delta, skipOccupied, l_);
}

/// Calls f(word, bits) for each word of a brick's sorted voxels [from, to): `bits` has one per
/// voxel of the word.
template <class F>
inline void forEachWord(const std::uint64_t* from, const std::uint64_t* to, F&& f) {
    for (const std::uint64_t* c = from; c != to;) {
        const unsigned w = unsigned(*c >> 6) & 7;
        std::uint64_t bits = 0;
        for (; c != to && (unsigned(*c >> 6) & 7) == w; ++c) bits |= 1ULL << (*c & 63);
        f(w, bits);
    }
}

void BrickMap::applyShard(unsigned shard, const std::vector<Run>& free, const std::vector<Run>& groundHits,
                          const std::vector<Run>& obstacleHits) {
    Pool& groundPool = pools_[kGround * kShards + shard];
    Pool& obstaclePool = pools_[kObstacles * kShards + shard];
    const auto groundBits = std::int32_t((kGround * kShards + shard) << kPoolShift);
    const auto obstacleBits = std::int32_t((kObstacles * kShards + shard) << kPoolShift);
    // Word by word; the two maps of a brick are apart (their own words and value pools), so each
    // map's voxels are updated in list order, one map after the other (a voxel's update does not
    // depend on another's: a word's voxels are updated together, updateWord()).
    for (const Run& r : free) {
        if (r.shard != shard) continue;
        Brick& b = bricks_[r.brick];
        for (unsigned w = 0; w < 8; ++w) {
            const std::uint64_t bits = r.from[w];
            if (!bits) continue;
            updateWord(b.map[kGround], w, bits, l_.miss, true, groundPool, groundBits);
            updateWord(b.map[kObstacles], w, bits, l_.miss, false, obstaclePool, obstacleBits);
        }
        collapseIfUniform(b.map[kGround], groundPool);
        collapseIfUniform(b.map[kObstacles], obstaclePool);
    }
    for (const Run& r : groundHits) {
        if (r.shard != shard) continue;
        Brick& b = bricks_[r.brick];
        forEachWord(r.from, r.to, [&](unsigned w, std::uint64_t bits) { updateWord(b.map[kGround], w, bits, l_.hit, false, groundPool, groundBits); });
        collapseIfUniform(b.map[kGround], groundPool);
    }
    for (const Run& r : obstacleHits) {
        if (r.shard != shard) continue;
        Brick& b = bricks_[r.brick];
        forEachWord(r.from, r.to, [&](unsigned w, std::uint64_t bits) {
            updateWord(b.map[kObstacles], w, bits, l_.hit, false, obstaclePool, obstacleBits);
            b.everObstacle[w] |= bits;
        });
        collapseIfUniform(b.map[kObstacles], obstaclePool);
    }
}

void BrickMap::applyScan(const VoxelBricks& free, const std::vector<std::uint64_t>& groundHits,
                         const std::vector<std::uint64_t>& obstacleHits) {
    // First, on this thread, every brick the scan touches (made in list order: the same bricks in
    // the same order as one voxel at a time), as runs: a free brick's eight words, or the codes of
    // one brick, consecutive in a sorted hit list. Then the shards, each on one thread (both maps
    // of its bricks).
    auto runsOf = [&](const std::vector<std::uint64_t>& codes, std::vector<Run>& runs) {
        runs.clear();
        for (std::size_t i = 0; i < codes.size();) {
            const std::uint64_t brick = codes[i] >> 9;
            std::size_t j = i;
            while (j < codes.size() && codes[j] >> 9 == brick) ++j;
            if (!(owned_ >> shardOf(brick) & 1)) {  // another process's brick (setOwnedShards())
                i = j;
                continue;
            }
            const Brick& b = brickOf(brick);
            runs.push_back({std::uint32_t(&b - bricks_.data()), shardOf(brick), codes.data() + i, codes.data() + j});
            i = j;
        }
    };
    std::vector<Run>& freeRuns = runs_[0];  // kept between scans (their memory)
    std::vector<Run>& groundRuns = runs_[1];
    std::vector<Run>& obstacleRuns = runs_[2];
    freeRuns.clear();
    for (std::size_t i = 0; i < free.bricks.size(); ++i) {
        const std::uint64_t brick = free.bricks[i];
        if (!(owned_ >> shardOf(brick) & 1)) continue;  // another process's brick (setOwnedShards())
        const Brick& b = brickOf(brick);
        freeRuns.push_back({std::uint32_t(&b - bricks_.data()), shardOf(brick), &free.words[8 * i], &free.words[8 * i] + 8});
    }
    runsOf(groundHits, groundRuns);
    runsOf(obstacleHits, obstacleRuns);
    auto part = [&](unsigned shard) { applyShard(shard, freeRuns, groundRuns, obstacleRuns); };
    const std::size_t voxels = free.voxels() + groundHits.size() + obstacleHits.size();
    const unsigned threads = voxels < 20000 ? 1u : std::min(threads_, kShards);  // small scans: not worth a thread
    if (threads <= 1) {
        for (unsigned k = 0; k < kShards; ++k) part(k);
        return;
    }
    std::vector<std::thread> helpers;
    std::vector<std::exception_ptr> errors(threads);
    auto share = [&](unsigned t) {
        try {
            for (unsigned k = t; k < kShards; k += threads) part(k);
        } catch (...) {
            errors[t] = std::current_exception();  // std::bad_alloc of a value block
        }
    };
    helpers.reserve(threads);
    unsigned started = 1;
    try {
        for (; started < threads; ++started) helpers.emplace_back(share, started);
    } catch (const std::system_error&) {  // no thread to be had (ulimit -u, address space): the rest here
    }
    share(0);
    for (unsigned t = started; t < threads; ++t) share(t);
    for (std::thread& h : helpers) h.join();
    for (const std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);
}

std::string BrickMap::encode() const {
    gseg::io::ByteWriter out;
    out.raw("GSB1", 4).u64(bricks_.size());
    for (std::size_t b = 0; b < bricks_.size(); ++b) {
        out.u64(codes_[b]);
        for (unsigned w = 0; w < 8; ++w) out.u64(bricks_[b].everObstacle[w]);
        for (const Words& t : bricks_[b].map)
            for (unsigned w = 0; w < 8; ++w) {
                out.u64(t.exists[w]);
                if (!t.exists[w]) continue;
                out.u32((t.block[w] >= 0 ? 1u : 0u) | unsigned(t.atMin[w]) << 8 | unsigned(t.atMax[w]) << 16);
                if (t.block[w] < 0) {
                    out.f32(t.uniform[w]);
                    continue;
                }
                const float* v = block(t.block[w]);
                for (unsigned k = 0; k < 64; ++k) out.f32(v[k]);
            }
    }
    return out.take();
}

void BrickMap::merge(const std::string& bytes) {
    if (bytes.compare(0, 4, "GSB1") != 0) throw std::runtime_error("the voxels of another process: not GSB1 bytes");
    gseg::io::ByteReader in(bytes, "the voxels of another process", 4);
    const std::uint64_t n = in.u64();
    for (std::uint64_t i = 0; i < n; ++i) {
        const std::uint64_t code = in.u64();
        bool inserted = false;
        const std::uint32_t at = index_.insert(code, inserted);
        if (!inserted) throw std::runtime_error("the voxels of another process: brick " + std::to_string(code) + " held twice");
        codes_.push_back(code), bricks_.emplace_back();
        Brick& b = bricks_[at];
        for (unsigned w = 0; w < 8; ++w) b.everObstacle[w] = in.u64();
        for (unsigned m = 0; m < 2; ++m) {
            Words& t = b.map[m];
            Pool& pool = pools_[m * kShards + shardOf(code)];
            const auto poolBits = std::int32_t((m * kShards + shardOf(code)) << kPoolShift);
            for (unsigned w = 0; w < 8; ++w) {
                t.exists[w] = in.u64();
                if (!t.exists[w]) continue;
                const std::uint32_t head = in.u32();
                t.atMin[w] = std::uint8_t(head >> 8), t.atMax[w] = std::uint8_t(head >> 16);
                if (head & 1) {
                    t.block[w] = takeBlock(pool, poolBits);
                    float* values = block(t.block[w]);
                    for (unsigned k = 0; k < 64; ++k) values[k] = in.f32();
                } else {
                    t.uniform[w] = in.f32();
                }
            }
        }
    }
    if (!in.done()) throw std::runtime_error("the voxels of another process: bytes left over");
}

std::size_t BrickMap::clearedObstacles() const {
    std::size_t n = 0;
    for (const Brick& b : bricks_)
        for (unsigned w = 0; w < 8; ++w)
            for (std::uint64_t bits = b.everObstacle[w]; bits; bits &= bits - 1)
                n += valueOf(b.map[kObstacles], w, unsigned(__builtin_ctzll(bits))) < l_.occupied;
    return n;
}

bool BrickMap::value(MapIndex m, std::uint64_t code, float& logOdds) const {
    const long b = index_.find(code >> 9);
    if (b < 0) return false;
    const Words& t = bricks_[std::size_t(b)].map[m];
    const unsigned w = unsigned(code >> 6) & 7, v = unsigned(code & 63);
    if (!(t.exists[w] >> v & 1)) return false;
    logOdds = valueOf(t, w, v);
    return true;
}

std::size_t BrickMap::count(MapIndex m, bool occupiedVoxels) const {
    std::size_t n = 0;
    for (const Brick& b : bricks_) {
        const Words& t = b.map[m];
        for (unsigned w = 0; w < 8; ++w) {
            if (t.block[w] < 0) {
                if ((t.uniform[w] >= l_.occupied) == occupiedVoxels) n += std::size_t(__builtin_popcountll(t.exists[w]));
                continue;
            }
            for (std::uint64_t bits = t.exists[w]; bits; bits &= bits - 1)
                n += (block(t.block[w])[__builtin_ctzll(bits)] >= l_.occupied) == occupiedVoxels;
        }
    }
    return n;
}

std::vector<std::size_t> BrickMap::sortedBricks() const {
    std::vector<std::size_t> order(bricks_.size());
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return codes_[a] < codes_[b]; });
    return order;
}

std::unique_ptr<MapTree> BrickMap::toTree(MapIndex m, const MapTree& configured) const {
    auto tree = std::make_unique<MapTree>(configured.getResolution());
    tree->setProbHit(configured.getProbHit()), tree->setProbMiss(configured.getProbMiss());
    tree->setClampingThresMin(configured.getClampingThresMin()), tree->setClampingThresMax(configured.getClampingThresMax());
    tree->setOccupancyThres(configured.getOccupancyThres());
    std::vector<std::uint64_t> codes;
    std::vector<float> values;
    for (std::size_t b : sortedBricks()) {
        const Words& t = bricks_[b].map[m];
        codes.clear(), values.clear();
        for (unsigned w = 0; w < 8; ++w)
            for (std::uint64_t bits = t.exists[w]; bits; bits &= bits - 1) {
                const unsigned v = unsigned(__builtin_ctzll(bits));
                codes.push_back((codes_[b] << 9) | (w << 6) | v);
                values.push_back(valueOf(t, w, v));
            }
        tree->setSorted(codes.data(), values.data(), codes.size());
    }
    return tree;
}

}  // namespace gseg::map::detail
