// SPDX-License-Identifier: GPL-3.0-or-later
// Tool: ground.
#include "processing/tools/ToolGroups.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/processing/GroundFilter.h>

namespace scandiff::detail {

void registerGroundTools(ToolRegistry& registry)
{
    const GroundFilterParams defaults;
    ToolSpec tool = oneCloudTool(
        "ground", "Ground filter", "Classification",
        "Finds the bare terrain under buildings and vegetation with the Simple Morphological Filter (Pingel et al. "
        "2013; PDAL's filters.smrf, same defaults): the lowest point of each grid cell, opened by windows growing up to "
        "the largest object's size; what the openings lower by more than the slope allows is an object; the points "
        "within a threshold (plus a share of the local slope) of the terrain left are ground. Writes the ASPRS "
        "field classification: 2 ground, 1 unclassified.",
        updatedCloud("Cloud with ground classes"));
    tool.parameters = {
        ParameterSpec::real("cell", "Cell", "Grid cell: about the ground's point spacing, or more", defaults.cell, 1e-4, 1e6, "m"),
        ParameterSpec::real("slope", "Slope", "Rise over run the terrain may have without being an object", defaults.slope, 0, 100),
        ParameterSpec::real("window", "Largest window", "Wider than the widest building or tree crown", defaults.window, 1e-4, 1e6, "m"),
        ParameterSpec::real("threshold", "Height threshold", "A point within this height of the terrain is ground",
                            defaults.threshold, 0, 1e6, "m"),
        ParameterSpec::real("scalar", "Slope scalar", "Added to the threshold per unit of the terrain's slope", defaults.scalar, 0, 1e6, "m"),
        ParameterSpec::boolean("overwrite-classes", "Overwrite classes",
                               "Replace a classification field the cloud already has (otherwise refused)", false),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        if (input.field("classification") && !values.boolean("overwrite-classes"))
            throw Error(ErrorCode::InvalidArgument, "ground: '" + input.name
                                                        + "' already has a classification field; give --overwrite-classes to replace it");
        GroundFilterParams params;
        params.cell = values.real("cell");
        params.slope = values.real("slope");
        params.window = values.real("window");
        params.threshold = values.real("threshold");
        params.scalar = values.real("scalar");
        const GroundFilterResult ground = filterGround(input, params, progress);
        PointCloud out = input.clone();
        ScalarField classes("classification", input.size());
        for (std::size_t i = 0; i < input.size(); ++i)
            classes.values()[i] = ground.ground[i] ? 2.f : 1.f;
        out.addField(std::move(classes));
        ToolResult result;
        result.summary = describe(ground.groundCount, " of ", input.size(), " points ground (class 2), the others 1; ",
                                  ground.objectCells, " cells of ", params.cell,
                                  " m with points marked as objects");
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

} // namespace scandiff::detail
