// SPDX-License-Identifier: GPL-3.0-or-later
// Tool: subsample.
#include "processing/tools/ToolGroups.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/processing/Subsampling.h>

namespace scandiff::detail {

void registerSubsamplingTools(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool(
        "subsample", "Subsample", "Subsample",
        "Keeps some of the points, with every field, colour and normal, in input order: a random count; points more "
        "than a distance apart (each point kept unless a point kept before it lies within the distance; exact, the "
        "same on any number of threads); or one point per cell of an octree level (the nearest to the cell's centre).",
        newCloud("Subsampled cloud"));
    tool.parameters = {
        ParameterSpec::integer("random", "Random count", "Keep this many points, drawn at random", 100000, 1,
                               std::numeric_limits<std::int64_t>::max(), "points")
            .asAlternative("method"),
        ParameterSpec::real("spatial", "Minimum distance", "Keep points more than this far apart", 0.05, 1e-9, 1e9, "m")
            .asAlternative("method"),
        ParameterSpec::integer("octree", "Octree level", "Keep one point per cell of this octree level", 8, 1, 21).asAlternative("method"),
        ParameterSpec::integer("seed", "Seed", "Random draw: the same seed gives the same points", 0, 0,
                               std::numeric_limits<std::int64_t>::max()),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        std::vector<std::size_t> kept;
        std::string how;
        if (values.has("random")) {
            kept = randomSubsample(input, static_cast<std::size_t>(values.integer("random")), static_cast<std::uint64_t>(values.integer("seed")));
            how = describe("random, seed ", values.integer("seed"));
        } else if (values.has("spatial")) {
            kept = spatialSubsample(input, values.real("spatial"), progress);
            how = describe("more than ", values.real("spatial"), " m apart");
        } else if (values.has("octree")) {
            kept = octreeSubsample(input, static_cast<int>(values.integer("octree")), progress);
            how = describe("one per cell of octree level ", values.integer("octree"));
        } else {
            throw Error(ErrorCode::InvalidArgument, "subsample: give one of --random N, --spatial D, --octree LEVEL");
        }
        PointCloud out = input.subset(kept);
        out.name = input.name + "_subsampled";
        ToolResult result;
        result.summary = describe("kept ", kept.size(), " of ", input.size(), " points (", how, ")");
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

} // namespace scandiff::detail
