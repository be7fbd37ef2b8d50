#pragma once
/// \file brick_map.hpp
/// Internal to the map layer: the working form of the two occupancy maps (ground, obstacles)
/// while a drive is integrated. Voxels live in bricks of 8 x 8 x 8 (the OctoMap subtree three
/// levels above the leaves), found by a hash of the brick's Morton code; a brick is eight words
/// of 4 x 4 x 4 voxels (one 64-bit mask each: which voxels exist). A scan's update then costs one
/// hash lookup per brick and a few instructions per voxel, instead of a walk down the octree and
/// a node allocation per voxel.
///
/// Every voxel keeps exactly the value (float log-odds, same operations, same clamping) that
/// OcTree::updateNode() calls would give it, and the OctoMap files are written from the bricks in
/// the exact bytes of that tree. A word whose existing voxels all sit at the same clamping bound
/// keeps one value instead of 64 (as OctoMap prunes such subtrees): most of a drive's free space.

#include <gseg/map/scan_update.hpp>

#include "../cpu_features.hpp"
#include "map_tree.hpp"
#include "voxel_keys.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace gseg::map::detail {

enum MapIndex { kGround = 0, kObstacles = 1 };

/// The occupancy parameters as OctoMap holds them (float log-odds).
struct LogOdds {
    float hit = 0, miss = 0, clampMin = 0, clampMax = 0, occupied = 0;
};

class BrickMap {
public:
    explicit BrickMap(const LogOdds& l) : l_(l) {}

    /// Threads that applyScan() may use (1: the calling thread only). The maps are the same
    /// whatever the number: each map's bricks are split into kShards fixed shards by brick
    /// position, each shard is updated by one thread in list order, with value blocks of its own
    /// (one pool per map and shard), so every voxel sees the same operations in the same order.
    void setThreads(unsigned threads) { threads_ = threads < 1 ? 1 : threads; }
    /// Whether a word's voxels are updated eight at a time where the CPU has AVX2 (the default),
    /// or one at a time; the values are the same (tested).
    void setEightAtOnce(bool on) { avx2_ = on && gseg::detail::cpuHasAvx2(); }

    /// The shards of the bricks this map holds (bit s: shard s; default all): applyScan() skips
    /// the voxels of the others (held by another process, merged with merge() before writing).
    /// Every voxel still sees the same updates in the same order as in one map.
    void setOwnedShards(unsigned mask) { owned_ = mask & ((1u << kShards) - 1); }
    /// The shard of a voxel (Morton code at map resolution): its brick's (shardOf()).
    static unsigned shardOfVoxel(std::uint64_t code) { return shardOf(code >> 9); }
    static constexpr unsigned shards() { return kShards; }

    /// Every brick as bytes (codes, voxels, values), for merge() in another process.
    std::string encode() const;
    /// Adds the bricks of `bytes` (encode() of a map holding other shards): none may exist here.
    /// Throws std::runtime_error on malformed bytes or a brick held by both.
    void merge(const std::string& bytes);

    /// One scan: misses on `free` in both maps (ground: only where not occupied), hits on the
    /// ground and obstacle voxels in their own map (which are remembered as ever obstacle). The
    /// hit lists sorted.
    void applyScan(const VoxelBricks& free, const std::vector<std::uint64_t>& groundHits,
                   const std::vector<std::uint64_t>& obstacleHits);

    /// Log-odds of a voxel; false if it does not exist in that map.
    bool value(MapIndex m, std::uint64_t code, float& logOdds) const;
    bool occupied(MapIndex m, std::uint64_t code) const {
        float v = 0;
        return value(m, code, v) && v >= l_.occupied;
    }
    /// Calls f(code, logOdds) for every voxel of map m (brick by brick, not sorted).
    template <class F>
    void forEachVoxel(MapIndex m, F&& f) const {
        for (std::size_t b = 0; b < bricks_.size(); ++b) {
            const Words& t = bricks_[b].map[m];
            for (unsigned w = 0; w < 8; ++w)
                for (std::uint64_t bits = t.exists[w]; bits; bits &= bits - 1) {
                    const unsigned v = unsigned(__builtin_ctzll(bits));
                    f((codes_[b] << 9) | (w << 6) | v, valueOf(t, w, v));
                }
        }
    }
    /// Calls f(code, logOdds) for every obstacle voxel that an obstacle point ever fell in (brick by brick).
    template <class F>
    void forEachEverObstacle(F&& f) const {
        for (std::size_t b = 0; b < bricks_.size(); ++b)
            for (unsigned w = 0; w < 8; ++w)
                for (std::uint64_t bits = bricks_[b].everObstacle[w]; bits; bits &= bits - 1) {
                    const unsigned v = unsigned(__builtin_ctzll(bits));
                    f((codes_[b] << 9) | (w << 6) | v, valueOf(bricks_[b].map[kObstacles], w, v));
                }
    }
    /// Obstacle voxels once occupied by a hit and free now (seen through).
    std::size_t clearedObstacles() const;
    /// Voxels of map m: occupied (>= the occupancy threshold) or free.
    std::size_t count(MapIndex m, bool occupiedVoxels) const;

