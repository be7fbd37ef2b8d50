#include <gseg/region_growing.hpp>

#include <algorithm>
#include <limits>
#include <utility>
#include <cmath>
#include <deque>

namespace gseg {
namespace {

// nanoflann's L2_Simple_Adaptor metric (what the KD-tree search before #21 compared with the
// squared radius): ((0 + d0^2) + d1^2) + d2^2 in float, d = query - point.
inline float squaredDistance(const Eigen::Vector3f& q, const Eigen::Vector3f& p) {
    float r = 0.f;
    for (int i = 0; i < 3; ++i) {
        const float d = q[i] - p[i];
        r += d * d;
    }
    return r;
}

// The centroids binned in square columns of half the search radius (a little more) in x, y: every
// neighbour of a centroid lies in the 5 x 5 columns around its own. Their coordinates are kept
// column by column in separate x, y, z arrays (a column's distance tests read contiguous memory).
// Columns are found in a dense table over the centroids' bounding box or, where that box is
// absurdly large for their number, by bisection in the sorted column keys.
class CentroidColumns {
public:
    CentroidColumns(const std::vector<Eigen::Vector3f>& pts, double radius) : size_(radius * 0.5 * 1.001) {
        const std::size_t n = pts.size();
        std::int64_t lo[2] = {std::numeric_limits<std::int64_t>::max(), std::numeric_limits<std::int64_t>::max()};
        std::int64_t hi[2] = {std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::min()};
        keys_.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const std::int64_t cx = coord(pts[i].x()), cy = coord(pts[i].y());
            lo[0] = std::min(lo[0], cx), hi[0] = std::max(hi[0], cx);
            lo[1] = std::min(lo[1], cy), hi[1] = std::max(hi[1], cy);
            keys_[i] = {cx, cy};
        }
        lo_[0] = lo[0], lo_[1] = lo[1];
        w_ = hi[0] - lo[0] + 1, h_ = hi[1] - lo[1] + 1;
        dense_ = double(w_) * double(h_) <= 4.0 * double(n) + 4096.0;
        items_.resize(n);
        if (dense_) {
            start_.assign(std::size_t(w_ * h_) + 1, 0);
            for (const auto& k : keys_) ++start_[std::size_t(index(k.first, k.second)) + 1];
            for (std::size_t b = 1; b < start_.size(); ++b) start_[b] += start_[b - 1];
            std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
            for (std::uint32_t i = 0; i < n; ++i) items_[fill[std::size_t(index(keys_[i].first, keys_[i].second))]++] = i;
        } else {
            for (std::uint32_t i = 0; i < n; ++i) items_[i] = i;
            std::stable_sort(items_.begin(), items_.end(), [&](std::uint32_t a, std::uint32_t b) { return keys_[a] < keys_[b]; });
            sortedKeys_.resize(n);
            for (std::size_t t = 0; t < n; ++t) sortedKeys_[t] = keys_[items_[t]];
        }
        x_.resize(n), y_.resize(n), z_.resize(n);
        slotOf_.resize(n);
        for (std::size_t t = 0; t < n; ++t) {
            const Eigen::Vector3f& p = pts[items_[t]];
            x_[t] = p.x(), y_[t] = p.y(), z_[t] = p.z();
            slotOf_[items_[t]] = std::uint32_t(t);
        }
        reached_.assign(n, 0);
    }

    /// Marks centroid i reached: nearUnreached() leaves it out from now on.
    void markReached(std::uint32_t i) { reached_[slotOf_[i]] = 1; }
    /// Marks centroid i accepted: nearestAccepted() considers it from now on.
    void markAccepted(std::uint32_t i) { reached_[slotOf_[i]] = 2; }

    /// Calls f(j) for every centroid j with squaredDistance(q, centroid j) < radiusSq, where q is
    /// centroid `from` (radiusSq at most the square of the radius given at construction), in the
    /// columns' order.
    template <class F>
    void near(const Eigen::Vector3f& q, std::uint32_t from, float radiusSq, F&& f) const {
        search<false>(q, from, radiusSq, f);
    }
    /// near() leaving out the centroids marked reached (markReached).
    template <class F>
    void nearUnreached(const Eigen::Vector3f& q, std::uint32_t from, float radiusSq, F&& f) const {
        search<true>(q, from, radiusSq, f);
    }

