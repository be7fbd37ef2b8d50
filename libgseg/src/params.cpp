#include <gseg/params.hpp>

#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <variant>

namespace gseg {
namespace {

using Field = std::variant<double Params::*, int Params::*, std::uint64_t Params::*, bool Params::*>;
struct Entry {
    const char* name;
    Field field;
};

// One row per key, in declaration order: the single place that maps names to fields.
const std::vector<Entry>& table() {
    static const std::vector<Entry> t = {
        {"distToGround", &Params::distToGround},
        {"robotRadius", &Params::robotRadius},
        {"cellSizeX", &Params::cellSizeX},
        {"cellSizeY", &Params::cellSizeY},
        {"cellSizeZPhase1", &Params::cellSizeZPhase1},
        {"cellSizeZPhase2", &Params::cellSizeZPhase2},
        {"gridGroundLevel", &Params::gridGroundLevel},
        {"minPointsPerCell", &Params::minPointsPerCell},
        {"minPointsForPca", &Params::minPointsForPca},
        {"lineRatioThreshold", &Params::lineRatioThreshold},
        {"planeRatioThreshold", &Params::planeRatioThreshold},
        {"slopeThresholdDegrees", &Params::slopeThresholdDegrees},
        {"checkPlaneNormal", &Params::checkPlaneNormal},
        {"stripMinSpread", &Params::stripMinSpread},
        {"groundInlierThreshold", &Params::groundInlierThreshold},
        {"minGroundInlierRatio", &Params::minGroundInlierRatio},
        {"ransacMaxIterations", &Params::ransacMaxIterations},
        {"ransacConfidence", &Params::ransacConfidence},
        {"ransacSeed", &Params::ransacSeed},
        {"seedHeightTolerance", &Params::seedHeightTolerance},
        {"centroidSearchRadius", &Params::centroidSearchRadius},
        {"heightGate", &Params::heightGate},
        {"recoverNearGround", &Params::recoverNearGround},
        {"recoveryThreshold", &Params::recoveryThreshold},
        {"sparsityLow", &Params::sparsityLow},
        {"sparsityMedium", &Params::sparsityMedium},
        {"maxGroundHeightDeviation", &Params::maxGroundHeightDeviation},
        {"belowGroundMargin", &Params::belowGroundMargin},
    };
    return t;
}

const Entry& find(const std::string& key) {
    for (const auto& e : table())
        if (key == e.name) return e;
    throw std::invalid_argument("unknown parameter '" + key + "'");
}

template <typename T>
T parse(const std::string& key, const std::string& text) {
    // Surrounding blanks are allowed; anything else after the number is not.
    const std::size_t b = text.find_first_not_of(" \t");
    const std::size_t e = text.find_last_not_of(" \t");
    T v{};
    bool ok = b != std::string::npos;
    if (ok) {
        const char* first = text.data() + b;
        const char* last = text.data() + e + 1;
        const auto [ptr, ec] = std::from_chars(first, last, v);
        ok = ec == std::errc() && ptr == last;
    }
    if (!ok)
        throw std::invalid_argument("parameter '" + key + "': cannot read '" + text + "' as a " +
                                    (std::is_floating_point_v<T> ? "number" : "whole number"));
    return v;
}

template <>
bool parse<bool>(const std::string& key, const std::string& text) {
    const std::size_t b = text.find_first_not_of(" \t");
    const std::size_t e = text.find_last_not_of(" \t");
    const std::string t = b == std::string::npos ? "" : text.substr(b, e - b + 1);
    if (t == "true" || t == "1") return true;
    if (t == "false" || t == "0") return false;
    throw std::invalid_argument("parameter '" + key + "': cannot read '" + text + "' as true or false");
}

void require(bool ok, const char* key, double value, const char* what) {
    if (ok) return;
    std::ostringstream msg;
    msg << "parameter '" << key << "' = " << value << " is invalid: " << what;
    throw std::invalid_argument(msg.str());
}

}  // namespace

const std::vector<std::string>& Params::keys() {
    static const std::vector<std::string> k = [] {
        std::vector<std::string> out;
        for (const auto& e : table()) out.emplace_back(e.name);
        return out;
    }();
    return k;
}

void Params::set(const std::string& key, const std::string& value) {
    const Entry& e = find(key);
    std::visit(
        [&](auto member) {
            using T = std::remove_reference_t<decltype(this->*member)>;
            this->*member = parse<T>(key, value);
        },
        e.field);
}

std::string Params::get(const std::string& key) const {
    const Entry& e = find(key);
    std::ostringstream out;
    out.imbue(std::locale::classic());
    out.precision(std::numeric_limits<double>::max_digits10);
    std::visit([&](auto member) { out << std::boolalpha << this->*member; }, e.field);
    return out.str();
}

void Params::validate() const {
    auto finite = [](double v) { return std::isfinite(v); };
    require(finite(distToGround), "distToGround", distToGround, "must be finite");
    require(finite(robotRadius) && robotRadius >= 0, "robotRadius", robotRadius, "must be >= 0");
    for (const auto& [name, v] : {std::pair{"cellSizeX", cellSizeX}, std::pair{"cellSizeY", cellSizeY},
                                  std::pair{"cellSizeZPhase1", cellSizeZPhase1},
                                  std::pair{"cellSizeZPhase2", cellSizeZPhase2}})
        require(finite(v) && v >= 0.01 && v <= 1000, name, v, "must be between 0.01 and 1000 m");
    require(gridGroundLevel >= 0 && gridGroundLevel < 1, "gridGroundLevel", gridGroundLevel, "must be in [0, 1)");
    require(minPointsPerCell >= 3, "minPointsPerCell", minPointsPerCell, "must be >= 3 (a plane needs 3 points)");
    require(minPointsForPca >= minPointsPerCell, "minPointsForPca", minPointsForPca, "must be >= minPointsPerCell");
    require(lineRatioThreshold > 1.0 / 3 && lineRatioThreshold <= 1, "lineRatioThreshold", lineRatioThreshold,
            "must be in (1/3, 1]");
    require(planeRatioThreshold >= 1.0 / 3 && planeRatioThreshold <= lineRatioThreshold, "planeRatioThreshold",
            planeRatioThreshold, "must be in [1/3, lineRatioThreshold]");
    require(finite(slopeThresholdDegrees) && slopeThresholdDegrees >= 0 && slopeThresholdDegrees <= 90,
            "slopeThresholdDegrees", slopeThresholdDegrees, "must be between 0 and 90 degrees");
    require(finite(groundInlierThreshold) && groundInlierThreshold > 0, "groundInlierThreshold",
            groundInlierThreshold, "must be > 0");
    require(minGroundInlierRatio >= 0 && minGroundInlierRatio < 1, "minGroundInlierRatio", minGroundInlierRatio,
            "must be in [0, 1)");
    require(ransacMaxIterations >= 1, "ransacMaxIterations", ransacMaxIterations, "must be >= 1");
    require(ransacConfidence > 0 && ransacConfidence < 1, "ransacConfidence", ransacConfidence,
            "must be in (0, 1)");
    require(finite(centroidSearchRadius) && centroidSearchRadius > 0, "centroidSearchRadius",
            centroidSearchRadius, "must be > 0");
    require(!std::isnan(heightGate) && heightGate > 0, "heightGate", heightGate, "must be > 0");
    require(finite(seedHeightTolerance) && seedHeightTolerance > 0, "seedHeightTolerance", seedHeightTolerance,
            "must be > 0");
    require(finite(stripMinSpread) && stripMinSpread >= 0, "stripMinSpread", stripMinSpread, "must be >= 0");
    require(finite(recoveryThreshold) && recoveryThreshold >= 0, "recoveryThreshold", recoveryThreshold,
            "must be >= 0");
    require(finite(sparsityLow) && sparsityLow >= 0, "sparsityLow", sparsityLow, "must be >= 0");
    require(finite(sparsityMedium) && sparsityMedium >= sparsityLow, "sparsityMedium", sparsityMedium,
            "must be >= sparsityLow");
    require(finite(belowGroundMargin) && belowGroundMargin >= 0, "belowGroundMargin", belowGroundMargin,
            "must be >= 0");
    require(finite(maxGroundHeightDeviation) && maxGroundHeightDeviation >= 0, "maxGroundHeightDeviation",
            maxGroundHeightDeviation, "must be >= 0");
}

}  // namespace gseg
