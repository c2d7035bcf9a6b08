// SPDX-License-Identifier: GPL-3.0-or-later
// Tools: normals, orient-normals, features.
#include "processing/tools/ToolGroups.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/processing/LocalFeatures.h>
#include <scandiff/core/processing/Normals.h>

namespace scandiff::detail {

namespace {

const char* kOrientHelp =
    "Side of the normals: +x -x +y -y +z -z, a direction DX,DY,DZ, sensor (the cloud's scanner positions), "
    "sensor:X,Y,Z, centroid (away from it), -centroid (towards it), mst (propagated over a minimum spanning tree, "
    "for closed or concave objects), none";

const std::vector<std::string> kOrientations{"+z", "-z", "+x", "-x", "+y", "-y", "sensor", "centroid", "-centroid", "mst", "none"};

const char* modelName(NormalModel model)
{
    return model == NormalModel::Plane ? "plane" : model == NormalModel::Quadric ? "quadric" : "triangulation";
}

NormalOrientation orientationFrom(const ParameterValues& values)
{
    NormalOrientation orientation = parseNormalOrientation(values.text("orient"));
    orientation.mstNeighbours = static_cast<std::size_t>(values.integer("mst-knn"));
    return orientation;
}

void addNormalsTool(ToolRegistry& registry)
{
    const NormalParams defaults;
    ToolSpec tool = oneCloudTool(
        "normals", "Compute normals", "Normals",
        "Fits a surface on each point's neighbourhood (its k nearest points, or every point within a radius) and "
        "takes its normal (thesis 000 annex A.2): the least-squares plane, a quadric height function over it, or the "
        "local Delaunay triangulation's triangles around the point; then orients them. Adds the normals and the field "
        "surface_variation (smallest eigenvalue over their sum: 0 on a plane).",
        updatedCloud("Cloud with normals"));
    tool.parameters = {
        ParameterSpec::integer("knn", "Neighbours", "Fit on the k nearest points (the default, 12, when no radius is given)",
                               static_cast<std::int64_t>(defaults.knn), 3, 10000, "points")
            .asAlternative("neighbourhood"),
        ParameterSpec::real("radius", "Radius", "Fit on every point within this radius", 0.1, 1e-9, 1e9, "m")
            .asAlternative("neighbourhood"),
        ParameterSpec::integer("min-neighbours", "At least",
                               "With a radius: a point with fewer points within it is fitted on this many nearest ones (0: never); "
                               "for a scan whose spacing grows with range",
                               0, 0, 10000, "points"),
        ParameterSpec::choice("model", "Local model", "Surface fitted on each neighbourhood", {"plane", "quadric", "triangulation"},
                              "plane"),
        ParameterSpec::text("orient", "Orientation", kOrientHelp, "+z").withSuggestions(kOrientations),
        ParameterSpec::integer("mst-knn", "MST neighbours", "Neighbours per point in the graph of the mst orientation", 10, 1, 1000,
                               "points"),
        ParameterSpec::boolean("flip", "Flip", "Reverse every normal after orienting it", false),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        NormalParams params;
        if (values.has("radius"))
            params.radius = values.real("radius");
        if (values.has("knn"))
            params.knn = static_cast<std::size_t>(values.integer("knn"));
        params.minNeighbours = static_cast<std::size_t>(values.integer("min-neighbours"));
        const std::string& model = values.text("model");
        params.model = model == "plane" ? NormalModel::Plane : model == "quadric" ? NormalModel::Quadric : NormalModel::Triangulation;
        params.orientation = orientationFrom(values);
        params.flip = values.boolean("flip");
        NormalResult normals = computeNormals(input, params, progress);
        PointCloud out = input.clone();
        out.enableNormals() = std::move(normals.normals);
        out.addField(std::move(normals.surfaceVariation));
        ToolResult result;
        result.summary = describe(input.size() - normals.unfitted, " normals (", modelName(params.model), ", ",
                                  params.radius ? describe("radius ", *params.radius, " m") : describe(params.knn, " neighbours"),
                                  "), oriented ", values.text("orient"), values.boolean("flip") ? ", flipped" : "",
                                  normals.components ? describe(" (", normals.components, " connected parts)") : std::string(),
                                  normals.unfitted ? describe("; ", normals.unfitted, " points without a normal") : std::string());
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

void addOrientTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool("orient-normals", "Orient normals", "Normals",
                                 "Turns the cloud's existing normals to one side: towards a direction, the scanner, away "
                                 "from the centroid, or consistently along a minimum spanning tree of the neighbourhood "
                                 "graph (Hoppe et al. 1992). With --flip, reverses them.",
                                 updatedCloud("Cloud with oriented normals"));
    tool.parameters = {
        ParameterSpec::text("orient", "Orientation", kOrientHelp, "mst").withSuggestions(kOrientations),
        ParameterSpec::integer("mst-knn", "MST neighbours", "Neighbours per point in the graph of the mst orientation", 10, 1, 1000,
                               "points"),
        ParameterSpec::boolean("flip", "Flip", "Reverse every normal after orienting it", false),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        if (!input.hasNormals())
            throw Error(ErrorCode::InvalidArgument, "orient-normals: cloud '" + input.name + "' has no normals (compute them first)");
        PointCloud out = input.clone();
        const std::size_t components = orientNormals(out, out.enableNormals(), orientationFrom(values), progress);
        if (values.boolean("flip"))
            for (auto& normal : out.enableNormals())
                normal = -normal;
        ToolResult result;
        result.summary = describe(out.size(), " normals oriented ", values.text("orient"), values.boolean("flip") ? ", flipped" : "",
                                  components ? describe(" (", components, " connected parts)") : std::string());
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

void addFeaturesTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool(
        "features", "Local features", "Normals",
        "Fields computed on the points within a radius of each point: density (neighbour count, points per m^2 or per "
        "m^3), roughness (distance to the least-squares plane of the neighbours), mean and Gaussian curvature (of a "
        "quadric fitted over that plane), verticality (1 - |n.z|). Without any feature flag, all of them.",
        updatedCloud("Cloud with feature fields"));
    tool.parameters = {
        ParameterSpec::real("radius", "Radius", "Neighbourhood radius", 0.1, 1e-9, 1e9, "m").asRequired(),
        ParameterSpec::boolean("density", "Density", "Add the density field", false),
        ParameterSpec::choice("density-kind", "Density kind", "count: neighbours; surface: per m^2; volume: per m^3",
                              {"count", "surface", "volume"}, "surface"),
        ParameterSpec::boolean("roughness", "Roughness", "Add the roughness field", false),
        ParameterSpec::boolean("curvature", "Curvature", "Add the mean and Gaussian curvature fields", false),
        ParameterSpec::boolean("verticality", "Verticality", "Add the verticality field", false),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        FeatureParams params;
        params.radius = values.real("radius");
        params.density = values.boolean("density");
        params.roughness = values.boolean("roughness");
        params.curvature = values.boolean("curvature");
        params.verticality = values.boolean("verticality");
        const std::string& kind = values.text("density-kind");
        params.densityKind = kind == "count" ? DensityKind::Count : kind == "surface" ? DensityKind::Surface : DensityKind::Volume;
        FeatureResult features = computeLocalFeatures(input, params, progress);
        PointCloud out = input.clone();
        std::string names;
        for (auto& f : features.fields) {
            names += (names.empty() ? "" : ", ") + f.name();
            out.addField(std::move(f));
        }
        ToolResult result;
        result.summary = describe(names, " in a radius of ", params.radius, " m on ", out.size(), " points");
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

} // namespace

void registerNormalTools(ToolRegistry& registry)
{
    addNormalsTool(registry);
    addOrientTool(registry);
    addFeaturesTool(registry);
}

} // namespace scandiff::detail
