// Readers and writers of the core io/ layer on hostile input: PLY and KITTI from memory, atomic
// outputs on a full disk, interrupted runs, and outputs that are inputs.
#include <gseg/io/atomic_file.hpp>
#include <gseg/io/bytes.hpp>
#include <gseg/io/kitti.hpp>
#include <gseg/io/ply.hpp>
#include <support/child.hpp>
#include <support/paths.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {


std::vector<float> ply(const std::string& text) {
    return gseg::io::parsePly(reinterpret_cast<const std::uint8_t*>(text.data()), text.size(), "t.ply");
}

std::string plyError(const std::string& text) {
    try {
        ply(text);
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    return "(no error)";
}

const std::string kXyz = "property float x\nproperty float y\nproperty float z\n";

fs::path freshDir(const std::string& name) { return gseg::test::freshDir("io", name); }

}  // namespace

// --- bytes (gseg/io/bytes.hpp): the one byte coding of the wire formats ----------------------

using gseg::io::ByteReader;
using gseg::io::ByteWriter;

TEST(Bytes, ValuesRoundTripBitForBit) {
    ByteWriter out;
    const double values[] = {0.1 + 0.2, -0.0, std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::infinity()};
    out.u64(0).u64(std::numeric_limits<std::uint64_t>::max()).str(std::string("a\0b", 3)).str("");
    for (double v : values) out.f64(v);
    out.f64(std::nan(""));
    EXPECT_EQ(out.bytes().size(), 8u * 2 + (8 + 3) + 8 + 8 * 5);
    EXPECT_EQ(out.bytes()[8], '\xff') << "little-endian";
    ByteReader in(out.bytes());
    EXPECT_EQ(in.u64(), 0u);
    EXPECT_EQ(in.u64(), std::numeric_limits<std::uint64_t>::max());
    EXPECT_EQ(in.str(), std::string("a\0b", 3));
    EXPECT_EQ(in.str(), "");
    for (double v : values) {
        const double back = in.f64();
        EXPECT_EQ(std::signbit(back), std::signbit(v));
        EXPECT_EQ(back, v);
    }
    EXPECT_TRUE(std::isnan(in.f64()));
    EXPECT_TRUE(in.done());
    EXPECT_THROW(in.u64(), std::runtime_error);
}

TEST(Bytes, AShortOrLyingMessageThrows) {
    ByteWriter out;
    out.u64(1000);  // a string length with no string after it
    ByteReader in(out.bytes());
    EXPECT_THROW(in.str(), std::runtime_error);
    const std::string three = "abc";
    ByteReader shortOne(three);
    EXPECT_THROW(shortOne.u64(), std::runtime_error);
}

TEST(Bytes, VarintsAndFloatsRoundTripAndAShortOrOverlongVarintThrowsNamingTheBytes) {
    ByteWriter out;
    const std::uint64_t values[] = {0, 1, 127, 128, 300, 1ULL << 35, std::numeric_limits<std::uint64_t>::max()};
    for (std::uint64_t v : values) out.varint(v);
    out.f32(-0.0f).f32(std::numeric_limits<float>::denorm_min()).u32(0xA1B2C3D4u).raw("GSU3", 4);
    EXPECT_EQ(out.bytes().substr(0, 5), std::string("\x00\x01\x7f\x80\x01", 5)) << "LEB128, low 7 bits first";
    ByteReader in(out.bytes());
    for (std::uint64_t v : values) EXPECT_EQ(in.varint(), v);
    EXPECT_TRUE(std::signbit(in.f32()));
    EXPECT_EQ(in.f32(), std::numeric_limits<float>::denorm_min());
    EXPECT_EQ(in.u32(), 0xA1B2C3D4u);
    EXPECT_EQ(in.remaining(), 4u);
    const std::string endless(11, '\x80'), cut("\x80", 1);
    ByteReader overlong(endless, "scan update");
    try {
        overlong.varint();
        ADD_FAILURE() << "a varint of more than 64 bits must throw";
    } catch (const std::runtime_error& e) {
        EXPECT_STREQ(e.what(), "scan update: malformed number");
    }
    ByteReader shortOne(cut, "scan update");
    try {
        shortOne.varint();
        ADD_FAILURE() << "a cut varint must throw";
    } catch (const std::runtime_error& e) {
        EXPECT_STREQ(e.what(), "scan update: truncated");
    }
}

