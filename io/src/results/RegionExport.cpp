// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/io/AtomicFile.h>
#include <scandiff/io/DxfWriter.h>
#include <scandiff/io/RegionExport.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <sstream>

namespace scandiff::io {

namespace {

//! A number for the CSV: empty when missing, otherwise round-trip precise.
std::string csvNumber(double v)
{
    if (!std::isfinite(v))
        return {};
    char text[64];
    std::snprintf(text, sizeof text, "%.10g", v);
    return text;
}

std::string coordinate(double v)
{
    char text[64];
    std::snprintf(text, sizeof text, "%.6f", v); // micrometres, even for UTM coordinates
    return text;
}

std::string shortNumber(double v)
{
    char text[64];
    std::snprintf(text, sizeof text, "%.3f", v);
    return text;
}

} // namespace

std::string regionLayerName(int id)
{
    char text[32];
    std::snprintf(text, sizeof text, "REGION_%04d", id);
    return text;
}

std::string regionLabel(const RegionStatistics& r)
{
    std::ostringstream s;
    s << "R" << r.id << ": " << r.pointCount << " pts";
    if (r.distanceCount > 0)
        s << ", mean " << shortNumber(r.meanDistance) << " m, max " << shortNumber(r.maxDistance) << " m, RMS "
          << shortNumber(r.rmsDistance) << " m";
    s << ", footprint " << shortNumber(r.footprintArea) << " m2";
    if (std::abs(r.outlineArea - r.footprintArea) > 0.05 * r.outlineArea)
        s << " (" << shortNumber(r.outlineArea) << " m2 in its plane)"; // a wall, a slope
    if (r.volume) {
        s << ", volume " << shortNumber(*r.volume) << " m3";
        if (r.volumeAdded > 0 && r.volumeRemoved > 0)
            s << " (+" << shortNumber(r.volumeAdded) << " -" << shortNumber(r.volumeRemoved) << ")";
        if (r.volumeCoverage < 0.999)
            s << " over " << shortNumber(100.0 * r.volumeCoverage) << " % of it";
    }
    if (r.distanceVolume)
        s << ", volume along the distances " << shortNumber(*r.distanceVolume) << " +/- " << shortNumber(*r.distanceVolumeUncertainty)
          << " m3";
    return s.str();
}

void writeRegionsDxf(const PointCloud& cloud, const std::vector<RegionStatistics>& regions, const std::filesystem::path& path,
                     const RegionDxfOptions& options, const std::string& regionField)
{
    if (!(options.textHeight >= 0.0 && std::isfinite(options.textHeight)))
        throw Error(ErrorCode::InvalidArgument, "region DXF: the text height must be > 0 (0: automatic)");
    std::map<int, std::vector<std::size_t>> members;
    if (options.includePoints) {
        const ScalarField* ids = cloud.field(regionField);
        if (!ids)
            throw Error(ErrorCode::InvalidArgument, "region DXF: cloud '" + cloud.name + "' has no field '" + regionField + "'");
        for (std::size_t i = 0; i < cloud.size(); ++i)
            if (ids->hasValue(i) && cloud.positions()[i].allFinite())
                members[static_cast<int>(std::lround(ids->value(i)))].push_back(i);
    }
    DxfDrawing drawing;
    for (const RegionStatistics& r : regions) {
        const std::string layer = regionLayerName(r.id);
        // Six plain AutoCAD colours (red, yellow, green, cyan, blue, magenta) in turn.
        drawing.addLayer(layer, 1 + (r.id - 1 + 6000) % 6);
        if (r.outlines.empty())
            throw Error(ErrorCode::InvalidArgument, "region DXF: region " + std::to_string(r.id) + " has no outline");
        for (const auto& ring : r.outlines)
            drawing.addPolyline(layer, ring, true);
        const double diagonal = (r.bounds.max - r.bounds.min).norm();
        const double height = options.textHeight > 0 ? options.textHeight : std::max(0.05, 0.03 * diagonal);
        // The label sits above the region, starting over its centroid.
        const Eigen::Vector3d at(r.centroid.x(), r.centroid.y(), r.bounds.max.z() + height);
        drawing.addText(layer, at, height, regionLabel(r));
        if (options.includePoints)
            for (std::size_t i : members[r.id])
                drawing.addPoint(layer, cloud.globalPosition(i));
    }
    drawing.write(path);
}

void writeRegionsCsv(const std::vector<RegionStatistics>& regions, const std::filesystem::path& path)
{
    AtomicFile file(path);
    std::ofstream& out = file.stream();
    out << "id,points,min_x,min_y,min_z,max_x,max_y,max_z,centroid_x,centroid_y,centroid_z,normal_x,normal_y,normal_z,"
           "footprint_area,outline_area,distance_count,mean_distance,max_distance,rms_distance,volume,volume_added,volume_removed,"
           "volume_coverage,distance_volume,distance_volume_uncertainty\n";
    for (const RegionStatistics& r : regions) {
        out << r.id << ',' << r.pointCount;
        for (const Eigen::Vector3d* v : {&r.bounds.min, &r.bounds.max, &r.centroid})
            for (int a = 0; a < 3; ++a)
                out << ',' << coordinate((*v)[a]);
        for (int a = 0; a < 3; ++a)
            out << ',' << csvNumber(r.planeNormal[a]);
        out << ',' << csvNumber(r.footprintArea) << ',' << csvNumber(r.outlineArea) << ',' << r.distanceCount << ','
            << csvNumber(r.meanDistance) << ',' << csvNumber(r.maxDistance) << ',' << csvNumber(r.rmsDistance);
        for (double value : {r.volume.value_or(0.0), r.volumeAdded, r.volumeRemoved, r.volumeCoverage})
            out << ',' << (r.volume ? csvNumber(value) : std::string());
        for (const std::optional<double>& value : {r.distanceVolume, r.distanceVolumeUncertainty})
            out << ',' << (value ? csvNumber(*value) : std::string());
        out << '\n';
    }
    file.commit();
}

namespace {

//! A folder beside the export's files where they are written first, removed
//! with whatever it holds when the export stops early.
class StagingFolder
{
public:
    explicit StagingFolder(const std::filesystem::path& dir)
    {
        std::random_device random;
        for (int attempt = 0; attempt < 100; ++attempt) {
            char name[64];
            std::snprintf(name, sizeof name, ".scandiff-export-%08x", static_cast<unsigned>(random()));
            std::error_code ec;
            if (std::filesystem::create_directory(dir / name, ec)) {
                path_ = dir / name;
                return;
            }
            if (ec)
                throw Error(ErrorCode::Io, "cannot create a working folder in '" + dir.string() + "': " + ec.message());
        }
        throw Error(ErrorCode::Io, "cannot create a working folder in '" + dir.string() + "'");
    }
    StagingFolder(const StagingFolder&) = delete;
    StagingFolder& operator=(const StagingFolder&) = delete;
    ~StagingFolder()
    {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

} // namespace

RegionExportFiles exportRegions(const FormatRegistry& registry, const PointCloud& cloud, const std::vector<RegionStatistics>& regions,
                                const std::filesystem::path& dir, const RegionExportOptions& options)
{
    const ScalarField* ids = cloud.field(options.regionField);
    if (!ids)
        throw Error(ErrorCode::InvalidArgument, "region export: cloud '" + cloud.name + "' has no field '" + options.regionField + "'");
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec)
        throw Error(ErrorCode::Io, "cannot create the folder '" + dir.string() + "': " + ec.message());
    // Check the extension before writing anything.
    (void)registry.forPath(dir / ("regions." + options.cloudExtension));

