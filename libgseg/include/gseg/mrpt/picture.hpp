#pragma once
/// \file picture.hpp
/// What every gseg picture shares (scan top views, failure breakdowns, traversability maps, the
/// eval plot): a title that names files, not paths; a legend that names every colour; a scale bar
/// of a round length; one orientation convention for top views (x forward up, y left to the left,
/// stated in the picture and drawn as an arrow); and PNG output written completely or not at all.

#include <gseg/point_cloud.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace mrpt::img {
class CImage;
}

namespace gseg::mrpt {

/// 8-bit RGB.
struct Colour {
    std::uint8_t r = 0, g = 0, b = 0;
};

/// One legend line: a colour swatch and its text (`swatch` false: text only, e.g. the orientation).
struct LegendEntry {
    Colour colour;
    std::string text;
    bool swatch = true;
};

/// Where a Picture drew a text, and the canvas: for tests (every text must lie inside its canvas).
struct DrawnText {
    int x = 0, y = 0, width = 0, height = 0;  ///< [px] the text's box, top-left corner and size
    std::string text;                         ///< as drawn (after fitting)
    int canvasWidth = 0, canvasHeight = 0;    ///< [px]
};

/// While one lives, every text the Pictures of this thread draw is appended to `sink`.
class TextRecorder {
public:
    explicit TextRecorder(std::vector<DrawnText>& sink);
    ~TextRecorder();
    TextRecorder(const TextRecorder&) = delete;
    TextRecorder& operator=(const TextRecorder&) = delete;

private:
    std::vector<DrawnText>* previous_;
};

/// The orientation line of every top view: "top view: x (forward) up, y (left) to the left".
extern const char* const kTopViewOrientation;

/// A name for a picture's title: the file name, with the folders of the KITTI layout kept
/// ("08/velodyne/000000.bin"), never the folders above it. Empty for an empty path.
std::string displayName(const std::string& path);

/// An RGB canvas (MRPT's CImage) with gseg's decorations. Text colour follows the background
/// (light on dark, black on light). Text drawing is serialised inside (MRPT 2.5.8's is not
/// thread-safe), so pictures can be drawn from several threads.
class Picture {
public:
    static constexpr int kLineHeight = 20;  ///< [px] legend and title line spacing
    static constexpr int kCharWidth = 9;    ///< [px] width of a character of the default font
    static constexpr int kTextHeight = 15;  ///< [px] height of a line of text (fonts 9x15, 9x15B)

    /// Throws std::invalid_argument on a size below 1 or above 16384 pixels a side.
    Picture(int width, int height, Colour background);
    ~Picture();
    Picture(Picture&&) noexcept;
    Picture& operator=(Picture&&) noexcept;

    int width() const { return width_; }
    int height() const { return height_; }
    Colour background() const { return background_; }
    Colour textColour() const;

    /// Sets one pixel (ignored outside the picture).
    void pixel(int x, int y, Colour c);
    /// Filled rectangle, corners inclusive, clipped to the picture.
    void fill(int x0, int y0, int x1, int y1, Colour c);
    void line(int x0, int y0, int x1, int y1, Colour c, int width = 1);
    void circle(int x, int y, int radius, Colour c);
    /// Text with its top-left corner at (x, y); in textColour() unless given. A text longer than
    /// the room up to the right edge is shortened in the middle ("08/velo...000000.bin"), so
    /// every text fits its canvas (titles too).
    void text(int x, int y, const std::string& s);
    void text(int x, int y, const std::string& s, Colour c);

    /// Title (bold) and a second line below it, at the top-left corner.
    void title(const std::string& title, const std::string& subtitle = "");
    /// Legend with its top-left corner at (x, y), one entry per line; returns the height used.
    int legend(int x, int y, const std::vector<LegendEntry>& entries);
    /// Height of legend() for n entries.
    static int legendHeight(std::size_t n) { return int(n) * kLineHeight; }
    /// Scale bar whose right end is at (xRight, y): the longest of 1, 2, 5 x 10^k m that fits in
    /// maxPixels, labelled above ("10 m").
    void scaleBar(int xRight, int y, double pixelsPerMetre, int maxPixels = 150);
    /// An arrow from (x, y) to (x + dx, y + dy) with its head at the end, labelled beside the head;
    /// in textColour() unless given.
    void arrow(int x, int y, int dx, int dy, const std::string& label, int width = 2);
    void arrow(int x, int y, int dx, int dy, const std::string& label, int width, Colour c);

    /// The picture as a PNG file (encodePng()).
    std::string png() const;
    /// Writes png() to `path` through gseg::io::AtomicFile (complete or absent).
    void save(const std::string& path) const;

    ::mrpt::img::CImage& image() { return *image_; }  ///< draw on it, never resize it (pixel() keeps its rows' address)
    const ::mrpt::img::CImage& image() const { return *image_; }

private:
    void record(int x, int y, const std::string& s) const;  ///< to the TextRecorder of this thread, if any

    std::unique_ptr<::mrpt::img::CImage> image_;
    int width_ = 0, height_ = 0;
    Colour background_;
    bool bgr_ = false;  ///< channel order of the image
    std::uint8_t* pixels_ = nullptr;  ///< the image's first row
    std::size_t stride_ = 0;          ///< [bytes] from one row to the next
};

/// "12 m", "0.5 m": a length as the pictures label it.
std::string metresLabel(double m);

}  // namespace gseg::mrpt
