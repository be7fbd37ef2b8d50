// The rawlog layout of RawlogWriter (gzip members of whole entries with gseg's size field) and
// RawlogReader's decode threads: seeded synthetic observations written, read back object by object
// with 1, 2 and 4 threads and by MRPT's own reader; a wrong size field, a flipped byte and a cut
// file are errors naming the entry; rawlogs of one gzip stream and plain ones still read; an object
// bigger than a member (a scene, a simple map) read back through MRPT.
#include <gseg/io/atomic_file.hpp>
#include <gseg/mrpt/gzip_stream.hpp>
#include <gseg/mrpt/rawlog_io.hpp>
#include <support/child.hpp>
#include <support/output_files.hpp>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/serialization/CArchive.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>

namespace fs = std::filesystem;
using ObjectPtr = mrpt::serialization::CSerializable::Ptr;

namespace {

/// Alternating point clouds (random points, 20,000 each: about 240 KB serialised) and odometry.
std::vector<ObjectPtr> syntheticDrive(std::size_t count) {
    std::mt19937 rng(35);
    std::uniform_int_distribution<int> cm(-5000, 5000);
    std::vector<ObjectPtr> out;
    for (std::size_t i = 0; i < count; ++i) {
        if (i % 2 == 0) {
            auto pts = mrpt::maps::CSimplePointsMap::Create();
            for (int k = 0; k < 20000; ++k) pts->insertPoint(0.01f * float(cm(rng)), 0.01f * float(cm(rng)), 0.001f * float(cm(rng)));
            auto obs = mrpt::obs::CObservationPointCloud::Create();
            obs->pointcloud = pts;
            obs->sensorLabel = "LIDAR";
            obs->timestamp = mrpt::Clock::fromDouble(1000.0 + double(i));
            out.push_back(obs);
        } else {
            auto odo = mrpt::obs::CObservationOdometry::Create();
            odo->odometry = mrpt::poses::CPose2D(0.01 * cm(rng), 0.01 * cm(rng), 0.0001 * cm(rng));
            odo->sensorLabel = "ODOMETRY";
            odo->timestamp = mrpt::Clock::fromDouble(1000.5 + double(i));
            out.push_back(odo);
        }
    }
    return out;
}

std::string serialised(const mrpt::serialization::CSerializable& obj) {
    mrpt::io::CMemoryStream mem;
    mrpt::serialization::archiveFrom(mem) << obj;
    return std::string(static_cast<const char*>(mem.getRawBufferData()), std::size_t(mem.getTotalBytesCount()));
}

std::string readFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

std::uint32_t le32(const std::string& s, std::size_t at) {
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = v << 8 | static_cast<unsigned char>(s[at + std::size_t(i)]);
    return v;
}

void putLe32(std::string& s, std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) s[at + std::size_t(i)] = char(v >> (8 * i));
}

struct MemberInfo {
    std::size_t offset, size, first, entries;
};

/// The members of `bytes` by their size fields (asserting each is one of gseg's headers).
std::vector<MemberInfo> members(const std::string& bytes) {
    std::vector<MemberInfo> out;
    std::size_t first = 0;
    for (std::size_t at = 0; at < bytes.size();) {
        EXPECT_EQ(bytes.substr(at, 4), std::string("\x1f\x8b\x08\x04", 4)) << at;
        EXPECT_EQ(bytes.substr(at + 10, 6), std::string("\x0c\x00GS\x08\x00", 6)) << at;
        const MemberInfo m{at, le32(bytes, at + 16), first, le32(bytes, at + 20)};
        if (m.size < 24 || testing::Test::HasFailure()) break;
        out.push_back(m);
        at += m.size, first += m.entries;
    }
    return out;
}

/// Every object of the rawlog `path` (RawlogReader, `threads` decode threads), or the error.
std::vector<ObjectPtr> readAll(const std::string& path, unsigned threads, std::string* error = nullptr) {
    std::vector<ObjectPtr> out;
    try {
        gseg::mrpt::RawlogReader reader(path, threads);
        while (auto obj = reader.next()) out.push_back(obj);
        EXPECT_EQ(reader.fraction(), 1.0);
    } catch (const std::runtime_error& e) {
        if (!error) throw;
        *error = e.what();
    }
    return out;
}

