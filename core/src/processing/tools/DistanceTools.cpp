// SPDX-License-Identifier: GPL-3.0-or-later
// Tools: m3c2, dod, volume.
#include "processing/tools/ToolGroups.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/distance/DemOfDifference.h>
#include <scandiff/core/distance/DistanceParameters.h>
#include <scandiff/core/distance/M3C2.h>
#include <scandiff/core/processing/Subsampling.h>

#include <limits>
#include <optional>

namespace scandiff::detail {

namespace {

std::vector<ParameterSpec> rasterParameters()
{
    return {
        ParameterSpec::real("cell", "Cell size", "Side of the square cells both epochs are rasterised on", 1.0, 1e-6, 1e6, "m").asRequired(),
        ParameterSpec::choice("statistic", "Cell height", "The height of a cell from its points' heights",
                              {"min", "mean", "max", "median"}, "mean"),
        ParameterSpec::integer("fill", "Fill passes",
                               "Passes filling empty cells with the mean of their filled neighbours (0: leave them empty)", 0, 0, 1000),
        ParameterSpec::real("reference-height", "Reference height",
                            "Without a reference cloud: compare with this constant height (a floor, a design level)", 0.0, -1e9, 1e9, "m")
            .asOptional(),
    };
}

std::vector<InputSpec> epochInputs()
{
    return {InputSpec{"reference", "Reference", "The first epoch (or give a reference height)", DataKind::Cloud, false, true},
            InputSpec{"compared", "Compared", "The second epoch", DataKind::Cloud, false, false}};
}

DemOfDifferenceParams rasterFrom(const ParameterValues& values)
{
    DemOfDifferenceParams params;
    params.cell = values.real("cell");
    params.statistic = parseCellStatistic(values.text("statistic"));
    params.fillPasses = static_cast<int>(values.integer("fill"));
    if (values.has("reference-height"))
        params.referenceHeight = values.real("reference-height");
    return params;
}

ToolResult rasterResult(const ToolInputs& inputs, const DemOfDifferenceParams& params, ProgressObserver* progress, bool dod)
{
    const PointCloud* reference = inputs.has("reference") ? &inputs.cloud("reference") : nullptr;
    DemOfDifferenceResult r = demOfDifference(reference, inputs.cloud("compared"), params, progress);
    ToolResult result;
    result.summary = dod ? describe(r.columns, " x ", r.rows, " cells of ", params.cell, " m: ", r.significantCells, " significant of ",
                                    r.matchingCells, "; deposition ", r.deposition, " +/- ", r.depositionError, " m3, erosion ",
                                    r.erosion, " +/- ", r.erosionError, " m3")
                         : describe("added ", r.added, " m3, removed ", r.removed, " m3 over ", r.matchingCells * r.cellArea,
                                    " m2 (", r.matchingCells, " cells with both heights)");
    result.add("report", r.report());
    result.add("output", std::move(r.cells));
    return result;
}

} // namespace

void registerRasterTools(ToolRegistry& registry)
{
    ToolSpec dod;
    dod.name = "dod";
    dod.title = "DEM of difference";
    dod.category = "Distances";
    dod.description =
        "Both epochs rasterised on one grid of square cells (min, mean, max or median height per cell; empty cells left "
        "empty or filled from their neighbours), the compared heights minus the reference's, thresholded by a minimum "
        "level of detection or by the propagated error 1.96 sqrt(dz1^2 + dz2^2) (dz: each cell's roughness, or a given "
        "height error); deposition and erosion volumes of the significant cells with their uncertainty. The grid is a "
        "cloud of cell centres (dod_difference, dod_lod, dod_significant, z_reference, z_compared): write it as .tif for "
        "a GeoTIFF with one band per field.";
    dod.inputs = epochInputs();
    dod.outputs = {OutputSpec{"output", "DEM of difference (cells)", DataKind::Cloud, false},
                   OutputSpec{"report", "Volumes", DataKind::Table, false}};
    dod.parameters = rasterParameters();
    dod.parameters.push_back(
        ParameterSpec::real("lod", "Level of detection", "Changes smaller than this are not significant", 0.1, 0.0, 1e6, "m").asOptional());
    dod.parameters.push_back(ParameterSpec::boolean(
        "propagated", "Propagated error", "Threshold each cell at 1.96 sqrt(dz1^2 + dz2^2) instead of one level of detection", false));
    dod.parameters.push_back(ParameterSpec::real("height-error", "Height error",
                                                 "The height error of every cell instead of its roughness", 0.01, 0.0, 1e6, "m")
                                 .asOptional());
    dod.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        DemOfDifferenceParams params = rasterFrom(values);
        if (values.has("lod"))
            params.lod = values.real("lod");
        params.propagated = values.boolean("propagated");
        if (values.has("height-error"))
            params.heightError = values.real("height-error");
        return rasterResult(inputs, params, progress, true);
    };
    registry.add(std::move(dod));

