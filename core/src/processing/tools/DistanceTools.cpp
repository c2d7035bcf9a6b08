// SPDX-License-Identifier: GPL-3.0-or-later
// Tool: m3c2.
#include "processing/tools/ToolGroups.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/distance/M3C2.h>
#include <scandiff/core/processing/Subsampling.h>

#include <limits>

namespace scandiff::detail {

namespace {

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

void registerDistanceTools(ToolRegistry& registry)
{
    ToolSpec tool;
    tool.name = "m3c2";
    tool.title = "M3C2";
    tool.category = "Distances";
    tool.description =
        "Change along the local normal with its level of detection (Lague, Brodu and Leroux 2013): at every core point, "
        "the normal of the reference within the normal scale, each epoch's points in the cylinder of the projection scale "
        "and maximum depth along it, the distance between their means (or medians) and LoD95 = 1.96 (sqrt(s1^2/n1 + "
        "s2^2/n2) + registration error); significant where |distance| > LoD95. Scales are diameters, as in CloudCompare's "
        "plugin. Fields m3c2_distance, m3c2_uncertainty, m3c2_significant, m3c2_n1, m3c2_n2, m3c2_std1, m3c2_std2, "
        "m3c2_normal_scale on the core points, with their normals.";
    tool.inputs = {
        InputSpec{"reference", "Reference", "The first epoch: its normals orient the comparison", DataKind::Cloud, false, false},
        InputSpec{"compared", "Compared", "The second epoch", DataKind::Cloud, false, false},
        InputSpec{"core-points", "Core points", "Where to measure (default: every reference point, or a subsample with "
                                                 "--core-spacing)",
                  DataKind::Cloud, false, true},
    };
    tool.outputs = {OutputSpec{"output", "M3C2 core points", DataKind::Cloud, false}};
    tool.parameters = {
        ParameterSpec::real("normal-scale", "Normal scale D", "Diameter of the reference neighbourhood the normal is fitted on",
                            1.0, 1e-6, 1e6, "m")
            .asRequired(),
        ParameterSpec::text("normal-scales", "Normal scales",
                            "Several diameters D1,D2,D3 (multi-scale normal: the most planar is kept); replaces the normal scale")
            .asOptional(),
        ParameterSpec::real("projection-scale", "Projection scale d", "Diameter of the cylinder each epoch is averaged in",
                            1.0, 1e-6, 1e6, "m")
            .asRequired(),
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
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& reference = inputs.cloud("reference");
        const PointCloud& compared = inputs.cloud("compared");
        M3c2Params params;
        params.normalScales = scalesFrom(values);
        params.projectionScale = values.real("projection-scale");
        params.maxDepth = values.real("max-depth");
        params.registrationError = values.real("registration-error");
        params.minPoints = static_cast<std::size_t>(values.integer("min-points"));
        params.robust = values.boolean("robust");
        params.sampleStd = values.boolean("sample-std");
        params.orientation = parseNormalOrientation(values.text("orientation"));
        if (inputs.has("core-points") && values.has("core-spacing"))
            throw Error(ErrorCode::InvalidArgument, "m3c2: give core points or a core spacing, not both");
        M3c2Result m;
        if (inputs.has("core-points")) {
            m = m3c2(reference, compared, inputs.cloud("core-points"), params, progress);
        } else if (values.has("core-spacing")) {
            PointCloud cores = reference.subset(spatialSubsample(reference, values.real("core-spacing"), progress));
            cores.name = reference.name + "_core";
            m = m3c2(reference, compared, cores, params, progress);
        } else {
            m = m3c2(reference, compared, reference, params, progress);
        }
        m.corePoints.name = reference.name + "_m3c2";
        ToolResult result;
        result.summary = describe("M3C2 at ", m.corePoints.size(), " core points: ", m.measuredCount, " measured, ",
                                  m.significantCount, " significant changes",
                                  m.withoutNormal ? describe(", ", m.withoutNormal, " without a normal") : std::string());
        result.add("output", std::move(m.corePoints));
        return result;
    };
    registry.add(std::move(tool));
}

} // namespace scandiff::detail
