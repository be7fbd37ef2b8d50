#include "remote_workers.hpp"

#include "common/bytes.hpp"

#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/errors.hpp>

#include <mrpt/io/CStream.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <new>
#include <stdexcept>
#include <thread>

using gseg::tools::ByteReader;
using gseg::tools::ByteWriter;

namespace rawlog_octomap {
namespace {

constexpr int kHelloTag = gseg::tools::Ranks::kFirstToolTag;  // rank r -> 0: its worker threads
constexpr int kJobTag = kHelloTag + 1000;                      // + thread: 0 -> r, a scan ("" = stop)
constexpr int kResultTag = kJobTag + 1000;                     // + thread: r -> 0, its result
constexpr std::uint64_t kResult = 1, kError = 2;

/// An MRPT stream over a string: appends when written (MRPT's CMemoryStream grows 4 KB at a time,
/// copying itself each time: 0.1 s for a 2 MB scan), reads from the start.
class StringStream : public mrpt::io::CStream {
public:
    explicit StringStream(std::string& bytes) : bytes_(bytes) {}
    std::size_t Read(void* out, std::size_t n) override {
        n = std::min(n, bytes_.size() - pos_);
        std::memcpy(out, bytes_.data() + pos_, n);
        pos_ += n;
        return n;
    }
    std::size_t Write(const void* in, std::size_t n) override {
        bytes_.append(static_cast<const char*>(in), n);
        return n;
    }
    std::uint64_t Seek(std::int64_t offset, TSeekOrigin origin) override {
        const std::int64_t base = origin == sFromBeginning ? 0 : origin == sFromCurrent ? std::int64_t(pos_) : std::int64_t(bytes_.size());
        pos_ = std::size_t(std::clamp<std::int64_t>(base + offset, 0, std::int64_t(bytes_.size())));
        return pos_;
    }
    std::uint64_t getTotalBytesCount() const override { return bytes_.size(); }
    std::uint64_t getPosition() const override { return pos_; }

private:
    std::string& bytes_;
    std::size_t pos_ = 0;
};

void writePose(ByteWriter& out, const mrpt::poses::CPose3D& pose) {
    const mrpt::math::CMatrixDouble44 m = pose.getHomogeneousMatrixVal<mrpt::math::CMatrixDouble44>();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) out.f64(m(r, c));
}

mrpt::poses::CPose3D readPose(ByteReader& in) {
    mrpt::math::CMatrixDouble44 m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = in.f64();
    return mrpt::poses::CPose3D(m);  // the same rotation matrix and translation, bit for bit
}

/// MRPT's serialisation of the observation, and its sensor pose exactly (MRPT stores a pose's
/// rotation as a quaternion, which need not give back the same matrix).
void writeObservation(ByteWriter& out, const mrpt::obs::CObservation::Ptr& obs) {
    out.u64(obs ? 1 : 0);
    if (!obs) return;
    std::string bytes;
    StringStream stream(bytes);
    auto archive = mrpt::serialization::archiveFrom(stream);
    archive << *obs;
    out.str(bytes);
    mrpt::poses::CPose3D sensorPose;
    obs->getSensorPose(sensorPose);
    writePose(out, sensorPose);
}

mrpt::obs::CObservation::Ptr readObservation(ByteReader& in) {
    if (in.u64() == 0) return nullptr;
    std::string bytes = in.str();
    StringStream stream(bytes);
    auto archive = mrpt::serialization::archiveFrom(stream);
    auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(archive.ReadObject());
    if (!obs) throw std::runtime_error("a scan sent between processes holds no observation");
    obs->setSensorPose(readPose(in));
    return obs;
}

std::string number(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", v);
    return text;
}

}  // namespace

std::string encodeJob(const ScanJob& job) {
    ByteWriter out;
    out.u64(job.index).u64(job.entry).str(job.label).f64(job.t).f64(job.fraction);
    writePose(out, job.robotPose);
    for (const auto* part : {&job.raw, &job.ground, &job.obstacles}) writeObservation(out, *part);
    return out.bytes();
}

ScanJob decodeJob(const std::string& bytes) {
    ByteReader in(bytes);
    ScanJob job;
    job.index = std::size_t(in.u64()), job.entry = std::size_t(in.u64());
    job.label = in.str();
    job.t = in.f64(), job.fraction = in.f64();
    job.robotPose = readPose(in);
    for (auto* part : {&job.raw, &job.ground, &job.obstacles}) *part = readObservation(in);
    return job;
}

