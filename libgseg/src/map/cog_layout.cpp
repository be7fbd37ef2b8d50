// The COG layout of a tiled GeoTIFF (see cog_layout.hpp). TIFF 6.0 and BigTIFF, little-endian.
#include "cog_layout.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace gseg::map::detail {
namespace {

constexpr std::uint16_t kTileOffsets = 324, kTileByteCounts = 325, kTileWidth = 322;

[[noreturn]] void bad(const std::string& what) { throw std::runtime_error("COG layout: " + what); }

/// Bytes of one value of a TIFF field type (0: unknown type).
std::uint64_t typeSize(std::uint16_t type) {
    switch (type) {
        case 1: case 2: case 6: case 7: return 1;   // BYTE, ASCII, SBYTE, UNDEFINED
        case 3: case 8: return 2;                   // SHORT, SSHORT
        case 4: case 9: case 11: case 13: return 4;  // LONG, SLONG, FLOAT, IFD
        case 5: case 10: case 12: case 16: case 17: case 18: return 8;  // RATIONAL, SRATIONAL, DOUBLE, LONG8, SLONG8, IFD8
        default: return 0;
    }
}

/// Little-endian reads within `data`, refusing what lies past its end.
struct Reader {
    std::string_view data;
    void need(std::uint64_t at, std::uint64_t n) const {
        if (at > data.size() || n > data.size() - at) bad("truncated TIFF (an offset past the end)");
    }
    std::uint64_t get(std::uint64_t at, int bytes) const {
        need(at, std::uint64_t(bytes));
        std::uint64_t v = 0;
        for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | std::uint8_t(data[std::size_t(at) + std::size_t(i)]);
        return v;
    }
};

struct Entry {
    std::uint16_t tag = 0, type = 0;
    std::uint64_t count = 0;
    std::string value;  // count * typeSize(type) bytes, little-endian
    std::uint64_t sourceAt = 0;  // where the value lay in the source (out-of-line values keep that order)
};

struct Directory {
    std::vector<Entry> entries;  // by tag, as read (the tile offsets and byte counts kept aside)
    std::vector<std::uint64_t> offsets, counts;
    std::uint16_t countsType = 16;  // the type libtiff gave the tile byte counts
    std::uint64_t width = 0;
};

/// The values of an integer array entry (SHORT, LONG, LONG8).
std::vector<std::uint64_t> integers(const Entry& e) {
    const std::uint64_t size = typeSize(e.type);
    if (e.type != 3 && e.type != 4 && e.type != 16) bad("tile offsets or byte counts that are not integers");
    std::vector<std::uint64_t> v(std::size_t(e.count));
    Reader r{e.value};
    for (std::uint64_t i = 0; i < e.count; ++i) v[std::size_t(i)] = r.get(i * size, int(size));
    return v;
}

std::vector<Directory> readDirectories(std::string_view tiff) {
    const Reader r{tiff};
    if (tiff.size() < 8 || tiff[0] != 'I' || tiff[1] != 'I') bad("not a little-endian TIFF");
    const std::uint64_t magic = r.get(2, 2);
    if (magic != 42 && magic != 43) bad("not a TIFF");
    const bool big = magic == 43;
    if (big && (r.get(4, 2) != 8 || r.get(6, 2) != 0)) bad("a BigTIFF with offsets that are not 8 bytes");
    const int offsetBytes = big ? 8 : 4;
    std::uint64_t next = big ? r.get(8, 8) : r.get(4, 4);
    std::vector<Directory> dirs;
    while (next != 0) {
        if (dirs.size() > 64) bad("more than 64 directories");
        const std::uint64_t n = r.get(next, big ? 8 : 2);
        const std::uint64_t first = next + (big ? 8 : 2), entryBytes = big ? 20 : 12;
        r.need(first, n * entryBytes + std::uint64_t(offsetBytes));
        Directory d;
        for (std::uint64_t i = 0; i < n; ++i) {
            const std::uint64_t at = first + i * entryBytes;
            Entry e;
            e.tag = std::uint16_t(r.get(at, 2));
            e.type = std::uint16_t(r.get(at + 2, 2));
            e.count = r.get(at + 4, big ? 8 : 4);
            const std::uint64_t size = typeSize(e.type);
            if (size == 0) bad("a field of unknown type " + std::to_string(e.type));
            if (e.count > tiff.size()) bad("a field longer than the file");
            const std::uint64_t bytes = size * e.count;
            const std::uint64_t valueAt = at + 4 + std::uint64_t(offsetBytes);
            const std::uint64_t where = bytes <= std::uint64_t(offsetBytes) ? valueAt : r.get(valueAt, offsetBytes);
            r.need(where, bytes);
            e.value.assign(tiff.substr(std::size_t(where), std::size_t(bytes)));
            e.sourceAt = where;
            if (e.tag == kTileOffsets) d.offsets = integers(e);
            else if (e.tag == kTileByteCounts) d.counts = integers(e), d.countsType = e.type;
            else {
                if (e.tag == 256) d.width = integers(e).at(0);
                d.entries.push_back(std::move(e));
            }
        }
        if (d.offsets.empty() || d.offsets.size() != d.counts.size()) bad("a directory that is not tiled");
        if (std::none_of(d.entries.begin(), d.entries.end(), [](const Entry& e) { return e.tag == kTileWidth; }))
            bad("a directory that is not tiled");
        for (std::size_t t = 0; t < d.offsets.size(); ++t)
            if (d.counts[t] != 0) r.need(d.offsets[t], d.counts[t]);
        dirs.push_back(std::move(d));
        next = r.get(first + n * entryBytes, offsetBytes);
    }
    if (dirs.empty()) bad("no image");
    return dirs;
}

/// Appends little-endian integers.
struct Writer {
    std::string& out;
    void put(std::uint64_t v, int bytes) {
        for (int i = 0; i < bytes; ++i, v >>= 8) out.push_back(char(v & 0xff));
    }
    void padTo(std::uint64_t at) {
        if (out.size() > at) bad("internal: layout overlap");
        out.append(std::size_t(at - out.size()), '\0');
    }
};

/// The COG ghost area GDAL writes after the header (GDAL's COG driver, "header ghost area").
const std::string& ghostArea() {
    static const std::string text = [] {
        const std::string body =
            "LAYOUT=IFDS_BEFORE_DATA\nBLOCK_ORDER=ROW_MAJOR\nBLOCK_LEADER=SIZE_AS_UINT4\nBLOCK_TRAILER=LAST_4_BYTES_REPEATED\n"
            "KNOWN_INCOMPATIBLE_EDITION=NO\n ";
        char size[64];
        std::snprintf(size, sizeof size, "GDAL_STRUCTURAL_METADATA_SIZE=%06d bytes\n", int(body.size()));
        return size + body;
    }();
    return text;
}

std::uint64_t even(std::uint64_t v) { return v + (v & 1); }

}  // namespace

