// BrickMap's OctoMap encoders: the .bt and .ot bytes of the tree the bricks stand for, written
// straight from the bricks (the store itself is brick_map.cpp).
#include "brick_map.hpp"

#include <algorithm>
#include <numeric>
#include <ostream>
#include <string>

namespace gseg::map::detail {

namespace {

/// OctoMap's binary encoding (OccupancyOcTreeBase::writeBinaryNode()): per inner node two bytes,
/// two bits per child i at bits 2i, 2i+1 of byte i / 4: 01 free leaf, 10 occupied leaf (as the
/// bit pair reads low to high), 11 inner node, 00 absent.
struct NodeBytes {
    std::uint8_t b[2] = {0, 0};
    void set(unsigned child, unsigned code) { b[child / 4] |= std::uint8_t(code << (2 * (child % 4))); }
};
constexpr unsigned kInner = 3, kOccupiedLeaf = 2, kFreeLeaf = 1;

/// The header of AbstractOccupancyOcTree::writeBinaryConst() / AbstractOcTree::write(), then the data.
void writeOctomapFile(std::ostream& out, const char* firstLine, const char* id, std::uint64_t nodes, double resolution,
                      const std::string& data) {
    out << firstLine << "\n# (feel free to add / change comments, but leave the first line as it is!)\n#\n";
    out << "id " << id << std::endl;
    out << "size " << nodes << std::endl;
    out << "res " << resolution << std::endl;
    out << "data" << std::endl;
    out.write(data.data(), std::streamsize(data.size()));
}

}  // namespace

void BrickMap::writeBinary(MapIndex m, std::ostream& out, double resolution) const {
    std::vector<std::size_t> order;
    for (std::size_t b : sortedBricks()) {
        const auto& e = bricks_[b].map[m].exists;
        if (std::any_of(std::begin(e), std::end(e), [](std::uint64_t w) { return w != 0; })) order.push_back(b);
    }
    std::string data;
    std::uint64_t nodes = order.empty() ? 0 : 1;
    auto put = [&](const NodeBytes& n) { data.append(reinterpret_cast<const char*>(n.b), 2); };
    // The node at depth 13 that a brick is: words (depth 14), bytes (depth 15), voxels (leaves).
    auto writeBrick = [&](const Words& t) {
        NodeBytes words;
        for (unsigned w = 0; w < 8; ++w)
            if (t.exists[w]) words.set(w, kInner), ++nodes;
        put(words);
        for (unsigned w = 0; w < 8; ++w) {
            if (!t.exists[w]) continue;
            NodeBytes bytes;
            for (unsigned j = 0; j < 8; ++j)
                if (t.exists[w] >> (8 * j) & 0xff) bytes.set(j, kInner), ++nodes;
            put(bytes);
            for (unsigned j = 0; j < 8; ++j) {
                const unsigned bits = unsigned(t.exists[w] >> (8 * j) & 0xff);
                if (!bits) continue;
                NodeBytes leaves;
                for (unsigned k = 0; k < 8; ++k) {
                    if (!(bits >> k & 1)) continue;
                    leaves.set(k, valueOf(t, w, (j << 3) | k) >= l_.occupied ? kOccupiedLeaf : kFreeLeaf), ++nodes;
                }
                put(leaves);
            }
        }
    };
    // A node above the bricks (depth < 13) holding order[lo, hi).
    auto writeInner = [&](auto&& self, std::size_t lo, std::size_t hi, int depth) -> void {
        NodeBytes children;
        std::size_t bounds[9];
        unsigned groups = 0;
        for (std::size_t i = lo; i < hi;) {
            const unsigned c = childIndex(codes_[order[i]] << 9, depth);
            std::size_t j = i;
            while (j < hi && childIndex(codes_[order[j]] << 9, depth) == c) ++j;
            children.set(c, kInner), ++nodes;
            bounds[groups++] = i;
            i = j;
        }
        bounds[groups] = hi;
        put(children);
        for (unsigned g = 0; g < groups; ++g) {
            if (depth + 1 < kTreeDepth - 3) self(self, bounds[g], bounds[g + 1], depth + 1);
            else writeBrick(bricks_[order[bounds[g]]].map[m]);
        }
    };
    if (!order.empty()) writeInner(writeInner, 0, order.size(), 0);
    writeOctomapFile(out, "# Octomap OcTree binary file", "OcTree", nodes, resolution, data);
}

namespace {

/// A node's colour in a ColorOcTree: the integer mean of its children's (all of them set here).
struct Colour {
    unsigned r = 0, g = 0, b = 0, n = 0;
    void add(const std::uint8_t* c) { r += c[0], g += c[1], b += c[2], ++n; }
    void add(const Colour& c) {
        const std::uint8_t m[3] = {std::uint8_t(c.r), std::uint8_t(c.g), std::uint8_t(c.b)};
        add(m);
    }
    Colour mean() const { return {r / n, g / n, b / n, 1}; }  // ColorOcTreeNode::getAverageChildColor()
};

}  // namespace

void BrickMap::writeColoured(std::ostream& out, double resolution, float leafLogOdds, const std::uint8_t ground[3],
                             const std::uint8_t obstacle[3]) const {
    // Per brick with an occupied voxel: which are obstacles (the rest of `any` is ground).
    struct Occupied {
        std::size_t brick;
        std::uint64_t any[8], obstacle[8];
        Colour colour;  // of the brick's node (depth 13)
    };
    std::vector<Occupied> bricks;
    for (std::size_t b : sortedBricks()) {
        Occupied o{b, {}, {}, {}};
        bool found = false;
        for (unsigned w = 0; w < 8; ++w) {
            for (const MapIndex m : {kObstacles, kGround}) {
                const Words& t = bricks_[b].map[m];
                for (std::uint64_t bits = t.exists[w]; bits; bits &= bits - 1) {
                    const unsigned v = unsigned(__builtin_ctzll(bits));
                    if (valueOf(t, w, v) < l_.occupied) continue;
                    if (m == kObstacles) o.obstacle[w] |= 1ULL << v;
                    o.any[w] |= 1ULL << v;
                    found = true;
                }
            }
        }
        if (found) bricks.push_back(o);
    }
    auto voxelColour = [&](const Occupied& o, unsigned w, unsigned v) {
        return (o.obstacle[w] >> v & 1) ? obstacle : ground;
    };
    auto byteColour = [&](const Occupied& o, unsigned w, unsigned j) {
        Colour c;
        for (unsigned k = 0; k < 8; ++k)
            if (o.any[w] >> (8 * j + k) & 1) c.add(voxelColour(o, w, 8 * j + k));
        return c.mean();
    };
    auto wordColour = [&](const Occupied& o, unsigned w) {
        Colour c;
        for (unsigned j = 0; j < 8; ++j)
            if (o.any[w] >> (8 * j) & 0xff) c.add(byteColour(o, w, j));
        return c.mean();
    };
    for (Occupied& o : bricks) {
        Colour c;
        for (unsigned w = 0; w < 8; ++w)
            if (o.any[w]) c.add(wordColour(o, w));
        o.colour = c.mean();
    }
    std::string data;
    std::uint64_t nodes = 0;
    // A node: its log-odds (all equal here: one hit each, inner nodes their maximum), colour, and
    // one bit per existing child (OcTreeBaseImpl::writeNodesRecurs(), ColorOcTreeNode::writeData()).
    auto node = [&](const Colour& c, unsigned childBits) {
        data.append(reinterpret_cast<const char*>(&leafLogOdds), sizeof leafLogOdds);
        data.push_back(char(c.r)), data.push_back(char(c.g)), data.push_back(char(c.b));
        data.push_back(char(childBits));
        ++nodes;
    };
    auto writeBrick = [&](const Occupied& o) {
        unsigned words = 0;
        for (unsigned w = 0; w < 8; ++w) words |= unsigned(o.any[w] != 0) << w;
        node(o.colour, words);
        for (unsigned w = 0; w < 8; ++w) {
            if (!o.any[w]) continue;
            unsigned bytes = 0;
            for (unsigned j = 0; j < 8; ++j) bytes |= unsigned((o.any[w] >> (8 * j) & 0xff) != 0) << j;
            node(wordColour(o, w), bytes);
            for (unsigned j = 0; j < 8; ++j) {
                const unsigned voxels = unsigned(o.any[w] >> (8 * j) & 0xff);
                if (!voxels) continue;
                node(byteColour(o, w, j), voxels);
                for (unsigned k = 0; k < 8; ++k) {
                    if (!(voxels >> k & 1)) continue;
                    const std::uint8_t* c = voxelColour(o, w, 8 * j + k);
                    node(Colour{c[0], c[1], c[2], 1}, 0);
                }
            }
        }
    };
    // Nodes above the bricks (depth < 13) holding bricks[lo, hi): colour first (it is written
    // before the children), then the subtree.
    auto groupsOf = [&](std::size_t lo, std::size_t hi, int depth, std::size_t* bounds) {
        unsigned groups = 0, bits = 0;
        for (std::size_t i = lo; i < hi;) {
            const unsigned c = childIndex(codes_[bricks[i].brick] << 9, depth);
            bounds[groups++] = i;
            bits |= 1u << c;
            while (i < hi && childIndex(codes_[bricks[i].brick] << 9, depth) == c) ++i;
        }
        bounds[groups] = hi;
        return std::make_pair(groups, bits);
    };
    auto colourOf = [&](auto&& self, std::size_t lo, std::size_t hi, int depth) -> Colour {
        if (depth == kTreeDepth - 3) return bricks[lo].colour;
        std::size_t bounds[9];
        const auto [groups, bits] = groupsOf(lo, hi, depth, bounds);
        (void)bits;
        Colour c;
        for (unsigned g = 0; g < groups; ++g) c.add(self(self, bounds[g], bounds[g + 1], depth + 1));
        return c.mean();
    };
    auto writeInner = [&](auto&& self, std::size_t lo, std::size_t hi, int depth) -> void {
        if (depth == kTreeDepth - 3) return writeBrick(bricks[lo]);
        std::size_t bounds[9];
        const auto [groups, bits] = groupsOf(lo, hi, depth, bounds);
        node(colourOf(colourOf, lo, hi, depth), bits);
        for (unsigned g = 0; g < groups; ++g) self(self, bounds[g], bounds[g + 1], depth + 1);
    };
    if (!bricks.empty()) writeInner(writeInner, 0, bricks.size(), 0);
    writeOctomapFile(out, "# Octomap OcTree file", "ColorOcTree", nodes, resolution, data);
}

}  // namespace gseg::map::detail
