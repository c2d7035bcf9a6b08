// SPDX-License-Identifier: GPL-3.0-or-later
// Registers primitive extraction as the tool "primitives".
#include <scandiff/core/Error.h>
#include <scandiff/core/Drawing.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/segmentation/RegionReport.h>
#include <scandiff/plugins/PluginRegistry.h>
#include <scandiff/plugins/primitives/PrimitiveDetection.h>

#include "ShapeSurfaces.h"

#include <nlohmann/json.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <variant>

namespace scandiff::plugins {

namespace {

constexpr double kDegrees = 180.0 / 3.14159265358979323846;

std::set<PrimitiveKind> kindsFrom(const std::string& text)
{
    std::set<PrimitiveKind> kinds;
    for (const std::string& name : splitList(text, ','))
        if (!name.empty())
            kinds.insert(parsePrimitiveKind(name));
    if (kinds.empty())
        throw Error(ErrorCode::InvalidArgument, "primitives: --shapes names at least one of plane, sphere, cylinder, cone, torus");
    return kinds;
}

//! One row per shape: its parameters in world coordinates (plane: n.x + d = 0),
//! support, RMS, area and the standard uncertainties.
Table primitivesTable(const PrimitiveDetectionResult& result)
{
    Table t;
    t.columns = {"id", "type", "inliers", "rms", "area", "x", "y", "z", "dx", "dy", "dz", "d", "radius", "minor_radius",
                 "half_angle_deg", "length", "sigma_direction_deg", "sigma_position", "sigma_radius", "text"};
    for (const DetectedPrimitive& s : result.primitives) {
        const Primitive& p = s.primitive;
        const double nan = std::numeric_limits<double>::quiet_NaN();
        auto sigma = [&](const std::string& name) {
            for (const auto& [key, value] : s.uncertainty)
                if (key == name)
                    return value;
            return nan;
        };
        const bool plane = p.kind == PrimitiveKind::Plane, sphere = p.kind == PrimitiveKind::Sphere;
        const double position = plane ? sigma("offset") : sphere || p.kind == PrimitiveKind::Torus ? sigma("centre")
                                                      : p.kind == PrimitiveKind::Cone              ? sigma("apex")
                                                                                                   : sigma("axis_position");
        const double radiusSigma = p.kind == PrimitiveKind::Cone ? sigma("half_angle_deg") : sigma("radius");
        t.rows.push_back({static_cast<double>(s.id), std::string(primitiveKindName(p.kind)), static_cast<double>(s.inliers.size()), s.rms,
                          s.area, p.point.x(), p.point.y(), p.point.z(), sphere ? nan : p.direction.x(), sphere ? nan : p.direction.y(),
                          sphere ? nan : p.direction.z(), plane ? -p.direction.dot(p.point) : nan,
                          plane || p.kind == PrimitiveKind::Cone ? nan : p.radius, p.kind == PrimitiveKind::Torus ? p.minorRadius : nan,
                          p.kind == PrimitiveKind::Cone ? p.halfAngle * kDegrees : nan, s.length > 0 ? s.length : nan,
                          sphere ? nan : sigma("direction_deg"), position, radiusSigma, primitiveText(p)});
    }
    return t;
}

//! One parameter of a shape: its key in primitives.json, its label in the
//! workbench's Properties panel, and its value (a number, a point or a unit direction).
struct ShapeParameter
{
    const char* key;
    const char* label;
    std::variant<double, Eigen::Vector3d> value;
    bool isDirection = false;
};

//! A shape's parameters in world coordinates, by type (plane: unit normal and
//! d with n.x + d = 0, and a point; sphere: centre, radius; cylinder: axis
//! point and direction, radius, length; cone: apex, axis, half-angle, length;
//! torus: centre, axis, both radii): the one list the JSON and the
//! Properties panel are made from.
std::vector<ShapeParameter> shapeParameters(const DetectedPrimitive& s)
{
    const Primitive& p = s.primitive;
    switch (p.kind) {
    case PrimitiveKind::Plane:
        return {{"normal", "Normal", p.direction.normalized(), true},
                {"d", "d (n·x + d = 0)", -p.direction.normalized().dot(p.point)},
                {"point", "Point", p.point}};
    case PrimitiveKind::Sphere: return {{"center", "Centre", p.point}, {"radius", "Radius (m)", p.radius}};
    case PrimitiveKind::Cylinder:
        return {{"axis_point", "Axis point", p.point},
                {"axis_direction", "Axis direction", p.direction, true},
                {"radius", "Radius (m)", p.radius},
                {"length", "Length (m)", s.length}};
    case PrimitiveKind::Cone:
        return {{"apex", "Apex", p.point},
                {"axis_direction", "Axis direction", p.direction, true},
                {"half_angle_deg", "Half-angle (°)", p.halfAngle * kDegrees},
                {"length", "Length (m)", s.length}};
    case PrimitiveKind::Torus:
        return {{"center", "Centre", p.point},
                {"axis_direction", "Axis direction", p.direction, true},
                {"major_radius", "Major radius (m)", p.radius},
                {"minor_radius", "Minor radius (m)", p.minorRadius}};
    }
    return {};
}

//! The shapes as the JSON document: {"primitives": [{"id", "type",
//! "inliers", "rms", "area", then the type's parameters (shapeParameters),
//! and "uncertainty" (standard uncertainties by name)}]}.
std::string primitivesJson(const PrimitiveDetectionResult& result)
{
    nlohmann::json list = nlohmann::json::array();
    for (const DetectedPrimitive& s : result.primitives) {
        nlohmann::json shape = {{"id", s.id}, {"type", primitiveKindName(s.primitive.kind)}, {"inliers", s.inliers.size()},
                                {"rms", s.rms}, {"area", s.area}};
        for (const ShapeParameter& parameter : shapeParameters(s)) {
            if (const auto* v = std::get_if<Eigen::Vector3d>(&parameter.value))
                shape[parameter.key] = nlohmann::json::array({v->x(), v->y(), v->z()});
            else
                shape[parameter.key] = std::get<double>(parameter.value);
        }
        nlohmann::json uncertainty = nlohmann::json::object();
        for (const auto& [name, value] : s.uncertainty)
            if (std::isfinite(value))
                uncertainty[name] = value;
        shape["uncertainty"] = uncertainty;
        list.push_back(shape);
    }
    return nlohmann::json({{"primitives", list}}).dump(1) + "\n";
}

std::string number(double v)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", v);
    return text;
}

//! A point to the 0.1 mm (UTM-sized values keep every digit that matters),
//! a unit direction to 1e-6.
std::string vectorText(const Eigen::Vector3d& v, bool isDirection)
{
    char text[96];
    std::snprintf(text, sizeof text, isDirection ? "%.6f, %.6f, %.6f" : "%.4f, %.4f, %.4f", v.x(), v.y(), v.z());
    return text;
}

//! What the workbench's Properties panel lists for a shape: the same values
//! as its row of the table and its entry of the JSON document.
OutputProperties shapeProperties(const DetectedPrimitive& s)
{
    OutputProperties rows = {{"Shape", std::string(primitiveKindName(s.primitive.kind)) + " " + std::to_string(s.id)},
                             {"Inliers", std::to_string(s.inliers.size())},
                             {"RMS (m)", number(s.rms)},
                             {"Area (m²)", number(s.area)}};
    for (const ShapeParameter& parameter : shapeParameters(s)) {
        const auto* v = std::get_if<Eigen::Vector3d>(&parameter.value);
        rows.push_back({parameter.label, v ? vectorText(*v, parameter.isDirection) : number(std::get<double>(parameter.value))});
    }
    for (const auto& [name, value] : s.uncertainty)
        if (std::isfinite(value))
            rows.push_back({"σ " + name, number(value)});
    return rows;
}

//! Each plane's concave outline (and the outlines of its separate parts) in
//! its own plane, lifted back to 3D, on a layer per shape (PLANE_0003): the
//! drawing of a façade's or a room's planes for CAD. The outline grid is the
//! region report's (cells of 1.5 x the 4th-neighbour spacing of the shape's points).
Drawing planeOutlines(const PointCloud& cloud, const PrimitiveDetectionResult& detected, ProgressObserver* progress)
{
    ProgressTicker ticker(progress, "Primitives: plane outlines", detected.primitives.size());
    // The planes in parallel (one task each), their polylines then taken in the shapes' order.
    std::vector<std::vector<DrawingPolyline>> outlines(detected.primitives.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, outlines.size(), 1), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
            ticker.checkCancel(); // before each outline: a large plane takes a moment
            ticker.step();
            const DetectedPrimitive& shape = detected.primitives[k];
            if (shape.primitive.kind != PrimitiveKind::Plane || shape.inliers.size() < 3)
                continue;
            const Eigen::Vector3d normal = shape.primitive.direction.normalized();
            const Eigen::Vector3d e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
            const Eigen::Vector3d foot = shape.primitive.point;
            std::vector<Eigen::Vector2d> inPlane;
            std::vector<Eigen::Vector3f> local;
            inPlane.reserve(shape.inliers.size());
            for (std::uint32_t i : shape.inliers) {
                const Eigen::Vector3d v = cloud.globalPosition(i) - foot;
                inPlane.emplace_back(v.dot(e1), v.dot(e2));
                local.emplace_back(static_cast<float>(v.dot(e1)), static_cast<float>(v.dot(e2)), 0.0f);
            }
            BoundingBox box;
            box.empty = false;
            box.min = box.max = Eigen::Vector3d::Zero();
            for (const Eigen::Vector3f& p : local) {
                box.min = box.min.cwiseMin(p.cast<double>());
                box.max = box.max.cwiseMax(p.cast<double>());
            }
            const Outline2d outline = concaveOutline(inPlane, outlineCellFor(local, box));
            char layer[32];
            std::snprintf(layer, sizeof layer, "PLANE_%04d", shape.id);
            for (const Polygon2d& ring : outline.rings) {
                std::vector<Eigen::Vector3d> lifted;
                lifted.reserve(ring.size());
                for (const Eigen::Vector2d& q : ring)
                    lifted.push_back(foot + q.x() * e1 + q.y() * e2);
                if (lifted.size() >= 2)
                    outlines[k].push_back({layer, std::move(lifted), true});
            }
        }
    }, tbb::simple_partitioner());
    Drawing drawing;
    for (auto& polylines : outlines)
        for (auto& polyline : polylines)
            drawing.polylines.push_back(std::move(polyline));
    return drawing;
}

} // namespace

} // namespace scandiff::plugins