    /// The centroid horizontally nearest to q (ties: the lower index) among those marked accepted
    /// (markAccepted), no farther than `radius` horizontally; -1 if none. Searches rings of columns
    /// outward from q's and stops once no farther ring can hold a nearer one.
    std::int64_t nearestAccepted(const Eigen::Vector3f& q, double radius) const {
        const std::int64_t kx = coord(q.x()), ky = coord(q.y());
        const float radiusSq = float(radius * radius);
        float best = std::numeric_limits<float>::infinity();
        std::int64_t found = -1;
        // Ring r's centroids lie at least (r - 1) column sizes away horizontally. No ring beyond
        // the centroids' columns holds one, whatever the radius (a huge one must not loop for ever).
        const std::int64_t extent = std::max(std::max(kx - lo_[0], lo_[0] + w_ - 1 - kx),
                                             std::max(ky - lo_[1], lo_[1] + h_ - 1 - ky));
        const double ringsNeeded = std::ceil(radius / size_);
        const std::int64_t rings = ringsNeeded < double(extent) ? std::int64_t(ringsNeeded) : extent;
        const auto visit = [&](std::int64_t cx, std::int64_t cy) {
            std::size_t b = 0, e = 0;
            if (!columnsRange(cx, cy, cy, b, e)) return;
            for (std::size_t t = b; t < e; ++t) {
                if (reached_[t] != 2) continue;
                const float dx = q.x() - x_[t], dy = q.y() - y_[t];
                const float d = dx * dx + dy * dy;
                const std::uint32_t i = items_[t];
                if (d > radiusSq || d > best || (d == best && std::int64_t(i) > found)) continue;
                best = d, found = i;
            }
        };
        for (std::int64_t r = 0; r <= rings; ++r) {
            // Ring r's columns only (its perimeter): the nearest with the lowest index wins, in any order.
            if (r == 0) {
                visit(kx, ky);
            } else {
                for (std::int64_t cx = kx - r; cx <= kx + r; ++cx) visit(cx, ky - r), visit(cx, ky + r);
                for (std::int64_t cy = ky - r + 1; cy <= ky + r - 1; ++cy) visit(kx - r, cy), visit(kx + r, cy);
            }
            // Every centroid of ring r + 1 lies at least r column sizes away horizontally.
            const double reach = double(r) * size_;
            if (found >= 0 && double(best) <= reach * reach) break;
        }
        return found;
    }

private:
    template <bool kSkipReached, class F>
    void search(const Eigen::Vector3f& q, std::uint32_t from, float radiusSq, F& f) const {
        const auto& k = keys_[from];
        const std::uint8_t* const reached = reached_.data();
        const std::uint32_t* const items = items_.data();
        const float* const xs = x_.data();
        const float* const ys = y_.data();
        const float* const zs = z_.data();
        const float qx = q.x(), qy = q.y(), qz = q.z();
        for (std::int64_t cx = k.first - 2; cx <= k.first + 2; ++cx) {
            // The columns (cx, cy - 2 .. cy + 2) hold consecutive slots: one range per cx.
            std::size_t b = 0, e = 0;
            if (!columnsRange(cx, k.second - 2, k.second + 2, b, e)) continue;
            for (std::size_t t = b; t < e; ++t) {
                if (kSkipReached && reached[t]) continue;
                // squaredDistance(q, p), term by term in the same order
                const float dx = qx - xs[t], dy = qy - ys[t], dz = qz - zs[t];
                float r = 0.f;
                r += dx * dx;
                r += dy * dy;
                r += dz * dz;
                if (r < radiusSq) f(items[t]);
            }
        }
    }

    // The slots [b, e) of the columns (cx, cy0 .. cy1), which follow each other in the slots (the
    // columns' order: by cx, then cy); false where none lies in the dense table.
    bool columnsRange(std::int64_t cx, std::int64_t cy0, std::int64_t cy1, std::size_t& b, std::size_t& e) const {
        if (dense_) {
            cy0 = std::max(cy0, lo_[1]), cy1 = std::min(cy1, lo_[1] + h_ - 1);
            if (cx < lo_[0] || cx >= lo_[0] + w_ || cy0 > cy1) return false;
            b = start_[std::size_t(index(cx, cy0))], e = start_[std::size_t(index(cx, cy1)) + 1];
        } else {
            b = std::size_t(std::lower_bound(sortedKeys_.begin(), sortedKeys_.end(), std::make_pair(cx, cy0)) -
                            sortedKeys_.begin());
            e = std::size_t(std::upper_bound(sortedKeys_.begin(), sortedKeys_.end(), std::make_pair(cx, cy1)) -
                            sortedKeys_.begin());
        }
        return b < e;
    }
    std::int64_t coord(float v) const {
        const double c = std::floor(double(v) / size_);
        return std::int64_t(std::max(-1e15, std::min(1e15, c)));
    }
    std::int64_t index(std::int64_t cx, std::int64_t cy) const { return (cx - lo_[0]) * h_ + (cy - lo_[1]); }

