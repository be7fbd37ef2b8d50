#include <gseg/eval/breakdown.hpp>
#include <gseg/grid.hpp>

#include <cmath>
#include <unordered_map>

namespace gseg {
namespace {

std::uint64_t cellKey(std::int32_t ix, std::int32_t iy) {
    return (std::uint64_t(std::uint32_t(ix)) << 32) | std::uint32_t(iy);
}

/// Mean z of the labelled ground per horizontal cell; the local ground of a point is the mean of
/// the cells in the nearest ring (own cell first) that holds any.
class LocalGround {
public:
    LocalGround(const PointCloudView& cloud, const std::vector<std::uint32_t>& labels, const BreakdownOptions& o)
        : cell_(o.groundCell), rings_(o.groundSearchCells) {
        for (std::size_t i = 0; i < cloud.size(); ++i)
            if (isGroundTruth(labels[i] & 0xFFFFu, cloud.z(i), o.protocol)) {
                Sum& s = cells_[cellKey(cellCoord(cloud.x(i), cell_), cellCoord(cloud.y(i), cell_))];
                s.z += cloud.z(i), ++s.n;
            }
    }

    /// False if no labelled ground lies within the search rings.
    bool heightAt(float x, float y, double& z) const {
        const std::int32_t cx = cellCoord(x, cell_), cy = cellCoord(y, cell_);
        for (int ring = 0; ring <= rings_; ++ring) {
            double sum = 0;
            int count = 0;
            for (int dx = -ring; dx <= ring; ++dx)
                for (int dy = -ring; dy <= ring; ++dy) {
                    if (std::max(std::abs(dx), std::abs(dy)) != ring) continue;
                    const auto it = cells_.find(cellKey(cx + dx, cy + dy));
                    if (it != cells_.end()) sum += it->second.z / double(it->second.n), ++count;
                }
            if (count > 0) {
                z = sum / count;
                return true;
            }
        }
        return false;
    }

private:
    struct Sum {
        double z = 0;
        std::uint64_t n = 0;
    };
    double cell_;
    int rings_;
    std::unordered_map<std::uint64_t, Sum> cells_;
};

int heightBin(bool known, double h) {
    if (!known) return HeightBins::kCount - 1;
    int b = 0;
    while (b < int(HeightBins::kEdges.size()) && h >= HeightBins::kEdges[std::size_t(b)]) ++b;
    return b;
}

int rangeBin(float x, float y) {
    const double r = std::hypot(double(x), double(y));
    int b = 0;
    while (b < int(RangeBins::kEdges.size()) && r >= RangeBins::kEdges[std::size_t(b)]) ++b;
    return b;
}

}  // namespace

const char* HeightBins::name(int bin) {
    static const char* const names[kCount] = {"below -0.3 m", "-0.3..0.25 m", "0.25..0.5 m", "0.5..1 m",
                                              "1..2 m",       "above 2 m",    "no ground near"};
    return bin >= 0 && bin < kCount ? names[bin] : "?";
}

const char* RangeBins::name(int bin) {
    static const char* const names[kCount] = {"0..10 m", "10..20 m", "20..30 m", "30..50 m", "beyond 50 m"};
    return bin >= 0 && bin < kCount ? names[bin] : "?";
}

Breakdown& Breakdown::operator+=(const Breakdown& o) {
    for (const auto& [k, v] : o.falseByClass) falseByClass[k] += v;
    for (const auto& [k, v] : o.missedByClass) missedByClass[k] += v;
    for (std::size_t b = 0; b < falseByHeight.size(); ++b) falseByHeight[b] += o.falseByHeight[b];
    for (std::size_t b = 0; b < falseByRange.size(); ++b) falseByRange[b] += o.falseByRange[b];
    for (std::size_t b = 0; b < missedByRange.size(); ++b) missedByRange[b] += o.missedByRange[b];
    falseGround += o.falseGround, missedGround += o.missedGround, trueGround += o.trueGround;
    return *this;
}

Breakdown breakdownFrame(const PointCloudView& cloud, const std::vector<std::uint32_t>& labels,
                         const std::vector<std::uint8_t>& pred, const BreakdownOptions& o,
                         std::vector<PointOutcome>* outcomes) {
    checkScoringInputs(cloud.size(), labels, pred);
    const LocalGround local(cloud, labels, o);
    Breakdown b;
    if (outcomes) outcomes->assign(cloud.size(), PointOutcome::TrueNonGround);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const std::uint32_t id = labels[i] & 0xFFFFu;
        const bool truth = isGroundTruth(id, cloud.z(i), o.protocol);
        PointOutcome out = PointOutcome::TrueNonGround;
        if (pred[i] == 1 && (truth || isOutlierClass(id))) {
            out = PointOutcome::TrueGround;
            ++b.trueGround;
        } else if (pred[i] == 1) {
            out = PointOutcome::FalseGround;
            ++b.falseGround;
            ++b.falseByClass[id];
            double z = 0;
            const bool known = local.heightAt(cloud.x(i), cloud.y(i), z);
            ++b.falseByHeight[std::size_t(heightBin(known, double(cloud.z(i)) - z))];
            ++b.falseByRange[std::size_t(rangeBin(cloud.x(i), cloud.y(i)))];
        } else if (truth) {
            out = PointOutcome::MissedGround;
            ++b.missedGround;
            ++b.missedByClass[id];
            ++b.missedByRange[std::size_t(rangeBin(cloud.x(i), cloud.y(i)))];
        }
        if (outcomes) (*outcomes)[i] = out;
    }
    return b;
}

std::string semanticClassName(std::uint32_t id) {
    static const std::map<std::uint32_t, const char*> names = {
        {0, "unlabeled"},         {1, "outlier"},          {10, "car"},
        {11, "bicycle"},          {13, "bus"},             {15, "motorcycle"},
        {16, "on-rails"},         {18, "truck"},           {20, "other-vehicle"},
        {30, "person"},           {31, "bicyclist"},       {32, "motorcyclist"},
        {40, "road"},             {44, "parking"},         {48, "sidewalk"},
        {49, "other-ground"},     {50, "building"},        {51, "fence"},
        {52, "other-structure"},  {60, "lane-marking"},    {70, "vegetation"},
        {71, "trunk"},            {72, "terrain"},         {80, "pole"},
        {81, "traffic-sign"},     {99, "other-object"},    {252, "moving-car"},
        {253, "moving-bicyclist"}, {254, "moving-person"}, {255, "moving-motorcyclist"},
        {256, "moving-on-rails"}, {257, "moving-bus"},     {258, "moving-truck"},
        {259, "moving-other-vehicle"}};
    const auto it = names.find(id);
    return it != names.end() ? it->second : "class " + std::to_string(id);
}

}  // namespace gseg