// --- PLY: memory follows what the file can hold ------------------------------------------------

TEST(PlyHostile, VertexCountNearTwoToThe62IsRejectedNotWrapped) {
    // 2^62 vertices of 12 bytes: the byte count wraps to 0 in 64 bits.
    const std::string binary = "ply\nformat binary_little_endian 1.0\nelement vertex 4611686018427387904\n" + kXyz +
                               "end_header\n" + std::string(24, '\0');
    EXPECT_NE(plyError(binary).find("truncated PLY"), std::string::npos) << plyError(binary);
    // In ascii, 4 * 2^62 floats wrap to an empty buffer that the values were written into.
    const std::string ascii = "ply\nformat ascii 1.0\nelement vertex 4611686018427387904\n" + kXyz + "end_header\n1 2 3\n";
    EXPECT_NE(plyError(ascii).find("truncated PLY"), std::string::npos) << plyError(ascii);
}

TEST(PlyHostile, HugeCountInATinyFileFailsBeforeAllocating) {
    for (const char* count : {"200000000", "1000000000000"}) {
        const std::string text = std::string("ply\nformat binary_little_endian 1.0\nelement vertex ") + count + "\n" +
                                 kXyz + "end_header\n" + std::string(12, '\0');
        const std::string err = plyError(text);
        // The message states what the file can hold (12 bytes: 1 vertex): nothing was allocated.
        EXPECT_NE(err.find("hold at most 1"), std::string::npos) << err;
        const std::string ascii = std::string("ply\nformat ascii 1.0\nelement vertex ") + count + "\n" + kXyz +
                                  "end_header\n1 2 3\n";
        EXPECT_NE(plyError(ascii).find("hold at most 1"), std::string::npos) << plyError(ascii);
    }
}