namespace scandiff::plugins {
namespace {

PrimitiveDetectionParams detectionParamsFrom(const ParameterValues& values)
{
    PrimitiveDetectionParams params;
    params.method = parsePrimitiveMethod(values.text("method"));
    params.kinds = kindsFrom(values.text("shapes"));
    if (values.has("epsilon"))
        params.epsilon = values.real("epsilon");
    if (values.has("cluster-epsilon"))
        params.clusterEpsilon = values.real("cluster-epsilon");
    params.normalDeviationDegrees = values.real("normal-deviation");
    params.minPoints = static_cast<std::size_t>(values.integer("min-points"));
    params.probability = values.real("probability");
    params.seed = static_cast<std::uint64_t>(values.integer("seed"));
    params.orientationToleranceDegrees = values.real("orientation-tolerance");
    params.growOn = parseGrowOn(values.text("grow-on"));
    params.smoothnessDegrees = values.real("smoothness");
    if (values.has("curvature"))
        params.curvature = values.real("curvature");
    params.valueField = values.text("field");
    if (values.has("tolerance"))
        params.valueTolerance = values.real("tolerance");
    if (values.has("radius"))
        params.valueRadius = values.real("radius");
    return params;
}

//! The input with primitive_id, primitive_type and primitive_distance.
PointCloud labelledCloud(const PointCloud& input, const PrimitiveDetectionResult& detected)
{
    PointCloud labelled = input.clone();
    // The three fields are added before any is held: adding a field may
    // move the others (a reference kept across addField dangles).
    for (const char* name : {"primitive_id", "primitive_type", "primitive_distance"})
        labelled.addField(name);
    std::vector<float>& id = labelled.field("primitive_id")->values();
    std::vector<float>& type = labelled.field("primitive_type")->values();
    std::vector<float>& distance = labelled.field("primitive_distance")->values();
    for (std::size_t i = 0; i < input.size(); ++i) {
        id[i] = static_cast<float>(detected.primitiveId[i]);
        type[i] = detected.primitiveId[i] < 0
                      ? -1.0f
                      : static_cast<float>(detected.primitives[static_cast<std::size_t>(detected.primitiveId[i])].primitive.kind);
        distance[i] = detected.distance[i];
    }
    return labelled;
}

//! Each shape's surface, coloured as its points are by primitive_id (one
//! colour per shape): the shapes in parallel, in their order.
std::vector<Mesh> shapeSurfaces(const PointCloud& input, const PrimitiveDetectionResult& detected, ProgressObserver* progress)
{
    ProgressTicker surfaces(progress, "Primitives: shape surfaces", detected.primitives.size());
    std::vector<Mesh> meshes(detected.primitives.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, meshes.size(), 1), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
            surfaces.checkCancel();
            const DetectedPrimitive& shape = detected.primitives[k];
            Mesh& mesh = meshes[k];
            mesh = shapeSurface(shape.primitive, input, shape.inliers, shapeCellSize(input, shape.inliers));
            mesh.name = std::string(primitiveKindName(shape.primitive.kind)) + "_surface";
            mesh.vertices.addField(ScalarField("primitive_id", mesh.vertices.size()));
            std::fill(mesh.vertices.field("primitive_id")->values().begin(), mesh.vertices.field("primitive_id")->values().end(),
                      static_cast<float>(shape.id));
            surfaces.step();
        }
    }, tbb::simple_partitioner());
    return meshes;
}

