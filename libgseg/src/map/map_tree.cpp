#include "map_tree.hpp"

#include "voxel_keys.hpp"

#include <algorithm>
#include <limits>

namespace gseg::map::detail {

void MapTree::setSorted(const std::uint64_t* codes, const float* values, std::size_t n) {
    if (n == 0) return;
    // Children done: the node takes their maximum, and eight equal clamped leaves are pruned.
    auto settle = [&](octomap::OcTreeNode* node) {
        float maxChild = -std::numeric_limits<float>::max(), first = 0;
        bool equalLeaves = true;
        for (unsigned i = 0; i < 8; ++i) {
            if (!nodeChildExists(node, i)) {
                equalLeaves = false;
                continue;
            }
            const octomap::OcTreeNode* c = getNodeChild(node, i);
            const float v = c->getLogOdds();
            maxChild = std::max(maxChild, v);
            if (i == 0) first = v;
            equalLeaves = equalLeaves && v == first && !nodeHasChildren(c);
        }
        node->setLogOdds(maxChild);
        if (equalLeaves && (first == clamping_thres_min || first == clamping_thres_max)) pruneNode(node);
    };
    if (!root) {
        root = new octomap::OcTreeNode();
        ++tree_size;
        size_changed = true;
    }
    octomap::OcTreeNode* path[kTreeDepth + 1];
    path[0] = root;
    int depth = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (i > 0)
            for (const int keep = std::min(depth, sharedDepth(codes[i - 1], codes[i])); depth > keep; --depth)
                if (nodeHasChildren(path[depth])) settle(path[depth]);
        for (; depth < kTreeDepth; ++depth) {
            const unsigned child = childIndex(codes[i], depth);
            path[depth + 1] = nodeChildExists(path[depth], child) ? getNodeChild(path[depth], child)
                                                                   : createNodeChild(path[depth], child);
        }
        path[kTreeDepth]->setLogOdds(values[i]);
    }
    for (; depth >= 0; --depth)
        if (nodeHasChildren(path[depth])) settle(path[depth]);
}

}  // namespace gseg::map::detail