TEST(PlyHostile, MalformedHeadersAreRejected) {
    const struct {
        std::string text, expect;
    } cases[] = {
        {"ply\nformat ascii 1.0\nelement vertex 1\n" + kXyz + "element vertex 1\n" + kXyz + "end_header\n1 2 3\n4 5 6\n",
         "second 'element vertex'"},
        {"ply\nformat ascii 1.0\nelement vertex 1\n" + kXyz + "property float x\nend_header\n1 2 3 4\n", "given twice"},
        {"ply\nformat ascii 1.0\nelement vertex 2e8\n" + kXyz + "end_header\n1 2 3\n", "element count '2e8'"},
        {"ply\nformat ascii 1.0\nelement vertex -1\n" + kXyz + "end_header\n", "element count '-1'"},
        {"ply\nformat ascii 1.0\nformat ascii 1.0\nelement vertex 1\n" + kXyz + "end_header\n1 2 3\n", "second PLY format"},
        {"ply\nformat ascii 1.0\nproperty float x\nelement vertex 1\n" + kXyz + "end_header\n1 2 3\n", "before any element"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nbogus line\n" + kXyz + "end_header\n1 2 3\n", "unknown PLY header"},
        {"ply\nformat binary_big_endian 1.0\nelement vertex 1\n" + kXyz + "end_header\n", "unsupported PLY format"},
        {"ply\nformat ascii 1.0\nelement face 1\nelement vertex 1\n" + kXyz + "end_header\n1 2 3\n", "must come first"},
        {"ply\nformat ascii 1.0\nelement vertex 1\n" + kXyz + "end_header\n1 2 x3\n", "malformed PLY at vertex 0"},
        {"ply\ncomment " + std::string(5000, 'c') + "\nend_header\n", "longer than 4096"},
    };
    for (const auto& c : cases) EXPECT_NE(plyError(c.text).find(c.expect), std::string::npos) << c.text << "\n" << plyError(c.text);
}

TEST(PlyHostile, ValuesBeyondFloatRangeBecomeInfinityAndPlusSignsParse) {
    const auto pts = ply("ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n"
                         "property double z\nend_header\n1e300 -1e300 +1.5\n");
    ASSERT_EQ(pts.size(), 4u);
    EXPECT_TRUE(std::isinf(pts[0]) && pts[0] > 0);
    EXPECT_TRUE(std::isinf(pts[1]) && pts[1] < 0);
    EXPECT_EQ(pts[2], 1.5f);
    // Binary doubles too.
    std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty double x\nproperty double y\n"
                      "property double z\nend_header\n";
    const double v[3] = {1e300, 2.0, -3.0};
    bin.append(reinterpret_cast<const char*>(v), sizeof v);
    const auto b = ply(bin);
    EXPECT_TRUE(std::isinf(b[0]));
    EXPECT_EQ(b[1], 2.f);
}

TEST(PlyHostile, ZeroVerticesAndTrailingElementsAreFine) {
    EXPECT_TRUE(ply("ply\nformat ascii 1.0\nelement vertex 0\n" + kXyz + "end_header\n").empty());
    const auto pts = ply("ply\nformat ascii 1.0\nelement vertex 1\n" + kXyz +
                         "element face 1\nproperty list uchar int vertex_indices\nend_header\n1 2 3\n3 0 0 0\n");
    EXPECT_EQ(pts, (std::vector<float>{1, 2, 3, 0}));
}

// --- KITTI and files -------------------------------------------------------------------------

TEST(KittiHostile, SizesAndNonRegularFiles) {
    const std::uint8_t bytes[20] = {};
    EXPECT_THROW(gseg::io::parseKittiBin(bytes, 20, "x.bin"), std::runtime_error);
    EXPECT_THROW(gseg::io::parseKittiBin(bytes, 0, "x.bin"), std::runtime_error);
    EXPECT_EQ(gseg::io::parseKittiBin(bytes, 16, "x.bin").size(), 4u);
    EXPECT_THROW(gseg::io::parseKittiLabels(bytes, 6, "x.label"), std::runtime_error);
    EXPECT_THROW(gseg::io::parseKittiLabels(bytes, 8, "x.label", 3), std::runtime_error);
    const fs::path dir = freshDir("kitti");
    try {
        gseg::io::readKittiBin(dir.string());  // a folder
        ADD_FAILURE() << "a folder was read as a scan";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
    }
    EXPECT_THROW(gseg::io::readFileBytes("/dev/zero"), std::runtime_error);
}

// --- Atomic outputs ------------------------------------------------------------------------------

TEST(AtomicFile, CommittedOrNothingAndNoTemporary) {
    const fs::path dir = freshDir("atomic");
    const std::string target = (dir / "out.bin").string();
    {
        gseg::io::AtomicFile f(target);
        f.write("abc", 3);
        EXPECT_EQ(gseg::io::registeredTemporaries().size(), 1u);
    }  // not committed: nothing
    EXPECT_FALSE(fs::exists(target));
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp"), "");
    EXPECT_TRUE(gseg::io::registeredTemporaries().empty());
    gseg::io::writeFileAtomic(target, "hello", 5);
    EXPECT_EQ(fs::file_size(target), 5u);
    EXPECT_THROW(gseg::io::writeFileAtomic((dir / "no" / "such" / "dir").string(), "x", 1), std::runtime_error);
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp"), "");
}

TEST(AtomicFile, FullDiskIsAnErrorAndLeavesNothing) {
    // A file-size limit makes write() fail exactly as a full disk does (installTemporaryCleanup
    // ignores SIGXFSZ so that the failure is reported, not fatal).
    const fs::path dir = freshDir("full");
    const std::string target = (dir / "big.bin").string();
    const auto r = gseg::test::runInChild([&] {
        gseg::io::installTemporaryCleanup("test");
        const rlimit lim{8192, 8192};
        ::setrlimit(RLIMIT_FSIZE, &lim);
        const std::vector<char> data(100000, 'x');
        try {
            gseg::io::writeFileAtomic(target, data.data(), data.size());
        } catch (const std::runtime_error& e) {
            return std::string(e.what()).find("write failed after 8192 bytes") != std::string::npos ? 7 : 8;
        }
        return 0;
    });
    EXPECT_TRUE(r.exited);
    EXPECT_EQ(r.code, 7);
    EXPECT_FALSE(fs::exists(target));
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp"), "");
}

TEST(AtomicFile, InterruptedOrCrashedRunLeavesNoTemporary) {
    const fs::path dir = freshDir("signals");
    for (int sig : {SIGTERM, SIGINT, SIGHUP, SIGSEGV, SIGABRT}) {
        const std::string target = (dir / ("out" + std::to_string(sig))).string();
        const auto r = gseg::test::runInChild([&] {
            gseg::io::installTemporaryCleanup("test");
            gseg::io::setActivity("writing " + target);
            gseg::io::AtomicFile f(target);
            f.write("partial", 7);
            ::raise(sig);
            return 0;
        });
        EXPECT_FALSE(r.exited) << "signal " << sig;
        EXPECT_EQ(r.signal, sig);
        EXPECT_FALSE(fs::exists(target));
    }
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp"), "");
    // Without the handlers (the state before this helper existed), the temporary stays.
    const auto r = gseg::test::runInChild([&] {
        gseg::io::AtomicFile f((dir / "unguarded").string());
        ::raise(SIGTERM);
        return 0;
    });
    EXPECT_EQ(r.signal, SIGTERM);
    EXPECT_NE(gseg::test::entriesContaining(dir.string(), ".tmp"), "");
}

TEST(AtomicFile, InheritedIgnoredSigintStaysIgnored) {
    const fs::path dir = freshDir("ignored");
    const auto r = gseg::test::runInChild([&] {
        ::signal(SIGINT, SIG_IGN);  // as for a background job of a non-interactive shell
        gseg::io::installTemporaryCleanup("test");
        gseg::io::AtomicFile f((dir / "out").string());
        ::raise(SIGINT);
        f.write("done", 4);
        f.commit();
        return 3;
    });
    EXPECT_TRUE(r.exited);
    EXPECT_EQ(r.code, 3);
    EXPECT_TRUE(fs::exists(dir / "out"));
}

// --- Where outputs land: links, pipes, other writers, dead runs (#18) ---------------------------

namespace {

std::string bytesOf(const fs::path& p) { return gseg::test::readText(p.string()); }

}  // namespace

TEST(AtomicFile, ASymbolicLinkIsWrittenThroughNotReplaced) {
    const fs::path dir = freshDir("symlink");
    std::ofstream(dir / "target.rawlog") << "old";
    fs::create_symlink("target.rawlog", dir / "sym.rawlog");  // relative, as `ln -s` makes them
    gseg::io::writeFileAtomic((dir / "sym.rawlog").string(), "new", 3);
    EXPECT_TRUE(fs::is_symlink(dir / "sym.rawlog"));
    EXPECT_EQ(bytesOf(dir / "target.rawlog"), "new");
    // A chain of links, and a dangling one: its destination is created, the links stay.
    fs::create_symlink(dir / "sym.rawlog", dir / "chain");
    gseg::io::writeFileAtomic((dir / "chain").string(), "newer", 5);
    EXPECT_EQ(bytesOf(dir / "target.rawlog"), "newer");
    fs::create_symlink("made-by-link", dir / "dangling");
    gseg::io::writeFileAtomic((dir / "dangling").string(), "made", 4);
    EXPECT_TRUE(fs::is_symlink(dir / "dangling"));
    EXPECT_EQ(bytesOf(dir / "made-by-link"), "made");
    // A loop is refused with its name, never written.
    fs::create_symlink("loop-b", dir / "loop-a");
    fs::create_symlink("loop-a", dir / "loop-b");
    try {
        gseg::io::writeFileAtomic((dir / "loop-a").string(), "x", 1);
        ADD_FAILURE() << "a link loop was written";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("loop of symbolic links"), std::string::npos) << e.what();
    }
    EXPECT_THROW(gseg::io::checkOutputs({}, {{"-o", (dir / "loop-a").string()}}, {true, false}), std::invalid_argument);
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp"), "");
}

