// SPDX-License-Identifier: GPL-3.0-or-later
#include "CliSupport.h"
#include "Commands.h"

#include <scandiff/core/Error.h>
#include <scandiff/io/AtomicFile.h>
#include <scandiff/io/DxfReader.h>
#include <scandiff/io/DxfWriter.h>
#include <scandiff/io/ResultFiles.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
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
    case DataKind::Drawing: return "drawing (DXF)";
    case DataKind::Document: return "document";
    }
    return "";
}

std::string extensionFor(const OutputSpec& spec, const OutputData& data, const std::string& cloudExtension)
{
    if (const auto* table = std::get_if<Table>(&data))
        return table->plainNumbers ? ".txt" : ".csv";
    if (spec.kind == DataKind::Transform)
        return ".txt";
    if (spec.kind == DataKind::Drawing)
        return ".dxf";
    if (const auto* document = std::get_if<TextDocument>(&data))
        return document->extension;
    return cloudExtension;
}

//! Where an output goes, by priority: its own --ROLE-out, else into --out-dir
//! (DIR/ROLE.ext, a repeated output under its entity's name), else for the
//! first declared output -o, for the others beside it (FILE's stem + "_" +
//! role). Empty: printed (tables, matrices) or not written.
struct OutputPlaces
{
    std::string primary, directory;
    std::map<std::string, std::string> byRole;
};

std::filesystem::path outputPath(const ToolSpec& tool, const OutputSpec& spec, const ToolOutput& output, const OutputPlaces& places,
                                 std::size_t repeat)
{
    const auto own = places.byRole.find(spec.role);
    if (own != places.byRole.end() && !own->second.empty())
        return own->second;
    if (!places.directory.empty()) {
        std::string name = spec.fileStem.empty() ? spec.role : spec.fileStem;
        if (spec.repeated) {
            const PointCloud* cloud = std::get_if<PointCloud>(&output.data);
            const Mesh* mesh = std::get_if<Mesh>(&output.data);
            name = cloud && !cloud->name.empty() ? cloud->name : mesh && !mesh->name.empty() ? mesh->name : spec.role;
            name += "_" + std::to_string(repeat);
            for (char& c : name)
                if (c == '/' || c == '\\')
                    c = '_';
        }
        return std::filesystem::path(places.directory) / (name + extensionFor(spec, output.data, ".ply"));
    }
    if (places.primary.empty())
        return {};
    const std::filesystem::path primary(places.primary);
    if (&spec == &tool.outputs.front() && !spec.repeated)
        return primary;
    return primary.parent_path() / (primary.stem().string() + "_" + spec.role + (spec.repeated ? "_" + std::to_string(repeat) : "") +
                                     extensionFor(spec, output.data, primary.extension().string()));
}

//! Every place an output will go, checked (and --out-dir created) before the
//! inputs are read: a refused output must not cost the run.
void checkOutputPlaces(const ToolSpec& tool, const OutputPlaces& places, const std::string& report, const io::FormatRegistry& formats)
{
    const auto isEntity = [](const OutputSpec& spec) { return spec.kind == DataKind::Cloud || spec.kind == DataKind::Mesh; };
    if (!places.directory.empty())
        prepareOutputFolder(places.directory);
    if (!places.primary.empty()) {
        const OutputSpec& first = tool.outputs.front();
        checkOutputFile(places.primary, isEntity(first) && !first.repeated ? &formats : nullptr);
    }
    for (const auto& spec : tool.outputs) {
        const auto own = places.byRole.find(spec.role);
        if (own != places.byRole.end() && !own->second.empty())
            checkOutputFile(own->second, isEntity(spec) ? &formats : nullptr);
    }
    if (!report.empty())
        checkOutputFile(report);
}

