// The GeoTIFF of a map's 2.5D layers (GDAL's GTiff driver, built in memory under /vsimem/ and
// written by gseg's atomic writer; read back with GDAL, refusing what is not a layer file).
#include <gseg/io/kitti.hpp>  // regularFileSize
#include <gseg/map/layer_file.hpp>

#include "cog_layout.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <mutex>
#include <set>
#include <stdexcept>
#include <vector>

namespace gseg::map {
namespace {

/// The map frame as a local engineering CRS: metres, tied to no place on Earth (see the header).
constexpr const char* kMapFrameWkt =
    "LOCAL_CS[\"gseg map frame\",UNIT[\"metre\",1,AUTHORITY[\"EPSG\",\"9001\"]],AXIS[\"x\",EAST],AXIS[\"y\",NORTH]]";
/// [cells] the largest grid the reader accepts (1 GiB of float32 per band): a damaged header
/// claiming more is refused instead of exhausting memory.
constexpr std::uint64_t kMaxCells = std::uint64_t(1) << 28;
/// [values] the most cells x bands read (4 GiB of float32), checked before the bands are read.
constexpr std::uint64_t kMaxValues = std::uint64_t(1) << 30;

void registerDrivers() {
    static std::once_flag once;
    std::call_once(once, [] { GDALAllRegister(); });
}

/// While alive, GDAL's errors on this thread are collected here instead of printed (the library
/// never prints): the first failure's text for the exception.
class GdalErrors {
public:
    GdalErrors() {
        CPLPushErrorHandlerEx(&GdalErrors::handle, this);
        CPLErrorReset();
    }
    ~GdalErrors() { CPLPopErrorHandler(); }
    GdalErrors(const GdalErrors&) = delete;
    GdalErrors& operator=(const GdalErrors&) = delete;

