// The picture of one layer of a LayerGrid on the map page (gseg/map/map_page.hpp: x right, y up,
// as the costmap PGM): colour bar or class legend, unknown cells named, scale bar, axes, a title
// wrapped to the canvas.
#include <gseg/map/layer_picture.hpp>
#include <gseg/map/map_colours.hpp>
#include <gseg/map/map_page.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace gseg::map {
namespace {

using gseg::mrpt::Colour;
using gseg::mrpt::LegendEntry;
using gseg::mrpt::Picture;

constexpr int kEnlargeTo = 640;               // [px] longer side of a small grid
constexpr int kBarWidth = 20, kBarHeight = 256;  // [px] the colour bar
const Colour kOtherClass{255, 255, 255};      // a class value other than 1 and 2
const Colour kPlusInfinity{255, 255, 255}, kMinusInfinity{0, 0, 0};
constexpr double kLowPercentile = 2, kHighPercentile = 98;  // [%] the colour bar's range when not given

/// matplotlib's viridis at t = 0, 1/8, ..., 1.
constexpr unsigned char kViridis[9][3] = {{68, 1, 84},   {71, 45, 123},  {59, 82, 139},  {44, 114, 142}, {33, 145, 140},
                                          {40, 174, 128}, {94, 201, 98}, {173, 220, 48}, {253, 231, 37}};

std::string unitSuffix(const std::string& unit) { return unit.empty() || unit == "-" ? "" : " " + unit; }

/// "12.35 m": decimals enough to tell the ends of a range `span` wide apart.
std::string valueLabel(double v, double span, const std::string& unit) {
    const int decimals = span > 0 ? std::clamp(int(std::ceil(-std::log10(span / 100))), 0, 6) : 2;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf + unitSuffix(unit);
}

const LayerGrid::Layer& checkedLayer(const LayerGrid& grid, const std::string& name, const LayerPictureOptions& o) {
    if (grid.cells() == 0) throw std::invalid_argument("layer picture: the grid has no cells");
    const LayerGrid::Layer& layer = grid.layer(name);
    if (layer.values.size() != grid.cells())
        throw std::invalid_argument("layer picture: layer '" + name + "' has " + std::to_string(layer.values.size()) + " values for " +
                                    std::to_string(grid.cells()) + " cells");
    if (std::isinf(o.min) || std::isinf(o.max) || (o.min > o.max)) throw std::invalid_argument("layer picture: colour bar min / max must be finite, min <= max");
    if (o.maxSide < 16) throw std::invalid_argument("layer picture: maxSide must be at least 16 pixels");
    return layer;
}

/// The `p` percentile (0 to 100) of `sorted` values: the value at rank p / 100 * (n - 1),
/// rounded down for the low end of a range (`down`), up for the high end.
double percentile(const std::vector<float>& sorted, double p, bool down) {
    const double rank = p / 100.0 * double(sorted.size() - 1);
    return sorted[std::size_t(down ? std::floor(rank) : std::ceil(rank))];
}

/// The colour bar's range of the finite values `v` (sorted here): the 2nd to 98th percentile; if
/// those are equal (a layer almost all one value, e.g. step 0), the 0.5th to 99.5th; if those
/// too, the whole range (the rare other values must still show).
std::pair<double, double> robustRange(std::vector<float>& v) {
    std::sort(v.begin(), v.end());
    for (const double tail : {kLowPercentile, 0.5}) {
        const double lo = percentile(v, tail, true), hi = percentile(v, 100 - tail, false);
        if (hi > lo) return {lo, hi};
    }
    return {v.front(), v.back()};
}

/// The legend line of +inf cells: what no limit means in this layer.
std::string plusInfinityText(const LayerGrid::Layer& layer) {
    return layer.name == "clearance" ? "+inf: no obstacle above the ground (no limit)" : "+inf: no limit";
}

/// The legend lines under the map.
std::vector<LegendEntry> legendEntries(const LayerPictureLayout& l, const LayerGrid::Layer& layer, bool otherClasses) {
    std::vector<LegendEntry> e;
    if (l.classes) {
        e.push_back({colourOf(ColumnClass::Traversable), "1: traversable"});
        e.push_back({colourOf(ColumnClass::Obstacle), "2: not traversable"});
        if (otherClasses) e.push_back({kOtherClass, "another class value"});
    } else if (l.barHeight > 0) {
        e.push_back({{}, "colour map: viridis (low dark blue, high yellow)", false});
    }
    if (!l.classes && l.positiveInfinite) e.push_back({kPlusInfinity, plusInfinityText(layer)});
    if (!l.classes && l.negativeInfinite) e.push_back({kMinusInfinity, "-inf: no limit below"});
    e.push_back({colourOf(ColumnClass::Unknown), "unknown (NaN): no data for " + layer.name});
    e.push_back({{}, "the darker page around the map: outside the grid", false});
    return e;
}

/// The value each map pixel block shows: the largest of its cells (NaN if all are NaN), row-major
/// over the blocks of the map area.
std::vector<float> blockValues(const LayerGrid& grid, const LayerGrid::Layer& layer, const MapPage& page) {
    const int across = page.blocksWide();
    std::vector<float> v(std::size_t(across) * std::size_t(page.blocksHigh()), std::numeric_limits<float>::quiet_NaN());
    for (int cy = 0; cy < grid.height(); ++cy)
        for (int cx = 0; cx < grid.width(); ++cx) {
            const float value = layer.values[grid.index(cx, cy)];
            int col = 0, row = 0;
            if (std::isnan(value) || !page.blockOf(cx, cy, col, row)) continue;
            float& b = v[std::size_t(row) * std::size_t(across) + std::size_t(col)];
            if (std::isnan(b) || value > b) b = value;
        }
    return v;
}

Colour colourFor(float v, const LayerPictureLayout& l) {
    if (std::isnan(v)) return colourOf(ColumnClass::Unknown);
    if (std::isinf(v) && !l.classes) return v > 0 ? kPlusInfinity : kMinusInfinity;
    if (l.classes) {
        const long c = std::lround(v);
        return c == long(ColumnClass::Traversable) ? colourOf(ColumnClass::Traversable)
               : c == long(ColumnClass::Obstacle) ? colourOf(ColumnClass::Obstacle) : kOtherClass;
    }
    return viridis(l.high > l.low ? (double(v) - l.low) / (l.high - l.low) : 0.5);
}

}  // namespace

