// The canvas of every gseg picture: lines, text, title, legend, scale bar, arrows (MRPT CImage).
#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/picture.hpp>
#include <gseg/mrpt/png.hpp>

#include <mrpt/img/CImage.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <stdexcept>

namespace gseg::mrpt {
namespace {

::mrpt::img::TColor tcolor(Colour c) { return ::mrpt::img::TColor(c.r, c.g, c.b); }

thread_local std::vector<DrawnText>* tRecorded = nullptr;  // TextRecorder's sink on this thread

/// `s` as it fits between x and the right edge of a canvas `width` wide (4 px margin): unchanged
/// when it fits, else its start and end around "..." (a file name keeps its end).
std::string fitted(const std::string& s, int x, int width) {
    const int room = (width - 4 - x) / Picture::kCharWidth;
    if (int(s.size()) <= room) return s;
    if (room <= 3) return s.substr(0, std::size_t(std::max(0, room)));
    const std::size_t keep = std::size_t(room - 3), head = keep / 3;
    return s.substr(0, head) + "..." + s.substr(s.size() - (keep - head));
}

/// MRPT 2.5.8's CImage text drawing is not thread-safe (eval's workers crashed the heap without it).
std::mutex& textMutex() {
    static std::mutex m;
    return m;
}



}  // namespace

std::string metresLabel(double m) {
    char buf[32];
    std::snprintf(buf, sizeof buf, m >= 1 ? "%.0f m" : "%.1f m", m);
    return buf;
}

std::string displayName(const std::string& path) {
    const std::filesystem::path p = std::filesystem::path(path).lexically_normal();
    const std::string name = p.filename().string();
    const std::filesystem::path folder = p.parent_path();
    if (folder.filename() == "velodyne" && !folder.parent_path().filename().empty())
        return (folder.parent_path().filename() / "velodyne" / name).string();
    return name;
}

Picture::Picture(int width, int height, Colour background)
    : width_(width), height_(height), background_(background) {
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw std::invalid_argument("Picture: " + std::to_string(width) + " x " + std::to_string(height) +
                                    " pixels: each side must be 1 to 16384");
    image_ = std::make_unique<::mrpt::img::CImage>(width, height, ::mrpt::img::CH_RGB);
    bgr_ = image_->getChannelsOrder() == "BGR";
    // The pixels stay where they are for the picture's life (nothing resizes it): rows are found
    // from the first row's address, not through CImage's checked access per pixel.
    pixels_ = image_->ptrLine<std::uint8_t>(0), stride_ = image_->getRowStride();
    fill(0, 0, width - 1, height - 1, background);
}

Picture::~Picture() = default;
Picture::Picture(Picture&&) noexcept = default;
Picture& Picture::operator=(Picture&&) noexcept = default;

Colour Picture::textColour() const {
    const int luminance = (299 * background_.r + 587 * background_.g + 114 * background_.b) / 1000;
    return luminance < 128 ? Colour{235, 235, 235} : Colour{0, 0, 0};
}

void Picture::pixel(int x, int y, Colour c) {
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
    std::uint8_t* p = pixels_ + std::size_t(y) * stride_ + 3 * std::size_t(x);
    p[0] = bgr_ ? c.b : c.r, p[1] = c.g, p[2] = bgr_ ? c.r : c.b;
}

void Picture::fill(int x0, int y0, int x1, int y1, Colour c) {
    x0 = std::max(x0, 0), y0 = std::max(y0, 0), x1 = std::min(x1, width_ - 1), y1 = std::min(y1, height_ - 1);
    if (x0 > x1 || y0 > y1) return;  // wholly outside: no row address beyond the image is formed
    const std::uint8_t a = bgr_ ? c.b : c.r, b = c.g, d = bgr_ ? c.r : c.b;
    for (int y = y0; y <= y1; ++y) {
        std::uint8_t* p = pixels_ + std::size_t(y) * stride_ + 3 * std::size_t(x0);
        for (int x = x0; x <= x1; ++x, p += 3) p[0] = a, p[1] = b, p[2] = d;
    }
}

void Picture::line(int x0, int y0, int x1, int y1, Colour c, int width) {
    image_->line(x0, y0, x1, y1, tcolor(c), unsigned(std::max(1, width)));
}

void Picture::circle(int x, int y, int radius, Colour c) { image_->drawCircle(x, y, radius, tcolor(c)); }

void Picture::text(int x, int y, const std::string& s) { text(x, y, s, textColour()); }

void Picture::text(int x, int y, const std::string& s, Colour c) {
    const std::string shown = fitted(s, x, width_);
    record(x, y, shown);
    const std::lock_guard<std::mutex> lock(textMutex());
    image_->textOut(x, y, shown, tcolor(c));
}

void Picture::record(int x, int y, const std::string& s) const {
    if (tRecorded) tRecorded->push_back({x, y, int(s.size()) * kCharWidth, kTextHeight, s, width_, height_});
}

TextRecorder::TextRecorder(std::vector<DrawnText>& sink) : previous_(tRecorded) { tRecorded = &sink; }
TextRecorder::~TextRecorder() { tRecorded = previous_; }

void Picture::title(const std::string& title, const std::string& subtitle) {
    const int lines = subtitle.empty() ? 1 : 2;
    const std::string shown = fitted(title, 10, width_);
    const std::size_t chars = std::max(shown.size(), fitted(subtitle, 10, width_).size());
    fill(0, 0, std::min(width_ - 1, 16 + int(chars) * kCharWidth), 8 + lines * kLineHeight, background_);
    record(10, 8, shown);
    {
        const std::lock_guard<std::mutex> lock(textMutex());
        image_->selectTextFont("9x15B");
        image_->textOut(10, 8, shown, tcolor(textColour()));
        image_->selectTextFont("9x15");
    }
    if (!subtitle.empty()) text(10, 8 + kLineHeight, subtitle);
}

int Picture::legend(int x, int y, const std::vector<LegendEntry>& entries) {
    std::size_t chars = 0;
    for (const auto& e : entries) chars = std::max(chars, e.text.size());
    const int h = legendHeight(entries.size());
    fill(x - 6, y - 4, x + 30 + int(chars) * kCharWidth, y + h, background_);  // readable over points
    for (const auto& e : entries) {
        if (e.swatch) fill(x, y + 3, x + 16, y + 13, e.colour);
        text(x + (e.swatch ? 24 : 0), y, e.text);
        y += kLineHeight;
    }
    return h;
}

void Picture::scaleBar(int xRight, int y, double pixelsPerMetre, int maxPixels) {
    if (!(pixelsPerMetre > 0)) return;
    double length = 0;
    for (double decade = 0.01; decade <= 1e6; decade *= 10)
        for (double m : {1.0, 2.0, 5.0})
            if (m * decade * pixelsPerMetre <= maxPixels) length = m * decade;
    if (length <= 0) return;
    const int px = std::max(1, int(std::lround(length * pixelsPerMetre)));
    const std::string label = metresLabel(length);
    fill(xRight - std::max(px, int(label.size()) * kCharWidth) - 6, y - 26, xRight + 4, y + 8, background_);
    fill(xRight - px, y, xRight, y + 4, textColour());
    fill(xRight - px, y - 4, xRight - px + 1, y + 4, textColour());
    fill(xRight - 1, y - 4, xRight, y + 4, textColour());
    text(xRight - px / 2 - int(label.size()) * kCharWidth / 2, y - 22, label);
}

void Picture::arrow(int x, int y, int dx, int dy, const std::string& label, int width) {
    arrow(x, y, dx, dy, label, width, textColour());
}

void Picture::arrow(int x, int y, int dx, int dy, const std::string& label, int width, Colour c) {
    const double length = std::hypot(double(dx), double(dy));
    if (length < 1) return;
    const int x1 = x + dx, y1 = y + dy;
    line(x, y, x1, y1, c, width);
    const double ux = dx / length, uy = dy / length, head = std::min(12.0, 0.4 * length);
    for (double side : {-1.0, 1.0}) {  // two strokes at +-30 deg from the shaft
        const double hx = -ux * 0.866 - side * uy * 0.5, hy = -uy * 0.866 + side * ux * 0.5;
        line(x1, y1, x1 + int(std::lround(hx * head)), y1 + int(std::lround(hy * head)), c, width);
    }
    if (!label.empty()) text(x1 + (dx < 0 ? -int(label.size()) * kCharWidth - 6 : 8), y1 - 8, label);
}

std::string Picture::png() const { return encodePng(*image_); }

void Picture::save(const std::string& path) const {
    const std::string bytes = png();
    gseg::io::writeFileAtomic(path, bytes.data(), bytes.size());
}



}  // namespace gseg::mrpt