    bool failed() const { return failed_; }
    /// "GDAL: <first failure>", or `fallback` if GDAL said nothing.
    std::string text(const std::string& fallback) const { return first_.empty() ? fallback : "GDAL: " + first_; }

private:
    static void CPL_STDCALL handle(CPLErr level, CPLErrorNum, const char* message) {
        auto* self = static_cast<GdalErrors*>(CPLGetErrorHandlerUserData());
        if (!self || level < CE_Failure) return;  // warnings (e.g. of a foreign TIFF's tags) are not ours to show
        self->failed_ = true;
        if (self->first_.empty() && message) self->first_ = message;
    }
    bool failed_ = false;
    std::string first_;
};

/// A dataset closed on scope exit.
struct Dataset {
    GDALDatasetH h = nullptr;
    explicit Dataset(GDALDatasetH d) : h(d) {}
    ~Dataset() { close(); }
    Dataset(const Dataset&) = delete;
    Dataset& operator=(const Dataset&) = delete;
    void close() {
        if (h) GDALClose(h);
        h = nullptr;
    }
};

/// A /vsimem/ file name no other call uses at the same time (the name is not part of the bytes).
std::string memoryFileName() {
    static std::atomic<unsigned long long> counter{0};
    return "/vsimem/gseg_layers_" + std::to_string(counter.fetch_add(1)) + ".tif";
}

void validate(const LayerGrid& grid) {
    if (grid.cells() == 0) throw std::invalid_argument("layer GeoTIFF: the grid has no cells");
    if (grid.layers().empty()) throw std::invalid_argument("layer GeoTIFF: the grid has no layers");
    std::set<std::string> names;
    for (const auto& l : grid.layers()) {
        if (l.name.empty()) throw std::invalid_argument("layer GeoTIFF: a layer without a name");
        if (!names.insert(l.name).second) throw std::invalid_argument("layer GeoTIFF: two layers named '" + l.name + "'");
        if (l.values.size() != grid.cells())
            throw std::invalid_argument("layer GeoTIFF: layer '" + l.name + "' has " + std::to_string(l.values.size()) +
                                        " values for " + std::to_string(grid.cells()) + " cells");
    }
}

/// A band's name, unit, meaning and nodata; +-inf as +-kNoLimit, said in the band's metadata
/// (`infinite`: the band holds some), so GDAL's statistics stay finite.
void describeBand(GDALRasterBandH band, const std::string& name, const std::string& unit, const std::string& meaning, bool infinite) {
    GDALSetDescription(band, name.c_str());
    GDALSetRasterUnitType(band, unit.c_str());
    GDALSetMetadataItem(band, "UNIT", unit.c_str(), nullptr);
    GDALSetMetadataItem(band, "MEANING", meaning.c_str(), nullptr);
    GDALSetRasterNoDataValue(band, std::numeric_limits<double>::quiet_NaN());
    if (infinite) {
        char text[32];
        std::snprintf(text, sizeof text, "%g", double(kNoLimit));
        GDALSetMetadataItem(band, "NO_LIMIT", text, nullptr);
    }
}

/// The dataset-level metadata, geotransform and CRS of a layer file whose lower-left corner is
/// at (originX, originY) [m], `height` rows of `res` [m].
void describeDataset(GDALDatasetH ds, double originX, double originY, int height, double res) {
    double gt[6] = {originX, res, 0.0, originY + height * res, 0.0, -res};  // north-up
    GDALSetGeoTransform(ds, gt);
    GDALSetProjection(ds, kMapFrameWkt);
    GDALSetMetadataItem(ds, "GSEG_CONTENT", "gseg 2.5D map layers: one float32 band per layer, NaN = unknown", nullptr);
    GDALSetMetadataItem(ds, "GSEG_FRAME", "map frame (the rawlog's world frame) in metres: columns along +x, rows along -y (first row: largest y)", nullptr);
}

/// The in-memory (MEM driver) dataset of the grid: bands, names, units, nodata, geotransform, CRS.
GDALDatasetH memoryDataset(const LayerGrid& grid) {
    const int w = grid.width(), h = grid.height(), n = int(grid.layers().size());
    GDALDatasetH ds = GDALCreate(GDALGetDriverByName("MEM"), "", w, h, n, GDT_Float32, nullptr);
    if (!ds) return nullptr;
    describeDataset(ds, grid.originX(), grid.originY(), h, grid.resolution());
    for (int b = 0; b < n; ++b) {
        const LayerGrid::Layer& layer = grid.layers()[std::size_t(b)];
        GDALRasterBandH band = GDALGetRasterBand(ds, b + 1);
        const bool infinite = std::any_of(layer.values.begin(), layer.values.end(), [](float v) { return std::isinf(v); });
        describeBand(band, layer.name, layer.unit, layer.meaning, infinite);
        std::vector<float> capped(infinite ? std::size_t(w) : 0);
        for (int row = 0; row < h; ++row) {  // image row 0 = the grid's last row (largest y)
            const float* src = layer.values.data() + grid.index(0, h - 1 - row);
            if (infinite) {
                for (int cx = 0; cx < w; ++cx) capped[std::size_t(cx)] = std::isinf(src[cx]) ? (src[cx] > 0 ? kNoLimit : -kNoLimit) : src[cx];
                src = capped.data();
            }
            if (GDALRasterIO(band, GF_Write, 0, row, w, 1, const_cast<float*>(src), w, 1, GDT_Float32, 0, 0) != CE_None) {
                GDALClose(ds);
                return nullptr;
            }
        }
    }
    return ds;
}

[[noreturn]] void refuse(const std::string& path, const std::string& what) { throw std::runtime_error(path + ": " + what); }

}  // namespace

std::string encodeLayersGeoTiff(const LayerGrid& grid) {
    validate(grid);
    GdalErrors errors;  // also around the registration: a plugin that fails to load must not print
    registerDrivers();
    Dataset source(memoryDataset(grid));
    if (!source.h || errors.failed()) throw std::runtime_error("layer GeoTIFF: " + errors.text("cannot build the raster in memory"));
    const std::string name = memoryFileName();
    const char* options[] = {"COMPRESS=DEFLATE", "PREDICTOR=3", "INTERLEAVE=BAND", nullptr};
    Dataset copy(GDALCreateCopy(GDALGetDriverByName("GTiff"), name.c_str(), source.h, FALSE, const_cast<char**>(options), nullptr, nullptr));
    copy.close();  // flushes the file
    std::string bytes;
    vsi_l_offset size = 0;
    if (const GByte* data = VSIGetMemFileBuffer(name.c_str(), &size, FALSE)) bytes.assign(reinterpret_cast<const char*>(data), std::size_t(size));
    VSIUnlink(name.c_str());
    if (errors.failed() || bytes.empty()) throw std::runtime_error("layer GeoTIFF: " + errors.text("GDAL wrote no file"));
    return bytes;
}

namespace {

/// Writes the cells of `tiles` that fall in `band`'s raster (image pixel (col, row) = cell
/// (x0 + col, yEnd - 1 - row)) block by block: only blocks with an allocated tile are written (a
/// sparse GTiff leaves the others out: nodata). False on a GDAL failure.
bool writeSparseBands(GDALDatasetH ds, int overview, const LayerTiles& tiles, std::int64_t x0, std::int64_t yEnd, int block) {
    GDALRasterBandH first = GDALGetRasterBand(ds, 1);
    if (overview >= 0) first = GDALGetOverview(first, overview);
    const int w = GDALGetRasterBandXSize(first), h = GDALGetRasterBandYSize(first);
    std::set<std::pair<int, int>> blocks;  // (block row, block column) with data
    const std::int64_t n = LayerTiles::kTile;
    for (const auto& [tx, ty] : tiles.tileList()) {
        const std::int64_t c0 = std::max<std::int64_t>(0, tx * n - x0), c1 = std::min<std::int64_t>(w - 1, (tx + 1) * n - 1 - x0);
        const std::int64_t r0 = std::max<std::int64_t>(0, yEnd - (ty + 1) * n), r1 = std::min<std::int64_t>(h - 1, yEnd - 1 - ty * n);
        if (c0 > c1 || r0 > r1) continue;
        for (std::int64_t br = r0 / block; br <= r1 / block; ++br)
            for (std::int64_t bc = c0 / block; bc <= c1 / block; ++bc) blocks.insert({int(br), int(bc)});
    }
    // All bands of a block in one call: the block of a pixel-interleaved GTiff is then encoded
    // once, when complete (band by band, the block cache could flush a block half written).
    GDALDatasetH level = GDALGetBandDataset(first);
    if (!level) return false;
    const int bands = GDALGetRasterCount(level);
    std::vector<float> values;
    for (const auto& [br, bc] : blocks) {
        const int col0 = bc * block, row0 = br * block;
        const int bw = std::min(block, w - col0), bh = std::min(block, h - row0);
        const LayerGrid g = tiles.window(x0 + col0, yEnd - row0 - bh, bw, bh);
        if (int(g.layers().size()) != bands) return false;
        values.resize(std::size_t(bw) * std::size_t(bh) * std::size_t(bands));
        float* dst = values.data();
        for (int b = 0; b < bands; ++b) {
            const std::vector<float>& v = g.layers()[std::size_t(b)].values;
            for (int r = 0; r < bh; ++r) {
                const float* src = v.data() + g.index(0, bh - 1 - r);
                for (int c = 0; c < bw; ++c) *dst++ = std::isinf(src[c]) ? (src[c] > 0 ? kNoLimit : -kNoLimit) : src[c];
            }
        }
        if (GDALDatasetRasterIO(level, GF_Write, col0, row0, bw, bh, values.data(), bw, bh, GDT_Float32, bands, nullptr, 0, 0, 0) != CE_None)
            return false;
    }
    return true;
}

/// Whether any allocated cell of layer `l` is infinite.
bool anyInfinite(const LayerTiles& tiles, std::size_t l) {
    const std::int64_t n = LayerTiles::kTile;
    for (const auto& [tx, ty] : tiles.tileList())
        for (std::int64_t iy = ty * n; iy < (ty + 1) * n; ++iy)
            for (std::int64_t ix = tx * n; ix < (tx + 1) * n; ++ix)
                if (std::isinf(tiles.get(l, ix, iy))) return true;
    return false;
}

}  // namespace

int cogOverviewCount(std::int64_t width, std::int64_t height, int block) {
    int count = 0;
    for (std::int64_t side = std::max(width, height); side > block; side = (side + 1) / 2) ++count;
    return count;
}

std::string encodeLayersCog(const LayerTiles& tiles, int block) {
    if (tiles.boxWidth() == 0 || tiles.boxHeight() == 0) throw std::invalid_argument("layer COG: the map has no cells");
    if (tiles.layers().empty()) throw std::invalid_argument("layer COG: the map has no layers");
    if (block < 16 || block % 16 != 0) throw std::invalid_argument("layer COG: the block size must be a multiple of 16");
    // The image's corners on the grid of the coarsest overview: its cells are whole overview cells.
    const int levels = cogOverviewCount(tiles.boxWidth(), tiles.boxHeight(), block);
    const std::int64_t f = std::int64_t(1) << levels;
    const std::int64_t x0 = LayerTiles::floorDiv(tiles.minX(), f) * f, yEnd = -LayerTiles::floorDiv(-(tiles.maxY() + 1), f) * f;
    const std::int64_t y0 = LayerTiles::floorDiv(tiles.minY(), f) * f, xEnd = -LayerTiles::floorDiv(-(tiles.maxX() + 1), f) * f;
    const std::int64_t w = xEnd - x0, h = yEnd - y0;
    if (w > (1 << 30) || h > (1 << 30)) throw std::invalid_argument("layer COG: the map is too big");
    GdalErrors errors;
    registerDrivers();
    // The blocks written here go through GDAL's block cache: at its default (5 % of the machine's
    // memory) it could hold gigabytes of them; 64 MB is as fast. Restored when done.
    const GIntBig cacheBefore = GDALGetCacheMax64();
    if (cacheBefore > (GIntBig(64) << 20)) GDALSetCacheMax64(GIntBig(64) << 20);
    struct RestoreCache {
        GIntBig bytes;
        ~RestoreCache() { GDALSetCacheMax64(bytes); }
    } restore{cacheBefore};
    // A tiled, sparse GTiff with internal overviews whose tiles are compressed as GDAL's COG
    // driver compresses them (DEFLATE at its level 6, floating-point predictor, pixel-interleaved,
    // overviews in blocks of the same size); then its tiles are copied into the COG layout
    // (detail::cogLayout()). GDAL's COG driver would read every block of the box, the empty ones
    // too: 15 s for a pose jump's box of 21700 cells a side, where this writes the blocks seen.
    const std::string source = memoryFileName();
    const std::string blockText = std::to_string(block);
    const std::string blockX = "BLOCKXSIZE=" + blockText, blockY = "BLOCKYSIZE=" + blockText;
    const char* sourceOptions[] = {"TILED=YES", blockX.c_str(), blockY.c_str(), "SPARSE_OK=TRUE", "COMPRESS=DEFLATE", "PREDICTOR=3",
                                   "INTERLEAVE=PIXEL", "BIGTIFF=YES", nullptr};
    const int n = int(tiles.layers().size());
    Dataset ds(GDALCreate(GDALGetDriverByName("GTiff"), source.c_str(), int(w), int(h), n, GDT_Float32, const_cast<char**>(sourceOptions)));
    if (!ds.h) throw std::runtime_error("layer COG: " + errors.text("cannot create the raster"));
    describeDataset(ds.h, double(x0) * tiles.resolution(), double(y0) * tiles.resolution(), int(h), tiles.resolution());
    for (int b = 0; b < n; ++b) {
        const LayerTiles::Info& l = tiles.layers()[std::size_t(b)];
        describeBand(GDALGetRasterBand(ds.h, b + 1), l.name, l.unit, l.meaning, anyInfinite(tiles, std::size_t(b)));
    }
    bool ok = writeSparseBands(ds.h, -1, tiles, x0, yEnd, block);
    // The overviews, computed by gseg from the tiles (LayerTiles::overview(): class and cost the
    // most blocking cell, the rest the mean), so no pass over the empty box is made.
    std::vector<int> factors;
    for (int k = 1; k <= levels; ++k) factors.push_back(1 << k);
    if (ok && levels > 0) {
        CPLSetThreadLocalConfigOption("GDAL_TIFF_OVR_BLOCKSIZE", blockText.c_str());
        ok = GDALBuildOverviews(ds.h, "NONE", levels, factors.data(), 0, nullptr, nullptr, nullptr) == CE_None;
        CPLSetThreadLocalConfigOption("GDAL_TIFF_OVR_BLOCKSIZE", nullptr);
    }
    for (int k = 0; ok && k < levels; ++k)
        ok = writeSparseBands(ds.h, k, tiles.overview(factors[std::size_t(k)]), x0 / factors[std::size_t(k)], yEnd / factors[std::size_t(k)], block);
    ds.close();  // flushes the blocks and directories
    if (!ok || errors.failed()) {
        VSIUnlink(source.c_str());
        throw std::runtime_error("layer COG: " + errors.text("cannot write the raster"));
    }
    // BigTIFF as GDAL's BIGTIFF=IF_SAFER decides it: when the image and its overviews, not
    // compressed, exceed 2 GB.
    double uncompressed = 0;
    for (int k = 0; k <= levels; ++k) uncompressed += double((w + (1 << k) - 1) >> k) * double((h + (1 << k) - 1) >> k) * n * 4.0;
    std::string bytes;
    vsi_l_offset size = 0;
    if (const GByte* data = VSIGetMemFileBuffer(source.c_str(), &size, FALSE)) {
        try {
            bytes = detail::cogLayout(std::string_view(reinterpret_cast<const char*>(data), std::size_t(size)), uncompressed > 2e9);
        } catch (...) {
            VSIUnlink(source.c_str());
            throw;
        }
    }
    VSIUnlink(source.c_str());
    if (errors.failed() || bytes.empty()) throw std::runtime_error("layer COG: " + errors.text("GDAL wrote no file"));
    return bytes;
}

LayerGrid readLayersGeoTiff(const std::string& path) {
    {
        try {
            gseg::io::regularFileSize(path);  // stat before open: a FIFO is refused, not waited on
        } catch (const std::exception& e) {
            throw std::runtime_error(std::string(e.what()) + " (a layer GeoTIFF)");
        }
        std::ifstream probe(path, std::ios::binary);
        if (!probe) refuse(path, std::string("cannot open: ") + std::strerror(errno));
        char magic[4] = {};
        probe.read(magic, 4);
        const bool tiff = probe.gcount() == 4 && ((std::memcmp(magic, "II", 2) == 0 && (magic[2] == 42 || magic[2] == 43) && magic[3] == 0) ||
                                                  (std::memcmp(magic, "MM", 2) == 0 && magic[2] == 0 && (magic[3] == 42 || magic[3] == 43)));
        if (!tiff) refuse(path, "not a GeoTIFF (no TIFF header)");
    }
    GdalErrors errors;
    registerDrivers();
    const char* const drivers[] = {"GTiff", nullptr};
    Dataset ds(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, drivers, nullptr, nullptr));
    if (!ds.h) refuse(path, "not a readable GeoTIFF (" + errors.text("GDAL cannot open it") + ")");
    const int w = GDALGetRasterXSize(ds.h), h = GDALGetRasterYSize(ds.h), n = GDALGetRasterCount(ds.h);
    if (n < 1) refuse(path, "no bands");
    if (w < 1 || h < 1) refuse(path, "no cells");
    if (std::uint64_t(w) * std::uint64_t(h) > kMaxCells)
        refuse(path, "too large (" + std::to_string(w) + " x " + std::to_string(h) + " cells; at most " + std::to_string(kMaxCells) + ")");
    if (std::uint64_t(w) * std::uint64_t(h) * std::uint64_t(n) > kMaxValues)
        refuse(path, "too large: " + std::to_string(n) + " bands of " + std::to_string(w) + " x " + std::to_string(h) +
                         " cells would take " + std::to_string(std::uint64_t(w) * std::uint64_t(h) * std::uint64_t(n) * 4 >> 20) +
                         " MiB; at most " + std::to_string(kMaxValues * 4 >> 20) + " MiB of layers are read");
    if (OGRSpatialReferenceH srs = GDALGetSpatialRef(ds.h); srs && OSRIsGeographic(srs))
        refuse(path, "its coordinates are geographic (degrees of latitude and longitude); gseg's layers are in metres of the "
                     "map frame (reproject it, e.g. gdalwarp -t_srs to a projected CRS in metres)");
    double gt[6];
    if (GDALGetGeoTransform(ds.h, gt) != CE_None) refuse(path, "no geotransform (a TIFF, not a GeoTIFF in map-frame metres)");
    if (gt[2] != 0.0 || gt[4] != 0.0) refuse(path, "rotated or sheared geotransform (only axis-aligned grids are layer files)");
    const double res = gt[1];
    if (!(std::isfinite(res) && res > 0) || !(std::fabs(std::fabs(gt[5]) - res) <= 1e-9 * res))
        refuse(path, "pixels are not square cells with x growing to the right (geotransform " + std::to_string(gt[1]) + ", " +
                         std::to_string(gt[5]) + ")");
    const bool northUp = gt[5] < 0;
    LayerGrid grid;
    try {
        grid = LayerGrid(w, h, res, gt[0], northUp ? gt[3] - h * res : gt[3]);
    } catch (const std::exception& e) {
        refuse(path, e.what());
    }
    std::vector<float> buffer(std::size_t(w) * std::size_t(h));
    for (int b = 1; b <= n; ++b) {
        GDALRasterBandH band = GDALGetRasterBand(ds.h, b);
        std::string name = GDALGetDescription(band);
        if (name.empty()) name = "band " + std::to_string(b);
        if (grid.find(name)) refuse(path, "two bands named '" + name + "'");
        std::string unit = GDALGetRasterUnitType(band);
        if (unit.empty())
            if (const char* u = GDALGetMetadataItem(band, "UNIT", nullptr)) unit = u;
        const char* meaning = GDALGetMetadataItem(band, "MEANING", nullptr);
        const char* noLimitText = GDALGetMetadataItem(band, "NO_LIMIT", nullptr);
        const float noLimit = noLimitText ? std::strtof(noLimitText, nullptr) : 0.0f;
        if (GDALRasterIO(band, GF_Read, 0, 0, w, h, buffer.data(), w, h, GDT_Float32, 0, 0) != CE_None || errors.failed())
            refuse(path, "truncated or damaged: band " + std::to_string(b) + " cannot be read (" + errors.text("no message") + ")");
        int hasNodata = 0;
        const double nodata = GDALGetRasterNoDataValue(band, &hasNodata);
        LayerGrid::Layer& layer = grid.add(name, unit, meaning ? meaning : "");
        for (int row = 0; row < h; ++row) {
            const int cy = northUp ? h - 1 - row : row;
            const float* src = buffer.data() + std::size_t(row) * std::size_t(w);
            float* dst = layer.values.data() + grid.index(0, cy);
            for (int cx = 0; cx < w; ++cx) {
                dst[cx] = hasNodata && !std::isnan(nodata) && src[cx] == float(nodata) ? std::numeric_limits<float>::quiet_NaN() : src[cx];
                if (noLimit > 0 && std::fabs(dst[cx]) == noLimit) dst[cx] = std::copysign(std::numeric_limits<float>::infinity(), dst[cx]);
            }
        }
    }
    return grid;
}

}  // namespace gseg::map
