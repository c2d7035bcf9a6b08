// SPDX-License-Identifier: GPL-3.0-or-later
// `segment` and `compare`: change regions from a distance field (thesis 000
// chapter 3), and the whole chain c2c + segment in one command for batch users.
#include "CliSupport.h"
#include "Commands.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToCloud.h>
#include <scandiff/core/distance/DistanceParameters.h>
#include <scandiff/core/distance/M3C2.h>
#include <scandiff/core/segmentation/RegionReport.h>
#include <scandiff/core/segmentation/SegmentationParameters.h>
#include <scandiff/io/RegionExport.h>

#include <chrono>
#include <cstdio>
#include <iomanip>
#include <memory>

namespace scandiff::cli {

namespace {

//! Options of the export shared by both commands.
struct ExportFlags
{
    std::string outDir;
    bool dxfPoints = false;
    double textHeight = 0.0;
    std::string cloudFormat = "ply";

    void addTo(CLI::App& command)
    {
        command.add_option("--out-dir", outDir, "Output folder: regions.ply, region_NNNN.ply, regions.dxf, regions.csv")->required();
        command.add_flag("--dxf-points", dxfPoints, "Also draw each region's points in the DXF");
        command.add_option("--dxf-text-height", textHeight, "Height of the DXF labels (m); default 3 % of the region's size")
            ->check(CLI::PositiveNumber);
        command.add_option("--cloud-format", cloudFormat, "Extension of the region clouds (default ply)");
    }