    /// What OcTree::writeBinaryConst() writes for map m updated voxel by voxel (header included).
    void writeBinary(MapIndex m, std::ostream& out, double resolution) const;
    /// What ColorOcTree::write() writes for a ColorOcTree holding, by one OcTree::updateNode(key,
    /// true) each, the occupied obstacle voxels in `obstacle` colour and the other occupied ground
    /// voxels in `ground` colour, after updateInnerOccupancy() (inner nodes: the children's
    /// maximum log-odds and their mean colour). `leafLogOdds`: the tree's hit log-odds.
    void writeColoured(std::ostream& out, double resolution, float leafLogOdds, const std::uint8_t ground[3],
                       const std::uint8_t obstacle[3]) const;
    /// Map m as an OcTree (pruned where eight leaves are equal and clamped).
    std::unique_ptr<MapTree> toTree(MapIndex m, const MapTree& configured) const;

    std::size_t bricks() const { return bricks_.size(); }
    std::size_t blocksInUse() const {  ///< words with 64 values
        std::size_t n = 0;
        for (const Pool& p : pools_) n += p.count - p.free.size();
        return n;
    }
    std::size_t bytes() const {  ///< memory held (capacity, not size)
        std::size_t n = index_.bytes() + codes_.capacity() * sizeof(std::uint64_t) + bricks_.capacity() * sizeof(Brick);
        for (const Pool& p : pools_) n += p.chunks.size() * kBlocksPerChunk * 64 * sizeof(float) + p.free.capacity() * sizeof(std::int32_t);
        return n;
    }

private:
    /// One map's part of a brick: per word of 64 voxels, which exist, and their values (a block
    /// of 64, or one value for all).
    struct Words {
        std::uint64_t exists[8] = {0, 0, 0, 0, 0, 0, 0, 0};
        std::int32_t block[8] = {-1, -1, -1, -1, -1, -1, -1, -1};
        float uniform[8] = {0, 0, 0, 0, 0, 0, 0, 0};
        std::uint8_t atMin[8] = {0, 0, 0, 0, 0, 0, 0, 0}, atMax[8] = {0, 0, 0, 0, 0, 0, 0, 0};  ///< values at each bound
    };
    struct Brick {
        Words map[2];
        std::uint64_t everObstacle[8] = {0, 0, 0, 0, 0, 0, 0, 0};  ///< obstacle hit at least once
    };
    static constexpr std::size_t kBlocksPerChunk = 1024;
    /// Shards per map: bricks by the lowest bit of their x and y (a checkerboard of 2 x 2 bricks).
    static constexpr unsigned kShards = 4;
    static unsigned shardOf(std::uint64_t brickCode) { return unsigned(brickCode & 3); }
    /// A block id: the pool (map * kShards + shard) in the bits from kPoolShift, the block within it below.
    static constexpr int kPoolShift = 27;
    /// Value blocks of one (map, shard): kBlocksPerChunk x 64 floats per chunk, and the free ones.
    struct Pool {
        std::vector<std::unique_ptr<float[]>> chunks;
        std::vector<std::int32_t> free;  ///< block ids (pool bits included)
        std::size_t count = 0;           ///< blocks made
    };

    LogOdds l_;
    CodeIndex index_;                   ///< brick code -> position in bricks_
    std::vector<std::uint64_t> codes_;  ///< brick code (Morton code >> 9) per brick
    std::vector<Brick> bricks_;
    Pool pools_[2 * kShards];
    unsigned threads_ = 1;
    bool avx2_ = gseg::detail::cpuHasAvx2();  ///< updateWord() eight voxels at a time
    unsigned owned_ = (1u << kShards) - 1;  ///< setOwnedShards()

    const float* block(std::int32_t b) const {
        const std::size_t local = std::size_t(b) & ((std::size_t(1) << kPoolShift) - 1);
        return &pools_[std::size_t(b) >> kPoolShift].chunks[local / kBlocksPerChunk][(local % kBlocksPerChunk) * 64];
    }
    float* block(std::int32_t b) { return const_cast<float*>(static_cast<const BrickMap*>(this)->block(b)); }
    float valueOf(const Words& t, unsigned w, unsigned v) const { return t.block[w] >= 0 ? block(t.block[w])[v] : t.uniform[w]; }
    Brick& brickOf(std::uint64_t brickCode);
    /// A block of 64 values from `pool` (a free one, or a new one: poolBits say which pool).
    std::int32_t takeBlock(Pool& pool, std::int32_t poolBits);
    void collapseIfUniform(Words& t, Pool& pool);
    /// OccupancyOcTreeBase::updateNode(key, delta) (OctoMap 1.9.7 semantics) for every voxel of
    /// word w in `bits`; `skipOccupied`: an occupied voxel keeps its value. A word with one value
    /// for all gets a block of 64 only where a voxel changes.
    void updateWord(Words& t, unsigned w, std::uint64_t bits, float delta, bool skipOccupied, Pool& pool, std::int32_t poolBits);
    /// The voxels of one brick in one of a scan's lists (applyScan()): codes [from, to) of a hit
    /// list, or the brick's eight words of the free set (`from`).
    struct Run {
        std::uint32_t brick;       ///< position in bricks_
        std::uint32_t shard;
        const std::uint64_t *from, *to;
    };
    std::vector<Run> runs_[3];  ///< applyScan()'s runs of free, ground and obstacle voxels
    void applyShard(unsigned shard, const std::vector<Run>& free, const std::vector<Run>& groundHits, const std::vector<Run>& obstacleHits);
    std::vector<std::size_t> sortedBricks() const;
};

}  // namespace gseg::map::detail