void expectSameObjects(const std::vector<ObjectPtr>& got, const std::vector<ObjectPtr>& want, std::size_t count) {
    ASSERT_EQ(got.size(), count);
    for (std::size_t i = 0; i < count; ++i) ASSERT_EQ(serialised(*got[i]), serialised(*want[i])) << "entry " << i;
}

class RawlogMembers : public testing::Test {
protected:
    static void SetUpTestSuite() { objects_ = new std::vector<ObjectPtr>(syntheticDrive(40)); }
    static void TearDownTestSuite() {
        delete objects_;
        objects_ = nullptr;
    }
    /// The drive written by RawlogWriter, in a folder of this test's own (ctest runs the tests of
    /// this file in parallel processes).
    void SetUp() override {
        std::string test = testing::UnitTest::GetInstance()->current_test_info()->name();
        std::replace(test.begin(), test.end(), '/', '_');
        path_ = (gseg::test::freshDir("rawlog_members", "drive_" + test) / "drive.rawlog").string();
        gseg::mrpt::RawlogWriter w(path_);
        for (const auto& obj : *objects_) w.write(*obj);
        w.commit();
        bytes_ = readFile(path_);
    }
    /// A copy of the drive with `edit` applied, and the error reading it gave.
    std::string errorOfEdited(const std::string& name, const std::function<void(std::string&)>& edit, std::size_t& objectsBefore) {
        std::string bytes = bytes_;
        edit(bytes);
        const std::string path = (gseg::test::freshDir("rawlog_members", name) / "edited.rawlog").string();
        gseg::test::writeBytes(path, bytes);
        std::string error;
        objectsBefore = readAll(path, 2, &error).size();
        return error;
    }
    static std::vector<ObjectPtr>* objects_;
    std::string path_, bytes_;
};
std::vector<ObjectPtr>* RawlogMembers::objects_ = nullptr;

}  // namespace

TEST_F(RawlogMembers, SeveralMembersEachWithItsSizeAndAnEndMember) {
    const auto ms = members(bytes_);
    ASSERT_GE(ms.size(), 3u);  // about 5 MB serialised: members of 1 MB and more, and the end member
    std::size_t total = 0, entries = 0;
    for (const auto& m : ms) total += m.size, entries += m.entries;
    EXPECT_EQ(total, bytes_.size());
    EXPECT_EQ(entries, objects_->size());
    EXPECT_GT(ms[0].entries, 1u);
    EXPECT_EQ(ms.back().entries, 0u);
    for (std::size_t i = 0; i + 1 < ms.size(); ++i) EXPECT_GT(ms[i].entries, 0u) << "member " << i;
}

class RawlogMembersThreads : public RawlogMembers, public testing::WithParamInterface<unsigned> {};

TEST_P(RawlogMembersThreads, ReadBackObjectByObject) {
    gseg::mrpt::RawlogReader reader(path_, GetParam());
    EXPECT_EQ(reader.decodeThreads(), GetParam());
    std::vector<ObjectPtr> got;
    double fraction = 0;
    while (auto obj = reader.next()) {
        EXPECT_EQ(reader.index(), got.size());
        EXPECT_GT(reader.fraction(), fraction) << "entry " << got.size();  // grows object by object, not member by member
        fraction = reader.fraction();
        got.push_back(obj);
    }
    EXPECT_EQ(reader.next(), nullptr);  // stays at the end
    EXPECT_EQ(reader.fraction(), 1.0);
    expectSameObjects(got, *objects_, objects_->size());
}

INSTANTIATE_TEST_SUITE_P(DecodeThreads, RawlogMembersThreads, testing::Values(1u, 2u, 4u));

TEST_F(RawlogMembers, DefaultThreadCountIsAtLeastOne) { EXPECT_GE(gseg::mrpt::RawlogReader(path_).decodeThreads(), 1u); }

TEST_F(RawlogMembers, StoppingEarlyEndsTheDecodeThreads) {
    gseg::mrpt::RawlogReader reader(path_, 4);
    ASSERT_NE(reader.next(), nullptr);
    EXPECT_LT(reader.fraction(), 1.0);
}  // the destructor ends and joins them (a hang here fails by the test's timeout)

