#include "common/cli.hpp"
#include "common/ranks.hpp"

#include <gseg/version.hpp>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <iostream>
#include <thread>
#include <vector>

#include <sched.h>

namespace gseg::tools {
namespace {

Verbosity g_verbosity = Verbosity::Normal;

void vprint(std::FILE* out, const char* format, std::va_list args) {
    std::vfprintf(out, format, args);
    std::fflush(out);  // in order with stderr and with other ranks' lines
}

}  // namespace

Verbosity verbosity() { return g_verbosity; }
void setVerbosity(Verbosity v) { g_verbosity = v; }

void say(const char* format, ...) {
    if (g_verbosity == Verbosity::Quiet) return;
    std::va_list args;
    va_start(args, format);
    vprint(stdout, format, args);
    va_end(args);
}

void detail(const char* format, ...) {
    if (g_verbosity != Verbosity::Verbose) return;
    std::va_list args;
    va_start(args, format);
    vprint(stdout, format, args);
    va_end(args);
}

void note(const char* format, ...) {
    if (g_verbosity == Verbosity::Quiet) return;
    std::va_list args;
    va_start(args, format);
    vprint(stderr, format, args);
    va_end(args);
}

std::string versionLine(const std::string& toolName) {
    return toolName + (toolName.rfind("gseg", 0) == 0 ? " " : " (gseg) ") + GSEG_VERSION;
}

unsigned usableCores() {
    cpu_set_t set;
    CPU_ZERO(&set);
    if (::sched_getaffinity(0, sizeof set, &set) == 0) {
        const int n = CPU_COUNT(&set);
        if (n > 0) return unsigned(n);
    }
    return std::max(1u, std::thread::hardware_concurrency());
}

/// The number at the start of `text` into `n`; the characters it took (0: none).
static std::size_t leadingNumber(const std::string& text, double& n) {
    std::size_t used = 0;
    try {
        n = std::stod(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    return used;
}

double parseMemorySize(const std::string& flag, const std::string& value) {
    double n = -1;
    const std::size_t used = leadingNumber(value, n);
    std::string unit = used ? value.substr(used) : "";
    if (!unit.empty() && (unit.back() == 'B' || unit.back() == 'b')) unit.pop_back();
    double scale = 0;
    if (unit.empty()) scale = 1e6;
    else if (unit.size() == 1)
        switch (unit[0]) {
            case 'k': case 'K': scale = 1e3; break;
            case 'm': case 'M': scale = 1e6; break;
            case 'g': case 'G': scale = 1e9; break;
            case 't': case 'T': scale = 1e12; break;
            default: break;
        }
    if (used == 0 || scale == 0 || !(n > 0) || !std::isfinite(n))
        throw std::invalid_argument(flag + " needs a size > 0 in MB, or with a unit (K, M, G, T: 2G), got '" + value + "'");
    return n * scale;
}

std::FILE* progressOut() { return g_verbosity == Verbosity::Quiet ? nullptr : stderr; }

/// TCLAP's output with gseg's conventions: the version in --help and --version, a usage error as
/// one line. Records what happened, for parse()'s exit code.
class CommandLine::Output : public TCLAP::StdOutput {
public:
    Output(const std::string& name, bool printing) : name_(name), printing_(printing) {}

    void usage(TCLAP::CmdLineInterface& c) override {
        done_ = true;
        if (!printing_) return;
        std::cout << versionLine(name_) << "\n";
        TCLAP::StdOutput::usage(c);
        std::cout << std::flush;
    }
    void version(TCLAP::CmdLineInterface&) override {
        done_ = true;
        if (printing_) std::cout << versionLine(name_) << std::endl;
    }
    void failure(TCLAP::CmdLineInterface&, TCLAP::ArgException& e) override {
        failed_ = true;
        if (printing_)
            std::cerr << name_ << ": " << e.error() << " (" << e.argId() << "); see " << name_ << " --help" << std::endl;
    }

    bool done_ = false, failed_ = false;

private:
    std::string name_;
    bool printing_;
};

CommandLine::CommandLine(std::string name, const std::string& description, bool writesFiles, bool printing)
    : name_(std::move(name)), printing_(printing), cmd_(description, ' ', GSEG_VERSION),
      output_(std::make_unique<Output>(name_, printing)),
      quiet_("q", "quiet", "print errors only (no progress, no summary)", cmd_, false),
      verbose_("v", "verbose", "print more detail (the parameters in effect, one line per item)", cmd_, false),
      mpiTimeoutSeconds_(Ranks::kDefaultTimeout) {
    delete cmd_.getOutput();  // TCLAP's default output, not deleted once replaced
    cmd_.setOutput(output_.get());
    if (writesFiles)
        overwrite_ = std::make_unique<TCLAP::SwitchArg>("w", "overwrite", "replace outputs that exist (default: refuse, "
                                                        "exit 2, before any work)", cmd_, false);
}

CommandLine::~CommandLine() = default;

void CommandLine::addMpiTimeout() {
    char text[200];
    std::snprintf(text, sizeof text, "[s] under mpirun/srun: a rank silent this long (stopped, or its machine gone) "
                  "ends the job, naming it (default %g; 0: wait for ever)", Ranks::kDefaultTimeout);
    mpiTimeout_ = std::make_unique<TCLAP::ValueArg<std::string>>("", "mpi-timeout", text, false, "", "SECONDS", cmd_);
}

int CommandLine::parse(int argc, char** argv) {
    std::vector<const char*> args(argv, argv + argc);
    args.at(0) = name_.c_str();  // the name in TCLAP's usage lines, not the path of the executable
    if (!cmd_.parse(int(args.size()), args.data())) return output_->failed_ || !output_->done_ ? kBadUsage : kDone;
    if (quiet_.getValue() && verbose_.getValue()) return usageError("give --quiet or --verbose, not both");
    for (TCLAP::Arg* arg : cmd_.getArgList()) {  // `-o ""` is refused now, not after all the work
        auto* text = dynamic_cast<TCLAP::ValueArg<std::string>*>(arg);
        if (text && text->isSet() && text->getValue().empty())
            return usageError(dynamic_cast<const TCLAP::UnlabeledValueArg<std::string>*>(arg)
                                  ? "the " + arg->getName() + " is an empty name"
                                  : (arg->getFlag().empty() ? "--" + arg->getName() : "-" + arg->getFlag()) + " is empty");
    }
    setVerbosity(quiet_.getValue() ? Verbosity::Quiet : verbose_.getValue() ? Verbosity::Verbose : Verbosity::Normal);
    if (mpiTimeout_ && mpiTimeout_->isSet()) {
        const std::string& v = mpiTimeout_->getValue();
        double s = -1;
        if (leadingNumber(v, s) != v.size() || !(s >= 0) || !std::isfinite(s))
            return usageError("--mpi-timeout needs a number of seconds >= 0 (0: none), got '" + v + "'");
        mpiTimeoutSeconds_ = s;
    }
    return -1;
}

int CommandLine::usageError(const std::string& what) const {
    if (printing_) std::fprintf(stderr, "%s: %s; see %s --help\n", name_.c_str(), what.c_str(), name_.c_str());
    return kBadUsage;
}

}  // namespace gseg::tools
