#pragma once
/// \file voxel_keys.hpp
/// Internal to the map layer: OctoMap voxel keys as Morton codes, and the sets the ray casting
/// fills. Header-only so that tests (also under UBSan) can use it directly.
///
/// Morton code of a key (16 bits per axis): bit 3b of the code is bit b of x, 3b+1 of y, 3b+2 of
/// z. The three bits at level b are OctoMap's child index at tree depth 15 - b, so sorting codes
/// sorts voxels in the tree's depth-first order (children 0..7): a sorted list updates a tree in
/// one walk.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include <octomap/OcTreeKey.h>  // needs <cstddef>, <cstdint> and <vector> first

namespace gseg::map::detail {

constexpr int kTreeDepth = 16;  ///< OctoMap's tree depth (16-bit keys)

/// Spreads the 16 bits of v to every third bit (bit i goes to bit 3i).
inline std::uint64_t spreadBits(std::uint64_t v) {
    v &= 0xffff;
    v = (v | (v << 16)) & 0x0000ff0000ffULL;
    v = (v | (v << 8)) & 0x00f00f00f00fULL;
    v = (v | (v << 4)) & 0x0c30c30c30c3ULL;
    v = (v | (v << 2)) & 0x249249249249ULL;
    return v;
}

/// Inverse of spreadBits(): every third bit (from bit 0) back into 16 bits.
inline std::uint16_t compactBits(std::uint64_t v) {
    v &= 0x249249249249ULL;
    v = (v | (v >> 2)) & 0x0c30c30c30c3ULL;
    v = (v | (v >> 4)) & 0x00f00f00f00fULL;
    v = (v | (v >> 8)) & 0x0000ff0000ffULL;
    v = (v | (v >> 16)) & 0xffffULL;
    return std::uint16_t(v);
}

inline std::uint64_t mortonCode(const octomap::OcTreeKey& k) {
    return spreadBits(k[0]) | (spreadBits(k[1]) << 1) | (spreadBits(k[2]) << 2);
}

inline octomap::OcTreeKey keyOfCode(std::uint64_t code) {
    return octomap::OcTreeKey(compactBits(code), compactBits(code >> 1), compactBits(code >> 2));
}

/// Child index (0..7) taken at tree depth `depth` (0 = root) on the way to the voxel `code`.
inline unsigned childIndex(std::uint64_t code, int depth) { return unsigned(code >> (3 * (kTreeDepth - 1 - depth))) & 7u; }

/// Deepest tree depth whose node holds both voxels (0 = only the root): where their paths split.
inline int sharedDepth(std::uint64_t a, std::uint64_t b) {
    const std::uint64_t diff = a ^ b;
    if (diff == 0) return kTreeDepth;
    const int highest = 63 - __builtin_clzll(diff);
    return kTreeDepth - 1 - highest / 3;
}

/// Last code inside the node at `depth` that holds `code`.
inline std::uint64_t lastCodeBelow(std::uint64_t code, int depth) {
    const int bits = 3 * (kTreeDepth - depth);
    return bits >= 64 ? ~0ULL : code | ((1ULL << bits) - 1);
}

/// Two signed 32-bit indices (a grid column, a tile) as one hash key; no shift of a negative value.
inline std::uint64_t pairKey(std::int64_t a, std::int64_t b) {
    return (std::uint64_t(std::uint32_t(std::int32_t(a))) << 32) | std::uint64_t(std::uint32_t(std::int32_t(b)));
}
inline std::pair<std::int64_t, std::int64_t> splitPairKey(std::uint64_t key) {
    return {std::int32_t(std::uint32_t(key >> 32)), std::int32_t(std::uint32_t(key))};
}

inline std::uint64_t mixBits(std::uint64_t x) {  // SplitMix64 finaliser: a good hash of a code
    x ^= x >> 30, x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27, x *= 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

/// Open-addressing map from 64-bit codes (any value but ~0) to dense indices 0, 1, 2, ...
/// in insertion order. Grows by doubling; no removal.
class CodeIndex {
public:
    static constexpr std::uint64_t kEmpty = ~0ULL;

    /// Index of `code`, inserting it as the next index if new (`inserted` says which).
    std::uint32_t insert(std::uint64_t code, bool& inserted) {
        if (2 * (size_ + 1) > slots_.size()) grow();
        std::size_t s = mixBits(code) & mask_;
        while (slots_[s].code != kEmpty) {
            if (slots_[s].code == code) {
                inserted = false;
                return slots_[s].index;
            }
            s = (s + 1) & mask_;
        }
        slots_[s] = {code, std::uint32_t(size_)};
        inserted = true;
        return std::uint32_t(size_++);
    }
    /// Index of `code`, or -1.
    long find(std::uint64_t code) const {
        if (slots_.empty()) return -1;
        for (std::size_t s = mixBits(code) & mask_;; s = (s + 1) & mask_) {
            if (slots_[s].code == code) return long(slots_[s].index);
            if (slots_[s].code == kEmpty) return -1;
        }
    }
    std::size_t size() const { return size_; }
    std::size_t bytes() const { return slots_.capacity() * sizeof(Slot); }
    /// Empties the index, keeping its memory.
    void clear() {
        if (size_ == 0) return;
        std::fill(slots_.begin(), slots_.end(), Slot());
        size_ = 0;
    }

private:
    struct Slot {
        std::uint64_t code = kEmpty;
        std::uint32_t index = 0;
    };
    std::vector<Slot> slots_;
    std::size_t mask_ = 0, size_ = 0;

    void grow() {
        std::vector<Slot> old = std::move(slots_);
        slots_.assign(std::max<std::size_t>(1024, 2 * old.size()), Slot());
        mask_ = slots_.size() - 1;
        for (const Slot& o : old) {
            if (o.code == kEmpty) continue;
            std::size_t s = mixBits(o.code) & mask_;
            while (slots_[s].code != kEmpty) s = (s + 1) & mask_;
            slots_[s] = o;
        }
    }
};

/// A set of voxels stored as bricks of 8 x 8 x 8 voxels (the subtrees three levels above the
/// leaves): one 512-bit mask per touched brick, bit = the voxel's last 9 Morton bits. Ray casting
/// marks many voxels of the same brick in a row, so the last brick is cached.
class BrickSet {
public:
    /// Adds the voxel; true if it was not in the set.
    bool insert(std::uint64_t code) {
        std::uint64_t& word = wordOf(code);
        const std::uint64_t bit = 1ULL << (code & 63);
        const bool added = !(word & bit);
        word |= bit;
        return added;
    }
    bool contains(std::uint64_t code) const {
        const long b = index_.find(code >> 9);
        return b >= 0 && (masks_[std::size_t(b)][(code >> 6) & 7] >> (code & 63) & 1);
    }
    /// Empties the set, keeping its memory.
    void clear() {
        index_.clear();
        bricks_.clear();
        masks_.clear();
        cachedBrick_ = CodeIndex::kEmpty;
        recentBricks_.fill(CodeIndex::kEmpty);
    }
    /// The voxels of brick `brick` in `words` (its eight words of 64) into this set.
    void insertBrick(std::uint64_t brick, const std::uint64_t* words) {
        auto& m = maskOf(brick);
        for (int w = 0; w < 8; ++w) m[std::size_t(w)] |= words[w];
    }
    /// Calls f(brick, words) for every brick of the set (in the order they were added).
    template <class F>
    void forEachBrick(F&& f) const {
        for (std::size_t b = 0; b < bricks_.size(); ++b) f(bricks_[b], masks_[b].data());
    }
    /// Every voxel of `other` into this set.
    void merge(const BrickSet& other) {
        for (std::size_t b = 0; b < other.bricks_.size(); ++b) {
            auto& m = maskOf(other.bricks_[b]);
            for (int w = 0; w < 8; ++w) m[std::size_t(w)] |= other.masks_[b][std::size_t(w)];
        }
    }
    /// The voxels of this set that are in none of `minus`, brick by brick: the bricks left with a
    /// voxel in increasing order (`bricks`), eight words each (`words`).
    void sortedBricks(std::vector<std::uint64_t>& bricks, std::vector<std::uint64_t>& words,
                      const std::vector<const BrickSet*>& minus = {}) const {
        std::vector<std::uint32_t> order(bricks_.size());
        for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return bricks_[a] < bricks_[b]; });
        bricks.clear(), words.clear();
        bricks.reserve(order.size()), words.reserve(8 * order.size());
        for (std::uint32_t b : order) {
            std::array<std::uint64_t, 8> m = masks_[b];
            for (const BrickSet* other : minus) {
                const long o = other->index_.find(bricks_[b]);
                if (o < 0) continue;
                for (int w = 0; w < 8; ++w) m[std::size_t(w)] &= ~other->masks_[std::size_t(o)][std::size_t(w)];
            }
            if ((m[0] | m[1] | m[2] | m[3] | m[4] | m[5] | m[6] | m[7]) == 0) continue;
            bricks.push_back(bricks_[b]);
            words.insert(words.end(), m.begin(), m.end());
        }
    }
    /// The voxels of this set that are in none of `minus`, as sorted Morton codes.
    std::vector<std::uint64_t> sortedCodes(const std::vector<const BrickSet*>& minus = {}) const {
        std::vector<std::uint64_t> bricks, words, out;
        sortedBricks(bricks, words, minus);
        for (std::size_t b = 0; b < bricks.size(); ++b)
            for (std::uint64_t w = 0; w < 8; ++w)
                for (std::uint64_t bits = words[8 * b + w]; bits; bits &= bits - 1)
                    out.push_back((bricks[b] << 9) | (w << 6) | std::uint64_t(__builtin_ctzll(bits)));
        return out;
    }

private:
    CodeIndex index_;
    std::vector<std::uint64_t> bricks_;                  ///< brick code (Morton code >> 9) per brick
    std::vector<std::array<std::uint64_t, 8>> masks_;  ///< 512 voxel bits per brick
    std::uint64_t cachedBrick_ = CodeIndex::kEmpty;
    std::size_t cachedIndex_ = 0;
    /// The bricks used lately, by their lowest Morton bits (16 x 8 x 8 bricks around any one):
    /// the rays of a scan are cast in the order of its points, so neighbouring rays cross the
    /// same bricks, and most brick changes are found here instead of in index_.
    static constexpr std::size_t kRecent = 1024;
    std::array<std::uint64_t, kRecent> recentBricks_ = filledRecent();
    std::array<std::uint32_t, kRecent> recentIndices_{};
    static std::array<std::uint64_t, kRecent> filledRecent() {
        std::array<std::uint64_t, kRecent> a;
        a.fill(CodeIndex::kEmpty);
        return a;
    }

    std::array<std::uint64_t, 8>& maskOf(std::uint64_t brick) {
        if (brick != cachedBrick_) {
            const std::size_t r = brick & (kRecent - 1);
            if (recentBricks_[r] == brick) {
                cachedIndex_ = recentIndices_[r];
            } else {
                bool inserted = false;
                cachedIndex_ = index_.insert(brick, inserted);
                if (inserted) bricks_.push_back(brick), masks_.push_back({});
                recentBricks_[r] = brick, recentIndices_[r] = std::uint32_t(cachedIndex_);
            }
            cachedBrick_ = brick;
        }
        return masks_[cachedIndex_];
    }
    std::uint64_t& wordOf(std::uint64_t code) { return maskOf(code >> 9)[(code >> 6) & 7]; }
};

}  // namespace gseg::map::detail
