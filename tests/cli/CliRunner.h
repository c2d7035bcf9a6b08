// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Runs scandiff-cli in the test's process (cli::runCli), capturing what it
//! prints: the CLI test files share it.

#include "Commands.h"

#include <sstream>
#include <string>
#include <vector>

namespace scandiff::test {

struct CliRun
{
    int status = 0;
    std::string out, err;
};

inline CliRun runCliInProcess(const PluginRegistry& registry, std::vector<std::string> args)
{
    args.insert(args.begin(), "scandiff-cli");
    std::vector<const char*> argv;
    for (const auto& a : args)
        argv.push_back(a.c_str());
    std::ostringstream out, err;
    CliRun run;
    run.status = cli::runCli(static_cast<int>(argv.size()), argv.data(), registry, {out, err});
    run.out = out.str();
    run.err = err.str();
    return run;
}

} // namespace scandiff::test
