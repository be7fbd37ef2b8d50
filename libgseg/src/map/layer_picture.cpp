// The picture of one layer of a LayerGrid: map area (x up, y to the left), colour bar or class
// legend, unknown cells named, scale bar, axes, a title wrapped to the canvas.
#include <gseg/io/atomic_file.hpp>
#include <gseg/map/layer_picture.hpp>
#include <gseg/map/map_colours.hpp>

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

constexpr int kMargin = 12, kMinWidth = 760;  // [px]
constexpr int kEnlargeTo = 640;               // [px] longer side of a small grid
constexpr int kBarWidth = 20, kBarHeight = 256;  // [px] the colour bar
constexpr int kAxesBlock = 240;               // [px] right of the legend band: axes and scale bar
constexpr int kAxesBandHeight = 140;          // [px] height they need
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

/// `text` in lines of at most `width` characters, broken at spaces where it can be.
std::vector<std::string> wrap(const std::string& text, std::size_t width) {
    std::vector<std::string> lines;
    std::string rest = text;
    width = std::max<std::size_t>(width, 8);
    while (rest.size() > width) {
        std::size_t cut = rest.rfind(' ', width);
        if (cut == std::string::npos || cut < width / 2) cut = width;  // a long word: broken
        lines.push_back(rest.substr(0, cut));
        rest = rest.substr(cut);
        if (!rest.empty() && rest[0] == ' ') rest.erase(0, 1);
    }
    lines.push_back(rest);
    return lines;
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
    e.push_back({{}, "top view: x up, y (left) to the left", false});
    return e;
}

