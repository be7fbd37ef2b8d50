#include "common/cli.hpp"
#include "common/ranks.hpp"

#include <gseg/mrpt/errors.hpp>
#include <gseg/text.hpp>
#include <gseg/version.hpp>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cctype>
#include <cstdlib>
#include <iostream>
#include <map>
#include <stdexcept>
#include <vector>


namespace gseg::tools {
namespace {

Verbosity g_verbosity = Verbosity::Normal;

void vprint(std::FILE* out, const char* format, std::va_list args) {
    std::vfprintf(out, format, args);
    std::fflush(out);  // in order with stderr and with other ranks' lines
}

}  // namespace

std::string currentError() {
    try {
        throw;
    } catch (const std::exception& e) {
        return gseg::mrpt::errorReason(e);
    } catch (...) {
        return "unknown error";
    }
}

int exitCodeOf(InvalidArgument meaning) {
    try {
        throw;
    } catch (const std::invalid_argument&) {
        return meaning == InvalidArgument::BadUsage ? kBadUsage : kBadInput;
    } catch (...) {
        return kBadInput;
    }
}

int reportError(const std::string& tool, InvalidArgument meaning) {
    std::fprintf(stderr, "%s: %s\n", tool.c_str(), currentError().c_str());
    return exitCodeOf(meaning);
}

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

void noteWarnings(const std::string& tool, const std::vector<std::string>& warnings) {
    for (const std::string& w : warnings) note("%s: warning: %s\n", tool.c_str(), w.c_str());
}

std::string versionLine(const std::string& toolName) {
    return toolName + (toolName.rfind("gseg", 0) == 0 ? " " : " (gseg) ") + GSEG_VERSION;
}

double parseMemorySize(const std::string& flag, const std::string& value) {
    // The number (gseg::parseNumber), then at most one unit letter and an optional B.
    std::string number = value;
    if (!number.empty() && (number.back() == 'B' || number.back() == 'b')) number.pop_back();
    double scale = 0;
    if (!number.empty())
        switch (number.back()) {
            case 'k': case 'K': scale = 1e3; break;
            case 'm': case 'M': scale = 1e6; break;
            case 'g': case 'G': scale = 1e9; break;
            case 't': case 'T': scale = 1e12; break;
            default: break;
        }
    if (scale != 0) number.pop_back();
    else scale = 1e6;  // no unit letter: MB
    const std::optional<double> n = parseNumber<double>(number);
    if (!n || !(*n > 0) || !std::isfinite(*n))
        throw std::invalid_argument(flag + " needs a size > 0 in MB, or with a unit (K, M, G, T: 2G), got '" + value + "'");
    return *n * scale;
}

/// Edit distance between `a` and `b` (insertions, deletions, substitutions and swaps of two
/// neighbours: --mpa for --map is one), ignoring case.
static std::size_t editDistance(const std::string& a, const std::string& b) {
    auto same = [](char x, char y) { return std::tolower((unsigned char)x) == std::tolower((unsigned char)y); };
    std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
    for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
    for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i)
        for (std::size_t j = 1; j <= b.size(); ++j) {
            d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (same(a[i - 1], b[j - 1]) ? 0 : 1)});
            if (i > 1 && j > 1 && same(a[i - 1], b[j - 2]) && same(a[i - 2], b[j - 1]))
                d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
        }
    return d[a.size()][b.size()];
}

