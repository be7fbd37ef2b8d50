// gseg: GSeg3D ground segmentation tools (segment one scan, evaluate, benchmark).
#include "commands.hpp"
#include "common/cli.hpp"

#include <gseg/io/atomic_file.hpp>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace {

struct Command {
    const char* name;
    int (*run)(int, char**);                       ///< runs in one process
    int (*runOnRanks)(int, char**, gseg::tools::Ranks&);  ///< spreads its work over MPI ranks
    const char* summary;
};

const Command kCommands[] = {
    {"segment", gseg::app::runSegment, nullptr, "label one scan (KITTI .bin, PLY or rawlog) as ground / non-ground"},
    {"eval", nullptr, gseg::app::runEval, "precision / recall on SemanticKITTI (Ground Segmentation Benchmark protocol)"},
    {"eval-map", gseg::app::runEvalMap, nullptr, "score a 2D map (map_server YAML) against a labelled KITTI drive"},
    {"bench", gseg::app::runBench, nullptr, "time the segmentation per scan, phase and step"},
};

void usage(std::FILE* out) {
    std::fprintf(out, "%s\nusage: gseg <command> [options]   (gseg <command> --help for its options)\n\ncommands:\n",
                 gseg::tools::versionLine("gseg").c_str());
    for (const Command& c : kCommands) std::fprintf(out, "  %-9s %s\n", c.name, c.summary);
    std::fprintf(out, "\nevery command takes its inputs with -i (the positional form works too) and has -q/--quiet, "
                      "-v/--verbose, --version and --help; those that write files refuse to replace one without "
                      "-w/--overwrite\n");
}

int runCommand(int argc, char** argv, gseg::tools::Ranks& ranks) {
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    const std::string cmd = argv[1];
    if (cmd == "-h" || cmd == "--help" || cmd == "help") {
        if (ranks.root()) usage(stdout);
        return 0;
    }
    if (cmd == "--version") {
        if (ranks.root()) std::printf("%s\n", gseg::tools::versionLine("gseg").c_str());
        return 0;
    }
    for (const Command& c : kCommands)
        if (cmd == c.name) {
            std::string name = std::string("gseg ") + c.name;
            argv[1] = name.data();
            // An interrupted or crashed run removes its temporary outputs (every sub-command).
            gseg::io::installTemporaryCleanup(name);
            if (c.runOnRanks) return c.runOnRanks(argc - 1, argv + 1, ranks);
            if (ranks.size() == 1) return c.run(argc - 1, argv + 1);
            std::fprintf(stderr, "gseg %s runs in one process (only eval is spread over MPI ranks): start it without mpirun\n",
                         c.name);
            return 2;
        }
    std::vector<std::string> names;
    for (const Command& c : kCommands) names.push_back(c.name);
    const std::string near = gseg::tools::nearestName(cmd, names);
    if (!near.empty()) {  // one line, as the commands' own usage errors
        std::fprintf(stderr, "gseg: unknown command '%s' (did you mean '%s'?); see gseg --help\n", cmd.c_str(), near.c_str());
        return 2;
    }
    std::fprintf(stderr, "gseg: unknown command '%s'\n", cmd.c_str());
    usage(stderr);
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    gseg::tools::Ranks ranks(argc, argv);
    return ranks.exitCode(runCommand(argc, argv, ranks));
}