    double size_;
    bool dense_ = true;
    std::int64_t lo_[2] = {0, 0}, w_ = 0, h_ = 0;
    std::vector<std::pair<std::int64_t, std::int64_t>> keys_, sortedKeys_;
    std::vector<std::uint32_t> start_, items_;
    std::vector<std::uint32_t> slotOf_;  // per centroid: its slot in items_ (and x_, y_, z_)
    std::vector<std::uint8_t> reached_;  // per slot: 1 marked reached (markReached), 2 accepted (markAccepted)
    std::vector<float> x_, y_, z_;
};

// One round of bridges (ExpansionSettings::bridgeRadius): per candidate never reached (state 0),
// in index order, the accepted candidate (state 2) horizontally nearest within bridgeRadius (ties:
// the lower index) if the candidate lies within bridgeGate of its ground plane, at most bridgeGate
// above it and at most bridgeMaxDrop below it (bridgeGapGate for bridgeGate beyond `radius`), and
// the two planes' normals agree within bridgeMinNormalCos; -1 where none.
// `fresh` (optional): the candidates accepted since the last round, the only ones that can change
// a candidate's answer (it had none then); a candidate none of them lies near is not searched.
std::vector<std::int32_t> bridges(const std::vector<Eigen::Vector3f>& centroids, const ExpansionSettings& s,
                                  const std::vector<std::uint8_t>& state, const CentroidColumns& columns,
                                  const std::vector<std::uint32_t>* fresh) {
    std::vector<std::int32_t> from(centroids.size(), -1);
    const float radiusSq = float(s.bridgeRadius * s.bridgeRadius);
    for (std::uint32_t j = 0; j < centroids.size(); ++j) {
        if (state[j] != 0) continue;
        if (fresh && std::none_of(fresh->begin(), fresh->end(), [&](std::uint32_t f) {
                return (centroids[f] - centroids[j]).head<2>().squaredNorm() <= radiusSq;
            }))
            continue;
        const std::int64_t found = columns.nearestAccepted(centroids[j], s.bridgeRadius);
        if (found < 0) continue;
        const std::size_t k = std::size_t(found);
        const Eigen::Vector3f d = centroids[j] - centroids[k];
        // Both along k's ground plane and in height: across a gap of up to bridgeRadius, a plane
        // tilted by a few degrees (a slab of a bush's top, one ring's line) would lift the gate.
        // Downwards the height may fall by up to bridgeMaxDrop (ground falling away from the
        // road, a downhill beyond a gap) where k's plane predicts it.
        // Across a gap (k farther than `radius`: the walk never compared the two, e.g. far rings)
        // the gate is bridgeGapGate: the ground's own rise over 5-10 m.
        const float along = s.normals ? std::abs((*s.normals)[k].dot(d)) : 0.f;
        const bool gap = d.head<2>().squaredNorm() > float(s.radius * s.radius);
        const float gate = float(gap ? std::max(s.bridgeGate, s.bridgeGapGate) : s.bridgeGate);
        const float drop = std::max(gate, float(s.bridgeMaxDrop));
        // The two ground planes agree (a bush's top, a car's bonnet beside the road tilt away).
        if (s.normals && (*s.normals)[j].dot((*s.normals)[k]) < s.bridgeMinNormalCos) continue;
        if (along <= gate && d.z() <= gate && d.z() >= -drop) from[j] = std::int32_t(k);
    }
    return from;
}

}  // namespace