TEST_F(RawlogMembers, MrptsOwnGzipReaderReadsOneStream) {
    mrpt::io::CFileGZInputStream in;
    ASSERT_TRUE(in.open(path_));
    auto archive = mrpt::serialization::archiveFrom(in);
    std::vector<ObjectPtr> got;
    try {
        for (;;) {
            ObjectPtr obj;
            archive >> obj;
            got.push_back(obj);
        }
    } catch (const mrpt::serialization::CExceptionEOF&) {
    }
    expectSameObjects(got, *objects_, objects_->size());
}

TEST_F(RawlogMembers, WrongSizeFieldNamesTheEntry) {
    const auto ms = members(bytes_);
    ASSERT_GE(ms.size(), 3u);
    for (const MemberInfo& m : {ms[0], ms[1]})
        for (const std::int64_t change : {-1, 100}) {
            std::size_t before = 0;
            const std::string error =
                errorOfEdited("size", [&](std::string& b) { putLe32(b, m.offset + 16, std::uint32_t(std::int64_t(m.size) + change)); }, before);
            EXPECT_NE(error.find("edited.rawlog: entry " + std::to_string(m.first) + " is corrupt or truncated ("), std::string::npos) << error;
            EXPECT_EQ(before, m.first) << error;  // every entry before it was read
        }
    std::size_t before = 0;  // a size field past the end of the file, a huge entry count: errors, nothing allocated
    const std::string huge = errorOfEdited("size", [&](std::string& b) { putLe32(b, ms[1].offset + 16, 0xfffffff0u); }, before);
    EXPECT_NE(huge.find("entry " + std::to_string(ms[1].first) + " is corrupt or truncated (the gzip member at byte " + std::to_string(ms[1].offset) +
                        " has a size field of 4294967280 bytes"),
              std::string::npos)
        << huge;
    const std::string count = errorOfEdited("count", [&](std::string& b) { putLe32(b, ms[0].offset + 20, 0xfffffff0u); }, before);
    EXPECT_NE(count.find("entry " + std::to_string(ms[1].first) + " is corrupt or truncated (the gzip member at byte 0 ends after " +
                         std::to_string(ms[0].entries) + " of the 4294967280 entries its header counts)"),
              std::string::npos)
        << count;
    EXPECT_EQ(before, ms[0].entries);
    // one member too long: the next one's first bytes in it
    const std::string longer = errorOfEdited("size", [&](std::string& b) { putLe32(b, ms[0].offset + 16, std::uint32_t(ms[0].size + 100)); }, before);
    EXPECT_NE(longer.find("entry 0 is corrupt or truncated (the gzip member at byte 0: it does not inflate to the"), std::string::npos) << longer;
    EXPECT_NE(longer.find("or a wrong size field)"), std::string::npos) << longer;
}

TEST_F(RawlogMembers, FlippedByteNamesTheEntry) {
    const auto ms = members(bytes_);
    ASSERT_GE(ms.size(), 3u);
    for (std::size_t at : {ms[1].offset + ms[1].size / 2, ms[1].offset + ms[1].size - 6}) {  // deflate data; the CRC-32
        std::size_t before = 0;
        const std::string error = errorOfEdited("flip", [&](std::string& b) { b[at] = char(b[at] ^ 0x10); }, before);
        EXPECT_NE(error.find("edited.rawlog: entry " + std::to_string(ms[1].first) + " is corrupt or truncated (the gzip member at byte " +
                             std::to_string(ms[1].offset)),
                  std::string::npos)
            << error;
        EXPECT_NE(error.find("damaged"), std::string::npos) << error;
        EXPECT_EQ(before, ms[1].first);
    }
}

