#include <gseg/eval/metrics.hpp>

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace gseg {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
double ratio(std::uint64_t a, std::uint64_t b) { return b == 0 ? kNaN : 100.0 * double(a) / double(b); }
constexpr std::uint32_t kVegetation = 70;
}  // namespace

double Counts::precision() const { return ratio(tp, tp + fp); }
double Counts::recall() const { return ratio(tp, tp + fn); }
double Counts::f1() const {
    const double p = precision(), r = recall();
    return (std::isnan(p) || std::isnan(r) || p + r == 0) ? kNaN : 2 * p * r / (p + r);
}
Counts& Counts::operator+=(const Counts& o) {
    tp += o.tp, fp += o.fp, fn += o.fn, tn += o.tn;
    return *this;
}

bool isGroundClass(std::uint32_t id) {
    return id == 40 || id == 44 || id == 48 || id == 49 || id == 60 || id == 72;
}

bool isGroundTruth(std::uint32_t id, float z, const ProtocolOptions& opt) {
    return id == kVegetation ? z < opt.vegetationZ : isGroundClass(id);
}

void checkScoringInputs(std::size_t points, const std::vector<std::uint32_t>& labels,
                        const std::vector<std::uint8_t>& pred) {
    if (labels.size() != points || pred.size() != points) {
        std::ostringstream msg;
        msg << "scoring: size mismatch: " << points << " points, " << labels.size() << " labels, " << pred.size()
            << " predictions";
        throw std::invalid_argument(msg.str());
    }
    for (std::size_t i = 0; i < points; ++i)
        if (pred[i] > 1) {
            std::ostringstream msg;
            msg << "scoring: prediction " << i << " is " << int(pred[i]) << " (must be 0 or 1)";
            throw std::invalid_argument(msg.str());
        }
}

FrameScore scoreFrame(const PointCloudView& cloud, const std::vector<std::uint32_t>& labels,
                      const std::vector<std::uint8_t>& pred, const ProtocolOptions& opt) {
    checkScoringInputs(cloud.size(), labels, pred);
    const std::size_t n = cloud.size();
    // Counters per range bin k (rangeLimits[k-1] <= r < rangeLimits[k]); bin 10 = beyond the last limit.
    struct Bin {
        std::uint64_t predicted = 0, truth = 0, hit = 0, outlierHit = 0;
    };
    std::array<Bin, 11> bins{};
    std::uint64_t truthNoVeg = 0, hitNoVeg = 0, dontCareHit = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t id = labels[i] & 0xFFFFu;
        const bool p = pred[i] == 1;
        const bool veg = id == kVegetation;
        const bool truth = isGroundTruth(id, cloud.z(i), opt);
        const bool outlier = isOutlierClass(id);
        const double r = std::hypot(double(cloud.x(i)), double(cloud.y(i)));
        std::size_t k = 0;
        while (k < opt.rangeLimits.size() && r >= opt.rangeLimits[k]) ++k;
        Bin& b = bins[k];
        b.predicted += p;
        b.truth += truth;
        b.hit += p && truth;
        b.outlierHit += p && !truth && outlier;
        // Without vegetation: only the six ground classes are ground; vegetation is don't-care.
        if (isGroundClass(id)) {
            ++truthNoVeg;
            hitNoVeg += p;
        } else if (p && (outlier || veg)) {
            ++dontCareHit;
        }
    }
    auto toCounts = [n](std::uint64_t predicted, std::uint64_t truth, std::uint64_t tp, std::uint64_t hit) {
        Counts c;
        c.tp = tp;
        c.fp = predicted - tp;
        c.fn = truth - hit;
        c.tn = n - c.tp - c.fp - c.fn;
        return c;
    };
    FrameScore s;
    s.points = n;
    Bin total, cumulative;
    for (std::size_t k = 0; k < bins.size(); ++k) {
        total.predicted += bins[k].predicted, total.truth += bins[k].truth;
        total.hit += bins[k].hit, total.outlierHit += bins[k].outlierHit;
    }
    s.withVegetation = toCounts(total.predicted, total.truth, total.hit + total.outlierHit, total.hit);
    s.withoutVegetation = toCounts(total.predicted, truthNoVeg, hitNoVeg + dontCareHit, hitNoVeg);
    // Range-limited scores: cumulate the bins below each limit (tn is not kept per range).
    for (std::size_t k = 0; k < opt.rangeLimits.size(); ++k) {
        cumulative.predicted += bins[k].predicted, cumulative.truth += bins[k].truth;
        cumulative.hit += bins[k].hit, cumulative.outlierHit += bins[k].outlierHit;
        Counts c;
        c.tp = cumulative.hit + cumulative.outlierHit;
        c.fp = cumulative.predicted - c.tp;
        c.fn = cumulative.truth - cumulative.hit;
        s.byRange[k] = c;
    }
    return s;
}

MeanStd meanStd(const std::vector<double>& values) {
    MeanStd m;
    double sum = 0;
    for (double v : values)
        if (!std::isnan(v)) sum += v, ++m.count;
    if (m.count == 0) {
        m.mean = m.stddev = kNaN;
        return m;
    }
    m.mean = sum / double(m.count);
    double sq = 0;
    for (double v : values)
        if (!std::isnan(v)) sq += (v - m.mean) * (v - m.mean);
    m.stddev = std::sqrt(sq / double(m.count));
    return m;
}

}  // namespace gseg
