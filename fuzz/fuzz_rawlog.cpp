// libFuzzer target: rawlog streaming with the observation filter (what rawlog-gseg runs). The
// fuzzer's bytes describe a rawlog: LiDAR observations of every kind gseg reads, with point
// vectors of independent lengths, any float values, range images whose size disagrees with their
// header, Velodyne packets of random bytes, 2D scans, actions, and sensory frames holding them. It
// is serialized by MRPT, optionally cut short, and streamed through forEachRawlogEntry() and
// RawlogSegmenter into an output rawlog that must read back.
//
// Why not raw bytes: MRPT 2.5.8's deserializer trusts the size fields of its input (a few bytes
// make it allocate gigabytes; README, "Limits"), so raw mutations only ever find that. Cutting a
// valid stream short is the corruption MRPT does handle, and it is exercised here.
#include "fuzz_input.hpp"

#include <gseg/mrpt/rawlog_io.hpp>
#include <gseg/mrpt/rawlog_segmenter.hpp>

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CPointsMapXYZI.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <stdexcept>

namespace {

using gseg::fuzz::FuzzInput;

const char* const kLabels[] = {"LIDAR", "LIDAR_ground", "LIDAR_obstacles", "VLP", "X"};

float coordinate(FuzzInput& in, int mode) {
    if (mode == 0) return in.anyFloat();
    const std::int16_t v = in.take<std::int16_t>();
    return mode == 1 ? 0.01f * v : (v % 7 == 0 ? -1.7f : 0.002f * v);
}

void common(FuzzInput& in, mrpt::obs::CObservation& obs) {
    obs.sensorLabel = kLabels[in.count(4)];
    obs.timestamp = mrpt::Clock::fromDouble(double(in.count(3)));
}

mrpt::poses::CPose3D pose(FuzzInput& in) {
    if (!in.flag()) return mrpt::poses::CPose3D();
    return mrpt::poses::CPose3D(in.uniform(-5, 5), in.uniform(-5, 5), in.uniform(-3, 3), in.uniform(-3.2, 3.2),
                                in.uniform(-1.6, 1.6), in.uniform(-3.2, 3.2));
}

mrpt::obs::CObservation::Ptr pointCloud(FuzzInput& in) {
    auto obs = mrpt::obs::CObservationPointCloud::Create();
    common(in, *obs);
    obs->sensorPose = pose(in);
    const int mode = in.take<std::uint8_t>() % 3;
    const std::size_t n = in.count(3000);
    mrpt::maps::CPointsMap::Ptr map;
    if (in.flag()) map = mrpt::maps::CPointsMapXYZI::Create();
    else map = mrpt::maps::CSimplePointsMap::Create();
    for (std::size_t i = 0; i < n && in.remaining(); ++i)
        map->insertPointFast(coordinate(in, mode), coordinate(in, mode), coordinate(in, mode));
    if (in.flag()) obs->pointcloud = map;  // or none at all
    return obs;
}

mrpt::obs::CObservation::Ptr velodyne(FuzzInput& in) {
    auto obs = mrpt::obs::CObservationVelodyneScan::Create();
    common(in, *obs);
    obs->sensorPose = pose(in);
    const int mode = in.take<std::uint8_t>() % 3;
    auto& pc = obs->point_cloud;
    for (auto* v : {&pc.x, &pc.y, &pc.z}) {
        const std::size_t n = in.count(2000);
        for (std::size_t i = 0; i < n && in.remaining(); ++i) v->push_back(coordinate(in, mode));
    }
    pc.intensity.resize(in.count(2000), 7);
    if (in.flag()) {  // packets of random bytes, with or without a calibration
        const std::size_t packets = in.count(4);
        for (std::size_t p = 0; p < packets; ++p) {
            mrpt::obs::CObservationVelodyneScan::TVelodyneRawPacket pkt{};
            for (std::size_t b = 0; b < sizeof pkt && in.remaining(); ++b) reinterpret_cast<std::uint8_t*>(&pkt)[b] = in.take<std::uint8_t>();
            obs->scan_packets.push_back(pkt);
        }
        const std::size_t calib = in.count(3);
        if (calib == 1) obs->calibration = mrpt::obs::VelodyneCalibration::LoadDefaultCalibration("VLP16");
        if (calib == 2) obs->calibration = mrpt::obs::VelodyneCalibration::LoadDefaultCalibration("HDL32");
    }
    return obs;
}

mrpt::obs::CObservation::Ptr rangeScan3D(FuzzInput& in) {
    auto obs = mrpt::obs::CObservation3DRangeScan::Create();
    common(in, *obs);
    obs->sensorPose = pose(in);
    if (in.flag()) {
        obs->hasPoints3D = true;
        const int mode = in.take<std::uint8_t>() % 3;
        for (auto* v : {&obs->points3D_x, &obs->points3D_y, &obs->points3D_z}) {
            const std::size_t n = in.count(1000);
            for (std::size_t i = 0; i < n && in.remaining(); ++i) v->push_back(coordinate(in, mode));
        }
    } else if (in.flag()) {
        obs->hasRangeImage = true;
        const std::size_t rows = in.count(24), cols = in.count(32);
        obs->rangeImage.setZero(int(rows), int(cols));
        for (std::size_t r = 0; r < rows; ++r)
            for (std::size_t c = 0; c < cols; ++c) obs->rangeImage(int(r), int(c)) = in.take<std::uint16_t>();
        obs->rangeUnits = float(in.logUniform(1e-4, 1));
        obs->cameraParams.ncols = std::uint32_t(in.count(40));
        obs->cameraParams.nrows = std::uint32_t(in.count(40));
        obs->cameraParams.setIntrinsicParamsFromValues(in.uniform(-100, 500), in.uniform(-100, 500), in.uniform(-50, 50),
                                                       in.uniform(-50, 50));
    }
    return obs;
}

mrpt::obs::CObservation::Ptr rotating(FuzzInput& in) {
    auto obs = mrpt::obs::CObservationRotatingScan::Create();
    common(in, *obs);
    obs->sensorPose = pose(in);
    const char* const models[] = {"VLP-16", "HDL-32E", "HDL64", "Unknown", ""};
    obs->lidarModel = models[in.count(4)];
    const std::size_t rows = in.count(70), cols = in.count(400);
    obs->rowCount = std::uint16_t(in.flag() ? rows : in.count(70));
    obs->columnCount = std::uint16_t(in.flag() ? cols : in.count(400));
    obs->rangeImage.setZero(int(rows), int(cols));
    const std::size_t returns = in.count(2000);
    for (std::size_t k = 0; k < returns && rows && cols && in.remaining(); ++k)
        obs->rangeImage(int(in.count(rows - 1)), int(in.count(cols - 1))) = in.take<std::uint16_t>();
    if (in.flag()) obs->intensityImage.setZero(int(in.flag() ? rows : in.count(70)), int(cols));
    obs->rangeResolution = in.flag() ? 0.002 : double(in.anyFloat());
    obs->startAzimuth = in.flag() ? in.uniform(-4, 4) : double(in.anyFloat());
    obs->azimuthSpan = in.flag() ? in.uniform(-7, 7) : double(in.anyFloat());
    return obs;
}

mrpt::obs::CObservation::Ptr observation(FuzzInput& in) {
    switch (in.count(5)) {
        case 0: return pointCloud(in);
        case 1: return velodyne(in);
        case 2: return rangeScan3D(in);
        case 3: return rotating(in);
        default: {
            auto laser = mrpt::obs::CObservation2DRangeScan::Create();
            common(in, *laser);
            laser->resizeScanAndAssign(in.count(50), 1.f, true);
            return laser;
        }
    }
}

/// What was written to `mem` (its buffer is larger: reading it back directly reads garbage).
std::vector<std::uint8_t> written(const mrpt::io::CMemoryStream& mem) {
    const auto* p = static_cast<const std::uint8_t*>(mem.getRawBufferData());
    return std::vector<std::uint8_t>(p, p + mem.getTotalBytesCount());
}

/// The rawlog the bytes describe, serialized; empty if MRPT refused to serialize it.
std::vector<std::uint8_t> describedRawlog(FuzzInput& in) {
    mrpt::io::CMemoryStream mem;
    auto out = mrpt::serialization::archiveFrom(mem);
    try {
        const std::size_t entries = 1 + in.count(5);
        for (std::size_t e = 0; e < entries && in.remaining(); ++e) {
            const std::size_t kind = in.count(7);
            if (kind == 6) {
                mrpt::obs::CSensoryFrame sf;
                const std::size_t n = in.count(3);
                for (std::size_t k = 0; k < n; ++k) sf.insert(observation(in));
                out << sf;
            } else if (kind == 7) {
                out << mrpt::obs::CActionCollection();
            } else {
                out << *observation(in);
            }
        }
    } catch (const std::exception&) {
        return {};  // an object MRPT cannot write: not a rawlog a user can have
    }
    std::vector<std::uint8_t> bytes = written(mem);
    if (in.flag()) bytes.resize(in.count(bytes.size()));  // cut short: a truncated file
    return bytes;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    FuzzInput in(data, size);
    gseg::mrpt::LoadedConfig cfg;
    cfg.distToGroundAuto = in.flag();
    cfg.params.distToGround = in.uniform(0.2, 3);
    cfg.params.centroidSearchRadius = in.uniform(1, 10);
    gseg::mrpt::RawlogSegmenterOptions options;
    options.replace = in.flag();
    if (in.flag()) options.sensors = {kLabels[in.count(4)]};
    options.frame = in.flag() ? gseg::GroundFilter::OutputFrame::Vehicle : gseg::GroundFilter::OutputFrame::Sensor;
    std::vector<std::uint8_t> rawlog = describedRawlog(in);
    if (rawlog.empty()) return 0;

    mrpt::io::CMemoryStream output;
    auto outArchive = mrpt::serialization::archiveFrom(output);
    std::size_t emitted = 0;
    gseg::mrpt::RawlogSegmenter segmenter(
        cfg, options,
        [&](const mrpt::serialization::CSerializable& o) {
            outArchive << o;
            ++emitted;
        },
        [&](const gseg::mrpt::ScanReport& r) {
            GSEG_FUZZ_CHECK(r.skipped.empty() ? r.ground + r.nonFinite <= r.points : r.points == 0);
        });
    mrpt::io::CMemoryStream input;
    input.assignMemoryNotOwn(rawlog.data(), rawlog.size());
    bool complete = true;
    try {
        gseg::mrpt::forEachRawlogEntry(input, "fuzz.rawlog", [&](std::size_t entry, const auto& obj) {
            segmenter.push(entry, obj);  // nothing a scan holds may make this throw
            return true;
        });
    } catch (const std::runtime_error& e) {
        complete = false;  // a cut-short stream: named entry, then stop; garbage at entry 0: "not a rawlog"
        const std::string what = e.what();
        GSEG_FUZZ_CHECK(what.find("fuzz.rawlog: entry ") == 0 || what.find("fuzz.rawlog: not an MRPT rawlog (") == 0);
    }
    segmenter.finish();
    const auto& t = segmenter.totals();
    GSEG_FUZZ_CHECK(emitted >= t.entries);  // every entry passes through or is replaced by its halves
    (void)complete;

    // The output is a rawlog MRPT reads back, entry for entry.
    const std::vector<std::uint8_t> out = written(output);
    mrpt::io::CMemoryStream again;
    again.assignMemoryNotOwn(out.data(), out.size());
    std::size_t readBack = 0;
    gseg::mrpt::forEachRawlogEntry(again, "output", [&](std::size_t, const auto&) {
        ++readBack;
        return true;
    });
    GSEG_FUZZ_CHECK(readBack == emitted);
    return 0;
}
