// BrickMap: the voxel store of the two maps while a drive is integrated (brick_map.hpp); its
// OctoMap byte encoders are in brick_map_octomap_bytes.cpp.
#include "brick_map.hpp"

#include <algorithm>
#include <numeric>
#include <string>

namespace gseg::map::detail {

inline BrickMap::Brick& BrickMap::brickOf(std::uint64_t brickCode) {
    bool inserted = false;
    const std::uint32_t i = index_.insert(brickCode, inserted);
    if (inserted) codes_.push_back(brickCode), bricks_.emplace_back();
    return bricks_[i];
}

inline void BrickMap::collapseIfUniform(Words& t) {
    for (unsigned w = 0; w < 8; ++w) {
        if (t.block[w] < 0) continue;
        const int n = __builtin_popcountll(t.exists[w]);
        if (t.atMin[w] != n && t.atMax[w] != n) continue;
        t.uniform[w] = t.atMin[w] == n ? l_.clampMin : l_.clampMax;
        freeBlocks_.push_back(t.block[w]);
        t.block[w] = -1;
    }
}

inline void BrickMap::update(Words& t, unsigned local, float delta, bool skipOccupied) {
    const unsigned w = local >> 6, v = local & 63;
    const std::uint64_t bit = 1ULL << v;
    const bool exists = t.exists[w] & bit;
    const float old = exists ? valueOf(t, w, v) : 0.f;
    if (skipOccupied && exists && old >= l_.occupied) return;  // ground does not move
    float value = old + delta;  // OcTreeNode::addValue(), then the clamping of updateNodeLogOdds()
    if (value < l_.clampMin) value = l_.clampMin;
    else if (value > l_.clampMax) value = l_.clampMax;
    if (exists && value == old) return;  // at the bound already
    if (t.block[w] < 0) {  // one value for the word so far: give it 64
        if (freeBlocks_.empty()) {
            if (blockCount_ % kBlocksPerChunk == 0) chunks_.emplace_back(new float[kBlocksPerChunk * 64]);
            freeBlocks_.push_back(std::int32_t(blockCount_++));
        }
        t.block[w] = freeBlocks_.back();
        freeBlocks_.pop_back();
        std::fill(block(t.block[w]), block(t.block[w]) + 64, t.uniform[w]);
    }
    if (exists) {
        t.atMin[w] -= old == l_.clampMin;
        t.atMax[w] -= old == l_.clampMax;
    }
    t.exists[w] |= bit;
    block(t.block[w])[v] = value;
    t.atMin[w] += value == l_.clampMin;
    t.atMax[w] += value == l_.clampMax;
}

void BrickMap::applyScan(const std::vector<std::uint64_t>& free, const std::vector<std::uint64_t>& groundHits,
                         const std::vector<std::uint64_t>& obstacleHits) {
    // Brick by brick: the codes of one brick are consecutive in a sorted list.
    auto forEachBrick = [&](const std::vector<std::uint64_t>& codes, auto&& perBrick) {
        for (std::size_t i = 0; i < codes.size();) {
            const std::uint64_t brick = codes[i] >> 9;
            std::size_t j = i;
            while (j < codes.size() && codes[j] >> 9 == brick) ++j;
            perBrick(brickOf(brick), &codes[i], &codes[j]);
            i = j;
        }
    };
    forEachBrick(free, [&](Brick& b, const std::uint64_t* from, const std::uint64_t* to) {
        for (const std::uint64_t* c = from; c != to; ++c) {
            update(b.map[kGround], unsigned(*c & 511), l_.miss, true);
            update(b.map[kObstacles], unsigned(*c & 511), l_.miss, false);
        }
        collapseIfUniform(b.map[kGround]);
        collapseIfUniform(b.map[kObstacles]);
    });
    forEachBrick(groundHits, [&](Brick& b, const std::uint64_t* from, const std::uint64_t* to) {
        for (const std::uint64_t* c = from; c != to; ++c) update(b.map[kGround], unsigned(*c & 511), l_.hit, false);
        collapseIfUniform(b.map[kGround]);
    });
    forEachBrick(obstacleHits, [&](Brick& b, const std::uint64_t* from, const std::uint64_t* to) {
        for (const std::uint64_t* c = from; c != to; ++c) {
            update(b.map[kObstacles], unsigned(*c & 511), l_.hit, false);
            b.everObstacle[(*c >> 6) & 7] |= 1ULL << (*c & 63);
        }
        collapseIfUniform(b.map[kObstacles]);
    });
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