//! "12 shapes (7 planes, 3 cylinders, 2 spheres), ... points assigned; epsilon ...".
std::string primitivesSummary(const PrimitiveDetectionResult& detected, std::size_t pointCount)
{
    std::ostringstream summary;
    std::map<std::string, int> counts;
    std::size_t assigned = 0;
    for (const DetectedPrimitive& shape : detected.primitives) {
        ++counts[primitiveKindName(shape.primitive.kind)];
        assigned += shape.inliers.size();
    }
    summary << detected.primitives.size() << " shapes (";
    bool first = true;
    for (const auto& [name, count] : counts) {
        summary << (first ? "" : ", ") << count << " " << (count > 1 ? (name == "torus" ? "tori" : name + "s") : name);
        first = false;
    }
    summary << "), " << assigned << " of " << pointCount << " points assigned; epsilon " << detected.epsilon
            << " m, cluster epsilon " << detected.clusterEpsilon << " m";
    for (const std::string& note : detected.notes)
        summary << "; " << note;
    return summary.str();
}

ToolResult runPrimitives(const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress)
{
    const PointCloud& input = inputs.cloud();
    const PrimitiveDetectionResult detected = detectPrimitives(input, detectionParamsFrom(values), progress);
    ToolResult result;
    PointCloud labelled = labelledCloud(input, detected);
    // Each shape's points with every field, the primitive ones included.
    std::vector<PointCloud> parts;
    for (const DetectedPrimitive& shape : detected.primitives) {
        std::vector<std::size_t> indices(shape.inliers.begin(), shape.inliers.end());
        parts.push_back(labelled.subset(indices));
    }
    result.add("primitives", std::move(labelled));
    // The surfaces, then the outlines, not both at once: the largest plane's
    // surface and outline side by side raised the peak by 40 MB a million points.
    std::vector<Mesh> meshes = shapeSurfaces(input, detected, progress);
    Drawing outlines = planeOutlines(input, detected, progress);
    for (std::size_t k = 0; k < meshes.size(); ++k) {
        const DetectedPrimitive& shape = detected.primitives[k];
        parts[k].name = primitiveKindName(shape.primitive.kind); // the CLI adds the shape's id: plane_0.ply
        result.add("shape", std::move(parts[k]), shapeProperties(shape));
        result.add("surface", std::move(meshes[k]), shapeProperties(shape));
    }
    result.add("table", primitivesTable(detected));
    result.add("outlines", std::move(outlines));
    result.add("document", TextDocument{".json", primitivesJson(detected)});
    result.summary = primitivesSummary(detected, input.size());
    return result;
}

} // namespace
} // namespace scandiff::plugins

