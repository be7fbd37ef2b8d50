#pragma once
/// \file layer_file.hpp
/// The 2.5D layers of a map (gseg/map/layer_grid.hpp) as a GeoTIFF: what `gdalinfo`,
/// `gdal_translate`, QGIS and `gseg eval-map` read. The one writer and reader of gseg for it
/// (GDAL's GTiff driver).
///
/// The file: one float32 band per layer, in the grid's order; the band's description is the
/// layer's name (`elevation`, `slope`, ...), its unit type (GDAL's `GetUnitType()`) and its
/// metadata items `UNIT` and `MEANING` the layer's unit and one-line meaning; NaN is the nodata
/// value (unknown). +inf ("no limit": the clearance where no obstacle is above the ground) is
/// written as the finite kNoLimit (1000, in the band's unit) and the band gets the metadata item
/// `NO_LIMIT=1000` saying so; -inf likewise as -kNoLimit. So GDAL's statistics (`gdalinfo -stats`,
/// QGIS's default stretch) stay finite, where +inf made them NaN; readLayersGeoTiff() turns the
/// cap of such a band back into +inf / -inf. The geotransform is in map-frame metres, north-up: the image's first row is the
/// largest y (cells of row cy of the grid are image row height - 1 - cy), its first column the
/// smallest x, so pixel (col, row) covers x in [originX + col * res, ...) and
/// y in [originY + (height - 1 - row) * res, ...). The CRS is a local engineering one
/// (`LOCAL_CS["gseg map frame", UNIT["metre", 1], AXIS["x", EAST], AXIS["y", NORTH]]`: map x
/// drawn to the right, y up, as GIS tools draw a north-up raster): the map frame is the rawlog's world frame,
/// tied to no place on Earth, and a local CRS says so and that its unit is the metre, where a file
/// without a CRS leaves viewers to guess (some assume degrees). Deflate-compressed (floating-point
/// predictor), band-interleaved; the same grid always gives the same bytes.

#include <gseg/map/layer_grid.hpp>
#include <gseg/map/layer_tiles.hpp>

#include <cstdint>

#include <string>

namespace gseg::map {

/// [band unit] What +inf ("no limit") is written as in a layer GeoTIFF (-inf: -kNoLimit); no layer
/// holds so large a finite value (a clearance of 1 km, a slope beyond 90 deg).
constexpr float kNoLimit = 1000.0f;

/// The GeoTIFF bytes of `grid`. Throws std::invalid_argument on a grid without cells or layers,
/// a layer whose values are not width * height, an empty or duplicate layer name, and
/// std::runtime_error with GDAL's message if GDAL fails.
std::string encodeLayersGeoTiff(const LayerGrid& grid);

/// The layers of a big map (#35) as one Cloud-Optimized GeoTIFF (the bytes of GDAL's COG driver,
/// written from the blocks with cells only: src/map/cog_layout.hpp): the bands,
/// names, units, nodata, +-inf and CRS as encodeLayersGeoTiff(), in blocks of `block` x `block`
/// cells (blocks without a cell of a tile are left out: sparse), with cogOverviewCount()
/// overviews of factor 2, 4, 8, ... computed from the tiles (LayerTiles::overview()). The image
/// covers the box of `tiles`, widened to whole cells of the coarsest overview (NaN there), so an
/// overview pixel holds exactly `factor` x `factor` cells. QGIS and `gdalinfo` open it at once.
/// Throws std::invalid_argument on a map without cells or layers or a block size that is not a
/// multiple of 16, std::runtime_error with GDAL's message if GDAL fails.
std::string encodeLayersCog(const LayerTiles& tiles, int block = 512);

/// The overviews encodeLayersCog() makes: halvings until the longer side fits in one block.
int cogOverviewCount(std::int64_t width, std::int64_t height, int block);

/// Reads a GeoTIFF of layers: any file of the format written above, and any single- or
/// multi-band GeoTIFF whose geotransform is axis-aligned with square pixels (north-up, or with
/// its first row the smallest y). Band i becomes layer i named by its description ("band N" if
/// it has none), its unit from the unit type (else the `UNIT` metadata item), its meaning from the
/// `MEANING` item; values read as float32, a band's nodata value becomes NaN, and +-kNoLimit of a
/// band with the `NO_LIMIT` item +-inf. Throws
/// std::runtime_error naming `path` and what is wrong: missing or unreadable, not a GeoTIFF,
/// truncated (a band that cannot be read whole), no geotransform, a rotated or sheared one,
/// non-square pixels, no bands.
LayerGrid readLayersGeoTiff(const std::string& path);

}  // namespace gseg::map
