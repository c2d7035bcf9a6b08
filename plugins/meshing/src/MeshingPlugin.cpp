// SPDX-License-Identifier: GPL-3.0-or-later
// Registers the 2.5D Delaunay meshing as the tool "mesh", and the height
// above the ground's TIN as "hag".
#include <scandiff/core/ClassSelection.h>
#include <scandiff/plugins/PluginRegistry.h>
#include <scandiff/plugins/meshing/Delaunay25D.h>
#include <scandiff/plugins/meshing/HeightAboveGround.h>

#include <cmath>
#include <sstream>

namespace {

void registerHeightAboveGround(scandiff::PluginRegistry& registry)
{
    using namespace scandiff;
    ToolSpec tool;
    tool.name = "hag";
    tool.title = "Height above ground";
    tool.category = "Classification";
    tool.description =
        "Each point's height over the terrain of its ground points (classes 2 by default, as `ground` writes them): "
        "their Delaunay triangulation in XY (a TIN), interpolated linearly in the triangle under the point, as PDAL's "
        "filters.hag_delaunay; beyond the TIN's outline, the height over the nearest ground point. Adds the field "
        "height_above_ground (m): 0 on the ground points (where several share one XY place, on the one the terrain "
        "keeps), canopy and roof heights above.";
    tool.outputs = {OutputSpec{"output", "Cloud with heights above ground", DataKind::Cloud, true}};
    tool.parameters = {
        ParameterSpec::text("ground-classes", "Ground classes", "The classes the terrain is made of, e.g. 2 or 2,8 (ASPRS: 2 ground, 8 model key points)", "2"),
        ParameterSpec::text("class-field", "Class field", "The field holding the classes", "classification"),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        plugins::HeightAboveGroundParams params;
        params.classField = values.text("class-field");
        params.groundClasses = parseClassList(values.text("ground-classes"), "hag: --ground-classes");
        plugins::HeightAboveGroundResult hag = plugins::heightAboveGround(input, params, progress);
        PointCloud out = input.clone();
        if (out.field("height_above_ground"))
            out.removeField("height_above_ground");
        ScalarField& field = out.addField("height_above_ground");
        field.values() = std::move(hag.height);
        std::ostringstream summary;
        summary << "heights above a TIN of " << hag.groundPoints << " ground points for " << input.size() << " points";
        if (hag.outsideHull)
            summary << "; " << hag.outsideHull << " beyond its outline over their nearest ground point";
        ToolResult result;
        result.summary = summary.str();
        result.add("output", std::move(out));
        return result;
    };
    registry.tools.add(std::move(tool));
}

} // namespace

void scandiff_register_plugin_meshing(scandiff::PluginRegistry& registry)
{
    using namespace scandiff;
    registry.plugins.push_back({"meshing", "2.5D Delaunay meshing of a cloud projected on a plane, and heights above the ground's TIN", "CGAL (2D triangulation)"});

    ToolSpec tool;
    tool.name = "mesh";
    tool.title = "Mesh (2.5D Delaunay)";
    tool.category = "Surfaces";
    tool.description =
        "Triangulates the points projected on a plane (vertical axis by default, or the x or y axis, or the "
        "least-squares plane of a wall) by Delaunay, and lifts the triangles back onto the points (thesis 000 annex C). "
        "A maximum edge length leaves holes and concave borders open. The mesh keeps every point and attribute, and "
        "C2M can use it as a reference.";
    tool.outputs = {OutputSpec{"output", "Mesh", DataKind::Mesh, false}};
    tool.parameters = {
        ParameterSpec::choice("projection", "Projection", "Plane the points are triangulated on: z (terrain), x, y, best-fit (a wall)",
                              {"z", "x", "y", "best-fit"}, "z"),
        ParameterSpec::real("max-edge", "Maximum edge", "Drop triangles with an edge longer than this", 1.0, 1e-9, 1e9, "m").asOptional(),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        plugins::Delaunay25DParams params;
        const std::string& projection = values.text("projection");
        params.projection = projection == "z"   ? plugins::ProjectionPlane::AlongZ
                            : projection == "x" ? plugins::ProjectionPlane::AlongX
                            : projection == "y" ? plugins::ProjectionPlane::AlongY
                                                : plugins::ProjectionPlane::BestFit;
        if (values.has("max-edge"))
            params.maxEdgeLength = values.real("max-edge");
        plugins::Delaunay25DResult meshed = plugins::delaunay25D(input, params, progress);
        std::ostringstream summary;
        summary.precision(6);
        summary << meshed.mesh.triangles.size() << " triangles on " << input.size() << " points, area " << meshed.area << " m^2";
        if (meshed.dropped)
            summary << "; " << meshed.dropped << " triangles longer than the limit dropped";
        if (meshed.duplicates)
            summary << "; " << meshed.duplicates << " points at the place of another left out";
        ToolResult result;
        result.summary = summary.str();
        result.add("output", std::move(meshed.mesh));
        return result;
    };
    registry.tools.add(std::move(tool));
    registerHeightAboveGround(registry);
}