    //! The folder created and the region clouds' format checked before anything is read.
    void prepare(const io::FormatRegistry& formats) const
    {
        prepareOutputFolder(outDir);
        checkOutputFile(std::filesystem::path(outDir) / ("regions." + cloudFormat), &formats);
    }
};

//! The segmentation options: the declared parameters, with `range` taking the
//! issue's two-value form `--range A B`.
std::shared_ptr<std::map<std::string, std::string>> addSegmentationOptions(CLI::App& command)
{
    auto values = std::make_shared<std::map<std::string, std::string>>();
    auto options = addParameterOptions(command, segmentationParameters(), values);
    for (const char* a : {"range", "above", "kmeans", "stat-test"})
        for (const char* b : {"range", "above", "kmeans", "stat-test", "propagate"})
            if (std::string(a) != b)
                options.at(a)->excludes(options.at(b));
    options.at("fit-box")->excludes(options.at("noise"));
    return values;
}

//! Segments `cloud` (adding the fields), reports and exports the regions, and
//! prints what was done.
void segmentAndExport(PointCloud& cloud, const ParameterValues& values, const PointCloud* reference, const ExportFlags& flags,
                      const io::FormatRegistry& formats, const io::WriteOptions& write, ProgressObserver* progress, Streams streams)
{
    const auto start = std::chrono::steady_clock::now();
    SegmentationRun run = runSegmentation(cloud, values, progress);
    streams.out << "segment " << run.summary << '\n';
    attachFields(cloud, std::move(run));
    const std::vector<RegionStatistics> report = regionReport(cloud, regionReportSettings(values, reference), progress);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (const RegionStatistics& r : report)
        streams.out << "  " << io::regionLabel(r) << '\n';
    streams.out << std::fixed << std::setprecision(3) << seconds << " s\n" << std::defaultfloat;

    io::RegionExportOptions options;
    options.dxf.includePoints = flags.dxfPoints;
    options.dxf.textHeight = flags.textHeight;
    options.write = write;
    options.cloudExtension = flags.cloudFormat;
    const io::RegionExportFiles files = io::exportRegions(formats, cloud, report, flags.outDir, options);
    streams.out << "wrote " << files.allRegions.string() << ", " << files.regionClouds.size() << " region clouds, "
                << files.dxf.string() << ", " << files.csv.string() << '\n';
}

} // namespace

void addSegmentCommand(CLI::App& app, const PluginRegistry& registry, Streams streams)
{
    struct Args
    {
        std::string input, reference;
        std::shared_ptr<std::map<std::string, std::string>> values;
        ExportFlags exportFlags;
        int threads = 0;
        ReadFlags read;
        WriteFlags write;
    };
    auto args = std::make_shared<Args>();
    CLI::App* c = app.add_subcommand(
        "segment", "Segment the changes of a distance field into regions and export them (thesis 000 chapter 3)");
    c->add_option("IN", args->input, "Cloud holding the field (e.g. the output of c2c)")->required();
    args->values = addSegmentationOptions(*c);
    c->add_option("--reference", args->reference, "The other epoch: adds the volume between the epochs to the report");
    args->exportFlags.addTo(*c);
    ThreadLimit::addOption(*c, args->threads);
    args->read.addTo(*c);
    args->write.addTo(*c);
    c->callback([args, &registry, streams] {
        const ThreadLimit threadLimit(args->threads);
        // Parameters are checked before the (possibly long) reads.
        const ParameterValues values = resolveParameters(segmentationParameters(), *args->values, "segment");
        args->exportFlags.prepare(registry.formats);
        TerminalProgress progress;
        const io::ReadOptions readOptions = args->read.toOptions(&progress);
        PointCloud cloud = io::readPointCloud(registry.formats, args->input, readOptions);
        std::optional<PointCloud> reference;
        if (!args->reference.empty())
            reference = io::readPointCloud(registry.formats, args->reference, readOptions);
        segmentAndExport(cloud, values, reference ? &*reference : nullptr, args->exportFlags, registry.formats,
                         args->write.toOptions(&progress), &progress, streams);
    });
}

namespace {

//! compare --method m3c2 segments the significant changes, reported with
//! their distances, unless told otherwise.
std::map<std::string, std::string> withM3c2SegmentDefaults(std::map<std::string, std::string> segmentText)
{
    segmentText.emplace("field", fields::kM3c2Significant);
    if (!segmentText.count("range") && !segmentText.count("kmeans") && !segmentText.count("stat-test") &&
        !segmentText.count("propagate") && segmentText["field"] == fields::kM3c2Significant)
        segmentText.emplace("above", "0.5");
    segmentText.emplace("components", "true");
    segmentText.emplace("report-field", fields::kM3c2Distance);
    return segmentText;
}

//! compare --method m3c2: the m3c2 tool (its declaration, as `scandiff-cli
//! m3c2` and the workbench run it), then the significant core points
//! segmented and exported; DIR/core_points.EXT holds every M3C2 field and the
//! regions, DIR/m3c2_raster.tif the raster when --raster-cell is given.
void compareByM3c2(const ToolSpec& tool, const ParameterValues& m3c2Values, const std::string& corePointsFile,
                   const ParameterValues& segmentValues, const PointCloud& reference, const PointCloud& compared,
                   const ExportFlags& flags, const PluginRegistry& registry, const io::ReadOptions& readOptions,
                   const io::WriteOptions& write, TerminalProgress& progress, Streams streams)
{
    std::optional<PointCloud> corePoints;
    if (!corePointsFile.empty())
        corePoints = io::readPointCloud(registry.formats, corePointsFile, readOptions);
    ToolInputs inputs;
    inputs.add("reference", reference);
    inputs.add("compared", compared);
    if (corePoints)
        inputs.add("core-points", *corePoints);
    ToolResult result = tool.execute(inputs, m3c2Values, &progress);
    streams.out << "m3c2: " << result.summary << '\n';
    PointCloud& cores = std::get<PointCloud>(result.find("output")->data);
    segmentAndExport(cores, segmentValues, nullptr, flags, registry.formats, write, &progress, streams);

    const std::filesystem::path dir(flags.outDir);
    const std::filesystem::path coreFile = dir / ("core_points." + flags.cloudFormat);
    io::writePointCloud(registry.formats, cores, coreFile, write);
    streams.out << "wrote " << coreFile.string() << '\n';
    if (ToolOutput* raster = result.find("raster")) {
        const std::filesystem::path rasterFile = dir / "m3c2_raster.tif";
        io::writePointCloud(registry.formats, std::get<PointCloud>(raster->data), rasterFile, write);
        streams.out << "wrote " << rasterFile.string() << '\n';
    }
}

} // namespace

void addCompareCommand(CLI::App& app, const PluginRegistry& registry, Streams streams)
{
    struct Args
    {
        std::string reference, compared, method = "c2c", corePoints;
        std::shared_ptr<std::map<std::string, std::string>> distanceValues = std::make_shared<std::map<std::string, std::string>>();
        std::shared_ptr<std::map<std::string, std::string>> m3c2Values = std::make_shared<std::map<std::string, std::string>>();
        std::map<std::string, std::string> m3c2Renamed; // option name -> the m3c2 parameter it stands for
        std::shared_ptr<std::map<std::string, std::string>> segmentValues;
        ExportFlags exportFlags;
        int threads = 0;
        ReadFlags read;
        WriteFlags write;
    };
    auto args = std::make_shared<Args>();
    CLI::App* c = app.add_subcommand("compare",
                                     "The whole change detection in one command: c2c or M3C2 distances, then segment, then "
                                     "export (DIR/compared.ply, or DIR/core_points.ply for M3C2, with every field, and the "
                                     "region files of segment)");
    c->add_option("--reference", args->reference, "Reference cloud (the earlier epoch)")->required();
    c->add_option("--compared", args->compared, "Compared cloud (the later epoch)")->required();
    c->add_option("--method", args->method,
                  "c2c (default): nearest-neighbour distances, segmented as you choose; m3c2: M3C2 at core points, its "
                  "significant changes segmented into regions (default --field m3c2_significant --above 0.5 --components "
                  "--report-field m3c2_distance), each with its volume +/- uncertainty")
        ->check(CLI::IsMember({"c2c", "m3c2"}));
    const auto distanceOptions = addParameterOptions(*c, cloudToCloudParameters(), args->distanceValues);
    distanceOptions.at("knn")->excludes(distanceOptions.at("radius"));
    args->segmentValues = addSegmentationOptions(*c);
    // The m3c2 tool's own parameters; a name c2c or segment already uses
    // (min-points) gets the prefix m3c2-. Required only with --method m3c2.
    const ToolSpec* m3c2Tool = registry.tools.find("m3c2");
    if (m3c2Tool) {
        std::vector<ParameterSpec> m3c2Parameters = m3c2Tool->parameters;
        for (ParameterSpec& p : m3c2Parameters) {
            const std::string original = p.name;
            if (c->get_option_no_throw("--" + p.name))
                p.name = "m3c2-" + p.name;
            p.required = false;
            args->m3c2Renamed[p.name] = original;
        }
        addParameterOptions(*c, m3c2Parameters, args->m3c2Values);
        c->add_option("--core-points", args->corePoints, "m3c2: where to measure (default: every reference point, or --core-spacing)");
    }
    args->exportFlags.addTo(*c);
    ThreadLimit::addOption(*c, args->threads);
    args->read.addTo(*c);
    args->write.addTo(*c);
    c->callback([args, &registry, streams, m3c2Tool] {
        const ThreadLimit threadLimit(args->threads);
        const bool m3c2 = args->method == "m3c2";
        if (m3c2 && !args->distanceValues->empty())
            throw Error(ErrorCode::InvalidArgument, "compare: --" + args->distanceValues->begin()->first + " is a c2c option; drop it with --method m3c2");
        if (!m3c2 && (!args->m3c2Values->empty() || !args->corePoints.empty()))
            throw Error(ErrorCode::InvalidArgument, "compare: --" + (args->corePoints.empty() ? args->m3c2Values->begin()->first : std::string("core-points")) +
                                                        " is an M3C2 option; add --method m3c2");
        if (m3c2 && !m3c2Tool)
            throw Error(ErrorCode::Unsupported, "compare: this build has no m3c2 tool");
        args->exportFlags.prepare(registry.formats);
        TerminalProgress progress;
        const io::ReadOptions readOptions = args->read.toOptions(&progress);
        const io::WriteOptions write = args->write.toOptions(&progress);
        if (m3c2) {
            std::map<std::string, std::string> m3c2Text;
            for (const auto& [name, text] : *args->m3c2Values)
                m3c2Text[args->m3c2Renamed.at(name)] = text;
            // Bad parameters are reported before the (possibly long) reads.
            const ParameterValues m3c2Values = m3c2Tool->resolve(m3c2Text);
            const ParameterValues segmentValues =
                resolveParameters(segmentationParameters(), withM3c2SegmentDefaults(*args->segmentValues), "compare");
            const PointCloud reference = io::readPointCloud(registry.formats, args->reference, readOptions);
            const PointCloud compared = io::readPointCloud(registry.formats, args->compared, readOptions);
            compareByM3c2(*m3c2Tool, m3c2Values, args->corePoints, segmentValues, reference, compared, args->exportFlags, registry,
                          readOptions, write, progress, streams);
            return;
        }
        const ParameterValues distanceValues = resolveParameters(cloudToCloudParameters(), *args->distanceValues, "compare");
        const ParameterValues segmentValues = resolveParameters(segmentationParameters(), *args->segmentValues, "compare");
        PointCloud reference = io::readPointCloud(registry.formats, args->reference, readOptions);
        PointCloud compared = io::readPointCloud(registry.formats, args->compared, readOptions);
        CloudToCloudRun run = runCloudToCloud(compared, reference, distanceValues, &progress);
        printStatistics(streams.out, "c2c " + std::string(localModelName(run.params.model)) + " (compared -> reference)",
                        run.forward.statistics);
        std::optional<PointCloud> closest = std::move(run.forward.closest);
        attachFields(compared, std::move(run.forward));
        segmentAndExport(compared, segmentValues, &reference, args->exportFlags, registry.formats, write, &progress, streams);

        const std::filesystem::path dir(args->exportFlags.outDir);
        const std::string ext = "." + args->exportFlags.cloudFormat;
        io::writePointCloud(registry.formats, compared, dir / ("compared" + ext), write);
        streams.out << "wrote " << (dir / ("compared" + ext)).string() << '\n';
        if (closest) {
            io::writePointCloud(registry.formats, *closest, dir / ("closest" + ext), write);
            streams.out << "wrote " << (dir / ("closest" + ext)).string() << '\n';
        }
        if (run.reverse) {
            printStatistics(streams.out, "c2c reverse (reference -> compared)", run.reverse->statistics);
            attachFields(reference, std::move(*run.reverse));
            io::writePointCloud(registry.formats, reference, dir / ("reference" + ext), write);
            streams.out << "wrote " << (dir / ("reference" + ext)).string() << '\n';
        }
    });
}

} // namespace scandiff::cli