TEST(AtomicFile, APipeOrTerminalIsStreamedInto) {
    const fs::path dir = freshDir("fifo");
    const std::string fifo = (dir / "fifo").string();
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    // An existing FIFO (or /dev/stdout) is no file to protect: no -w needed.
    EXPECT_NO_THROW(gseg::io::checkOutputs({}, {{"-o", fifo}, {"--log", "/dev/stdout"}}, {false, false}));
    std::string received;
    std::thread reader([&] {
        std::ifstream in(fifo, std::ios::binary);
        received.assign(std::istreambuf_iterator<char>(in), {});
    });
    {
        gseg::io::AtomicFile f(fifo);
        EXPECT_TRUE(f.streamed());
        f.write("streamed ", 9);
        f.write([](std::ostream& out) { out << "bytes"; });
        f.commit();
    }
    reader.join();
    EXPECT_EQ(received, "streamed bytes");
    struct stat st {};
    ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
    EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced";
    // A link to a process's descriptor (what /dev/stdout is) is written into, whatever it leads to.
    const int fds[2] = {0, 0};
    ASSERT_EQ(::pipe(const_cast<int*>(fds)), 0);
    fs::create_symlink("/proc/self/fd/" + std::to_string(fds[1]), dir / "stdout-link");
    gseg::io::writeFileAtomic((dir / "stdout-link").string(), "through", 7);
    ::close(fds[1]);
    char buf[16] = {0};
    EXPECT_EQ(::read(fds[0], buf, sizeof buf), 7);
    EXPECT_STREQ(buf, "through");
    ::close(fds[0]);
    EXPECT_TRUE(fs::is_symlink(dir / "stdout-link"));
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp"), "");
}