TEST_F(RawlogMembers, CutFileNamesTheEntry) {
    const auto ms = members(bytes_);
    ASSERT_GE(ms.size(), 3u);
    const MemberInfo& last = ms[ms.size() - 2];  // the last member holding entries
    std::size_t before = 0;
    const std::string inside = errorOfEdited("cut", [&](std::string& b) { b.resize(last.offset + last.size / 2); }, before);
    EXPECT_NE(inside.find("edited.rawlog: entry " + std::to_string(last.first) + " is corrupt or truncated"), std::string::npos) << inside;
    EXPECT_NE(inside.find(": truncated"), std::string::npos) << inside;
    EXPECT_EQ(before, last.first);
    // Cut where a member ends: the end member is missing.
    const std::string atEnd = errorOfEdited("cutend", [&](std::string& b) { b.resize(ms.back().offset); }, before);
    EXPECT_NE(atEnd.find("entry " + std::to_string(objects_->size()) + " is corrupt or truncated (the file ends at byte " +
                         std::to_string(ms.back().offset) + " without its end member"),
              std::string::npos)
        << atEnd;
    EXPECT_EQ(before, objects_->size());
}

TEST_F(RawlogMembers, OneGzipStreamAndPlainRawlogsReadSerially) {
    std::string plain;
    for (std::size_t i = 0; i < 6; ++i) plain += serialised(*(*objects_)[i]);
    const fs::path dir = gseg::test::freshDir("rawlog_members", "old");
    const std::string plainPath = (dir / "plain.rawlog").string(), gzPath = (dir / "old.rawlog").string();
    gseg::test::writeBytes(plainPath, plain);
    {
        mrpt::io::CFileGZOutputStream gz;  // one gzip stream, as MRPT and gseg before its members write
        ASSERT_TRUE(gz.open(gzPath, 1));
        ASSERT_EQ(gz.Write(plain.data(), plain.size()), plain.size());
    }
    for (const std::string& path : {plainPath, gzPath}) {
        gseg::mrpt::RawlogReader reader(path, 4);
        EXPECT_EQ(reader.decodeThreads(), 0u) << path;
        std::vector<ObjectPtr> got;
        while (auto obj = reader.next()) got.push_back(obj);
        expectSameObjects(got, *objects_, 6);
    }
}

TEST(RawlogMembersEmpty, EmptyRawlogIsOneEndMember) {
    const std::string path = (gseg::test::freshDir("rawlog_members", "empty") / "empty.rawlog").string();
    gseg::mrpt::RawlogWriter w(path);
    w.commit();
    const auto ms = members(readFile(path));
    ASSERT_EQ(ms.size(), 1u);
    EXPECT_EQ(ms[0].entries, 0u);
    EXPECT_TRUE(readAll(path, 2).empty());
}

namespace {

TEST(GzipMembers, AnObjectOfSeveralMembersReadsBackThroughMrptsReader) {
    // A scene or simple map is written as plain gzip members of kMemberBytes (libdeflate, one call
    // each): one of 3 million points (36 MB serialised) makes several, and MRPT's own reader (what
    // SceneViewer3D and observations2map use) reads them as one stream.
    auto pts = mrpt::maps::CSimplePointsMap::Create();
    std::mt19937 rng(43);
    std::uniform_int_distribution<int> cm(-5000, 5000);
    for (int k = 0; k < 3000000; ++k) pts->insertPoint(0.01f * float(cm(rng)), 0.01f * float(cm(rng)), 0.001f * float(cm(rng)));
    const std::string path = (gseg::test::freshDir("rawlog_members", "object") / "points.gz").string();
    {
        gseg::io::AtomicFile file(path);
        gseg::mrpt::writeGzipObject(file, *pts);
        file.commit();
    }
    const std::string bytes = readFile(path);
    std::size_t headers = 0;  // plain gzip headers: deflate, no flags, no time stamp, XFL 4, OS 3
    for (std::size_t at = bytes.find(std::string("\x1f\x8b\x08\x00\x00\x00\x00\x00\x04\x03", 10)); at != std::string::npos;
         at = bytes.find(std::string("\x1f\x8b\x08\x00\x00\x00\x00\x00\x04\x03", 10), at + 1))
        ++headers;
    const std::string want = serialised(*pts);
    EXPECT_GE(headers, want.size() / gseg::mrpt::GzipOutputStream::kMemberBytes) << "several members";
    mrpt::io::CFileGZInputStream in;
    ASSERT_TRUE(in.open(path));
    ObjectPtr got;
    mrpt::serialization::archiveFrom(in) >> got;
    ASSERT_NE(got, nullptr);
    EXPECT_TRUE(serialised(*got) == want);
}

}  // namespace
