#include <gseg/option_table.hpp>
#include <gseg/traversability_options.hpp>

#include <sstream>
#include <stdexcept>

namespace gseg::map {
namespace {

const OptionTable<TraversabilityOptions>& table() {
    using O = TraversabilityOptions;
    static const OptionTable<O> t(
        "traversability option",
        {
            {"resolution", &O::resolution, "m", "voxel edge (also the top-down grid cell), 0.01 to 10"},
            {"maxRange", &O::maxRange, "m", "longer rays clear free space up to this range and add no hit"},
            {"probHit", &O::probHit, "-", "occupancy probability of a hit, in (0.5, 1)"},
            {"probMiss", &O::probMiss, "-", "occupancy probability of a ray passing through, in (0, 0.5)"},
            {"clampMin", &O::clampMin, "-", "lower clamping of the occupancy probability, in (0, 0.5)"},
            {"clampMax", &O::clampMax, "-", "upper clamping, in (0.5, 1) (lower: quicker clearing of moved obstacles)"},
            {"occupancyThreshold", &O::occupancyThreshold, "-", "a voxel is occupied above this probability, in (0, 1)"},
            {"clearance", &O::clearance, "m",
             "obstacle voxels higher than this above the column's ground do not block it (branches, bridges)"},
        });
    return t;
}

/// lo < v < hi (or lo <= v <= hi with `inclusive`).
void requireInRange(double v, const char* name, double lo, double hi, bool inclusive = false) {
    const bool ok = inclusive ? (v >= lo && v <= hi) : (v > lo && v < hi);
    if (!ok) {
        std::ostringstream s;
        s << "TraversabilityOptions." << name << " = " << v << ": must lie in " << (inclusive ? "[" : "(") << lo << ", "
          << hi << (inclusive ? "]" : ")");
        throw std::invalid_argument(s.str());
    }
}

}  // namespace

void TraversabilityOptions::validate() const {
    requireInRange(resolution, "resolution [m]", 0.01, 10.0, true);
    if (!(maxRange > 0)) throw std::invalid_argument("TraversabilityOptions.maxRange = " + std::to_string(maxRange) + ": must be > 0 m");
    if (maxRange / resolution > kMaxRayVoxels)
        throw std::invalid_argument("TraversabilityOptions: maxRange / resolution = " + std::to_string(maxRange) + " / " +
                                    std::to_string(resolution) + " gives rays of " + std::to_string(long(maxRange / resolution)) +
                                    " voxels: at most " + std::to_string(long(kMaxRayVoxels)));
    requireInRange(probHit, "probHit", 0.5, 1.0);
    requireInRange(probMiss, "probMiss", 0.0, 0.5);
    requireInRange(clampMin, "clampMin", 0.0, 0.5);
    requireInRange(clampMax, "clampMax", 0.5, 1.0);
    requireInRange(occupancyThreshold, "occupancyThreshold", 0.0, 1.0);
    if (!(clearance > 0)) throw std::invalid_argument("TraversabilityOptions.clearance = " + std::to_string(clearance) + ": must be > 0 m");
}

const std::vector<std::string>& TraversabilityOptions::keys() { return table().names(); }

void TraversabilityOptions::set(const std::string& key, const std::string& value) { table().set(*this, key, value); }

std::string TraversabilityOptions::get(const std::string& key) const { return table().get(*this, key); }

std::pair<std::string, std::string> TraversabilityOptions::describe(const std::string& key) { return table().describe(key); }

}  // namespace gseg::map
