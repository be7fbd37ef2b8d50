// gseg eval: precision / recall against the range limit, drawn with mrpt::img::CImage.
#include "eval_plot.hpp"

#include <mrpt/img/CImage.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <unistd.h>

namespace gseg::app {
namespace {

using ::mrpt::img::TColor;

void savePng(const ::mrpt::img::CImage& img, const std::string& path) {
    const std::string tmp = path + ".tmp" + std::to_string(::getpid()) + ".png";
    if (!img.saveToFile(tmp)) {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
        throw std::runtime_error(path + ": cannot write the PNG");
    }
    std::filesystem::rename(tmp, path);
}

constexpr int kW = 900, kH = 560, kLeft = 70, kRight = 210, kTop = 50, kBottom = 60;
const TColor kBlack(0, 0, 0), kGrey(210, 210, 210), kWhite(255, 255, 255);
const TColor kPalette[] = {{31, 119, 180}, {214, 39, 40},  {44, 160, 44},   {148, 103, 189},
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

void drawAxes(::mrpt::img::CImage& img, double lo, const std::function<int(double)>& yOf) {
    for (double v = lo; v <= 100.0 + 1e-9; v += 5) {
        img.line(kLeft, yOf(v), kW - kRight, yOf(v), kGrey);
        img.textOut(kLeft - 36, yOf(v) - 7, std::to_string(int(v)), kBlack);
    }
    for (int d = 10; d <= 100; d += 10) {
        img.line(xOf(d), kTop, xOf(d), kH - kBottom, kGrey);
        img.line(xOf(d), kH - kBottom, xOf(d), kH - kBottom + 5, kBlack);
        img.textOut(xOf(d) - 9, kH - kBottom + 9, std::to_string(d), kBlack);
    }
    img.line(kLeft, kTop, kLeft, kH - kBottom, kBlack);
    img.line(kLeft, kH - kBottom, kW - kRight, kH - kBottom, kBlack);
    img.textOut(kLeft, 14, "GSB precision and recall within a horizontal range limit", kBlack);
    img.textOut(kLeft - 36, kTop - 24, "[%]", kBlack);
    img.textOut((kLeft + kW - kRight) / 2 - 60, kH - 26, "range limit [m]", kBlack);
}

void drawSequence(::mrpt::img::CImage& img, const SequenceSummary& s, const TColor& c,
                  const std::function<int(double)>& yOf) {
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
            img.filledRectangle(x - 3, y - 3, x + 3, y + 3, c);
        }
}

void drawLegend(::mrpt::img::CImage& img, const std::vector<SequenceSummary>& seqs) {
    const int x = kW - kRight + 20;
    int y = kTop;
    img.line(x, y + 7, x + 30, y + 7, kBlack, 3);
    img.textOut(x + 38, y, "precision", kBlack);
    y += 20;
    img.line(x, y + 7, x + 30, y + 7, kBlack, 1);
    img.filledRectangle(x + 12, y + 4, x + 18, y + 10, kBlack);
    img.textOut(x + 38, y, "recall", kBlack);
    y += 30;
    for (std::size_t i = 0; i < seqs.size(); ++i, y += 20) {
        img.filledRectangle(x, y + 2, x + 30, y + 12, kPalette[i % 8]);
        img.textOut(x + 38, y, "seq " + seqs[i].sequence, kBlack);
    }
}

}  // namespace

void plotRanges(const std::string& path, const std::vector<SequenceSummary>& seqs) {
    const double lo = lowerBound(seqs);
    const std::function<int(double)> yOf = [lo](double v) {
        return kTop + int(std::lround((100.0 - v) / (100.0 - lo) * (kH - kTop - kBottom)));
    };
    ::mrpt::img::CImage img(kW, kH, ::mrpt::img::CH_RGB);
    img.filledRectangle(0, 0, kW - 1, kH - 1, kWhite);
    drawAxes(img, lo, yOf);
    for (std::size_t i = 0; i < seqs.size(); ++i) drawSequence(img, seqs[i], kPalette[i % 8], yOf);
    drawLegend(img, seqs);
    savePng(img, path);
}

void plotOutcomes(const std::string& path, const PointCloudView& cloud, const std::vector<PointOutcome>& outcomes,
                  const std::string& title) {
    // MRPT 2.5.8's CImage text drawing is not thread-safe (eval's workers crash the heap without this).
    static std::mutex mutex;
    const std::lock_guard<std::mutex> lock(mutex);
    constexpr int kSize = 900, kRange = 50;  // px, m (half-width shown)
    constexpr double kScale = 0.5 * kSize / kRange;
    constexpr int c = kSize / 2;
    const TColor kBack(24, 24, 30), kText(235, 235, 235);
    const TColor colours[4] = {TColor(95, 95, 105), TColor(40, 170, 70), TColor(255, 40, 40), TColor(60, 140, 255)};
    const char* names[4] = {"non-ground (correct)", "true ground", "false ground", "missed ground"};
    ::mrpt::img::CImage img(kSize, kSize, ::mrpt::img::CH_RGB);
    img.filledRectangle(0, 0, kSize - 1, kSize - 1, kBack);
    std::size_t counts[4] = {0, 0, 0, 0};
    // Errors last, so they are drawn over the correct points.
    for (const PointOutcome kind : {PointOutcome::TrueNonGround, PointOutcome::TrueGround, PointOutcome::MissedGround,
                                    PointOutcome::FalseGround}) {
        const int k = int(kind), r = kind == PointOutcome::TrueNonGround || kind == PointOutcome::TrueGround ? 0 : 1;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (outcomes[i] != kind) continue;
            ++counts[k];
            const int u = c - int(std::lround(cloud.y(i) * kScale)), v = c - int(std::lround(cloud.x(i) * kScale));
            if (u < r || v < r || u >= kSize - 1 - r || v >= kSize - 1 - r) continue;
            img.filledRectangle(u - r, v - r, u + r, v + r, colours[k]);
        }
    }
    // Sensor, forward arrow (x), scale bar.
    img.line(c, c + 8, c, c - 40, kText, 2);
    img.line(c, c - 40, c - 6, c - 30, kText, 2);
    img.line(c, c - 40, c + 6, c - 30, kText, 2);
    img.textOut(c + 8, c - 44, "x (forward)", kText);
    const int bar = int(std::lround(10 * kScale));
    img.filledRectangle(kSize - 30 - bar, kSize - 30, kSize - 30, kSize - 26, kText);
    img.textOut(kSize - 30 - bar, kSize - 50, "10 m", kText);
    img.textOut(10, 8, title, kText);
    img.textOut(10, 26, "top view, sensor at the centre, x forward up, y left; 50 m each side", kText);
    int y = kSize - 100;
    for (int k : {1, 2, 3, 0}) {
        img.filledRectangle(10, y + 3, 26, y + 13, colours[k]);
        img.textOut(34, y, std::string(names[k]) + ": " + std::to_string(counts[k]), kText);
        y += 20;
    }
    savePng(img, path);
}

}  // namespace gseg::app