TEST(AtomicFile, ASecondWriterOfANewFileFailsInsteadOfOverwriting) {
    const fs::path dir = freshDir("exclusive");
    const std::string target = (dir / "same.rawlog").string();
    gseg::io::AtomicFile first(target), second(target);  // both started before either finished
    first.write("first", 5);
    second.write("second", 6);
    first.commit();
    try {
        second.commit();
        ADD_FAILURE() << "the second writer replaced the first's file";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("was created by another program while this run worked"), std::string::npos)
            << e.what();
    }
    EXPECT_EQ(bytesOf(target), "first");
    // Checked without -w, made by someone else afterwards: refused when the writer starts.
    const std::string later = (dir / "later.csv").string();
    gseg::io::checkOutputs({}, {{"--report", later}}, {false, false});
    std::ofstream(later) << "another run";
    EXPECT_THROW(gseg::io::AtomicFile{later}, std::runtime_error);
    EXPECT_EQ(bytesOf(later), "another run");
    // An existing file a writer was allowed to replace (-w) is replaced.
    gseg::io::checkOutputs({}, {{"-o", target}}, {true, false});
    gseg::io::writeFileAtomic(target, "replaced", 8);
    EXPECT_EQ(bytesOf(target), "replaced");
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp"), "");
}

TEST(AtomicFile, TemporariesOfDeadRunsOfThisOutputAreRemovedByTheNextRun) {
    const fs::path dir = freshDir("stale");
    const std::string target = (dir / "map_ground.bt").string();
    // A temporary named as this host's run `pid` would name it.
    auto sideFileOf = [&](const std::string& output, pid_t pid, const char* kind) {
        std::string name = fs::path(gseg::io::sideFilePath(output, kind)).filename().string();
        const std::string mine = "-" + std::to_string(::getpid()) + "-";
        name.replace(name.rfind(mine), mine.size(), "-" + std::to_string(pid) + "-");
        std::ofstream(dir / name) << "left by " << pid;
        return name;
    };
    const pid_t dead = fork();
    if (dead == 0) _exit(0);
    ASSERT_GT(dead, 0);
    int status = 0;
    ::waitpid(dead, &status, 0);  // reaped: no process has this pid now
    const std::string deadTmp = sideFileOf(target, dead, "tmp"), deadBak = sideFileOf(target, dead, "bak");
    const std::string liveTmp = sideFileOf(target, ::getppid(), "tmp");  // a run still going: kept
    const std::string otherTmp = sideFileOf((dir / "other.bt").string(), dead, "tmp");  // another output: kept
    std::ofstream(dir / ".map_ground.bt.gseg-otherhost-1-0.tmp") << "another host's";  // cannot be proved dead: kept
    gseg::io::writeFileAtomic(target, "map", 3);
    EXPECT_FALSE(fs::exists(dir / deadTmp));
    EXPECT_FALSE(fs::exists(dir / deadBak));
    EXPECT_TRUE(fs::exists(dir / liveTmp));
    EXPECT_TRUE(fs::exists(dir / otherTmp));
    EXPECT_TRUE(fs::exists(dir / ".map_ground.bt.gseg-otherhost-1-0.tmp"));
    EXPECT_EQ(bytesOf(target), "map");
}

