// SPDX-License-Identifier: GPL-3.0-or-later
#include "CliSupport.h"
#include "Commands.h"

#include <scandiff/core/Error.h>
#include <scandiff/io/ResultFiles.h>

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <map>
#include <memory>

namespace scandiff::cli {

namespace {

const char* kindName(DataKind kind)
{
    switch (kind) {
    case DataKind::Cloud: return "point cloud";
    case DataKind::Mesh: return "mesh";
    case DataKind::Table: return "table (CSV)";
    case DataKind::Transform: return "4x4 matrix (text)";
    }
    return "";
}

//! Where output `spec` goes: the first declared output to -o, each later one
//! beside it (FILE's stem + "_" + role), tables as .csv and matrices as .txt.
std::filesystem::path outputPath(const ToolSpec& tool, const OutputSpec& spec, const std::filesystem::path& primary)
{
    if (&spec == &tool.outputs.front())
        return primary;
    std::string extension = primary.extension().string();
    if (spec.kind == DataKind::Table)
        extension = ".csv";
    else if (spec.kind == DataKind::Transform)
        extension = ".txt";
    return primary.parent_path() / (primary.stem().string() + "_" + spec.role + extension);
}

std::string outputHelp(const ToolSpec& tool)
{
    std::string help = "Output file (nothing is written without it, tables and matrices are then printed):";
    for (const auto& o : tool.outputs)
        help += " " + std::string(&o == &tool.outputs.front() ? "FILE" : "FILE_" + o.role) + " = " + o.label + " (" +
                kindName(o.kind) + ")" + (&o == &tool.outputs.back() ? "" : ";");
    return help;
}

//! Reads every input file of the command line, in declaration order.
struct LoadedInputs
{
    std::vector<std::unique_ptr<Entity>> entities; // stable addresses for ToolInputs
    std::map<std::string, std::vector<Entity*>> byRole;
    ToolInputs inputs;
};

void loadInputs(const ToolSpec& tool, const std::map<std::string, std::vector<std::string>>& files,
                const PluginRegistry& registry, const io::ReadOptions& options, LoadedInputs& loaded)
{
    for (const auto& spec : tool.inputs) {
        const auto it = files.find(spec.role);
        if (it == files.end())
            continue;
        for (const auto& path : it->second) {
            auto entity = std::make_unique<Entity>(io::readFile(registry.formats, path, options));
            if (spec.kind == DataKind::Mesh && !std::holds_alternative<Mesh>(*entity))
                throw Error(ErrorCode::InvalidArgument, path + " holds a point cloud; --" + spec.role + " needs a mesh");
            loaded.inputs.add(spec.role, *entity);
            loaded.byRole[spec.role].push_back(entity.get());
            loaded.entities.push_back(std::move(entity));
        }
    }
}

//! Writes (or prints) one output. A cloud that updates a mesh input of the
//! same size is written as that mesh with the new vertices, so normals or
//! fields computed on a mesh's vertices keep its triangles.
void emitOutput(const OutputSpec& spec, ToolOutput& output, const std::filesystem::path& path, LoadedInputs& loaded,
                const ToolSpec& tool, const PluginRegistry& registry, const io::WriteOptions& options, Streams streams)
{
    if (auto* table = std::get_if<Table>(&output.data)) {
        if (path.empty()) {
            streams.out << table->toCsv();
            return;
        }
        io::writeTable(*table, path);
    } else if (auto* matrix = std::get_if<Eigen::Matrix4d>(&output.data)) {
        streams.out << spec.label << ":\n" << io::matrixText(*matrix);
        if (path.empty())
            return;
        io::writeMatrix(*matrix, path);
    } else if (path.empty()) {
        return;
    } else if (auto* cloud = std::get_if<PointCloud>(&output.data)) {
        Entity* firstInput = nullptr;
        if (spec.updatesInput && !tool.inputs.empty() && loaded.byRole.count(tool.inputs.front().role))
            firstInput = loaded.byRole[tool.inputs.front().role].front();
        Mesh* mesh = firstInput ? std::get_if<Mesh>(firstInput) : nullptr;
        if (mesh && mesh->vertices.size() == cloud->size()) {
            mesh->vertices = std::move(*cloud);
            io::writeMesh(registry.formats, *mesh, path, options);
        } else {
            io::writePointCloud(registry.formats, *cloud, path, options);
        }
    } else {
        io::writeMesh(registry.formats, std::get<Mesh>(output.data), path, options);
    }
    streams.out << "wrote " << path.string() << " (" << spec.label << ")\n";
}

void addOneTool(CLI::App& app, const ToolSpec& tool, const PluginRegistry& registry, Streams streams)
{
    struct Args
    {
        std::map<std::string, std::vector<std::string>> inputs; // file names by role
        std::string output;
        std::shared_ptr<std::map<std::string, std::string>> values = std::make_shared<std::map<std::string, std::string>>();
        int threads = 0;
        ReadFlags read;
        WriteFlags write;
    };
    auto args = std::make_shared<Args>();
    CLI::App* command = app.add_subcommand(tool.name, tool.title + ": " + tool.description);
    command->group(tool.category.empty() ? "Tools" : tool.category);
    for (const auto& input : tool.inputs) {
        std::vector<std::string>& files = args->inputs[input.role];
        const std::string help = input.label + (input.description.empty() ? "" : ": " + input.description);
        CLI::Option* option = input.role == "input" ? command->add_option("IN", files, help)
                                                    : command->add_option("--" + input.role, files, help);
        option->expected(input.repeated ? -1 : 1);
        if (!input.optional)
            option->required();
    }
    if (!tool.outputs.empty())
        command->add_option("-o,--output", args->output, outputHelp(tool));
    // Options come from the tool's own parameter declarations: one source of truth.
    addParameterOptions(*command, tool.parameters, args->values);
    ThreadLimit::addOption(*command, args->threads);
    args->read.addTo(*command);
    args->write.addTo(*command);
    const ToolSpec* toolPtr = &tool;
    command->callback([args, toolPtr, &registry, streams] {
        const ThreadLimit threadLimit(args->threads);
        // Parameters are checked before the (possibly long) reading of the inputs.
        const ParameterValues values = toolPtr->resolve(*args->values);
        TerminalProgress progress;
        LoadedInputs loaded;
        loadInputs(*toolPtr, args->inputs, registry, args->read.toOptions(&progress), loaded);
        const auto start = std::chrono::steady_clock::now();
        ToolResult result = toolPtr->execute(loaded.inputs, values, &progress);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        streams.out << toolPtr->name << ": " << result.summary << " [" << std::fixed << std::setprecision(3) << seconds << " s]\n";
        streams.out.unsetf(std::ios::floatfield);
        const io::WriteOptions writeOptions = args->write.toOptions(&progress);
        for (const auto& spec : toolPtr->outputs) {
            ToolOutput* output = result.find(spec.role);
            if (!output)
                continue;
            const std::filesystem::path path =
                args->output.empty() ? std::filesystem::path() : outputPath(*toolPtr, spec, args->output);
            emitOutput(spec, *output, path, loaded, *toolPtr, registry, writeOptions, streams);
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