Colour positiveInfinityColour() { return kPlusInfinity; }
Colour negativeInfinityColour() { return kMinusInfinity; }

Colour viridis(double t) {
    if (!(t > 0)) t = 0;
    if (t > 1) t = 1;
    const double f = t * 8;
    const int i = std::min(int(f), 7);
    const double w = f - i;
    auto mix = [&](int k) { return std::uint8_t(std::lround(kViridis[i][k] + w * (kViridis[i + 1][k] - kViridis[i][k]))); };
    return {mix(0), mix(1), mix(2)};
}

bool LayerPictureLayout::toPixel(int cx, int cy, int& col, int& row) const { return page.cellPixel(cx, cy, col, row); }

LayerPictureLayout layerPictureLayout(const LayerGrid& grid, const std::string& name, const LayerPictureOptions& o) {
    const LayerGrid::Layer& layer = checkedLayer(grid, name, o);
    LayerPictureLayout l;
    l.gridWidth = grid.width(), l.gridHeight = grid.height();
    l.classes = name == "class";
    // The range: the options', else the 2nd to 98th percentile of the layer's finite values.
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    std::vector<float> finite;
    for (float v : layer.values) {
        if (std::isfinite(v)) lo = std::min(lo, double(v)), hi = std::max(hi, double(v)), finite.push_back(v);
        else if (std::isinf(v)) ++(v > 0 ? l.positiveInfinite : l.negativeInfinite);
    }
    const std::size_t known = finite.size();
    if (!known) lo = hi = 0;
    double robustLow = lo, robustHigh = hi;
    if (known && !l.classes && (std::isnan(o.min) || std::isnan(o.max))) std::tie(robustLow, robustHigh) = robustRange(finite);
    l.low = std::isnan(o.min) ? robustLow : o.min;
    l.high = std::isnan(o.max) ? robustHigh : o.max;
    if (l.high < l.low) std::swap(l.low, l.high);  // one of them given, beyond the other end of the data
    l.clippedLow = known && lo < l.low, l.clippedHigh = known && hi > l.high;
    const bool bar = !l.classes && (known || !std::isnan(o.min) || !std::isnan(o.max));  // no bar for a layer without data
    if (bar) l.barHeight = kBarHeight;  // placed below
    // The colour bar's labels, right of the bar.
    const double span = l.high - l.low;
    std::vector<std::string> barLabels;
    if (bar) {
        barLabels = {name + unitSuffix(layer.unit.empty() ? "" : "[" + layer.unit + "]"),
                     (l.clippedHigh ? ">= " : "") + valueLabel(l.high, span, layer.unit),
                     valueLabel(0.5 * (l.low + l.high), span, layer.unit), (l.clippedLow ? "<= " : "") + valueLabel(l.low, span, layer.unit)};
        const bool given = !std::isnan(o.min) || !std::isnan(o.max);
        if (given) barLabels.push_back("(values beyond: end colours)");
        else if (l.clippedLow || l.clippedHigh) barLabels.push_back("(2nd-98th percentile; beyond: end colours)");
    }
    std::size_t barChars = 0;
    for (const auto& t : barLabels) barChars = std::max(barChars, t.size());
    bool otherClasses = false;
    if (l.classes)
        for (float v : layer.values)
            if (!std::isnan(v) && std::lround(v) != 1 && std::lround(v) != 2) otherClasses = true;
    // The title: the layer, its meaning, its figures.
    MapPageOptions page;
    page.maxSide = o.maxSide, page.enlargeTo = kEnlargeTo, page.maxEnlarge = 16;
    if (bar) page.sideWidth = kBarWidth + 12 + int(barChars) * Picture::kCharWidth, page.sideHeight = 28 + kBarHeight + (barLabels.size() > 4 ? 34 : 8);
    page.legend = legendEntries(l, layer, otherClasses);
    page.title.push_back("gseg map layer: " + name + unitSuffix(layer.unit.empty() ? "" : "[" + layer.unit + "]") +
                         (o.title.empty() ? std::string() : ": " + o.title));
    if (!layer.meaning.empty()) page.title.push_back(layer.meaning);
    char figures[256];
    std::snprintf(figures, sizeof figures, "%.2f m cells, %d x %d (x by y), %zu known", grid.resolution(), grid.width(), grid.height(),
                  known + l.positiveInfinite + l.negativeInfinite);
    std::string values = !known ? (l.positiveInfinite + l.negativeInfinite ? "; no finite value" : "; no known cell")
                                : l.classes ? "" : "; values " + valueLabel(lo, hi - lo, layer.unit) + " to " + valueLabel(hi, hi - lo, layer.unit);
    if (!l.classes && l.positiveInfinite) values += ", " + std::to_string(l.positiveInfinite) + " +inf";
    if (!l.classes && l.negativeInfinite) values += ", " + std::to_string(l.negativeInfinite) + " -inf";
    if (l.classes && known) {
        std::size_t counts[3] = {0, 0, 0};
        for (float v : layer.values)
            if (!std::isnan(v)) ++counts[std::lround(v) == 1 ? 0 : std::lround(v) == 2 ? 1 : 2];
        values = ": " + std::to_string(counts[0]) + " traversable, " + std::to_string(counts[1]) + " not traversable" +
                 (counts[2] ? ", " + std::to_string(counts[2]) + " other" : "");
    }
    page.title.push_back(figures + values);
    // The map area: x right (grid.width() cells across), y up (grid.height() cells down), as the costmap PGM.
    const MapPage probe = mapPage(0, 0, grid.width() - 1, grid.height() - 1, grid.resolution(), page);
    if (probe.cellsPerPixel > 1)
        page.title.push_back(std::to_string(probe.cellsPerPixel) + " x " + std::to_string(probe.cellsPerPixel) + " cells a pixel (the largest value shown)");
    l.page = mapPage(0, 0, grid.width() - 1, grid.height() - 1, grid.resolution(), page);
    const MapPage& p = l.page;
    l.width = p.width, l.height = p.height;
    l.mapLeft = p.mapLeft, l.mapTop = p.mapTop, l.mapWidth = p.mapWidth, l.mapHeight = p.mapHeight;
    l.pixelsPerCell = p.pixelsPerCell, l.cellsPerPixel = p.cellsPerPixel;
    l.legendTop = p.legendTop;
    for (std::size_t i = 0; i < p.titleLines.size(); ++i) l.texts.push_back({10, 8 + int(i) * Picture::kLineHeight, p.titleLines[i]});
    if (bar) {
        l.barLeft = p.sideLeft;
        l.barTop = l.mapTop + 28;  // the layer's name above it
        const int tx = l.barLeft + kBarWidth + 12;  // clear of the ticks
        l.texts.push_back({std::min(l.barLeft, l.width - MapPage::kMargin - int(barLabels[0].size()) * Picture::kCharWidth), l.mapTop, barLabels[0]});
        l.texts.push_back({tx, l.barTop - 7, barLabels[1]});
        l.texts.push_back({tx, l.barTop + kBarHeight / 2 - 7, barLabels[2]});
        l.texts.push_back({tx, l.barTop + kBarHeight - 8, barLabels[3]});
        if (barLabels.size() > 4) l.texts.push_back({tx, l.barTop + kBarHeight + 14, barLabels[4]});
    }
    int y = l.legendTop;
    for (const auto& e : p.legend) {
        l.texts.push_back({MapPage::kMargin + (e.swatch ? 24 : 0), y, e.text});
        y += Picture::kLineHeight;
    }
    return l;
}

