// SPDX-License-Identifier: GPL-3.0-or-later
#include "CliSupport.h"
#include "Commands.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToCloud.h>


#include <chrono>
#include <cmath>
#include <iomanip>
#include <memory>
#include <optional>

namespace scandiff::cli {

namespace {

double radians(double degrees) { return degrees * M_PI / 180.0; }

//! A viewpoint from --sensor X,Y,Z[,HEADING,PITCH,ROLL] (degrees; heading about
//! Z, then pitch about Y, then roll about X), with the shared --sensor-step,
//! --sensor-fov and --sensor-range.
SensorPose parseSensor(const std::string& text, const std::string& step, const std::string& fov, double range)
{
    const std::vector<double> v = parseNumberList(text, "--sensor");
    if (v.size() != 3 && v.size() != 6)
        throw Error(ErrorCode::InvalidArgument, "--sensor: expected X,Y,Z or X,Y,Z,HEADING,PITCH,ROLL (degrees)");
    SensorPose pose;
    pose.position = {v[0], v[1], v[2]};
    if (v.size() == 6)
        pose.orientation = Eigen::AngleAxisd(radians(v[3]), Eigen::Vector3d::UnitZ()) *
                           Eigen::AngleAxisd(radians(v[4]), Eigen::Vector3d::UnitY()) *
                           Eigen::AngleAxisd(radians(v[5]), Eigen::Vector3d::UnitX());
    if (!step.empty()) {
        const std::vector<double> s = parseNumberList(step, "--sensor-step");
        if (s.empty() || s.size() > 2 || s[0] <= 0 || s.back() <= 0)
            throw Error(ErrorCode::InvalidArgument, "--sensor-step: expected DEG or YAWDEG,PITCHDEG, positive");
        pose.yawStep = radians(s[0]);
        pose.pitchStep = radians(s.back());
    }
    if (!fov.empty()) {
        const std::vector<double> f = parseNumberList(fov, "--sensor-fov");
        if (f.size() != 4 || f[0] >= f[1] || f[2] >= f[3])
            throw Error(ErrorCode::InvalidArgument, "--sensor-fov: expected YAWMIN,YAWMAX,PITCHMIN,PITCHMAX in degrees");
        pose.yawMin = radians(f[0]);
        pose.yawMax = radians(f[1]);
        pose.pitchMin = radians(f[2]);
        pose.pitchMax = radians(f[3]);
    }
    if (range > 0)
        pose.maxRange = range;
    return pose;
}

} // namespace

void addCloudToCloudCommand(CLI::App& app, const PluginRegistry& registry, Streams streams)
{
    struct Args
    {
        std::string reference, compared, output;
        std::optional<double> maxDistance;
        bool clamp = false;
        std::string model = "none";
        int knn = CloudToCloudParams{}.neighbours;
        std::optional<double> radius;
        bool split = false, signedDistances = false, bothWays = false, visibility = false;
        std::string closestOutput;
        std::vector<std::string> sensors;
        std::string sensorStep, sensorFov;
        double sensorRange = 0;
        double tolerance = VisibilityParams{}.tolerance;
        int level = 0;
        int threads = 0;
        ReadFlags read;
        WriteFlags write;
    };
    auto args = std::make_shared<Args>();
    CLI::App* c = app.add_subcommand("c2c", "Cloud-to-cloud distance: for each compared point, its distance to the reference cloud (thesis 000 §2.3)");
    c->add_option("--reference", args->reference, "Reference cloud")->required();
    c->add_option("--compared", args->compared, "Compared cloud (the output keeps its points, in order)")->required();
    c->add_option("-o,--output", args->output, "Output: the compared cloud with c2c_distance (nothing is written without it)");
    auto* maxDistance = c->add_option("--max-dist", args->maxDistance, "Points farther than this (m) get NaN, or the maximum with --clamp")
                            ->check(CLI::PositiveNumber);
    c->add_flag("--clamp", args->clamp, "With --max-dist: give farther points the maximum instead of NaN")->needs(maxDistance);
    c->add_option("--model", args->model, "Local model of the reference: none, plane, delaunay, quadric")
        ->check(CLI::IsMember({"none", "plane", "delaunay", "quadric"}));
    auto* knn = c->add_option("--knn", args->knn, "Local model neighbourhood: k nearest (default 12)")->check(CLI::Range(3, 500));
    auto* radius = c->add_option("--radius", args->radius, "Local model neighbourhood: radius (m)")->check(CLI::PositiveNumber);
    knn->excludes(radius);
    c->add_flag("--split-xyz", args->split, "Also write c2c_dx, c2c_dy, c2c_dz");
    c->add_flag("--signed", args->signedDistances, "Signed distances (reference normals or a local model)");
    c->add_option("--closest-points", args->closestOutput, "Write the matched reference points to this file");
    c->add_option("--sensor", args->sensors, "Reference viewpoint X,Y,Z[,HEADING,PITCH,ROLL] (degrees); repeat for several; turns on the visibility test");
    c->add_option("--sensor-step", args->sensorStep, "Angular step of the depth maps, DEG or YAWDEG,PITCHDEG (default: from the data)");
    c->add_option("--sensor-fov", args->sensorFov, "Field of view YAWMIN,YAWMAX,PITCHMIN,PITCHMAX (degrees)");
    c->add_option("--sensor-range", args->sensorRange, "Maximum range of the scanner (m)")->check(CLI::PositiveNumber);
    c->add_flag("--visibility", args->visibility, "Visibility test with the sensor poses stored in the reference file");
    c->add_option("--visibility-tolerance", args->tolerance, "Depth-map tolerance (m), default 0.05")->check(CLI::NonNegativeNumber);
    c->add_flag("--both-ways", args->bothWays, "Also compute reference -> compared (written beside OUT as <name>_reference.<ext>)");
    c->add_option("--octree-level", args->level, "Octree level 1..21 (default: automatic)")->check(CLI::Range(0, 21));
    ThreadLimit::addOption(*c, args->threads);
    args->read.addTo(*c);
    args->write.addTo(*c);
    c->callback([args, &registry, streams] {
        const ThreadLimit threadLimit(args->threads);
        CloudToCloudParams params;
        params.maxDistance = args->maxDistance;
        params.clampBeyondMax = args->clamp;
        params.model = parseLocalModel(args->model);
        params.neighbours = args->knn;
        params.radius = args->radius;
        params.splitComponents = args->split;
        params.signedDistances = args->signedDistances;
        params.closestPoints = !args->closestOutput.empty();
        params.octreeLevel = args->level;
        params.visibility.tolerance = args->tolerance;
        for (const auto& s : args->sensors)
            params.viewpoints.push_back(parseSensor(s, args->sensorStep, args->sensorFov, args->sensorRange));

        TerminalProgress progress;
        const io::ReadOptions readOptions = args->read.toOptions(&progress);
        PointCloud reference = io::readPointCloud(registry.formats, args->reference, readOptions);
        PointCloud compared = io::readPointCloud(registry.formats, args->compared, readOptions);
        if (args->visibility && params.viewpoints.empty()) {
            if (reference.sensors().empty())
                throw Error(ErrorCode::InvalidArgument, "--visibility: " + args->reference + " holds no sensor pose; give --sensor");
            params.viewpoints = reference.sensors();
        }
        const auto start = std::chrono::steady_clock::now();
        CloudToCloudResult result = cloudToCloud(compared, reference, params, &progress);
        std::optional<CloudToCloudResult> reverse;
        if (args->bothWays) {
            CloudToCloudParams reverseParams = params;
            reverseParams.viewpoints = compared.sensors(); // the compared scan's own viewpoints, if any
            reverseParams.closestPoints = false;
            reverse = cloudToCloud(reference, compared, reverseParams, &progress);
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        printStatistics(streams.out, "c2c " + std::string(localModelName(params.model)) + " (compared -> reference)",
                        result.statistics);
        if (reverse)
            printStatistics(streams.out, "c2c reverse (reference -> compared)", reverse->statistics);
        streams.out << "octree level " << result.level << ", " << std::fixed << std::setprecision(3) << seconds << " s\n";
        if (result.closest && !args->closestOutput.empty())
            io::writePointCloud(registry.formats, *result.closest, args->closestOutput, args->write.toOptions(&progress));
        if (!args->output.empty()) {
            attachFields(compared, std::move(result));
            io::writePointCloud(registry.formats, compared, args->output, args->write.toOptions(&progress));
            streams.out << "wrote " << args->output << '\n';
            if (reverse) {
                attachFields(reference, std::move(*reverse));
                const std::filesystem::path out(args->output);
                const auto referenceOutput = out.parent_path() / (out.stem().string() + "_reference" + out.extension().string());
                io::writePointCloud(registry.formats, reference, referenceOutput, args->write.toOptions(&progress));
                streams.out << "wrote " << referenceOutput.string() << '\n';
            }
        }
    });
}

} // namespace scandiff::cli