    ToolSpec volume;
    volume.name = "volume";
    volume.title = "2.5D volume";
    volume.category = "Distances";
    volume.description =
        "The volume between two epochs (or an epoch and a constant height) on a grid of square cells, as CloudCompare's "
        "\"Compute 2.5D volume\": added and removed volume over the cells where both have a height, their surface and "
        "their share of the cells; no threshold. The grid is a cloud of cell centres, as for the DEM of difference.";
    volume.inputs = epochInputs();
    volume.outputs = {OutputSpec{"output", "Volume grid (cells)", DataKind::Cloud, false},
                      OutputSpec{"report", "Volume report", DataKind::Table, false}};
    volume.parameters = rasterParameters();
    volume.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        return rasterResult(inputs, rasterFrom(values), progress, false);
    };
    registry.add(std::move(volume));

    ToolSpec rasterize;
    rasterize.name = "rasterize";
    rasterize.title = "Rasterize";
    rasterize.category = "Projection";
    rasterize.description =
        "A cloud on a grid of square cells in the horizontal plane, as CloudCompare's Rasterize: each cell holding points "
        "becomes one point at its centre, at the min, mean, max or median height of its points, with point_count and the "
        "mean of each scalar field (a 0/1 flag gives the share of 1s). Write it as .tif for a GeoTIFF with one band per "
        "field, georeferenced with the cloud's coordinate reference system.";
    rasterize.inputs = {InputSpec{"input", "Cloud", "The cloud to rasterise", DataKind::Cloud, false, false}};
    rasterize.outputs = {OutputSpec{"output", "Raster (cells)", DataKind::Cloud, false}};
    rasterize.parameters = {
        ParameterSpec::real("cell", "Cell size", "Side of the square cells", 1.0, 1e-6, 1e6, "m").asRequired(),
        ParameterSpec::choice("statistic", "Cell height", "The height of a cell from its points' heights",
                              {"min", "mean", "max", "median"}, "mean"),
        ParameterSpec::text("fields", "Fields", "Scalar fields to carry, separated by commas (default: every field)").asOptional(),
    };
    rasterize.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        RasteriseParams params;
        params.cell = values.real("cell");
        params.statistic = parseCellStatistic(values.text("statistic"));
        if (values.has("fields"))
            params.fields = splitList(values.text("fields"), ',');
        PointCloud cells = rasteriseCloud(inputs.cloud("input"), params, progress);
        ToolResult result;
        result.summary = describe(cells.size(), " cells of ", params.cell, " m holding points");
        result.add("output", std::move(cells));
        return result;
    };
    registry.add(std::move(rasterize));
}

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
    tool.outputs = {OutputSpec{"output", "M3C2 core points", DataKind::Cloud, false},
                    OutputSpec{"raster", "M3C2 raster (cells)", DataKind::Cloud, false}};
    tool.parameters = m3c2Parameters();
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& reference = inputs.cloud("reference");
        const PointCloud& compared = inputs.cloud("compared");
        M3c2Params params = m3c2Settings(values);
        if (inputs.has("core-points") && values.has("core-spacing"))
            throw Error(ErrorCode::InvalidArgument, "m3c2: give core points or a core spacing, not both");
        // A scale of 0 is guessed from the epochs, as CloudCompare's "guess parameters".
        std::string guessed;
        const bool guessNormal = params.normalScales.size() == 1 && params.normalScales.front() == 0.0;
        if (guessNormal || params.projectionScale == 0.0) {
            M3c2ScaleGuessParams guessing;
            if (params.projectionScale != 0.0)
                guessing.projectionScale = params.projectionScale; // D from the d the user gave
            const M3c2ScaleGuess guess = guessM3c2Scales(reference, compared, guessing, progress);
            if (guessNormal)
                params.normalScales = {guess.normalScale};
            if (params.projectionScale == 0.0)
                params.projectionScale = guess.projectionScale;
            guessed = describe(" (guessed: normal scale ", params.normalScales.front(), ", projection scale ", params.projectionScale,
                               " m; spacing ", guess.spacing, " m)");
        }

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
                                  m.withoutNormal ? describe(", ", m.withoutNormal, " without a normal") : std::string(), guessed);
        std::optional<PointCloud> cells;
        if (values.has("raster-cell")) {
            RasteriseParams raster;
            raster.cell = values.real("raster-cell");
            raster.fields = {fields::kM3c2Distance, fields::kM3c2Uncertainty, fields::kM3c2Significant};
            cells = rasteriseCloud(m.corePoints, raster, progress);
            cells->name = reference.name + "_m3c2_raster";
        }
        result.add("output", std::move(m.corePoints));
        if (cells)
            result.add("raster", std::move(*cells));
        return result;
    };
    registry.add(std::move(tool));

    ToolSpec scales;
    scales.name = "m3c2-scales";
    scales.title = "M3C2 scales (guess)";
    scales.category = "Distances";
    scales.description =
        "Guesses M3C2's scales from the two epochs, as CloudCompare's plugin does (Guess params), on the criteria of Lague, "
        "Brodu and Leroux (2013): the projection scale d from the point spacing, so that the median cylinder holds 30 points "
        "of each epoch, and the normal scale D from the roughness, D / sigma(D) >= 25; both rounded up to two digits. "
        "m3c2 uses them when its scales are 0.";
    scales.inputs = {InputSpec{"reference", "Reference", "The first epoch", DataKind::Cloud, false, false},
                     InputSpec{"compared", "Compared", "The second epoch", DataKind::Cloud, false, false}};
    scales.outputs = {OutputSpec{"output", "Guessed scales", DataKind::Table, false}};
    scales.parameters = {
        ParameterSpec::integer("points-per-cylinder", "Points per cylinder", "In the median cylinder, in each epoch", 30, 3, 100000),
        ParameterSpec::real("roughness-ratio", "Roughness ratio", "D / sigma(D) at the median sample", 25.0, 1.0, 1e6),
        ParameterSpec::integer("samples", "Samples", "Reference points the criteria are measured at", 2000, 10, 10000000),
    };
    scales.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        M3c2ScaleGuessParams params;
        params.pointsPerCylinder = static_cast<std::size_t>(values.integer("points-per-cylinder"));
        params.roughnessRatio = values.real("roughness-ratio");
        params.samples = static_cast<std::size_t>(values.integer("samples"));
        const M3c2ScaleGuess guess = guessM3c2Scales(inputs.cloud("reference"), inputs.cloud("compared"), params, progress);
        Table table;
        table.columns = {"quantity", "value"};
        table.rows = {{std::string("normal_scale"), guess.normalScale},
                      {std::string("projection_scale"), guess.projectionScale},
                      {std::string("spacing"), guess.spacing},
                      {std::string("median_points_reference"), guess.medianPointsReference},
                      {std::string("median_points_compared"), guess.medianPointsCompared},
                      {std::string("median_roughness_ratio"), guess.medianRoughnessRatio}};
        ToolResult result;
        result.summary = describe("normal scale ", guess.normalScale, " m, projection scale ", guess.projectionScale, " m (spacing ",
                                  guess.spacing, " m; ", guess.medianPointsReference, " and ", guess.medianPointsCompared,
                                  " points in the median cylinder; D / sigma(D) ", guess.medianRoughnessRatio,
                                  guess.roughnessRatioReached ? ")" : ", rougher than asked at 5 d, the widest tried)");
        result.add("output", std::move(table));
        return result;
    };
    registry.add(std::move(scales));
    registerRasterTools(registry);
}

} // namespace scandiff::detail