//! The run as JSON: what --report writes (tables and matrices by role).
nlohmann::json reportJson(const ToolSpec& tool, const ToolResult& result, double seconds)
{
    nlohmann::json tables = nlohmann::json::object(), matrices = nlohmann::json::object();
    for (const ToolOutput& output : result.outputs) {
        if (const auto* table = std::get_if<Table>(&output.data)) {
            nlohmann::json rows = nlohmann::json::array();
            for (const auto& row : table->rows) {
                nlohmann::json cells = nlohmann::json::array();
                for (const auto& cell : row) {
                    if (const auto* number = std::get_if<double>(&cell))
                        cells.push_back(std::isfinite(*number) ? nlohmann::json(*number) : nlohmann::json(nullptr));
                    else
                        cells.push_back(std::get<std::string>(cell));
                }
                rows.push_back(cells);
            }
            tables[output.role] = {{"columns", table->columns}, {"rows", rows}};
        } else if (const auto* matrix = std::get_if<Eigen::Matrix4d>(&output.data)) {
            nlohmann::json m = nlohmann::json::array();
            for (int r = 0; r < 4; ++r)
                m.push_back({(*matrix)(r, 0), (*matrix)(r, 1), (*matrix)(r, 2), (*matrix)(r, 3)});
            matrices[output.role] = m;
        }
    }
    return {{"tool", tool.name}, {"summary", result.summary}, {"seconds", seconds}, {"tables", tables}, {"matrices", matrices}};
}

std::string outputHelp(const ToolSpec& tool)
{
    std::string help = "Output file (nothing is written without it or --out-dir; tables and matrices are then printed):";
    for (const auto& o : tool.outputs)
        help += " " + std::string(&o == &tool.outputs.front() && !o.repeated ? "FILE" : "FILE_" + o.role) + " = " + o.label + " (" +
                kindName(o.kind) + (o.repeated ? ", one per entity" : "") + ")" + (&o == &tool.outputs.back() ? "" : ";");
    return help;
}

//! Reads every input file of the command line, in declaration order.
struct LoadedInputs
{
    std::vector<std::unique_ptr<Entity>> entities; // stable addresses for ToolInputs
    std::vector<std::unique_ptr<Drawing>> drawings;
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
            if (spec.kind == DataKind::Drawing) {
                loaded.drawings.push_back(std::make_unique<Drawing>(io::readDrawingDxf(path, options.progress)));
                loaded.inputs.add(spec.role, *loaded.drawings.back());
                continue;
            }
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
            streams.out << table->toText();
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
    } else if (const auto* drawing = std::get_if<Drawing>(&output.data)) {
        io::writeDrawingDxf(*drawing, path);
    } else if (const auto* document = std::get_if<TextDocument>(&output.data)) {
        io::AtomicFile file(path);
        file.stream() << document->text;
        file.commit();
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
        std::string output, report;
        OutputPlaces places;
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
    if (!tool.outputs.empty()) {
        command->add_option("-o,--output", args->output, outputHelp(tool));
        command->add_option("--out-dir", args->places.directory,
                            "Write every output into this folder (created when missing): DIR/ROLE.ext, one file per entity of a repeated output");
        for (const auto& o : tool.outputs)
            if (&o != &tool.outputs.front() && !o.repeated)
                command->add_option("--" + o.role + "-out", args->places.byRole[o.role], "Write the " + o.label + " to this file");
        command->add_option("--report", args->report, "Write the run's summary, tables and matrices as JSON to this file");
    }
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
        OutputPlaces places = args->places;
        places.primary = args->output;
        checkOutputPlaces(*toolPtr, places, args->report, registry.formats);
        TerminalProgress progress;
        LoadedInputs loaded;
        loadInputs(*toolPtr, args->inputs, registry, args->read.toOptions(&progress), loaded);
        const auto start = std::chrono::steady_clock::now();
        ToolResult result = toolPtr->execute(loaded.inputs, values, &progress);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        streams.out << toolPtr->name << ": " << result.summary << " [" << std::fixed << std::setprecision(3) << seconds << " s]\n";
        streams.out.unsetf(std::ios::floatfield);
        const io::WriteOptions writeOptions = args->write.toOptions(&progress);
        if (!args->report.empty()) {
            // Written first: the outputs below may move data out of the result.
            io::AtomicFile file(args->report);
            file.stream() << reportJson(*toolPtr, result, seconds).dump(2) << '\n';
            file.commit();
            streams.out << "wrote " << args->report << " (report)\n";
        }
        for (const auto& spec : toolPtr->outputs) {
            std::size_t repeat = 0;
            for (ToolOutput* output : result.findAll(spec.role)) {
                emitOutput(spec, *output, outputPath(*toolPtr, spec, *output, places, repeat), loaded, *toolPtr, registry, writeOptions,
                           streams);
                ++repeat;
                if (!spec.repeated)
                    break;
            }
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
