#include "map_tree.hpp"

#include "voxel_keys.hpp"

#include <algorithm>
#include <limits>
#include <string>

namespace gseg::map::detail {
namespace {

/// Nodes of a full subtree whose root is at `depth` (every voxel below it present).
std::uint64_t fullSubtreeSize(int depth) {
    std::uint64_t n = 0, level = 1;
    for (int d = depth; d <= kTreeDepth; ++d, level *= 8) n += level;
    return n;
}

/// Binary encoding of the unpruned tree (OctoMap's writeBinaryNode()): per inner node two bytes,
/// two bits per child: 00 absent, 01 occupied leaf, 10 free leaf, 11 inner node.
class UnprunedWriter {
public:
    UnprunedWriter(const MapTree& tree, std::ostream& out) : tree_(tree), out_(out) {}

    void node(const octomap::OcTreeNode* n, int depth) {
        std::uint8_t bits[2] = {0, 0};
        for (unsigned i = 0; i < 8; ++i) {
            if (!tree_.nodeChildExists(n, i)) continue;
            bits[i / 4] |= std::uint8_t(code(tree_.getNodeChild(n, i), depth + 1) << (2 * (i % 4)));
        }
        out_.write(reinterpret_cast<const char*>(bits), 2);
        for (unsigned i = 0; i < 8; ++i) {
            if (!tree_.nodeChildExists(n, i)) continue;
            const octomap::OcTreeNode* c = tree_.getNodeChild(n, i);
            if (tree_.nodeHasChildren(c)) node(c, depth + 1);
            else if (depth + 1 < kTreeDepth) full(depth + 1, tree_.isNodeOccupied(c));
        }
    }

    /// A pruned leaf at `depth` < 16 written as the full subtree it stands for.
    void full(int depth, bool occupied) {
        const int levels = kTreeDepth - depth;
        if (levels <= kCachedLevels) {
            out_ << cached(levels, occupied);
            return;
        }
        const char inner[2] = {char(0xff), char(0xff)};
        out_.write(inner, 2);
        for (int i = 0; i < 8; ++i) full(depth + 1, occupied);
    }

private:
    static constexpr int kCachedLevels = 6;
    const MapTree& tree_;
    std::ostream& out_;
    std::string cache_[2][kCachedLevels + 1];

    /// Two-bit code of a child at `depth`.
    unsigned code(const octomap::OcTreeNode* c, int depth) const {
        if (tree_.nodeHasChildren(c) || depth < kTreeDepth) return 3;  // inner, or pruned (written expanded)
        return tree_.isNodeOccupied(c) ? 2 : 1;  // bit 2i+1: occupied leaf, bit 2i: free leaf
    }