void scandiff_register_plugin_primitives(scandiff::PluginRegistry& registry)
{
    using namespace scandiff;
    using namespace scandiff::plugins;
    const PrimitiveDetectionParams defaults;
    registry.plugins.push_back({"primitives", "Planes, spheres, cylinders, cones and tori by efficient RANSAC; regions grown on planes, smoothness or intensity", "CGAL"});

    ToolSpec tool;
    tool.name = "primitives";
    tool.title = "Primitives";
    tool.category = "Primitives";
    tool.description =
        "Finds planes, spheres, cylinders, cones and tori (efficient RANSAC, Schnabel et al. 2007, through CGAL), or regions grown "
        "on planes (CGAL's), on smoothness (normals and curvature) or on intensity, splits each shape into connected parts, merges touching parts of one surface, keeps a curved shape only where it fits its points clearly better than a plane, and "
        "refits every shape by least squares with the uncertainty of its parameters. Adds primitive_id (-1: none), "
        "primitive_type (0 plane, 1 sphere, 2 cylinder, 3 cone, 4 torus) and primitive_distance to the cloud; gives one cloud "
        "per shape with its surface as a mesh (the part its points cover), a table of their parameters and the planes' outlines as a drawing (DXF, a layer per plane). Normals are fitted when the cloud has none (within 10 x the noise).";
    tool.parameters = {
        ParameterSpec::choice("method", "Method",
                              "efficient-ransac: every shape type, from random samples (seeded); region-growing: regions grown from "
                              "the flattest points (no random draw), on planes by default, as thesis 004 compares with RANSAC, or "
                              "on smoothness or intensity (see Grow on); sequential: thesis 001's "
                              "façade planes, one after the other by classes of orientation (across the façade, horizontal, "
                              "inclined, parallel to it), each the largest connected region of its inliers (connectivity "
                              "pixels of the connectivity distance), refitted by PCA; z must be up",
                              {"efficient-ransac", "region-growing", "sequential"}, "efficient-ransac"),
        ParameterSpec::text("shapes", "Shape types", "Comma-separated: plane, sphere, cylinder, cone, torus",
                            "plane,sphere,cylinder,cone,torus")
            .withSuggestions({"plane,sphere,cylinder,cone,torus", "plane", "plane,cylinder", "plane,sphere,cylinder"}),
        ParameterSpec::real("epsilon", "Distance threshold",
                            "Largest distance of a point to its shape; absent: 3 x the noise estimated from the points", 0.01, 1e-9,
                            1e9, "m")
            .asOptional(),
        ParameterSpec::real("cluster-epsilon", "Connectivity",
                            "Largest gap inside one shape's points: farther parts are separate shapes; absent: 3 x the median "
                            "point spacing",
                            0.1, 1e-9, 1e9, "m")
            .asOptional(),
        ParameterSpec::real("normal-deviation", "Normal deviation", "Largest angle between a point's normal and its shape's",
                            defaults.normalDeviationDegrees, 0.1, 89.9, "deg"),
        ParameterSpec::integer("min-points", "Minimum support", "Smallest number of points of a shape",
                               static_cast<std::int64_t>(defaults.minPoints), 10, 1000000000, "points"),
        ParameterSpec::real("probability", "Miss probability", "RANSAC's chance of overlooking the largest remaining shape",
                            defaults.probability, 1e-6, 0.5)
            .onlyWith("!method=region-growing"),
        ParameterSpec::integer("seed", "Seed", "Random sampling seed (the same seed, the same shapes)", 0, 0, 4294967295LL)
            .onlyWith("!method=region-growing"),
        ParameterSpec::real("orientation-tolerance", "Orientation tolerance",
                            "Sequential: a plane belongs to a class when its normal is within this angle of the class's axis "
                            "(the thesis's 1°)",
                            defaults.orientationToleranceDegrees, 0.01, 44.9, "deg")
            .onlyWith("method=sequential"),
        ParameterSpec::choice("grow-on", "Grow on",
                              "Region growing: plane: a point joins within the distance threshold of its region's plane, its "
                              "normal within the normal deviation; smoothness: neighbours' normals within the smoothness angle, "
                              "edges (points of high surface variation) stopping the region (Rabbani et al. 2006), each region "
                              "then typed as a plane, a sphere or a cylinder; intensity: neighbours of like values (thesis 003: "
                              "stones of a wall), each region then typed the same way",
                              {"plane", "smoothness", "intensity"}, "plane")
            .onlyWith("method=region-growing"),
        ParameterSpec::real("smoothness", "Smoothness", "Largest angle between the normals of two neighbours in one region",
                            defaults.smoothnessDegrees, 0.1, 89.9, "deg")
            .onlyWith("grow-on=smoothness"),
        ParameterSpec::real("curvature", "Curvature threshold",
                            "Points whose surface variation (smallest eigenvalue of their neighbourhood over the sum: 0 on a "
                            "plane, 1/3 at most) is above this join a region but do not spread it; absent: 2 x the median",
                            0.05, 0, 1.0 / 3.0)
            .asOptional()
            .onlyWith("grow-on=smoothness"),
        ParameterSpec::text("field", "Value field", "The scalar field the regions share (intensity, a colour channel...)", "intensity")
            .asFieldOf("input")
            .onlyWith("grow-on=intensity"),
        ParameterSpec::real("tolerance", "Value tolerance",
                            "Largest variance of the values of one region (thesis 003's tau); absent: 4 x the median variance "
                            "within the radius",
                            100, 1e-12, 1e18)
            .asOptional()
            .onlyWith("grow-on=intensity"),
        ParameterSpec::real("radius", "Growing radius",
                            "A region grows to the points within this distance of its points (thesis 003's R); absent: 2 x the "
                            "median point spacing",
                            0.05, 1e-9, 1e9, "m")
            .asOptional()
            .onlyWith("grow-on=intensity"),
    };
    // With --out-dir: primitives.ply, TYPE_ID.ply, TYPE_surface_ID.ply, primitives.csv, primitives.dxf, primitives.json.
    OutputSpec shape{"shape", "Shape", DataKind::Cloud, false, true};
    shape.showsField = "primitive_id";
    OutputSpec surface{"surface", "Shape surface", DataKind::Mesh, false, true};
    surface.under = "shape";
    surface.showsField = "primitive_id";
    tool.outputs = {OutputSpec{"primitives", "Cloud with primitive fields", DataKind::Cloud, true}, shape, surface,
                    OutputSpec{"table", "Primitives", DataKind::Table, false, false, "primitives"},
                    OutputSpec{"outlines", "Plane outlines", DataKind::Drawing, false, false, "primitives"},
                    OutputSpec{"document", "Primitives (JSON)", DataKind::Document, false, false, "primitives"}};
    tool.run = plugins::runPrimitives;
    registry.tools.add(std::move(tool));
}