std::vector<std::uint8_t> expandRegion(const std::vector<Eigen::Vector3f>& centroids,
                                       const ExpansionSettings& s, const AcceptFn& accept,
                                       std::vector<std::int32_t>* parents) {
    std::vector<std::uint8_t> state(centroids.size(), 0);
    if (parents) parents->assign(centroids.size(), -2);
    if (centroids.empty()) return state;
    CentroidColumns columns(centroids, s.radius);
    const float radiusSq = float(s.radius * s.radius);

    std::vector<std::uint32_t> found, neighbours;
    // The seed discs: every candidate within `radius` of the seed, in index order.
    auto searchSeed = [&](double radius, std::vector<std::uint32_t>& out) {
        out.clear();
        const float r2 = float(radius * radius);
        for (std::uint32_t j = 0; j < centroids.size(); ++j)
            if (squaredDistance(s.seed, centroids[j]) < r2) out.push_back(j);
    };
    // The step between two centroids, measured along the ground-plane normal of each (or along z):
    // a neighbour is taken only if the step lies in both planes within the gate.
    const bool noGate = std::isinf(s.heightGate) && s.heightGate > 0;
    auto gated = [&](std::uint32_t from, std::uint32_t j) {
        if (noGate) return true;
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
        float distanceSq = std::numeric_limits<float>::infinity();  // to the nearest candidate
        for (const Eigen::Vector3f& c : centroids) distanceSq = std::min(distanceSq, squaredDistance(s.seed, c));
        if (distanceSq > 0) discs.push_back(std::sqrt(double(distanceSq)) + s.seedRadius);
    }
    std::deque<std::uint32_t> queue;
    for (const double slope : {0.0, s.seedSlope}) {
        for (std::size_t d = 0; d < discs.size() && (d == 0 || queue.size() < s.fewSeeds); ++d) {
            searchSeed(discs[d], found);
            for (std::uint32_t j : found) {
                const float horizontal = (centroids[j] - s.seed).head<2>().norm();
                if (state[j] == 0 && std::abs(centroids[j].z() - s.seed.z()) <= s.seedGate + slope * horizontal) {
                    state[j] = 1;
                    columns.markReached(j);
                    queue.push_back(j);
                    if (parents) (*parents)[j] = -1;
                }
            }
        }
        if (!queue.empty()) break;
    }

    // Each candidate's neighbours (the search's order, itself excluded, within the gate), searched
    // when the walk reaches it.
    // The order of a candidate's neighbours (by column, then index) decides only the order of the
    // walk (and so Result's reachedFrom), never which candidates are accepted: accept() depends on
    // the candidate and the set of its neighbours alone, and every candidate connected to the seed
    // through accepted ones is reached in any order.
    const auto neighboursOf = [&](std::uint32_t c, std::vector<std::uint32_t>& out) {
        out.clear();
        columns.near(centroids[c], c, radiusSq, [&](std::uint32_t j) {
            if (j != c && gated(c, j)) out.push_back(j);
        });
    };

    const auto reach = [&](std::uint32_t c, std::uint32_t j) {
        state[j] = 1;
        columns.markReached(j);
        queue.push_back(j);
        if (parents) (*parents)[j] = std::int32_t(c);
    };
    std::vector<std::uint32_t> accepted;  // in the order of acceptance
    std::size_t bridgeRound = 0, acceptedBefore = 0;  // bridges: rounds so far; accepted before the last
    // The walk; with bridges, rounds of bridges and walks until a round adds nothing.
    for (;;) {
        while (!queue.empty()) {
            const std::uint32_t c = queue.front();
            queue.pop_front();
            if (!s.needsNeighbours || s.needsNeighbours(c)) {
                neighboursOf(c, neighbours);
            } else {
                // accept() does not look at this candidate's neighbours: decide first, then visit only
                // the neighbours not reached yet (the same ones, in the same order, as from the list).
                neighbours.clear();
                if (!accept(c, neighbours)) continue;
                state[c] = 2;
                accepted.push_back(c);
                columns.markAccepted(c);
                // The centroids marked reached are those with state != 0.
                columns.nearUnreached(centroids[c], c, radiusSq, [&](std::uint32_t j) {
                    if (j != c && gated(c, j)) reach(c, j);
                });
                continue;
            }
            if (!accept(c, neighbours)) continue;  // rejected: stays 1, does not propagate
            state[c] = 2;
            accepted.push_back(c);
            columns.markAccepted(c);
            for (std::uint32_t j : neighbours)
                if (state[j] == 0) reach(c, j);
        }
        if (!(s.bridgeRadius > 0)) break;
        // After the first round only the candidates accepted since the last one can make a bridge
        // (checked against each where they are few).
        const std::vector<std::uint32_t> fresh(accepted.begin() + std::ptrdiff_t(acceptedBefore), accepted.end());
        const bool fewFresh = bridgeRound > 0 && fresh.size() <= 64;
        const std::vector<std::int32_t> from = bridges(centroids, s, state, columns, fewFresh ? &fresh : nullptr);
        ++bridgeRound, acceptedBefore = accepted.size();
        for (std::uint32_t j = 0; j < from.size(); ++j)
            if (from[j] >= 0) reach(std::uint32_t(from[j]), j);
        if (queue.empty()) break;
    }
    return state;
}

}  // namespace gseg
