// SPDX-License-Identifier: GPL-3.0-or-later
#include "CliSupport.h"
#include "Commands.h"

#include <scandiff/core/Error.h>
#include <scandiff/io/CoordinateSystem.h>
#include <scandiff/io/E57.h>

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

nlohmann::json poseJson(const std::optional<io::E57Pose>& pose)
{
    if (!pose)
        return nullptr;
    const Eigen::Quaterniond& q = pose->rotation;
    return {{"translation", vectorJson(pose->translation)}, {"rotation_wxyz", {q.w(), q.x(), q.y(), q.z()}}};
}

//! The scans and images of an E57 file, as its XML section lists them.
nlohmann::json describeE57(const io::E57Summary& summary)
{
    nlohmann::json j;
    j["guid"] = summary.guid;
    j["written_by"] = summary.libraryVersion;
    j["scans"] = nlohmann::json::array();
    for (const io::E57ScanSummary& scan : summary.scans) {
        nlohmann::json s = {{"name", scan.name}, {"guid", scan.guid}, {"records", scan.recordCount}, {"pose", poseJson(scan.pose)},
                            {"coordinates", scan.spherical ? "spherical" : "cartesian"}, {"fields", scan.fields}};
        if (scan.intensityLimits)
            s["intensity_limits"] = {scan.intensityLimits->first, scan.intensityLimits->second};
        j["scans"].push_back(std::move(s));
    }
    j["images"] = nlohmann::json::array();
    for (const io::E57ImageSummary& image : summary.images)
        j["images"].push_back({{"name", image.name}, {"representation", image.representation}, {"format", image.format},
                               {"width", image.width}, {"height", image.height}, {"bytes", image.byteLength}, {"pose", poseJson(image.pose)}});
    return j;
}

void printE57(const nlohmann::json& j, std::ostream& out)
{
    auto pose = [](const nlohmann::json& p) {
        if (p.is_null())
            return std::string("no pose");
        std::ostringstream s;
        const auto& t = p["translation"];
        const auto& q = p["rotation_wxyz"];
        s << std::setprecision(10) << "at " << t[0].get<double>() << ", " << t[1].get<double>() << ", " << t[2].get<double>()
          << "  rotation (w x y z) " << q[0].get<double>() << " " << q[1].get<double>() << " " << q[2].get<double>() << " "
          << q[3].get<double>();
        return s.str();
    };
    out << "E57 scans:     " << j["scans"].size() << '\n';
    std::size_t index = 0;
    for (const auto& s : j["scans"]) {
        out << "  [" << index++ << "] '" << s["name"].get<std::string>() << "'  " << s["records"].get<std::uint64_t>() << " records, "
            << s["coordinates"].get<std::string>() << ", " << pose(s["pose"]) << '\n';
        std::string fields;
        for (const auto& f : s["fields"])
            fields += (fields.empty() ? "" : " ") + f.get<std::string>();
        out << "      fields: " << fields << '\n';
    }
    out << "E57 images:    " << j["images"].size() << '\n';
    index = 0;
    for (const auto& i : j["images"])
        out << "  [" << index++ << "] '" << i["name"].get<std::string>() << "'  " << i["representation"].get<std::string>() << ' '
            << i["format"].get<std::string>() << ' ' << i["width"].get<std::int64_t>() << " x " << i["height"].get<std::int64_t>() << ", "
            << i["bytes"].get<std::uint64_t>() << " bytes, " << pose(i["pose"]) << '\n';
}

void printText(const nlohmann::json& j, std::ostream& out)
{
    if (!j.contains("type")) {
        out << "file:          " << j["file"].get<std::string>() << '\n';
        printE57(j["e57"], out);
        return;
    }
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
    if (j.contains("e57"))
        printE57(j["e57"], out);
}

} // namespace

void addInfoCommand(CLI::App& app, const PluginRegistry& registry, Streams streams)
{
    struct Args
    {
        std::string file;
        bool json = false;
        std::string imageFolder;
        ReadFlags read;
    };
    auto args = std::make_shared<Args>();
    CLI::App* command = app.add_subcommand("info", "Describe a cloud or mesh file: counts, bounds, global shift, fields with min/max; an E57 file's scans (pose, counts) and images");
    command->add_option("FILE", args->file, "Input file")->required();
    command->add_flag("--json", args->json, "Print JSON instead of text");
    command->add_option("--extract-images", args->imageFolder, "E57: write the file's images (JPEG/PNG) into this folder");
    args->read.addTo(*command);
    command->callback([args, &registry, streams] {
        TerminalProgress progress;
        nlohmann::json j;
        if (io::lowerExtension(args->file) == "e57") {
            // Every scan and image the file lists; the points (all scans together) only when there are some.
            const io::E57Summary summary = io::inspectE57(args->file);
            if (!summary.scans.empty())
                j = describe(io::readFile(registry.formats, args->file, args->read.toOptions(&progress)), args->file);
            else
                j["file"] = args->file;
            j["e57"] = describeE57(summary);
            if (!args->imageFolder.empty())
                for (const auto& written : io::extractE57Images(args->file, args->imageFolder))
                    streams.err << "wrote " << written.string() << '\n';
        } else {
            if (!args->imageFolder.empty())
                throw scandiff::Error(ErrorCode::InvalidArgument, "--extract-images: only E57 files hold images");
            j = describe(io::readFile(registry.formats, args->file, args->read.toOptions(&progress)), args->file);
        }
        if (args->json)
            streams.out << j.dump(2) << '\n';
        else
            printText(j, streams.out);
    });
}

} // namespace scandiff::cli