std::string cogLayout(std::string_view tiff, bool bigTiff) {
    std::vector<Directory> dirs = readDirectories(tiff);
    // Full resolution first, then the overviews from the largest down (GDAL's order).
    std::stable_sort(dirs.begin(), dirs.end(), [](const Directory& a, const Directory& b) { return a.width > b.width; });
    const int offsetBytes = bigTiff ? 8 : 4;
    const std::uint64_t entryBytes = bigTiff ? 20 : 12;
    // Classic TIFF: 8-byte fields become 4-byte ones where their values fit.
    for (Directory& d : dirs)
        for (Entry& e : d.entries) {
            if (bigTiff || (e.type != 16 && e.type != 17 && e.type != 18)) continue;
            std::string narrow;
            Reader r{e.value};
            for (std::uint64_t i = 0; i < e.count; ++i) {
                const std::uint64_t v = r.get(i * 8, 8);
                if (e.type == 17 ? (std::int64_t(v) < INT32_MIN || std::int64_t(v) > INT32_MAX) : v > UINT32_MAX)
                    bad("a value that does not fit a classic TIFF");
                Writer{narrow}.put(v, 4);
            }
            e.value = std::move(narrow);
            e.type = e.type == 16 ? 4 : e.type == 17 ? 9 : 13;
        }
    // The tile offsets and byte counts as libtiff writes them: offsets LONG8 in a BigTIFF, LONG in
    // a classic one; byte counts LONG where they fit (LONG8 otherwise, BigTIFF only).
    struct Arrays {
        Entry offsets, counts;
    };
    std::vector<Arrays> arrays(dirs.size());
    for (std::size_t k = 0; k < dirs.size(); ++k) {
        const Directory& d = dirs[k];
        const std::uint64_t most = *std::max_element(d.counts.begin(), d.counts.end());
        if (!bigTiff && most > UINT32_MAX) bad("a tile that does not fit a classic TIFF");
        arrays[k].offsets = Entry{kTileOffsets, std::uint16_t(bigTiff ? 16 : 4), d.offsets.size(), {}, 0};
        arrays[k].counts = Entry{kTileByteCounts, std::uint16_t(most > UINT32_MAX || (bigTiff && d.countsType == 16) ? 16 : 4), d.counts.size(), {}, 0};
    }
    auto arrayBytes = [](const Entry& e) { return e.count * typeSize(e.type); };
    // Pass 1: where everything goes. GDAL's COG: the ghost area, each directory followed by its
    // out-of-line values (but the tile arrays) in libtiff's order (the source's), then the tile
    // arrays of every directory (offsets, byte counts), then the tiles.
    const std::string& ghost = ghostArea();
    std::uint64_t at = even((bigTiff ? 16 : 8) + ghost.size());
    std::vector<std::uint64_t> dirAt(dirs.size());
    for (std::size_t k = 0; k < dirs.size(); ++k) {
        Directory& d = dirs[k];
        dirAt[k] = at;
        const std::uint64_t n = d.entries.size() + 2;
        at += (bigTiff ? 8 : 2) + n * entryBytes + std::uint64_t(offsetBytes);
        for (const Entry& e : d.entries)
            if (e.value.size() > std::size_t(offsetBytes)) at = even(at + e.value.size());
    }
    std::vector<std::uint64_t> offsetsAt(dirs.size(), 0), countsAt(dirs.size(), 0);
    for (std::size_t k = 0; k < dirs.size(); ++k) {
        if (arrayBytes(arrays[k].offsets) > std::uint64_t(offsetBytes)) offsetsAt[k] = at, at = even(at + arrayBytes(arrays[k].offsets));
        if (arrayBytes(arrays[k].counts) > std::uint64_t(offsetBytes)) countsAt[k] = at, at = even(at + arrayBytes(arrays[k].counts));
    }
    // The tiles: smallest overview first, row-major, each as [size][bytes][last 4 bytes].
    std::vector<std::vector<std::uint64_t>> newOffsets(dirs.size());
    for (std::size_t k = dirs.size(); k-- > 0;) {
        const Directory& d = dirs[k];
        newOffsets[k].assign(d.offsets.size(), 0);
        for (std::size_t t = 0; t < d.offsets.size(); ++t) {
            if (d.counts[t] == 0) continue;
            newOffsets[k][t] = at + 4;
            at += 4 + d.counts[t] + 4;
        }
    }
    if (!bigTiff && at > UINT32_MAX) bad("the image does not fit a classic TIFF");
    for (std::size_t k = 0; k < dirs.size(); ++k)
        for (std::size_t t = 0; t < dirs[k].offsets.size(); ++t) {
            Writer{arrays[k].offsets.value}.put(newOffsets[k][t], int(typeSize(arrays[k].offsets.type)));
            Writer{arrays[k].counts.value}.put(dirs[k].counts[t], int(typeSize(arrays[k].counts.type)));
        }
    // Pass 2: the bytes.
    std::string out;
    out.reserve(std::size_t(at));
    Writer w{out};
    out += "II";
    if (bigTiff) {
        w.put(43, 2), w.put(8, 2), w.put(0, 2), w.put(dirAt[0], 8);
    } else {
        w.put(42, 2), w.put(dirAt[0], 4);
    }
    out += ghost;
    for (std::size_t k = 0; k < dirs.size(); ++k) {
        const Directory& d = dirs[k];
        std::vector<const Entry*> entries;
        for (const Entry& e : d.entries) entries.push_back(&e);
        entries.push_back(&arrays[k].offsets);
        entries.push_back(&arrays[k].counts);
        std::stable_sort(entries.begin(), entries.end(), [](const Entry* a, const Entry* b) { return a->tag < b->tag; });
        std::vector<const Entry*> outOfLine;
        for (const Entry& e : d.entries)
            if (e.value.size() > std::size_t(offsetBytes)) outOfLine.push_back(&e);
        std::stable_sort(outOfLine.begin(), outOfLine.end(), [](const Entry* a, const Entry* b) { return a->sourceAt < b->sourceAt; });
        std::vector<std::uint64_t> valueAt(outOfLine.size());
        std::uint64_t v = dirAt[k] + (bigTiff ? 8 : 2) + entries.size() * entryBytes + std::uint64_t(offsetBytes);
        for (std::size_t i = 0; i < outOfLine.size(); ++i) valueAt[i] = v, v = even(v + outOfLine[i]->value.size());
        w.padTo(dirAt[k]);
        w.put(entries.size(), bigTiff ? 8 : 2);
        for (const Entry* e : entries) {
            w.put(e->tag, 2), w.put(e->type, 2), w.put(e->count, offsetBytes);
            if (e->value.size() <= std::size_t(offsetBytes)) {
                out += e->value;
                out.append(std::size_t(offsetBytes) - e->value.size(), '\0');
            } else if (e == &arrays[k].offsets) {
                w.put(offsetsAt[k], offsetBytes);
            } else if (e == &arrays[k].counts) {
                w.put(countsAt[k], offsetBytes);
            } else {
                w.put(valueAt[std::size_t(std::find(outOfLine.begin(), outOfLine.end(), e) - outOfLine.begin())], offsetBytes);
            }
        }
        w.put(k + 1 < dirs.size() ? dirAt[k + 1] : 0, offsetBytes);
        for (std::size_t i = 0; i < outOfLine.size(); ++i) {
            w.padTo(valueAt[i]);
            out += outOfLine[i]->value;
        }
    }
    for (std::size_t k = 0; k < dirs.size(); ++k) {
        if (offsetsAt[k]) w.padTo(offsetsAt[k]), out += arrays[k].offsets.value;
        if (countsAt[k]) w.padTo(countsAt[k]), out += arrays[k].counts.value;
    }
    for (std::size_t k = dirs.size(); k-- > 0;) {
        const Directory& d = dirs[k];
        for (std::size_t t = 0; t < d.offsets.size(); ++t) {
            if (d.counts[t] == 0) continue;
            w.padTo(newOffsets[k][t] - 4);
            w.put(d.counts[t], 4);
            const std::string_view bytes = tiff.substr(std::size_t(d.offsets[t]), std::size_t(d.counts[t]));
            out += bytes;
            char trailer[4] = {0, 0, 0, 0};
            const std::size_t tail = std::min<std::size_t>(4, bytes.size());
            std::memcpy(trailer, bytes.data() + bytes.size() - tail, tail);
            out.append(trailer, 4);
        }
    }
    if (out.size() != at) bad("internal: layout size");
    return out;
}

}  // namespace gseg::map::detail