/// The value each map pixel block shows: the largest of its cells (NaN if all are NaN), row-major
/// over the blocks of the map area.
std::vector<float> blockValues(const LayerGrid& grid, const LayerGrid::Layer& layer, const LayerPictureLayout& l) {
    const int s = l.cellsPerPixel, across = l.mapWidth / l.pixelsPerCell, down = l.mapHeight / l.pixelsPerCell;
    std::vector<float> v(std::size_t(across) * std::size_t(down), std::numeric_limits<float>::quiet_NaN());
    for (int cy = 0; cy < grid.height(); ++cy)
        for (int cx = 0; cx < grid.width(); ++cx) {
            const float value = layer.values[grid.index(cx, cy)];
            if (std::isnan(value)) continue;
            float& b = v[std::size_t((grid.width() - 1 - cx) / s) * std::size_t(across) + std::size_t((grid.height() - 1 - cy) / s)];
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

bool LayerPictureLayout::toPixel(int cx, int cy, int& col, int& row) const {
    if (cx < 0 || cy < 0 || cx >= gridWidth || cy >= gridHeight) return false;
    const int across = gridHeight - 1 - cy, down = gridWidth - 1 - cx;
    col = mapLeft + across / cellsPerPixel * pixelsPerCell;
    row = mapTop + down / cellsPerPixel * pixelsPerCell;
    return true;
}

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
    // The map area: x up (grid.width() cells down), y to the left (grid.height() cells across).
    const std::uint64_t side = std::uint64_t(std::max(grid.width(), grid.height()));
    l.cellsPerPixel = int((side + std::uint64_t(o.maxSide) - 1) / std::uint64_t(o.maxSide));
    if (l.cellsPerPixel == 1) l.pixelsPerCell = std::clamp(int(std::uint64_t(kEnlargeTo) / side), 1, 16);
    const int s = l.cellsPerPixel;
    l.mapWidth = (grid.height() + s - 1) / s * l.pixelsPerCell;
    l.mapHeight = (grid.width() + s - 1) / s * l.pixelsPerCell;
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
    const int barBlock = !bar ? 0 : 24 + kBarWidth + 12 + int(barChars) * Picture::kCharWidth;
    bool otherClasses = false;
    if (l.classes)
        for (float v : layer.values)
            if (!std::isnan(v) && std::lround(v) != 1 && std::lround(v) != 2) otherClasses = true;
    const std::vector<LegendEntry> legend = legendEntries(l, layer, otherClasses);
    std::size_t legendChars = 0;
    for (const auto& e : legend) legendChars = std::max(legendChars, e.text.size() + (e.swatch ? 3 : 0));
    l.width = std::max({kMinWidth, kMargin + l.mapWidth + barBlock + kMargin,
                        kMargin + 30 + int(legendChars) * Picture::kCharWidth + 20 + kAxesBlock});
    // The title, wrapped to the width.
    const std::size_t chars = std::size_t((l.width - 20) / Picture::kCharWidth);
    std::vector<std::string> titleLines = wrap("gseg map layer: " + name + unitSuffix(layer.unit.empty() ? "" : "[" + layer.unit + "]") +
                                                   (o.title.empty() ? std::string() : ": " + o.title),
                                               chars);
    if (!layer.meaning.empty())
        for (auto& t : wrap(layer.meaning, chars)) titleLines.push_back(t);
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
    for (auto& t : wrap(figures + values, chars)) titleLines.push_back(t);
    if (s > 1)
        for (auto& t : wrap(std::to_string(s) + " x " + std::to_string(s) + " cells a pixel (the largest value shown)", chars))
            titleLines.push_back(t);
    for (std::size_t i = 0; i < titleLines.size(); ++i) l.texts.push_back({10, 8 + int(i) * Picture::kLineHeight, titleLines[i]});
    const int titleBand = 8 + int(titleLines.size()) * Picture::kLineHeight + 8;
    l.mapLeft = kMargin;
    l.mapTop = titleBand;
    int band = l.mapHeight;
    if (bar) {
        l.barLeft = l.mapLeft + l.mapWidth + 24;
        l.barTop = l.mapTop + 28;  // the layer's name above it
        const int tx = l.barLeft + kBarWidth + 12;  // clear of the ticks
        l.texts.push_back({l.barLeft, l.mapTop, barLabels[0]});
        l.texts.back().x = std::min(l.barLeft, l.width - kMargin - int(barLabels[0].size()) * Picture::kCharWidth);
        l.texts.push_back({tx, l.barTop - 7, barLabels[1]});
        l.texts.push_back({tx, l.barTop + kBarHeight / 2 - 7, barLabels[2]});
        l.texts.push_back({tx, l.barTop + kBarHeight - 8, barLabels[3]});
        if (barLabels.size() > 4) l.texts.push_back({tx, l.barTop + kBarHeight + 14, barLabels[4]});
        band = std::max(band, 28 + kBarHeight + (barLabels.size() > 4 ? 34 : 8));
    }
    const int legendTop = l.mapTop + band + kMargin;
    int y = legendTop;
    for (const auto& e : legend) {
        l.texts.push_back({kMargin + (e.swatch ? 24 : 0), y, e.text});
        y += Picture::kLineHeight;
    }
    l.legendTop = legendTop;
    l.height = legendTop + std::max(Picture::legendHeight(legend.size()), kAxesBandHeight) + kMargin;
    return l;
}

std::string encodeLayerPng(const LayerGrid& grid, const std::string& name, const LayerPictureOptions& o) {
    const LayerPictureLayout l = layerPictureLayout(grid, name, o);
    const LayerGrid::Layer& layer = grid.layer(name);
    Picture pic(l.width, l.height, backgroundColour());
    const std::vector<float> blocks = blockValues(grid, layer, l);
    const int across = l.mapWidth / l.pixelsPerCell, p = l.pixelsPerCell;
    for (int row = 0; row < l.mapHeight; ++row)
        for (int col = 0; col < l.mapWidth; ++col)
            pic.pixel(l.mapLeft + col, l.mapTop + row, colourFor(blocks[std::size_t(row / p) * std::size_t(across) + std::size_t(col / p)], l));
    if (l.barHeight > 0) {
        for (int r = 0; r < l.barHeight; ++r)
            pic.fill(l.barLeft, l.barTop + r, l.barLeft + kBarWidth - 1, l.barTop + r, viridis(1.0 - double(r) / (l.barHeight - 1)));
        for (int r : {0, l.barHeight / 2, l.barHeight - 1}) pic.fill(l.barLeft + kBarWidth, l.barTop + r, l.barLeft + kBarWidth + 4, l.barTop + r, pic.textColour());
    }
    // Texts: the title's first line in bold, the rest as laid out; the legend draws its own lines
    // (the same text at the same places) with their swatches.
    bool otherClasses = false;
    for (const auto& t : l.texts)
        if (t.text == "another class value") otherClasses = true;
    const std::vector<LegendEntry> legend = legendEntries(l, layer, otherClasses);
    pic.title(l.texts[0].text);
    for (std::size_t i = 1; i + legend.size() < l.texts.size(); ++i) pic.text(l.texts[i].x, l.texts[i].y, l.texts[i].text);
    pic.legend(kMargin, l.legendTop, legend);
    // Axes and scale bar at the right of the legend band.
    const int ax = l.width - 70, ay = l.legendTop + 70;
    pic.arrow(ax, ay, 0, -48, "x");
    pic.arrow(ax, ay, -48, 0, "y");
    pic.scaleBar(l.width - kMargin - 4, l.legendTop + 124, l.pixelsPerMetre(grid.resolution()), 200);
    return pic.png();
}

void writeLayerPng(const std::string& path, const LayerGrid& grid, const std::string& name, const LayerPictureOptions& options) {
    std::string png;
    try {
        png = encodeLayerPng(grid, name, options);
    } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(path + ": " + e.what());
    } catch (const std::out_of_range& e) {
        throw std::out_of_range(path + ": " + e.what());
    } catch (const std::exception& e) {
        throw std::runtime_error(path + ": " + e.what());
    }
    gseg::io::writeFileAtomic(path, png.data(), png.size());
}

}  // namespace gseg::map