    std::map<int, std::vector<std::size_t>> members = pointsByRegion(*ids);
    std::vector<std::size_t> all;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (ids->hasValue(i))
            all.push_back(i);

    // Every file is written in a staging folder first and moved into `dir` once
    // all are complete: a cancelled or failed export leaves `dir` as it was
    // (no new file, and a previous export's files untouched).
    const StagingFolder staging(dir);
    std::vector<std::string> names;
    names.push_back("regions." + options.cloudExtension);
    PointCloud allCloud = cloud.subset(all);
    allCloud.name = cloud.name.empty() ? "regions" : cloud.name + " regions";
    writePointCloud(registry, allCloud, staging.path() / names.back(), options.write);
    for (const RegionStatistics& r : regions) {
        char name[64];
        std::snprintf(name, sizeof name, "region_%04d.", r.id);
        names.push_back(name + options.cloudExtension);
        PointCloud part = cloud.subset(members[r.id]);
        part.name = regionLayerName(r.id);
        writePointCloud(registry, part, staging.path() / names.back(), options.write);
    }
    names.push_back("regions.dxf");
    writeRegionsDxf(cloud, regions, staging.path() / names.back(), options.dxf, options.regionField);
    names.push_back("regions.csv");
    writeRegionsCsv(regions, staging.path() / names.back());

    for (const std::string& name : names) {
        std::filesystem::rename(staging.path() / name, dir / name, ec);
        if (ec)
            throw Error(ErrorCode::Io, "cannot move '" + name + "' into '" + dir.string() + "': " + ec.message());
    }
    RegionExportFiles files;
    files.allRegions = dir / names.front();
    for (std::size_t k = 0; k < regions.size(); ++k)
        files.regionClouds.push_back(dir / names[1 + k]);
    files.dxf = dir / "regions.dxf";
    files.csv = dir / "regions.csv";
    return files;
}

} // namespace scandiff::io
