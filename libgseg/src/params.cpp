#include <gseg/option_table.hpp>
#include <gseg/params.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace gseg {
namespace {

// One row per key, in declaration order: the single place that maps names to fields.
const OptionTable<Params>& table() {
    static const OptionTable<Params> t("parameter", {
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
        {"sparseRecoveryThreshold", &Params::sparseRecoveryThreshold},
        {"bridgeRadius", &Params::bridgeRadius},
        {"bridgeGate", &Params::bridgeGate},
        {"bridgeGapGate", &Params::bridgeGapGate},
        {"bridgeMaxDrop", &Params::bridgeMaxDrop},
        {"bridgeMaxAngleDegrees", &Params::bridgeMaxAngleDegrees},
        {"sparsityLow", &Params::sparsityLow},
        {"sparsityMedium", &Params::sparsityMedium},
        {"maxGroundHeightDeviation", &Params::maxGroundHeightDeviation},
        {"floatingMinHeight", &Params::floatingMinHeight},
        {"floatingMaxDepth", &Params::floatingMaxDepth},
        {"floatingIgnoresLowOutliers", &Params::floatingIgnoresLowOutliers},
        {"belowGroundMargin", &Params::belowGroundMargin},
    });
    return t;
}

void require(bool ok, const char* key, double value, const char* what) { requireOption(ok, "parameter", key, value, what); }

}  // namespace

const std::vector<std::string>& Params::keys() { return table().names(); }

void Params::set(const std::string& key, const std::string& value) { table().set(*this, key, value); }

std::string Params::get(const std::string& key) const { return table().get(*this, key); }

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
    require(finite(sparseRecoveryThreshold) && sparseRecoveryThreshold >= 0, "sparseRecoveryThreshold",
            sparseRecoveryThreshold, "must be >= 0");
    require(finite(bridgeRadius) && bridgeRadius >= 0, "bridgeRadius", bridgeRadius, "must be >= 0");
    require(finite(bridgeGate) && bridgeGate >= 0, "bridgeGate", bridgeGate, "must be >= 0");
    require(finite(bridgeGapGate) && bridgeGapGate >= 0, "bridgeGapGate", bridgeGapGate, "must be >= 0");
    require(finite(bridgeMaxDrop) && bridgeMaxDrop >= 0, "bridgeMaxDrop", bridgeMaxDrop, "must be >= 0");
    require(finite(bridgeMaxAngleDegrees) && bridgeMaxAngleDegrees >= 0 && bridgeMaxAngleDegrees <= 90,
            "bridgeMaxAngleDegrees", bridgeMaxAngleDegrees, "must be in [0, 90]");
    require(finite(sparsityLow) && sparsityLow >= 0, "sparsityLow", sparsityLow, "must be >= 0");
    require(finite(sparsityMedium) && sparsityMedium >= sparsityLow, "sparsityMedium", sparsityMedium,
            "must be >= sparsityLow");
    require(finite(floatingMinHeight) && floatingMinHeight >= 0, "floatingMinHeight", floatingMinHeight, "must be >= 0");
    require(finite(floatingMaxDepth) && floatingMaxDepth >= 0, "floatingMaxDepth", floatingMaxDepth, "must be >= 0");
    require(finite(belowGroundMargin) && belowGroundMargin >= 0, "belowGroundMargin", belowGroundMargin,
            "must be >= 0");
    require(finite(maxGroundHeightDeviation) && maxGroundHeightDeviation >= 0, "maxGroundHeightDeviation",
            maxGroundHeightDeviation, "must be >= 0");
}

}  // namespace gseg
