// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The subcommands of scandiff-cli. Each adds itself to the app; its callback
//! loads inputs, calls the library and prints results (PDAL's kernels are the
//! model: a front end holds no algorithm).

#include <scandiff/plugins/PluginRegistry.h>

#include <CLI/CLI.hpp>

#include <ostream>

namespace scandiff::cli {

//! Output streams of the commands (tests capture them).
struct Streams
{
    std::ostream& out;
    std::ostream& err;
};

void addInfoCommand(CLI::App& app, const PluginRegistry& registry, Streams streams);
void addConvertCommand(CLI::App& app, const PluginRegistry& registry, Streams streams);
//! `c2c`: cloud-to-cloud distances (CloudToCloudCommand.cpp).
void addCloudToCloudCommand(CLI::App& app, const PluginRegistry& registry, Streams streams);
//! `c2m`: cloud-to-mesh distances (CloudToMeshCommand.cpp).
void addCloudToMeshCommand(CLI::App& app, const PluginRegistry& registry, Streams streams);
//! `segment`: change regions from a distance field, exported (SegmentCommand.cpp).
void addSegmentCommand(CLI::App& app, const PluginRegistry& registry, Streams streams);
//! `compare`: c2c, then segment, in one command (SegmentCommand.cpp).
void addCompareCommand(CLI::App& app, const PluginRegistry& registry, Streams streams);
//! `formats`, `tools`, and one subcommand per registered tool.
void addToolCommands(CLI::App& app, const PluginRegistry& registry, Streams streams);

//! Builds the whole command line and runs it; returns the process exit status.
//! Errors are printed on `streams.err` as "error: <message>".
int runCli(int argc, const char* const* argv, const PluginRegistry& registry, Streams streams);

} // namespace scandiff::cli
