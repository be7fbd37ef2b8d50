// The Cloud-Optimized GeoTIFF layout of a tiled GeoTIFF, written by gseg (#35): GDAL's COG driver
// reads every block of the image, empty ones included (GDAL 3.6 does not skip them when it copies
// a source with its overviews), so a pose jump's box of 21700 x 21700 cells took 15 s to write
// for the few blocks that hold data. Here the compressed tiles of a GTiff that GDAL wrote (tiled,
// sparse, internal overviews, compressed as the COG wants them) are copied as they are into the
// layout GDAL's COG driver writes: the same header ghost area, the image file directories first
// (full resolution, then the overviews), then the tiles, smallest overview first, each row-major
// with its 4-byte size before it and its last 4 bytes repeated after it; empty tiles stay absent.
#pragma once

#include <string>
#include <string_view>

namespace gseg::map::detail {

/// The COG bytes of `tiff`: a little-endian TIFF or BigTIFF whose directories are all tiled (one
/// image and its overviews, as GDAL's GTiff driver writes them). The output is BigTIFF when
/// `bigTiff`, else classic TIFF. Every tag is kept (the tile offsets and byte counts rewritten).
/// Throws std::runtime_error on a TIFF it cannot read (truncated, big-endian, stripped, an
/// offset past the end) or whose data does not fit a classic TIFF when !bigTiff.
std::string cogLayout(std::string_view tiff, bool bigTiff);

}  // namespace gseg::map::detail
