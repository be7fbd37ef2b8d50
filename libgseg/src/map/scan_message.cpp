#include <gseg/map/scan_message.hpp>

#include <gseg/io/bytes.hpp>
#include <gseg/map/scan_update.hpp>

#include <mrpt/io/CStream.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace gseg::map {
namespace {

using io::ByteReader;
using io::ByteWriter;

constexpr std::uint64_t kResult = 1, kError = 2;

/// An MRPT stream over a string: appends when written (MRPT's CMemoryStream grows 4 KB at a time,
/// copying itself each time: 0.1 s for a 2 MB scan), reads from the start.
class StringStream : public ::mrpt::io::CStream {
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

void writePose(ByteWriter& out, const ::mrpt::poses::CPose3D& pose) {
    const ::mrpt::math::CMatrixDouble44 m = pose.getHomogeneousMatrixVal<::mrpt::math::CMatrixDouble44>();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) out.f64(m(r, c));
}

::mrpt::poses::CPose3D readPose(ByteReader& in) {
    ::mrpt::math::CMatrixDouble44 m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = in.f64();
    return ::mrpt::poses::CPose3D(m);  // the same rotation matrix and translation, bit for bit
}

/// MRPT's serialisation of the observation, and its sensor pose exactly (MRPT stores a pose's
/// rotation as a quaternion, which need not give back the same matrix).
void writeObservation(ByteWriter& out, const ::mrpt::obs::CObservation::Ptr& obs) {
    out.u64(obs ? 1 : 0);
    if (!obs) return;
    std::string bytes;
    StringStream stream(bytes);
    auto archive = ::mrpt::serialization::archiveFrom(stream);
    archive << *obs;
    out.str(bytes);
    ::mrpt::poses::CPose3D sensorPose;
    obs->getSensorPose(sensorPose);
    writePose(out, sensorPose);
}

::mrpt::obs::CObservation::Ptr readObservation(ByteReader& in) {
    if (in.u64() == 0) return nullptr;
    std::string bytes = in.str();
    StringStream stream(bytes);
    auto archive = ::mrpt::serialization::archiveFrom(stream);
    auto obs = std::dynamic_pointer_cast<::mrpt::obs::CObservation>(archive.ReadObject());
    if (!obs) throw std::runtime_error("a scan sent between processes holds no observation");
    obs->setSensorPose(readPose(in));
    return obs;
}

}  // namespace

std::string encodeScanJob(const ScanJob& job) {
    ByteWriter out;
    out.u64(job.index).u64(job.entry).str(job.label).f64(job.t).f64(job.fraction);
    writePose(out, job.robotPose);
    for (const auto* part : {&job.raw, &job.ground, &job.obstacles}) writeObservation(out, *part);
    return out.bytes();
}

ScanJob decodeScanJob(const std::string& bytes) {
    ByteReader in(bytes);
    ScanJob job;
    job.index = std::size_t(in.u64()), job.entry = std::size_t(in.u64());
    job.label = in.str();
    job.t = in.f64(), job.fraction = in.f64();
    job.robotPose = readPose(in);
    for (auto* part : {&job.raw, &job.ground, &job.obstacles}) *part = readObservation(in);
    return job;
}

std::string encodeScanResult(const ScanResult& r) {
    ByteWriter out;
    out.u64(kResult).str(serializeScanUpdate(r.update));
    out.f64(r.times.segmentation).f64(r.times.transform).f64(r.times.rayCasting);
    out.str(r.skipped).str(r.describe).u64(r.presegmented).f64(r.fraction).u64(r.notes.reflections);
    out.str(r.notes.heightNote).str(r.notes.heightWarning);
    out.u64(std::uint64_t(r.rank));
    return out.bytes();
}

std::string encodeScanError(const std::string& message) { return ByteWriter().u64(kError).str(message).bytes(); }

ScanResult decodeScanResult(const std::string& bytes) {
    ByteReader in(bytes);
    const std::uint64_t kind = in.u64();
    if (kind == kError) throw std::runtime_error(in.str());
    if (kind != kResult) throw std::runtime_error("a scan result sent between processes is garbled");
    ScanResult r;
    r.update = deserializeScanUpdate(in.str());
    r.times.segmentation = in.f64(), r.times.transform = in.f64(), r.times.rayCasting = in.f64();
    r.skipped = in.str(), r.describe = in.str();
    r.presegmented = in.u64() != 0;
    r.fraction = in.f64();
    r.notes.reflections = std::size_t(in.u64());
    r.notes.heightNote = in.str();
    r.notes.heightWarning = in.str();
    r.rank = int(in.u64());
    return r;
}

}  // namespace gseg::map
