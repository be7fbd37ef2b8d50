#include <gseg/map/octomap_plugin.hpp>

#include <gseg/mrpt/config.hpp>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/core/initializer.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/serialization/CArchive.h>

#include <iostream>
#include <ostream>
#include <stdexcept>

namespace gseg_maps {

IMPLEMENTS_SERIALIZABLE(CTraversabilityOctoMap, mrpt::maps::CMetricMap, gseg_maps)

}  // namespace gseg_maps

// Registration on library load: INI name `gsegTraversabilityMap` (or the full class name).
MAP_DEFINITION_REGISTER("gseg_maps::CTraversabilityOctoMap,gsegTraversabilityMap", gseg_maps::CTraversabilityOctoMap)

MRPT_INITIALIZER(gseg_map_register_classes) {
    ::mrpt::rtti::registerClass(CLASS_ID(gseg_maps::CTraversabilityOctoMap));
}

namespace gseg_maps {

CTraversabilityOctoMap::TMapDefinition::TMapDefinition() = default;

void CTraversabilityOctoMap::TMapDefinition::loadFromConfigFile_map_specific(const ::mrpt::config::CConfigFileBase& source,
                                                                            const std::string& prefix) {
    // The tools' loader, so the INI refuses what a YAML file refuses (unknown and repeated keys).
    gseg::mrpt::IniSections sections;
    sections.params = prefix + "_gseg";
    sections.sensorHeight = prefix + "_sensorHeight";
    sections.traversability = prefix + "_creationOpts";
    config = gseg::mrpt::loadConfigFromIni(source, sections);
    for (const std::string& w : config.warnings) std::cerr << "gseg map plugin: warning: " << w << "\n";  // once per definition
}

void CTraversabilityOctoMap::TMapDefinition::dumpToTextStream_map_specific(std::ostream& out) const {
    out << gseg::mrpt::toYaml(config);
}

::mrpt::maps::CMetricMap* CTraversabilityOctoMap::internal_CreateFromMapDefinition(
    const ::mrpt::maps::TMetricMapInitializer& def) {
    const auto& d = dynamic_cast<const CTraversabilityOctoMap::TMapDefinition&>(def);
    return new CTraversabilityOctoMap(d.config.traversability, d.config);  // the whole configuration: distToGround auto included
}

namespace {

gseg::mrpt::LoadedConfig withParams(const gseg::Params& params) {
    gseg::mrpt::LoadedConfig c;
    c.params = params;
    return c;
}

}  // namespace

CTraversabilityOctoMap::CTraversabilityOctoMap(const gseg::map::TraversabilityOptions& options, const gseg::Params& params)
    : CTraversabilityOctoMap(options, withParams(params)) {}

CTraversabilityOctoMap::CTraversabilityOctoMap(const gseg::map::TraversabilityOptions& options,
                                               const gseg::mrpt::LoadedConfig& config)
    : builder_(config, options) {}

void CTraversabilityOctoMap::saveMetricMapRepresentationToFile(const std::string& prefix) const {
    if (!map().empty()) map().write(prefix);
}

void CTraversabilityOctoMap::getVisualizationInto(::mrpt::opengl::CSetOfObjects&) const {
    // Nothing: open the written .ot / .bt files in octovis instead.
}

std::string CTraversabilityOctoMap::asString() const {
    return "gseg traversability OctoMaps (" + std::to_string(map().path().size()) + " scans, " +
           std::to_string(map().options().resolution) + " m voxels)";
}

void CTraversabilityOctoMap::internal_clear() { builder_.clear(); }

bool CTraversabilityOctoMap::internal_insertObservation(const ::mrpt::obs::CObservation& obs,
                                                        const std::optional<const ::mrpt::poses::CPose3D>& robotPose) {
    return builder_.insert(obs, robotPose ? *robotPose : ::mrpt::poses::CPose3D());
}

double CTraversabilityOctoMap::internal_computeObservationLikelihood(const ::mrpt::obs::CObservation&,
                                                                     const ::mrpt::poses::CPose3D&) const {
    return 0;
}

bool CTraversabilityOctoMap::internal_canComputeObservationLikelihood(const ::mrpt::obs::CObservation&) const {
    return false;
}

uint8_t CTraversabilityOctoMap::serializeGetVersion() const { return 0; }

void CTraversabilityOctoMap::serializeTo(::mrpt::serialization::CArchive&) const {
    throw std::logic_error("gseg_maps::CTraversabilityOctoMap is not serialisable: save its OctoMap files instead");
}

void CTraversabilityOctoMap::serializeFrom(::mrpt::serialization::CArchive&, uint8_t) {
    throw std::logic_error("gseg_maps::CTraversabilityOctoMap is not serialisable: load its OctoMap files instead");
}

}  // namespace gseg_maps
