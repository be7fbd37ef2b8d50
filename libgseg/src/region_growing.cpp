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

    while (!queue.empty()) {
        const std::uint32_t c = queue.front();
        queue.pop_front();
        search(centroids[c], s.radius, found);
        neighbours.clear();
        for (std::uint32_t j : found)
            if (j != c && gated(c, j)) neighbours.push_back(j);
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
