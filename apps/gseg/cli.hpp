#pragma once
/// \file cli.hpp
/// Argument parsing shared by the gseg sub-commands and the rawlog tools (MRPT's TCLAP).

#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <cstring>

namespace gseg::app {

/// Parses; returns -1 to go on, otherwise the exit code: 0 after --help/--version (TCLAP printed
/// them), 2 after a usage error (TCLAP printed it). MRPT's TCLAP returns false in both cases.
inline int parseArgs(TCLAP::CmdLine& cmd, int argc, char** argv) {
    if (cmd.parse(argc, argv)) return -1;
    for (int i = 1; i < argc; ++i)
        if (!std::strcmp(argv[i], "-h") || !std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "--version"))
            return 0;
    return 2;
}

}  // namespace gseg::app
