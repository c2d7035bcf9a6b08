// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/ClassSelection.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/distance/DistanceParameters.h>
#include <scandiff/core/processing/CloudEditing.h>
#include <scandiff/core/processing/Normals.h>

#include <cmath>

namespace scandiff {

namespace {

double radians(double degrees) { return degrees * M_PI / 180.0; }

// Distances are positive; the smallest value a dialog can show stands for "> 0".
constexpr double kSmallestDistance = 1e-6;

ParameterSpec maxDistanceParameter()
{
    return ParameterSpec::real("max-dist", "Maximum distance",
                               "Points farther than this get NaN, or the maximum itself with clamp", 1.0, kSmallestDistance,
                               1e9, "m")
        .asOptional();
}

ParameterSpec clampParameter()
{
    return ParameterSpec::boolean("clamp", "Clamp to maximum", "With a maximum distance: farther points get the maximum instead of NaN",
                                  false)
        .onlyWith("max-dist");
}

ParameterSpec octreeLevelParameter(const std::string& automatic)
{
    return ParameterSpec::integer("octree-level", "Octree level", "Octree level 1..21; 0 = automatic (" + automatic + ")", 0, 0, 21)
        .withZeroMeaning("automatic");
}

void checkClamp(const ParameterValues& values)
{
    if (values.boolean("clamp") && !values.has("max-dist"))
        throw Error(ErrorCode::InvalidArgument, "clamp needs a maximum distance (max-dist)");
}

std::vector<double> scalesFrom(const ParameterValues& values)
{
    if (!values.has("normal-scales"))
        return {values.real("normal-scale")};
    std::vector<double> scales;
    for (const std::string& item : splitList(values.text("normal-scales"), ',')) {
        char* end = nullptr;
        const double d = std::strtod(item.c_str(), &end);
        if (end == item.c_str() || *end != '\0')
            throw Error(ErrorCode::InvalidArgument, "m3c2: --normal-scales takes diameters separated by commas, not '" + item + "'");
        scales.push_back(d);
    }
    return scales;
}

ParameterSpec m3c2Orientation()
{
    return ParameterSpec::text("orientation", "Normal orientation",
                               "The side every normal is turned to: +z (default), -x..., a direction x,y,z, sensor (towards "
                               "the reference's scanner), sensor:X,Y,Z, centroid (away from the core points' centroid), "
                               "-centroid; the sign of the distances follows it",
                               "+z")
        .withSuggestions({"+z", "-z", "+x", "+y", "sensor", "centroid", "-centroid"});
}

} // namespace

const std::vector<ParameterSpec>& cloudToCloudParameters()
{
    static const std::vector<ParameterSpec> parameters = [] {
        const CloudToCloudParams defaults;
        std::vector<ParameterSpec> list{
            maxDistanceParameter(),
            clampParameter(),
            ParameterSpec::choice("model", "Local model", "Model of the reference around each nearest neighbour (thesis 000 §2.3.2)",
                                  {"none", "plane", "delaunay", "quadric"}, localModelName(defaults.model)),
            ParameterSpec::integer("knn", "Model neighbours", "Local model fitted on the k nearest reference points", defaults.neighbours,
                                   3, 500, "points")
                .onlyWith("!model=none"),
            ParameterSpec::real("radius", "Model radius", "Local model fitted on the reference points within this radius instead of knn",
                                0.5, kSmallestDistance, 1e9, "m")
                .asOptional()
                .onlyWith("!model=none"),
            ParameterSpec::boolean("split-xyz", "Split X/Y/Z", "Also output c2c_dx, c2c_dy, c2c_dz", defaults.splitComponents),
            ParameterSpec::boolean("signed", "Signed distances", "Sign by the reference normals or the local model's normal",
                                   defaults.signedDistances),
            ParameterSpec::boolean("closest-points", "Closest points", "Also output the matched reference points as a cloud",
                                   defaults.closestPoints),
            ParameterSpec::boolean("both-ways", "Both ways", "Also compute reference -> compared, kept on the reference (§3.5)", false),
            ParameterSpec::boolean("visibility", "Visibility test",
                                   "Depth-map visibility (§2.3.3) from the sensor poses stored with the reference, or from 'sensor'",
                                   false),
            ParameterSpec::text("sensor", "Sensor pose",
                                "Reference viewpoint X,Y,Z[,HEADING,PITCH,ROLL] (degrees); several separated by ';'; turns on the "
                                "visibility test")
                .asOptional(),
            ParameterSpec::text("sensor-step", "Sensor angular step", "Depth-map step DEG or YAWDEG,PITCHDEG (default: from the data)")
                .asOptional()
                .onlyWith("sensor"),
            ParameterSpec::text("sensor-fov", "Sensor field of view", "YAWMIN,YAWMAX,PITCHMIN,PITCHMAX in degrees")
                .asOptional()
                .onlyWith("sensor"),
            ParameterSpec::real("sensor-range", "Sensor range", "Maximum range of the scanner", 100.0, kSmallestDistance, 1e9, "m")
                .asOptional()
                .onlyWith("sensor"),
            ParameterSpec::real("visibility-tolerance", "Visibility tolerance", "Depth-map tolerance", defaults.visibility.tolerance, 0.0,
                                1e9, "m"),
            octreeLevelParameter("from the reference's cell populations"),
        };
        for (ParameterSpec& spec : classParameters())
            list.push_back(std::move(spec));
        return list;
    }();
    return parameters;
}

SensorPose parseSensorPose(const std::string& text, const std::string& step, const std::string& fov, double range)
{
    const std::vector<double> v = parseNumberList(text, "sensor");
    if (v.size() != 3 && v.size() != 6)
        throw Error(ErrorCode::InvalidArgument, "sensor: expected X,Y,Z or X,Y,Z,HEADING,PITCH,ROLL (degrees)");
    SensorPose pose;
    pose.position = {v[0], v[1], v[2]};
    if (v.size() == 6)
        pose.orientation = orientationFromHeadingPitchRoll(v[3], v[4], v[5]);
    if (!step.empty()) {
        const std::vector<double> s = parseNumberList(step, "sensor-step");
        if (s.empty() || s.size() > 2 || s[0] <= 0 || s.back() <= 0)
            throw Error(ErrorCode::InvalidArgument, "sensor-step: expected DEG or YAWDEG,PITCHDEG, positive");
        pose.yawStep = radians(s[0]);
        pose.pitchStep = radians(s.back());
    }
    if (!fov.empty()) {
        const std::vector<double> f = parseNumberList(fov, "sensor-fov");
        if (f.size() != 4 || f[0] >= f[1] || f[2] >= f[3])
            throw Error(ErrorCode::InvalidArgument, "sensor-fov: expected YAWMIN,YAWMAX,PITCHMIN,PITCHMAX in degrees");
        pose.yawMin = radians(f[0]);
        pose.yawMax = radians(f[1]);
        pose.pitchMin = radians(f[2]);
        pose.pitchMax = radians(f[3]);
    }
    if (range > 0)
        pose.maxRange = range;
    return pose;
}

CloudToCloudParams cloudToCloudSettings(const ParameterValues& values, const PointCloud& reference)
{
    checkClamp(values);
    CloudToCloudParams params;
    if (values.has("max-dist"))
        params.maxDistance = values.real("max-dist");
    params.clampBeyondMax = values.boolean("clamp");
    params.model = parseLocalModel(values.text("model"));
    params.neighbours = static_cast<int>(values.integer("knn"));
    if (values.has("radius"))
        params.radius = values.real("radius");
    params.splitComponents = values.boolean("split-xyz");
    params.signedDistances = values.boolean("signed");
    params.closestPoints = values.boolean("closest-points");
    params.octreeLevel = static_cast<int>(values.integer("octree-level"));
    params.visibility.tolerance = values.real("visibility-tolerance");

    const std::string step = values.has("sensor-step") ? values.text("sensor-step") : std::string();
    const std::string fov = values.has("sensor-fov") ? values.text("sensor-fov") : std::string();
    const double range = values.has("sensor-range") ? values.real("sensor-range") : 0.0;
    if (values.has("sensor"))
        for (const std::string& pose : splitList(values.text("sensor"), ';'))
            if (pose.find_first_not_of(" \t") != std::string::npos)
                params.viewpoints.push_back(parseSensorPose(pose, step, fov, range));
    if (values.boolean("visibility") && params.viewpoints.empty()) {
        if (reference.sensors().empty())
            throw Error(ErrorCode::InvalidArgument, "visibility: the reference holds no sensor pose; give one with 'sensor'");
        params.viewpoints = reference.sensors();
    }
    return params;
}

bool cloudToCloudBothWays(const ParameterValues& values) { return values.boolean("both-ways"); }

namespace {

//! A result computed on the points `kept` of a cloud of `size` points, spread
//! over all of them: NaN (no value) on the others, reach 0 (none computed).
void spreadResult(CloudToCloudResult& result, const std::vector<std::size_t>& kept, std::size_t size)
{
    result.distance = spreadOver(result.distance, kept, size);
    for (std::optional<ScalarField>* field : {&result.dx, &result.dy, &result.dz, &result.visibility})
        if (*field)
            **field = spreadOver(**field, kept, size);
    if (!result.reach.empty()) {
        std::vector<float> reach(size, 0.0f);
        for (std::size_t k = 0; k < kept.size(); ++k)
            reach[kept[k]] = result.reach[k];
        result.reach = std::move(reach);
    }
}

} // namespace

CloudToCloudRun runCloudToCloud(const PointCloud& compared, const PointCloud& reference, const ParameterValues& values,
                                ProgressObserver* progress)
{
    // With classes (--classes, --exclude-classes): both clouds restricted to
    // them, the values spread back over every point (none on the others).
    const std::optional<std::vector<std::size_t>> comparedKept = pointsOfClasses(compared, values);
    if (comparedKept) {
        const std::vector<std::size_t> referenceKept = *pointsOfClasses(reference, values);
        ParameterValues unrestricted;
        for (const auto& [name, value] : values.all())
            if (name != kClassesParameter && name != kExcludeClassesParameter)
                unrestricted.set(name, value);
        CloudToCloudRun run =
            runCloudToCloud(compared.subset(*comparedKept), reference.subset(referenceKept), unrestricted, progress);
        spreadResult(run.forward, *comparedKept, compared.size());
        if (run.reverse)
            spreadResult(*run.reverse, referenceKept, reference.size());
        return run;
    }
    CloudToCloudRun run;
    run.params = cloudToCloudSettings(values, reference);
    const bool bothWays = cloudToCloudBothWays(values);
    PrefixedProgress forwardProgress(progress, bothWays ? "Compared -> reference: " : "");
    run.forward = cloudToCloud(compared, reference, run.params, forwardProgress.get());
    if (bothWays) {
        CloudToCloudParams reverseParams = run.params;
        reverseParams.viewpoints = compared.sensors();
        reverseParams.closestPoints = false;
        PrefixedProgress reverseProgress(progress, "Reference -> compared: ");
        run.reverse = cloudToCloud(reference, compared, reverseParams, reverseProgress.get());
    }
    return run;
}

const std::vector<ParameterSpec>& cloudToMeshParameters()
{
    static const std::vector<ParameterSpec> parameters = [] {
        const CloudToMeshParams defaults;
        return std::vector<ParameterSpec>{
            ParameterSpec::boolean("signed", "Signed distances",
                                   "+ on the side the closest triangle's normal points to (right-hand rule on its vertex order)",
                                   defaults.signedDistances),
            maxDistanceParameter(),
            clampParameter(),
            octreeLevelParameter("from the mean triangle size"),
        };
    }();
    return parameters;
}

CloudToMeshParams cloudToMeshSettings(const ParameterValues& values)
{
    checkClamp(values);
    CloudToMeshParams params;
    params.signedDistances = values.boolean("signed");
    if (values.has("max-dist"))
        params.maxDistance = values.real("max-dist");
    params.clampBeyondMax = values.boolean("clamp");
    params.octreeLevel = static_cast<int>(values.integer("octree-level"));
    return params;
}

const std::vector<ParameterSpec>& m3c2Parameters()
{
    static const std::vector<ParameterSpec> parameters = {
        ParameterSpec::real("normal-scale", "Normal scale D",
                            "Diameter of the reference neighbourhood the normal is fitted on; 0: guessed from the roughness "
                            "(D / sigma(D) >= 25, Lague et al. 2013)",
                            0.0, 0.0, 1e6, "m")
            .withZeroMeaning("guessed"),
        ParameterSpec::text("normal-scales", "Normal scales",
                            "Several diameters D1,D2,D3 (multi-scale normal: the most planar is kept); replaces the normal scale")
            .asOptional(),
        ParameterSpec::real("projection-scale", "Projection scale d",
                            "Diameter of the cylinder each epoch is averaged in; 0: guessed from the point spacing (30 points "
                            "of each epoch in the median cylinder)",
                            0.0, 0.0, 1e6, "m")
            .withZeroMeaning("guessed"),
        ParameterSpec::real("max-depth", "Maximum depth", "Half-length of the cylinder along the normal", 1.0, 1e-6, 1e6, "m")
            .asRequired(),
        ParameterSpec::real("registration-error", "Registration error", "Added to the level of detection", 0.0, 0.0, 1e6, "m"),
        ParameterSpec::integer("min-points", "Minimum points",
                               "Points each cylinder needs for a level of detection and a significance", 5, 1, 1000000),
        ParameterSpec::real("core-spacing", "Core point spacing",
                            "Core points: the reference subsampled to points this far apart (without core-points)", 0.1, 1e-9, 1e9, "m")
            .asOptional(),
        m3c2Orientation(),
        ParameterSpec::boolean("robust", "Median and IQR", "Median and IQR / 1.349 instead of mean and standard deviation", false),
        ParameterSpec::boolean("sample-std", "Sample standard deviation",
                               "Divide by n - 1 (as py4dgeo) rather than n (as CloudCompare)", false),
        ParameterSpec::real("raster-cell", "Raster cell",
                            "Also rasterise the results on square cells of this size (the raster output: mean distance, "
                            "uncertainty and share of significant core points per cell; write it as .tif for a GeoTIFF)",
                            1.0, 1e-6, 1e6, "m")
            .asOptional(),
    };
    return parameters;
}

M3c2Params m3c2Settings(const ParameterValues& values)
{
    M3c2Params params;
    params.normalScales = scalesFrom(values);
    params.projectionScale = values.real("projection-scale");
    params.maxDepth = values.real("max-depth");
    params.registrationError = values.real("registration-error");
    params.minPoints = static_cast<std::size_t>(values.integer("min-points"));
    params.robust = values.boolean("robust");
    params.sampleStd = values.boolean("sample-std");
    params.orientation = parseNormalOrientation(values.text("orientation"));
    return params;
}

} // namespace scandiff