std::string encodeLayerPng(const LayerGrid& grid, const std::string& name, const LayerPictureOptions& o) {
    const LayerPictureLayout l = layerPictureLayout(grid, name, o);
    const LayerGrid::Layer& layer = grid.layer(name);
    Picture pic = pageCanvas(l.page);
    const std::vector<float> values = blockValues(grid, layer, l.page);
    std::vector<Colour> blocks(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) blocks[i] = colourFor(values[i], l);
    paintBlocks(pic, l.page, blocks);
    if (l.barHeight > 0) {
        for (int r = 0; r < l.barHeight; ++r)
            pic.fill(l.barLeft, l.barTop + r, l.barLeft + kBarWidth - 1, l.barTop + r, viridis(1.0 - double(r) / (l.barHeight - 1)));
        for (int r : {0, l.barHeight / 2, l.barHeight - 1}) pic.fill(l.barLeft + kBarWidth, l.barTop + r, l.barLeft + kBarWidth + 4, l.barTop + r, pic.textColour());
    }
    // The bar's texts (after the title's lines, before the legend's); the page draws the rest.
    const std::size_t first = l.page.titleLines.size(), last = l.texts.size() - l.page.legend.size();
    for (std::size_t i = first; i < last; ++i) pic.text(l.texts[i].x, l.texts[i].y, l.texts[i].text);
    drawPageFrame(pic, l.page);
    return pic.png();
}

}  // namespace gseg::map
