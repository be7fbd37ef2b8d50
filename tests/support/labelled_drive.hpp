#pragma once
/// \file labelled_drive.hpp
/// Synthetic labelled drives for tests: a SemanticKITTI-style sequence folder (velodyne/NNNNNN.bin,
/// labels/NNNNNN.label, poses.txt, calib.txt) written from points with their labels. Header-only.

#include <support/child.hpp>
#include <support/output_files.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace gseg::test {

/// One labelled point of a synthetic frame.
struct Pt {
    float x, y, z;
    std::uint32_t label;
};

/// A KITTI pose or Tr line for the identity (3 x 4, row-major).
inline const char* const kIdentity12 = "1 0 0 0 0 1 0 0 0 0 1 0";
/// A calib.txt with an identity Tr (the velodyne frame is the camera frame).
inline const std::string kIdentityCalib = std::string("P0: ") + kIdentity12 + "\nTr: " + kIdentity12 + "\n";

/// Writes `n` bytes at `data` to `path` as they are.
inline void writeBytes(const std::filesystem::path& path, const void* data, std::size_t n) {
    std::ofstream(path, std::ios::binary).write(static_cast<const char*>(data), std::streamsize(n));
}
inline void writeText(const std::filesystem::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

/// A drive folder freshDir(group, name): one scan per entry of `frames` (frame k named k), identity
/// poses unless `poses` is given.
inline std::filesystem::path writeLabelledDrive(const std::string& group, const std::string& name, const std::vector<std::vector<Pt>>& frames,
                                                std::string poses = "", const std::string& calib = kIdentityCalib) {
    const std::filesystem::path dir = freshDir(group, name);
    std::filesystem::create_directories(dir / "velodyne"), std::filesystem::create_directories(dir / "labels");
    for (std::size_t k = 0; k < frames.size(); ++k) {
        char stem[32];
        std::snprintf(stem, sizeof stem, "%06zu", k);
        std::vector<float> xyzi;
        std::vector<std::uint32_t> labels;
        for (const Pt& p : frames[k]) xyzi.insert(xyzi.end(), {p.x, p.y, p.z, 0.f}), labels.push_back(p.label);
        writeBytes(dir / "velodyne" / (std::string(stem) + ".bin"), xyzi.data(), xyzi.size() * 4);
        writeBytes(dir / "labels" / (std::string(stem) + ".label"), labels.data(), labels.size() * 4);
    }
    if (poses.empty())
        for (std::size_t k = 0; k < frames.size(); ++k) poses += std::string(kIdentity12) + "\n";
    writeText(dir / "poses.txt", poses);
    writeText(dir / "calib.txt", calib);
    return dir;
}

/// n points of `label` at the centre of cell (cx, cy) of a 0.2 m grid at the origin, at heights z0, z0 + dz, ...
inline void addCell(std::vector<Pt>& pts, int cx, int cy, std::uint32_t label, int n, float z0, float dz = 0.01f) {
    for (int i = 0; i < n; ++i) pts.push_back({0.2f * float(cx) + 0.1f, 0.2f * float(cy) + 0.1f, z0 + dz * float(i), label});
}

/// A labelled drive with a map to score: `drive` holds one scan of 10 cells of road at y = 0 and,
/// at y = 3 (0.2 m cells), road under a building (label 50, 0.7 m up); `map` (in `dir`) is a
/// map_server map calling cells 0-4 of the road row free and the building row occupied.
struct RowsDriveCase {
    std::filesystem::path dir, drive, map;
};
inline RowsDriveCase rowsDriveCase(const std::string& group, const std::string& name) {
    RowsDriveCase c;
    std::vector<Pt> pts;
    for (int cx = 0; cx < 10; ++cx) {
        addCell(pts, cx, 0, 40, 3, -1.7f);
        addCell(pts, cx, 3, 40, 3, -1.7f);
        addCell(pts, cx, 3, 50, 2, -1.0f);
    }
    c.drive = writeLabelledDrive(group, name + "_drive", {pts});
    c.dir = freshDir(group, name);
    gseg::io::RosMap m = gseg::io::RosMap::unknown(10, 6, 0.2, 0.0, 0.0);
    for (int cx = 0; cx < 5; ++cx) m.value(cx, 0) = gseg::io::RosMap::kFree;
    for (int cx = 0; cx < 10; ++cx) m.value(cx, 3) = gseg::io::RosMap::kOccupied;
    writeRosMap((c.dir / "map").string(), m);
    c.map = c.dir / "map.yaml";
    return c;
}

/// Where drive 09's poses are, relative to the shared data (sharedData()).
inline const char* const kDrive09Poses = "semantickitti-drives/sequences/09/poses.txt";

/// Drive 09 (rural) of the shared labelled drives as the rawlog dir/<name>.rawlog (kitti2rawlog,
/// with its poses or without): "" where the shared data is absent or kitti2rawlog failed (reported).
inline std::string drive09Rawlog(const std::filesystem::path& dir, const std::string& name, bool poses = true) {
    const std::string p = sharedData(kDrive09Poses);
    if (p.empty()) return "";
    std::filesystem::create_directories(dir);
    const std::string out = (dir / (name + ".rawlog")).string();
    const auto k = runCommand("'" + tool("kitti2rawlog") + "' -q -w -i '" + std::filesystem::path(p).parent_path().string() + "' -o '" + out +
                              "'" + (poses ? "" : " --no-poses"));
    EXPECT_EQ(k.status, 0) << k.output;
    return k.status == 0 ? out : "";
}

}  // namespace gseg::test