TEST(AtomicFileSet, AllInPlaceOrNoneAndASignalWaitsForTheRenames) {
    const fs::path dir = freshDir("set");
    const std::vector<std::string> paths = {(dir / "a").string(), (dir / "b").string(), (dir / "c").string()};
    for (const auto& p : paths) std::ofstream(p) << "old";
    // A signal raised while the files are put in place takes effect once all are: all new.
    const auto r = gseg::test::runInChild([&] {
        gseg::io::installTemporaryCleanup("test");
        gseg::io::AtomicFileSet files(paths);
        for (std::size_t i = 0; i < files.size(); ++i) files[i].write("new", 3);
        {
            gseg::io::SignalDeferral hold;  // as commit() holds it, with the signal inside
            ::raise(SIGTERM);
            files.commit();
        }
        return 5;  // not reached: the held signal ends the process here
    });
    EXPECT_FALSE(r.exited);
    EXPECT_EQ(r.signal, SIGTERM);
    for (const auto& p : paths) EXPECT_EQ(bytesOf(p), "new") << p;
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp") + gseg::test::entriesContaining(dir.string(), ".bak"), "");
    // A set with a member that cannot be put in place changes nothing.
    {
        gseg::io::AtomicFileSet files(paths);
        for (std::size_t i = 0; i < files.size(); ++i) files[i].write("newer", 5);
        fs::remove(files[1].temporaryPath());
        EXPECT_THROW(files.commit(), std::runtime_error);
    }
    for (const auto& p : paths) EXPECT_EQ(bytesOf(p), "new") << p;
    // A member whose file another writer made meanwhile: none of the set is replaced.
    const std::vector<std::string> fresh = {(dir / "x").string(), (dir / "a").string()};
    {
        gseg::io::AtomicFileSet files(fresh);
        files[0].write("set", 3);
        files[1].write("set", 3);
        std::ofstream(fresh[0]) << "other writer";
        EXPECT_THROW(files.commit(), std::runtime_error);
    }
    EXPECT_EQ(bytesOf(fresh[0]), "other writer");
    EXPECT_EQ(bytesOf(fresh[1]), "new");
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ".tmp") + gseg::test::entriesContaining(dir.string(), ".bak"), "");
}

// --- Outputs that are inputs ------------------------------------------------------------------------

TEST(OutputPaths, SameFileByPathHardLinkOrSymlinkIsRefused) {
    const fs::path dir = freshDir("same");
    const fs::path in = dir / "scan.bin";
    std::ofstream(in) << "data";
    fs::create_hard_link(in, dir / "hard.bin");
    fs::create_symlink(in, dir / "soft.bin");
    using gseg::io::NamedPath;
    const std::vector<NamedPath> inputs = {{"input", in.string()}};
    for (const fs::path& out : {in, dir / "hard.bin", dir / "soft.bin", dir / "." / "scan.bin"})
        EXPECT_THROW(gseg::io::checkOutputsAreNotInputs(inputs, {{"--labels-out", out.string()}}), std::invalid_argument)
            << out;
    EXPECT_NO_THROW(gseg::io::checkOutputsAreNotInputs(inputs, {{"--labels-out", (dir / "new.labels").string()},
                                                                {"--ply-out", ""}}));
    // Two outputs naming one file, existing or not.
    EXPECT_THROW(gseg::io::checkOutputsAreNotInputs(inputs, {{"--ply-out", (dir / "a.ply").string()},
                                                             {"--png-out", (dir / "." / "a.ply").string()}}),
                 std::invalid_argument);
    try {
        gseg::io::checkOutputsAreNotInputs(inputs, {{"-o", (dir / "hard.bin").string()}});
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("refusing to overwrite an input"), std::string::npos) << e.what();
    }
    EXPECT_EQ(gseg::test::entriesContaining(dir.string(), ""), "hard.bin scan.bin soft.bin");
}
