#include <gseg/region_growing.hpp>

#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>
#include <deque>

namespace gseg {
namespace {

struct CentroidSet {
    const std::vector<Eigen::Vector3f>& pts;
    std::size_t kdtree_get_point_count() const { return pts.size(); }
    float kdtree_get_pt(std::size_t i, std::size_t dim) const { return pts[i][int(dim)]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const { return false; }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, CentroidSet>, CentroidSet,
                                                 3, std::uint32_t>;

// Collects indices only (nanoflann takes the *squared* radius), works with nanoflann 1.4 and 1.5.
struct IndexCollector {
    float radiusSq;
    std::vector<std::uint32_t>& out;
    void init() { out.clear(); }
    void clear() { out.clear(); }
    std::size_t size() const { return out.size(); }
    bool full() const { return true; }
    bool addPoint(float dist, std::uint32_t index) {
        if (dist < radiusSq) out.push_back(index);
        return true;
    }
    float worstDist() const { return radiusSq; }
};

}  // namespace

std::vector<std::uint8_t> expandRegion(const std::vector<Eigen::Vector3f>& centroids,
                                       const ExpansionSettings& s, const AcceptFn& accept,
                                       std::vector<std::int32_t>* parents) {
    std::vector<std::uint8_t> state(centroids.size(), 0);
    if (parents) parents->assign(centroids.size(), -2);
    if (centroids.empty()) return state;
    const CentroidSet set{centroids};
    const Tree tree(3, set, nanoflann::KDTreeSingleIndexAdaptorParams(16));

    std::vector<std::uint32_t> found, neighbours;
    auto search = [&](const Eigen::Vector3f& q, double radius, std::vector<std::uint32_t>& out) {
        out.clear();
        IndexCollector collector{float(radius * radius), out};
        // The tree is built deterministically from the centroids, so the order of the results is
        // deterministic too: no sort needed.
        tree.radiusSearchCustomCallback(q.data(), collector);
    };
    // The step between two centroids, measured along the ground-plane normal of each (or along z):
    // a neighbour is taken only if the step lies in both planes within the gate.
    auto gated = [&](std::uint32_t from, std::uint32_t j) {
        const Eigen::Vector3f d = centroids[j] - centroids[from];
        const float step = s.normals ? std::max(std::abs((*s.normals)[from].dot(d)), std::abs((*s.normals)[j].dot(d)))
                                     : std::abs(d.z());
        return step <= s.heightGate;
    };

    // Seed: the candidates near the robot within the height gate of the synthetic ground point.
    // Where the sensor sees (almost) no ground near the robot (a forward-looking sensor's or a high
    // mount's blind zone reaches beyond seedRadius: a VLP-16 2.5 m up first meets the ground 9.3 m
    // out, and a wheel of a car beside it may be all that is left), a second disc reaching
    // seedRadius beyond the nearest candidate adds its candidates under the same gate. Only if
    // neither disc holds a candidate at the robot's ground level (the robot stands on a slope and
    // its blind spot hides the ground at its own height) does the gate widen with horizontal
    // distance at the slope limit, again first in the near disc.
    std::vector<double> discs = {s.seedRadius};  // radii around the seed, searched in this order
    if (s.fewSeeds > 0) {
        std::uint32_t nearest = 0;
        float distanceSq = 0;
        if (tree.knnSearch(s.seed.data(), 1, &nearest, &distanceSq) == 1 && distanceSq > 0)
            discs.push_back(std::sqrt(double(distanceSq)) + s.seedRadius);
    }
    std::deque<std::uint32_t> queue;
    for (const double slope : {0.0, s.seedSlope}) {
        for (std::size_t d = 0; d < discs.size() && (d == 0 || queue.size() < s.fewSeeds); ++d) {
            search(s.seed, discs[d], found);
            for (std::uint32_t j : found) {
                const float horizontal = (centroids[j] - s.seed).head<2>().norm();
                if (state[j] == 0 && std::abs(centroids[j].z() - s.seed.z()) <= s.seedGate + slope * horizontal) {
                    state[j] = 1;
                    queue.push_back(j);
                    if (parents) (*parents)[j] = -1;
                }
            }
        }
        if (!queue.empty()) break;
    }

    // Each candidate's neighbours (the search's order, itself excluded, within the gate): searched
    // when the walk reaches it, or all before the walk on several threads (independent searches).
    const auto neighboursOf = [&](std::uint32_t c, std::vector<std::uint32_t>& hits, std::vector<std::uint32_t>& out) {
        search(centroids[c], s.radius, hits);
        out.clear();
        for (std::uint32_t j : hits)
            if (j != c && gated(c, j)) out.push_back(j);
    };
    std::vector<std::uint32_t> listStart, lists;  // CSR of the precomputed neighbours
    if (s.pool && s.pool->threads() > 1) {
        constexpr std::size_t chunk = 64;
        const std::size_t n = centroids.size(), parts = (n + chunk - 1) / chunk;
        std::vector<std::vector<std::uint32_t>> partLists(parts), partCounts(parts);
        std::vector<std::vector<std::uint32_t>> hits(s.pool->threads()), out(s.pool->threads());
        s.pool->forRange(n, chunk, [&](std::size_t b, std::size_t e, unsigned t) {
            auto& list = partLists[b / chunk];
            auto& counts = partCounts[b / chunk];
            for (std::size_t c = b; c < e; ++c) {
                neighboursOf(std::uint32_t(c), hits[t], out[t]);
                list.insert(list.end(), out[t].begin(), out[t].end());
                counts.push_back(std::uint32_t(out[t].size()));
            }
        });
        listStart.reserve(n + 1);
        listStart.push_back(0);
        for (std::size_t p = 0; p < parts; ++p) {
            lists.insert(lists.end(), partLists[p].begin(), partLists[p].end());
            for (std::uint32_t k : partCounts[p]) listStart.push_back(listStart.back() + k);
        }
    }

    while (!queue.empty()) {
        const std::uint32_t c = queue.front();
        queue.pop_front();
        if (listStart.empty())
            neighboursOf(c, found, neighbours);
        else
            neighbours.assign(lists.begin() + listStart[c], lists.begin() + listStart[c + 1]);
        if (!accept(c, neighbours)) continue;  // rejected: stays 1, does not propagate
        state[c] = 2;
        for (std::uint32_t j : neighbours)
            if (state[j] == 0) {
                state[j] = 1;
                queue.push_back(j);
                if (parents) (*parents)[j] = std::int32_t(c);
            }
    }
    return state;
}

}  // namespace gseg