std::string nearestName(const std::string& typed, const std::vector<std::string>& candidates) {
    std::string best, prefixed;
    std::size_t bestDistance = std::string::npos, prefixes = 0;
    for (const std::string& c : candidates) {
        const std::size_t d = editDistance(typed, c);
        if (d < bestDistance) bestDistance = d, best = c;
        if (typed.size() >= 3 && c.size() > typed.size() && c.compare(0, typed.size(), typed) == 0) ++prefixes, prefixed = c;
    }
    // Near enough: a third of the name's letters wrong at most (--ply_out, --theads, --resoluton).
    const std::size_t letters = best.size() - std::min(best.find_first_not_of('-'), best.size());
    if (!best.empty() && bestDistance <= std::max<std::size_t>(1, letters / 3)) return best;
    return prefixes == 1 ? prefixed : "";  // --over for --overwrite
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
        if (!printing_) return;
        // What CommandLine::checkArguments() leaves to TCLAP: a value of the wrong type. The
        // option as "-i/--input" (TCLAP's id is "Argument: -i (--input)").
        std::string id = e.argId();
        if (id.rfind("Argument: ", 0) == 0) id.erase(0, 10);
        if (const std::size_t open = id.find(" (--"); open != std::string::npos) id.replace(open, 2, "/");
        id.erase(std::remove(id.begin(), id.end(), '('), id.end());
        id.erase(std::remove(id.begin(), id.end(), ')'), id.end());
        const std::string cannotRead = "Couldn't read argument value from string ";
        const std::string what = e.error().rfind(cannotRead, 0) == 0
                                     ? "option " + id + ": cannot read " + e.error().substr(cannotRead.size()) + " as its value"
                                     : e.error() + (id.empty() || id == " " ? "" : " (" + id + ")");
        std::cerr << name_ << ": " << what << "; see " << name_ << " --help" << std::endl;
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

namespace {

/// An option as the user writes it: "-o/--output", "--ply-out", "-q".
std::string spelled(const TCLAP::Arg& a) {
    if (a.getFlag().empty()) return "--" + a.getName();
    if (a.getName().empty()) return "-" + a.getFlag();
    return "-" + a.getFlag() + "/--" + a.getName();
}

/// A positional argument (TCLAP's unlabeled arguments): it matches no spelling.
bool positional(TCLAP::Arg* a) {
    return dynamic_cast<TCLAP::UnlabeledValueArg<std::string>*>(a) || dynamic_cast<TCLAP::UnlabeledValueArg<int>*>(a) ||
           dynamic_cast<TCLAP::UnlabeledValueArg<long>*>(a) || dynamic_cast<TCLAP::UnlabeledValueArg<double>*>(a) ||
           dynamic_cast<TCLAP::UnlabeledMultiArg<std::string>*>(a);
}

/// An option that may be given more than once (-i A -i B).
bool repeatable(TCLAP::Arg* a) {
    return dynamic_cast<TCLAP::MultiArg<std::string>*>(a) || dynamic_cast<TCLAP::MultiArg<int>*>(a) ||
           dynamic_cast<TCLAP::MultiArg<double>*>(a) || dynamic_cast<TCLAP::MultiSwitchArg<>*>(a);
}

/// "FILE" of an option's "--ply-out <FILE>" (TCLAP keeps the value's name for its usage lines).
std::string valueName(const TCLAP::Arg& a) {
    const std::string id = a.longID();
    const std::size_t open = id.rfind('<'), close = id.rfind('>');
    return open != std::string::npos && close != std::string::npos && close > open ? id.substr(open + 1, close - open - 1)
                                                                                     : "a value";
}

/// A number (-1, -0.5, -1e3): a value, not an option.
bool looksNumeric(const std::string& token) { return parseNumber<double>(token).has_value(); }

}  // namespace

std::string CommandLine::checkArguments(std::vector<std::string>& args, std::string& helpOrVersion) {
    std::vector<TCLAP::Arg*> options;
    std::size_t positionalSlots = 0;
    bool positionalUnbounded = false;
    for (TCLAP::Arg* a : cmd_.getArgList()) {
        if (positional(a)) {
            if (dynamic_cast<TCLAP::UnlabeledMultiArg<std::string>*>(a)) positionalUnbounded = true;
            else ++positionalSlots;
        } else if (a->getName() != TCLAP::Arg::ignoreNameString()) {
            options.push_back(a);
        }
    }
    auto byFlag = [&](char f) -> TCLAP::Arg* {
        for (TCLAP::Arg* a : options)
            if (a->getFlag().size() == 1 && a->getFlag()[0] == f) return a;
        return nullptr;
    };
    auto byName = [&](const std::string& n) -> TCLAP::Arg* {
        for (TCLAP::Arg* a : options)
            if (a->getName() == n) return a;
        return nullptr;
    };
    auto unknown = [&](const std::string& token) {
        std::vector<std::string> spellings;
        for (TCLAP::Arg* a : options) {
            spellings.push_back("--" + a->getName());
            if (!a->getFlag().empty()) spellings.push_back("-" + a->getFlag());
        }
        std::string typed = token.substr(0, token.find('='));
        std::string near = nearestName(typed, spellings);
        if (near.empty() && typed.size() > 2 && typed[1] != '-') near = nearestName("-" + typed, spellings);  // -input
        return "unknown option '" + token + "'" + (near.empty() ? "" : " (did you mean '" + near + "'?)");
    };
    std::vector<std::string> errors;  // the first is said
    std::map<TCLAP::Arg*, int> given;
    std::size_t positionals = 0;
    for (std::size_t k = 0; k < args.size(); ++k) {
        const std::string token = args[k];
        if (token == "--") break;  // TCLAP's ignore_rest: the rest is not options
        std::vector<TCLAP::Arg*> named;  // the options this token gives
        if (token.size() > 2 && token.compare(0, 2, "--") == 0) {
            const std::size_t eq = token.find('=');
            TCLAP::Arg* a = byName(token.substr(2, eq == std::string::npos ? std::string::npos : eq - 2));
            if (!a) {
                errors.push_back(unknown(token));
                continue;
            }
            if (eq != std::string::npos) {
                if (!a->isValueRequired()) {
                    errors.push_back("option " + spelled(*a) + " takes no value");
                    continue;
                }
                args[k] = token.substr(0, eq);  // --ply-out=x.ply: --ply-out x.ply
                args.insert(args.begin() + std::ptrdiff_t(k) + 1, token.substr(eq + 1));
            }
            named.push_back(a);
        } else if (token.size() > 1 && token[0] == '-' && !looksNumeric(token)) {
            if (TCLAP::Arg* a = byFlag(token[1]); a && token.size() == 2) {
                named.push_back(a);
            } else {  // -qv: switches together
                for (std::size_t c = 1; c < token.size(); ++c) {
                    TCLAP::Arg* s = byFlag(token[c]);
                    if (!s || s->isValueRequired()) {
                        named.clear();
                        break;
                    }
                    named.push_back(s);
                }
                if (named.empty()) {
                    errors.push_back(unknown(token));
                    continue;
                }
            }
        } else {
            if (++positionals > positionalSlots && !positionalUnbounded)
                errors.push_back("unexpected argument '" + token + "'" +
                                 (positionalSlots ? "" : " (this tool takes its inputs with options)"));
            continue;
        }
        for (TCLAP::Arg* a : named) {
            if (a->getName() == "help" || a->getName() == "version") {
                helpOrVersion = "--" + a->getName();
                return "";
            }
            if (++given[a] == 2 && !repeatable(a)) errors.push_back("option " + spelled(*a) + " given twice");
        }
        if (named.size() == 1 && named[0]->isValueRequired()) {
            if (k + 1 == args.size()) errors.push_back("option " + spelled(*named[0]) + " needs a value (" + valueName(*named[0]) + ")");
            ++k;  // its value, whatever it looks like (--index -1)
        }
    }
    if (!errors.empty()) return errors.front();
    for (TCLAP::Arg* a : options)
        if (a->isRequired() && !given.count(a)) return "missing required option " + spelled(*a);
    return "";
}

int CommandLine::parse(int argc, char** argv) {
    std::vector<std::string> given(argv + std::min(argc, 1), argv + argc);
    std::string helpOrVersion;
    const std::string mistake = checkArguments(given, helpOrVersion);
    if (!mistake.empty()) return usageError(mistake);
    if (!helpOrVersion.empty()) given = {helpOrVersion};  // --help wins over whatever else is on the line
    std::vector<const char*> args = {name_.c_str()};  // the name in TCLAP's usage lines, not the executable's path
    for (const std::string& a : given) args.push_back(a.c_str());
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
        const std::optional<double> s = parseNumber<double>(v);
        if (!s || !(*s >= 0) || !std::isfinite(*s))
            return usageError("--mpi-timeout needs a number of seconds >= 0 (0: none), got '" + v + "'");
        mpiTimeoutSeconds_ = *s;
    }
    return -1;
}

int CommandLine::usageError(const std::string& what) const {
    if (printing_) std::fprintf(stderr, "%s: %s; see %s --help\n", name_.c_str(), what.c_str(), name_.c_str());
    return kBadUsage;
}

}  // namespace gseg::tools