std::string encodeResult(const ScanResult& r) {
    ByteWriter out;
    out.u64(kResult).str(gseg::map::serializeScanUpdate(r.update));
    const PhaseTimes& t = r.times;
    out.f64(t.read).f64(t.segmentation).f64(t.transform).f64(t.rayCasting).f64(t.mapUpdate).f64(t.writing);
    out.str(r.skipped).str(r.describe).u64(r.presegmented).f64(r.fraction).u64(r.reflections).str(r.heightNote);
    out.str(r.heightWarning);
    out.u64(std::uint64_t(r.rank));
    return out.bytes();
}

std::string encodeError(const std::string& message) { return ByteWriter().u64(kError).str(message).bytes(); }

ScanResult decodeResult(const std::string& bytes) {
    ByteReader in(bytes);
    const std::uint64_t kind = in.u64();
    if (kind == kError) throw std::runtime_error(in.str());
    if (kind != kResult) throw std::runtime_error("a scan result sent between processes is garbled");
    ScanResult r;
    r.update = gseg::map::deserializeScanUpdate(in.str());
    PhaseTimes& t = r.times;
    t.read = in.f64(), t.segmentation = in.f64(), t.transform = in.f64(), t.rayCasting = in.f64();
    t.mapUpdate = in.f64(), t.writing = in.f64();
    r.skipped = in.str(), r.describe = in.str();
    r.presegmented = in.u64() != 0;
    r.fraction = in.f64();
    r.reflections = std::size_t(in.u64());
    r.heightNote = in.str();
    r.heightWarning = in.str();
    r.rank = int(in.u64());
    return r;
}

RemoteWorkers::RemoteWorkers(gseg::tools::Ranks& ranks) : ranks_(ranks) {
    for (int r = 1; r < ranks.size(); ++r) {
        const std::string hello = ranks.receive(r, kHelloTag);
        ByteReader in(hello);
        for (std::uint64_t j = 0, n = in.u64(); j < n; ++j) slots_.emplace_back(r, int(j));
    }
}

RemoteWorkers::~RemoteWorkers() {
    for (const auto& [rank, thread] : slots_) ranks_.send(rank, kJobTag + thread, "");
}

ScanResult RemoteWorkers::operator()(unsigned slot, const ScanJob& job) {
    const auto [rank, thread] = slots_.at(slot);
    ranks_.send(rank, kJobTag + thread, encodeJob(job));
    return decodeResult(ranks_.receive(rank, kResultTag + thread));
}

void serveScans(gseg::tools::Ranks& ranks, const Cli& cli) {
    const unsigned threads = std::max(1u, cli.threads);
    std::vector<ScanWorker> workers;
    std::string setupError;
    try {
        for (unsigned i = 0; i < threads; ++i) workers.emplace_back(cli.loaded, cli.options);
    } catch (const std::exception& e) {
        setupError = gseg::mrpt::errorReason(e);
    }
    ranks.send(0, kHelloTag, ByteWriter().u64(threads).bytes());
    auto serve = [&](unsigned thread) {
        for (std::string bytes; !(bytes = ranks.receive(0, kJobTag + int(thread))).empty();) {
            std::string reply;
            std::string scan = "a scan";
            try {
                const ScanJob job = decodeJob(bytes);
                scan = job.describe();
                if (!setupError.empty()) throw std::runtime_error(scan + ": rank " + std::to_string(ranks.rank()) + ": " + setupError);
                ScanResult r = workers[thread](job);
                r.rank = ranks.rank();
                reply = encodeResult(r);
            } catch (const std::bad_alloc&) {
                reply = encodeError("out of memory while segmenting and ray casting " + scan + " on rank " +
                                    std::to_string(ranks.rank()) + " (at --resolution " + number(cli.options.resolution) +
                                    " m, --max-range " + number(cli.options.maxRange) + " m); nothing written");
            } catch (const std::exception& e) {  // the worker's errors name the scan
                const std::string reason = gseg::mrpt::errorReason(e);
                reply = encodeError(reason.rfind(scan, 0) == 0 ? reason : scan + " on rank " + std::to_string(ranks.rank()) + ": " + reason);
            }
            ranks.send(0, kResultTag + int(thread), reply);
        }
    };
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < threads; ++t) pool.emplace_back(serve, t);
    serve(0);
    for (auto& t : pool) t.join();
}

}  // namespace rawlog_octomap
