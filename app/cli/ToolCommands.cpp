// SPDX-License-Identifier: GPL-3.0-or-later
#include "CliSupport.h"
#include "Commands.h"

#include <scandiff/core/Error.h>

#include <chrono>
#include <iomanip>
#include <map>
#include <memory>

namespace scandiff::cli {

namespace {

void addOneTool(CLI::App& app, const ToolSpec& tool, const PluginRegistry& registry, Streams streams)
{
    struct Args
    {
        std::string input, output;
        std::shared_ptr<std::map<std::string, std::string>> values = std::make_shared<std::map<std::string, std::string>>();
        ReadFlags read;
        WriteFlags write;
    };
    auto args = std::make_shared<Args>();
    CLI::App* command = app.add_subcommand(tool.name, tool.title + ": " + tool.description);
    command->group(tool.category.empty() ? "Tools" : tool.category);
    command->add_option("IN", args->input, "Input cloud")->required();
    command->add_option("-o,--output", args->output, "Output file (nothing is written without it)");
    // Options come from the tool's own parameter declarations: one source of truth.
    addParameterOptions(*command, tool.parameters, args->values);
    args->read.addTo(*command);
    args->write.addTo(*command);
    const ToolSpec* toolPtr = &tool;
    command->callback([args, toolPtr, &registry, streams] {
        // Parameters are checked before the (possibly long) read of the input.
        const ParameterValues values = toolPtr->resolve(*args->values);
        TerminalProgress progress;
        const PointCloud input = io::readPointCloud(registry.formats, args->input, args->read.toOptions(&progress));
        const auto start = std::chrono::steady_clock::now();
        ToolResult result = toolPtr->run(input, values, &progress);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        streams.out << toolPtr->name << ": " << result.summary << " [" << std::fixed << std::setprecision(3) << seconds << " s]\n";
        if (!args->output.empty()) {
            io::writePointCloud(registry.formats, result.cloud, args->output, args->write.toOptions(&progress));
            streams.out << "wrote " << args->output << " (" << result.cloud.size() << " points)\n";
        }
    });
}

} // namespace

void addToolCommands(CLI::App& app, const PluginRegistry& registry, Streams streams)
{
    CLI::App* formats = app.add_subcommand("formats", "List the file formats this build reads and writes");
    formats->callback([&registry, streams] {
        for (const auto& h : registry.formats.handlers()) {
            streams.out << std::left << std::setw(22) << h.name << std::right;
            for (const auto& e : h.extensions)
                streams.out << " ." << e;
            streams.out << "   [" << (h.read ? "read" : "") << (h.read && (h.writeCloud || h.writeMesh) ? ", " : "")
                        << (h.writeCloud || h.writeMesh ? "write" : "") << "]\n";
        }
    });
    CLI::App* tools = app.add_subcommand("tools", "List the plugins and the tools they provide");
    tools->callback([&registry, streams] {
        for (const auto& p : registry.plugins)
            streams.out << "plugin " << p.name << ": " << p.description << '\n';
        for (const auto& t : registry.tools.tools())
            streams.out << "tool   " << t.name << ": " << t.title << '\n';
    });
    for (const auto& tool : registry.tools.tools())
        addOneTool(app, tool, registry, streams);
}

int runCli(int argc, const char* const* argv, const PluginRegistry& registry, Streams streams)
{
    CLI::App app{"scandiff-cli: compare 3D scans from the command line"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "scandiff 0.1.0");
    addInfoCommand(app, registry, streams);
    addConvertCommand(app, registry, streams);
    addCloudToCloudCommand(app, registry, streams);
    addCloudToMeshCommand(app, registry, streams);
    addSegmentCommand(app, registry, streams);
    addCompareCommand(app, registry, streams);
    addToolCommands(app, registry, streams);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // --help and --version are "errors" with status 0 in CLI11.
        return app.exit(e, streams.out, streams.err);
    } catch (const Error& e) {
        streams.err << "error: " << e.what() << '\n';
        return e.exitStatus();
    } catch (const std::exception& e) {
        streams.err << "error: " << e.what() << '\n';
        return static_cast<int>(ErrorCode::Internal);
    }
    return 0;
}

} // namespace scandiff::cli
