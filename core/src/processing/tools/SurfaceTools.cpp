// SPDX-License-Identifier: GPL-3.0-or-later
// Tools: primitive-distance, unroll, sample-mesh.
#include "processing/tools/ToolGroups.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/geometry/Primitives.h>
#include <scandiff/core/processing/MeshSampling.h>
#include <scandiff/core/processing/Unrolling.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace scandiff::detail {

namespace {

//! The surface the user gave (--surface KIND:NUMBERS), else the one fitted on the cloud.
PrimitiveFit surfaceFor(const PointCloud& cloud, PrimitiveKind kind, const ParameterValues& values, ProgressObserver* progress,
                        const char* tool)
{
    if (!values.has("surface"))
        return fitPrimitive(cloud, kind, progress);
    PrimitiveFit given;
    given.primitive = parsePrimitive(values.text("surface"));
    if (given.primitive.kind != kind)
        throw Error(ErrorCode::InvalidArgument, std::string(tool) + ": --surface is a " + primitiveKindName(given.primitive.kind) +
                                                    ", not a " + primitiveKindName(kind));
    double sum = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const double d = signedDistance(given.primitive, cloud.globalPosition(i));
        sum += d * d;
    }
    given.rms = cloud.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(cloud.size()));
    given.points = 0;
    return given;
}

const char* kSurfaceHelp = "The surface as KIND:NUMBERS (plane:PX,PY,PZ,NX,NY,NZ, sphere:CX,CY,CZ,R, "
                           "cylinder:PX,PY,PZ,DX,DY,DZ,R, cone:AX,AY,AZ,DX,DY,DZ,HALF_ANGLE_DEG); absent: fitted on the cloud";

void addDistanceTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool(
        "primitive-distance", "Distance to a primitive", "Surfaces",
        "The signed distance from every point to a plane, sphere, cylinder or cone, given by its numbers or fitted on "
        "the cloud by least squares (geometric distances, Levenberg-Marquardt); positive outside or on the normal's side. "
        "The surface's parameters come as a table.",
        updatedCloud("Cloud with the distance field"));
    tool.outputs.push_back(OutputSpec{"primitive", "Primitive parameters", DataKind::Table, false});
    tool.parameters = {
        ParameterSpec::choice("kind", "Primitive", "The kind of surface", {"plane", "sphere", "cylinder", "cone"}, "plane"),
        ParameterSpec::text("surface", "Surface", kSurfaceHelp).asOptional(),
        ParameterSpec::text("name", "Result name", "Name of the distance field", "primitive_distance"),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        const PrimitiveKind kind = parsePrimitiveKind(values.text("kind"));
        const PrimitiveFit fit = surfaceFor(input, kind, values, progress, "primitive-distance");
        ScalarField distance(values.text("name").empty() ? "primitive_distance" : values.text("name"), input.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, input.size(), 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i)
                distance.setValue(i, signedDistance(fit.primitive, input.globalPosition(i)));
        });
        PointCloud out = input.clone();
        out.addField(std::move(distance));
        ToolResult result;
        result.summary = describe(values.has("surface") ? "given " : "fitted ", primitiveText(fit.primitive), " (rms ", fit.rms, " m)");
        result.add("output", std::move(out));
        result.add("primitive", primitiveTable(fit.primitive, fit.rms));
        return result;
    };
    registry.add(std::move(tool));
}

void addUnrollTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool(
        "unroll", "Unroll", "Surfaces",
        "Unrolls the cloud about a cylinder (x = arc length, y = height along the axis, z = radial deviation) or a "
        "cone (developed into a plane sector, z = signed distance to it), given or fitted by least squares; adds "
        "unroll_deviation and unroll_angle. With --roll-back and the same surface, an unrolled cloud goes back.",
        newCloud("Unrolled cloud"));
    tool.outputs.push_back(OutputSpec{"surface", "Surface parameters", DataKind::Table, false});
    tool.parameters = {
        ParameterSpec::choice("shape", "Shape", "The surface unrolled about", {"cylinder", "cone"}, "cylinder"),
        ParameterSpec::text("surface", "Surface", kSurfaceHelp).asOptional(),
        ParameterSpec::real("start-angle", "Start angle", "Angle about the axis where the unrolled surface starts", 0, -360, 360, "deg"),
        ParameterSpec::boolean("roll-back", "Roll back", "Take an unrolled cloud back onto the surface (needs --surface)", false),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        const PrimitiveKind kind = parsePrimitiveKind(values.text("shape"));
        const bool back = values.boolean("roll-back");
        if (back && !values.has("surface"))
            throw Error(ErrorCode::InvalidArgument, "unroll: --roll-back needs the --surface the cloud was unrolled about");
        const PrimitiveFit fit = surfaceFor(input, kind, values, progress, "unroll");
        const double start = values.real("start-angle");
        PointCloud out = back ? rollCloud(input, fit.primitive, start, progress) : unrollCloud(input, fit.primitive, start, progress);
        ToolResult result;
        result.summary = describe(back ? "rolled back onto " : "unrolled about ", values.has("surface") ? "the given " : "the fitted ",
                                  primitiveText(fit.primitive), back ? std::string() : describe(" (rms ", fit.rms, " m)"));
        result.add("output", std::move(out));
        result.add("surface", primitiveTable(fit.primitive, back ? std::nullopt : std::optional<double>(fit.rms)));
        return result;
    };
    registry.add(std::move(tool));
}

void addSampleMeshTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool(
        "sample-mesh", "Sample points on a mesh", "Surfaces",
        "Points placed at random on the mesh's triangles, each triangle getting its share of the total by area: a "
        "count or a density (points per m^2). Vertex colours and fields are interpolated; normals are the triangles'.",
        newCloud("Sampled cloud"));
    tool.inputs = {InputSpec{"input", "Mesh", "The mesh to sample", DataKind::Mesh, false, false}};
    tool.parameters = {
        ParameterSpec::integer("count", "Count", "Number of points", 1000000, 1, 2000000000, "points").asAlternative("amount"),
        ParameterSpec::real("density", "Density", "Points per square metre", 100, 1e-9, 1e12, "points/m^2").asAlternative("amount"),
        ParameterSpec::integer("seed", "Seed", "The same seed gives the same points", 0, 0, std::numeric_limits<std::int64_t>::max()),
        ParameterSpec::boolean("no-normals", "No normals", "Do not give the points their triangle's normal", false),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const Mesh& mesh = inputs.mesh();
        MeshSamplingParams params;
        if (values.has("count"))
            params.count = static_cast<std::size_t>(values.integer("count"));
        else if (values.has("density"))
            params.density = values.real("density");
        else
            throw Error(ErrorCode::InvalidArgument, "sample-mesh: give --count N or --density D");
        params.seed = static_cast<std::uint64_t>(values.integer("seed"));
        params.normals = !values.boolean("no-normals");
        PointCloud out = sampleMesh(mesh, params, progress);
        ToolResult result;
        result.summary = describe(out.size(), " points on ", mesh.triangles.size(), " triangles");
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

} // namespace

void registerSurfaceTools(ToolRegistry& registry)
{
    addDistanceTool(registry);
    addUnrollTool(registry);
    addSampleMeshTool(registry);
}

} // namespace scandiff::detail