    const std::string& cached(int levels, bool occupied) {
        std::string& s = cache_[occupied][levels];
        if (!s.empty()) return s;
        if (levels == 1) return s = std::string(2, occupied ? char(0xaa) : char(0x55));
        const std::string& below = cached(levels - 1, occupied);
        s.reserve(2 + 8 * below.size());
        s.append(2, char(0xff));
        for (int i = 0; i < 8; ++i) s += below;
        return s;
    }
};

std::uint64_t countUnpruned(const MapTree& t, const octomap::OcTreeNode* n, int depth) {
    if (!t.nodeHasChildren(n)) return depth < kTreeDepth ? fullSubtreeSize(depth) : 1;
    std::uint64_t total = 1;
    for (unsigned i = 0; i < 8; ++i)
        if (t.nodeChildExists(n, i)) total += countUnpruned(t, t.getNodeChild(n, i), depth + 1);
    return total;
}

}  // namespace

void MapTree::applySorted(const std::vector<std::uint64_t>& codes, VoxelUpdate how) {
    if (codes.empty()) return;
    const float delta = how == VoxelUpdate::Hit ? prob_hit_log : prob_miss_log;
    // An existing node the update leaves as it is (OctoMap clamps, and skips occupied ground).
    auto unchanged = [&](const octomap::OcTreeNode* n) {
        if (how == VoxelUpdate::MissUnlessOccupied && isNodeOccupied(n)) return true;
        return delta >= 0 ? n->getLogOdds() >= clamping_thres_max : n->getLogOdds() <= clamping_thres_min;
    };
    // Children done: the node takes their maximum (OcTreeNode::updateOccupancyChildren()), and is
    // pruned if they are eight equal leaves at a clamping bound. Only there: values in between
    // change with the next scan, and a pruned node would be expanded again at once.
    auto settle = [&](octomap::OcTreeNode* n) {
        float maxChild = -std::numeric_limits<float>::max();
        bool equalLeaves = true;
        float first = 0;
        for (unsigned i = 0; i < 8; ++i) {
            if (!nodeChildExists(n, i)) {
                equalLeaves = false;
                continue;
            }
            const octomap::OcTreeNode* c = getNodeChild(n, i);
            const float v = c->getLogOdds();
            maxChild = std::max(maxChild, v);
            if (i == 0) first = v;
            equalLeaves = equalLeaves && v == first && !nodeHasChildren(c);
        }
        n->setLogOdds(maxChild);
        if (equalLeaves && (first == clamping_thres_min || first == clamping_thres_max)) pruneNode(n);
    };
    octomap::OcTreeNode* path[kTreeDepth + 1];
    bool fresh = false;  // path[depth] was created by this walk (so it is not a pruned leaf)
    if (!root) {
        root = new octomap::OcTreeNode();
        ++tree_size;
        size_changed = true;
        fresh = true;
    }
    path[0] = root;
    int depth = 0;
    for (std::size_t i = 0; i < codes.size();) {
        const std::uint64_t code = codes[i];
        if (i > 0) {
            const int keep = std::min(depth, sharedDepth(codes[i - 1], code));
            for (; depth > keep; --depth)
                if (nodeHasChildren(path[depth])) settle(path[depth]);
            fresh = false;
        }
        bool skipped = false;
        for (; depth < kTreeDepth; ++depth) {
            octomap::OcTreeNode* n = path[depth];
            if (!fresh && !nodeHasChildren(n)) {  // a pruned leaf: stands for every voxel below it
                if (unchanged(n)) {
                    const std::uint64_t last = lastCodeBelow(code, depth);
                    i = std::size_t(std::upper_bound(codes.begin() + long(i), codes.end(), last) - codes.begin());
                    skipped = true;
                    break;
                }
                expandNode(n);
            }
            const unsigned child = childIndex(code, depth);
            fresh = !nodeChildExists(n, child);
            path[depth + 1] = fresh ? createNodeChild(n, child) : getNodeChild(n, child);
        }
        if (skipped) continue;
        octomap::OcTreeNode* leaf = path[kTreeDepth];
        if (!(how == VoxelUpdate::MissUnlessOccupied && !fresh && isNodeOccupied(leaf))) {
            // OccupancyOcTreeBase::updateNodeLogOdds(): add, then clamp
            const float v = leaf->getLogOdds() + delta;
            leaf->setLogOdds(v < clamping_thres_min ? clamping_thres_min : v > clamping_thres_max ? clamping_thres_max : v);
        }
        ++i;
    }
    for (; depth >= 0; --depth)
        if (nodeHasChildren(path[depth])) settle(path[depth]);
}

std::uint64_t MapTree::unprunedSize() const { return root ? countUnpruned(*this, root, 0) : 0; }

void MapTree::writeUnprunedBinary(std::ostream& out) const {
    out << "# Octomap OcTree binary file\n# (feel free to add / change comments, but leave the first line as it is!)\n#\n";
    out << "id " << getTreeType() << std::endl;
    out << "size " << unprunedSize() << std::endl;
    out << "res " << getResolution() << std::endl;
    out << "data" << std::endl;
    if (!root) return;
    UnprunedWriter w(*this, out);
    if (nodeHasChildren(root)) w.node(root, 0);
    else w.full(0, isNodeOccupied(root));  // the whole tree pruned into its root
}

}  // namespace gseg::map::detail
