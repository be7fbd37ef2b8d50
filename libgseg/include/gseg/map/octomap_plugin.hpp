#pragma once
/// \file octomap_plugin.hpp
/// gseg's traversability OctoMaps as an MRPT metric map, so that an INI `[MAPS]` section can ask
/// for them and stock apps (`observations2map`) build them once `libgseg_map.so` is loaded
/// (LD_PRELOAD, or mrpt::system::loadPluginModule()).
///
/// INI (section prefix `<S>_gsegTraversabilityMap_<NN>` as MRPT builds it, S = the app's section):
/// \code
/// [MappingApplication]
/// gsegTraversabilityMap_count = 1
/// [MappingApplication_gsegTraversabilityMap_00_creationOpts]
/// resolution = 0.2      ; any gseg::map::TraversabilityOptions key (gseg/traversability_options.hpp)
/// [MappingApplication_gsegTraversabilityMap_00_gseg]
/// distToGround = 1.73   ; any gseg::Params key (see gseg/params.hpp), or auto
/// [MappingApplication_gsegTraversabilityMap_00_sensorHeight]
/// maxRange = 30         ; any gseg::SensorHeightOptions key (gseg/sensor_height.hpp), for distToGround = auto
/// \endcode
/// Saving (CMultiMetricMap names it `<prefix>_gseg_maps__CTraversabilityOctoMap_<NN>` (MRPT turns "::" into "__")) writes the
/// 17 files of TraversabilityMap::write() with that prefix (TraversabilityMap::outputPaths(): the
/// two OcTrees, the ColorOcTree, the voxel picture, PLY and .3Dscene, the costmap PGM + YAML a
/// planner loads, the layers' GeoTIFF and one picture per layer).

#include <gseg/map/map_builder.hpp>
#include <gseg/map/traversability_map.hpp>
#include <gseg/mrpt/config.hpp>
#include <gseg/params.hpp>

#include <mrpt/maps/CMetricMap.h>

/// Top-level namespace on purpose: MRPT's macros name `mrpt::...` unqualified, which inside
/// `namespace gseg` would find `gseg::mrpt` instead.
namespace gseg_maps {

/// Metric map holding a TraversabilityMap, a thin adapter over gseg::map::MapBuilder (the builder
/// of rawlog-octomap): each inserted 3D LiDAR observation is segmented with the configured height
/// policy, moved into the world and ray-cast there (observations already split by rawlog-gseg,
/// labels ending in `_ground` / `_obstacles`, are used as they are); other observation kinds, and
/// scans without points, are not used (insertion returns false). Not serialisable (the OctoMap
/// files are its persistent form); no likelihood.
class CTraversabilityOctoMap : public ::mrpt::maps::CMetricMap {
    DEFINE_SERIALIZABLE(CTraversabilityOctoMap, gseg_maps)

public:
    explicit CTraversabilityOctoMap(const gseg::map::TraversabilityOptions& options = gseg::map::TraversabilityOptions(),
                                    const gseg::Params& params = gseg::Params());
    /// The whole configuration (`distToGround: auto` included).
    CTraversabilityOctoMap(const gseg::map::TraversabilityOptions& options, const gseg::mrpt::LoadedConfig& config);

    const gseg::map::TraversabilityMap& map() const { return builder_.map(); }
    const gseg::map::MapBuilder& builder() const { return builder_; }

    bool isEmpty() const override { return builder_.map().empty(); }
    void saveMetricMapRepresentationToFile(const std::string& prefix) const override;
    void getVisualizationInto(::mrpt::opengl::CSetOfObjects& o) const override;
    std::string asString() const override;

    MAP_DEFINITION_START(CTraversabilityOctoMap)
    /// The whole configuration, as gseg::mrpt::loadConfigFromIni() reads it: params (and
    /// distToGroundAuto) from `<prefix>_gseg`, sensorHeight from `<prefix>_sensorHeight`,
    /// traversability from `<prefix>_creationOpts`. Unknown and repeated keys are refused.
    gseg::mrpt::LoadedConfig config;
    MAP_DEFINITION_END(CTraversabilityOctoMap)

protected:
    void internal_clear() override;
    bool internal_insertObservation(const ::mrpt::obs::CObservation& obs,
                                    const std::optional<const ::mrpt::poses::CPose3D>& robotPose = std::nullopt) override;
    double internal_computeObservationLikelihood(const ::mrpt::obs::CObservation& obs,
                                                 const ::mrpt::poses::CPose3D& takenFrom) const override;
    bool internal_canComputeObservationLikelihood(const ::mrpt::obs::CObservation& obs) const override;

private:
    gseg::map::MapBuilder builder_;
};

}  // namespace gseg_maps
