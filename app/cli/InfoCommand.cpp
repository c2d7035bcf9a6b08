// SPDX-License-Identifier: GPL-3.0-or-later
#include "CliSupport.h"
#include "Commands.h"

#include <scandiff/io/CoordinateSystem.h>

#include <nlohmann/json.hpp>

#include <iomanip>
#include <memory>

namespace scandiff::cli {

namespace {

nlohmann::json vectorJson(const Eigen::Vector3d& v)
{
    return nlohmann::json::array({v.x(), v.y(), v.z()});
}

//! NaN has no JSON spelling: an empty field reports null.
nlohmann::json numberOrNull(double v)
{
    return std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(v);
}

nlohmann::json describe(const io::Entity& entity, const std::string& file)
{
    const PointCloud& cloud = std::holds_alternative<Mesh>(entity) ? std::get<Mesh>(entity).vertices : std::get<PointCloud>(entity);
    nlohmann::json j;
    j["file"] = file;
    j["type"] = std::holds_alternative<Mesh>(entity) ? "mesh" : "cloud";
    j["points"] = cloud.size();
    if (const auto* mesh = std::get_if<Mesh>(&entity)) {
        j["triangles"] = mesh->triangles.size();
        j["degenerate_triangles"] = mesh->countDegenerateTriangles();
    }
    j["global_shift"] = vectorJson(cloud.origin());
    j["crs"] = cloud.crsWkt().empty() ? nlohmann::json(nullptr) : nlohmann::json(io::crsName(cloud.crsWkt()));
    j["crs_wkt"] = cloud.crsWkt().empty() ? nlohmann::json(nullptr) : nlohmann::json(cloud.crsWkt());
    const BoundingBox box = cloud.bounds();
    if (box.empty)
        j["bounds"] = nullptr;
    else
        j["bounds"] = {{"min", vectorJson(box.min)}, {"max", vectorJson(box.max)}};
    j["colors"] = cloud.hasColors();
    j["normals"] = cloud.hasNormals();
    j["sensors"] = cloud.sensors().size();
    j["fields"] = nlohmann::json::array();
    for (const auto& f : cloud.fields()) {
        const ValueRange r = f.range();
        j["fields"].push_back({{"name", f.name()}, {"min", numberOrNull(r.min)}, {"max", numberOrNull(r.max)}, {"valid", r.validCount}});
    }
    return j;
}

void printText(const nlohmann::json& j, std::ostream& out)
{
    out << std::setprecision(10);
    out << "file:          " << j["file"].get<std::string>() << '\n';
    out << "type:          " << j["type"].get<std::string>() << '\n';
    out << "points:        " << j["points"].get<std::size_t>() << '\n';
    if (j.contains("triangles")) {
        out << "triangles:     " << j["triangles"].get<std::size_t>();
        if (j["degenerate_triangles"].get<std::size_t>() > 0)
            out << " (" << j["degenerate_triangles"].get<std::size_t>() << " degenerate)";
        out << '\n';
    }
    auto vec = [](const nlohmann::json& v) {
        std::ostringstream s;
        s << std::fixed << std::setprecision(3) << v[0].get<double>() << ", " << v[1].get<double>() << ", " << v[2].get<double>();
        return s.str();
    };
    out << "global shift:  " << vec(j["global_shift"]) << '\n';
    out << "crs:           " << (j["crs"].is_null() ? std::string("(none)") : j["crs"].get<std::string>()) << '\n';
    if (j["bounds"].is_null())
        out << "bounds:        (empty)\n";
    else
        out << "bounds min:    " << vec(j["bounds"]["min"]) << "\nbounds max:    " << vec(j["bounds"]["max"]) << '\n';
    out << "colours:       " << (j["colors"].get<bool>() ? "yes" : "no") << '\n';
    out << "normals:       " << (j["normals"].get<bool>() ? "yes" : "no") << '\n';
    if (j["sensors"].get<std::size_t>() > 0)
        out << "sensor poses:  " << j["sensors"].get<std::size_t>() << '\n';
    out << "scalar fields: " << j["fields"].size() << '\n';
    for (const auto& f : j["fields"]) {
        out << "  " << std::left << std::setw(24) << f["name"].get<std::string>() << std::right;
        if (f["min"].is_null())
            out << " (no value)\n";
        else
            out << " min " << f["min"].get<double>() << "  max " << f["max"].get<double>() << "  (" << f["valid"].get<std::size_t>() << " values)\n";
    }
}

} // namespace

void addInfoCommand(CLI::App& app, const PluginRegistry& registry, Streams streams)
{
    struct Args
    {
        std::string file;
        bool json = false;
        ReadFlags read;
    };
    auto args = std::make_shared<Args>();
    CLI::App* command = app.add_subcommand("info", "Describe a cloud or mesh file: counts, bounds, global shift, fields with min/max");
    command->add_option("FILE", args->file, "Input file")->required();
    command->add_flag("--json", args->json, "Print JSON instead of text");
    args->read.addTo(*command);
    command->callback([args, &registry, streams] {
        TerminalProgress progress;
        const io::Entity entity = io::readFile(registry.formats, args->file, args->read.toOptions(&progress));
        const nlohmann::json j = describe(entity, args->file);
        if (args->json)
            streams.out << j.dump(2) << '\n';
        else
            printText(j, streams.out);
    });
}

} // namespace scandiff::cli
