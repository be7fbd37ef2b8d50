// gseg eval: precision / recall against the range limit, and the per-frame breakdown picture,
// drawn with the shared picture conventions (gseg/mrpt/picture.hpp).
#include "eval_plot.hpp"

#include <gseg/mrpt/picture.hpp>
#include <gseg/mrpt/png.hpp>
#include <gseg/mrpt/top_view.hpp>

#include <algorithm>
#include <cmath>
#include <functional>

namespace gseg::app {
namespace {

using mrpt::Colour;
using mrpt::Picture;

constexpr int kW = 900, kH = 570, kLeft = 70, kRight = 260, kTop = 70, kBottom = 60;
const Colour kBlack{0, 0, 0}, kGrey{210, 210, 210}, kWhite{255, 255, 255};
const Colour kPalette[] = {{31, 119, 180}, {214, 39, 40},  {44, 160, 44},   {148, 103, 189},
                           {255, 127, 14}, {140, 86, 75}, {227, 119, 194}, {23, 190, 207}};

int xOf(double metres) { return kLeft + int(std::lround((metres - 10) / 90.0 * (kW - kLeft - kRight))); }

/// The lowest value to show: 5 % steps below the smallest figure, at least 0.
double lowerBound(const std::vector<SequenceSummary>& seqs) {
    double lo = 100;
    for (const auto& s : seqs)
        for (std::size_t k = 0; k < 10; ++k)
            for (double v : {s.rangeP[k], s.rangeR[k]})
                if (!std::isnan(v)) lo = std::min(lo, v);
    return std::max(0.0, std::floor(lo / 5.0) * 5.0 - 5.0);
}

void drawAxes(Picture& img, double lo, const std::function<int(double)>& yOf) {
    for (double v = lo; v <= 100.0 + 1e-9; v += 5) {
        img.line(kLeft, yOf(v), kW - kRight, yOf(v), kGrey);
        img.text(kLeft - 36, yOf(v) - 7, std::to_string(int(v)));
    }
    for (int d = 10; d <= 100; d += 10) {
        img.line(xOf(d), kTop, xOf(d), kH - kBottom, kGrey);
        img.line(xOf(d), kH - kBottom, xOf(d), kH - kBottom + 5, kBlack);
        img.text(xOf(d) - 9, kH - kBottom + 9, std::to_string(d));
    }
    img.line(kLeft, kTop, kLeft, kH - kBottom, kBlack);
    img.line(kLeft, kH - kBottom, kW - kRight, kH - kBottom, kBlack);
    img.title("gseg eval: precision and recall within a horizontal range limit",
              "Ground Segmentation Benchmark protocol, mean over the frames of each sequence");
    img.text(kLeft - 36, kTop - 18, "[%]");
    img.text((kLeft + kW - kRight) / 2 - 60, kH - 26, "range limit [m]");
}

void drawSequence(Picture& img, const SequenceSummary& s, const Colour& c, const std::function<int(double)>& yOf) {
    for (std::size_t k = 0; k + 1 < 10; ++k) {
        const double d0 = 10.0 * double(k + 1), d1 = d0 + 10;
        if (!std::isnan(s.rangeP[k]) && !std::isnan(s.rangeP[k + 1]))
            img.line(xOf(d0), yOf(s.rangeP[k]), xOf(d1), yOf(s.rangeP[k + 1]), c, 3);
        if (!std::isnan(s.rangeR[k]) && !std::isnan(s.rangeR[k + 1]))
            img.line(xOf(d0), yOf(s.rangeR[k]), xOf(d1), yOf(s.rangeR[k + 1]), c, 1);
    }
    for (std::size_t k = 0; k < 10; ++k)
        if (!std::isnan(s.rangeR[k])) {
            const int x = xOf(10.0 * double(k + 1)), y = yOf(s.rangeR[k]);
            img.fill(x - 3, y - 3, x + 3, y + 3, c);
        }
}

void drawLegend(Picture& img, const std::vector<SequenceSummary>& seqs) {
    const int x = kW - kRight + 20;
    int y = kTop;
    img.line(x, y + 7, x + 16, y + 7, kBlack, 3);
    img.text(x + 24, y, "precision (thick)");
    y += Picture::kLineHeight;
    img.line(x, y + 7, x + 16, y + 7, kBlack, 1);
    img.fill(x + 5, y + 4, x + 11, y + 10, kBlack);
    img.text(x + 24, y, "recall (thin, squares)");
    y += Picture::kLineHeight + 10;
    std::vector<mrpt::LegendEntry> entries;
    for (std::size_t i = 0; i < seqs.size(); ++i) entries.push_back({kPalette[i % 8], "sequence " + seqs[i].sequence});
    img.legend(x, y, entries);
}

}  // namespace

std::string rangePlotPng(const std::vector<SequenceSummary>& seqs) {
    const double lo = lowerBound(seqs);
    const std::function<int(double)> yOf = [lo](double v) {
        return kTop + int(std::lround((100.0 - v) / (100.0 - lo) * (kH - kTop - kBottom)));
    };
    Picture img(kW, kH, kWhite);
    drawAxes(img, lo, yOf);
    for (std::size_t i = 0; i < seqs.size(); ++i) drawSequence(img, seqs[i], kPalette[i % 8], yOf);
    drawLegend(img, seqs);
    return img.png();
}

void plotOutcomes(const std::string& path, const PointCloudView& cloud, const std::vector<PointOutcome>& outcomes,
                  const std::string& title) {
    // Classes indexed by PointOutcome; errors drawn last (over the correct points) and larger.
    const std::vector<mrpt::PointClass> classes = {{{150, 150, 160}, "non-ground (correct)", 0, 1},
                                                   {{40, 170, 70}, "true ground", 1, 1},
                                                   {{255, 40, 40}, "false ground", 3, 3},
                                                   {{60, 140, 255}, "missed ground", 2, 3}};
    std::vector<std::uint8_t> classOf(outcomes.size());
    for (std::size_t i = 0; i < outcomes.size(); ++i) classOf[i] = std::uint8_t(outcomes[i]);
    mrpt::TopViewOptions options;
    options.sizePx = 900;
    options.rangeM = 50;
    options.title = title;
    mrpt::drawTopView(cloud, classOf, classes, options).save(path);
}

}  // namespace gseg::app
