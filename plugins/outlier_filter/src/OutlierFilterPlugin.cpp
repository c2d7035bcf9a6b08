// SPDX-License-Identifier: GPL-3.0-or-later
// Registers the statistical outlier filter as the tool "sor-filter".
#include <scandiff/plugins/PluginRegistry.h>
#include <scandiff/plugins/outlier_filter/OutlierFilter.h>

#include <sstream>

void scandiff_register_plugin_outlier_filter(scandiff::PluginRegistry& registry)
{
    using namespace scandiff;
    const plugins::OutlierFilterParams defaults;
    registry.plugins.push_back({"outlier_filter", "Statistical outlier removal on the octree's exact k nearest neighbours", ""});

    ToolSpec tool;
    tool.name = "sor-filter";
    tool.title = "Statistical outlier filter";
    tool.category = "Filters";
    tool.description =
        "Removes isolated points: for each point the mean distance to its k nearest neighbours is computed, and "
        "points whose mean exceeds mu + n_sigma * sigma of all means are dropped (Rusu et al. 2008; the SOR "
        "filter of PCL and CloudCompare). The output keeps every attribute and adds the field sor_mean_distance.";
    tool.parameters = {
        ParameterSpec::integer("k", "Neighbours", "Number of nearest neighbours averaged for each point",
                               defaults.neighbours, 1, 1000, "points"),
        ParameterSpec::real("n-sigma", "Tolerance (sigma)",
                            "Points farther than mean + n-sigma standard deviations are outliers", defaults.nSigma, 0.0,
                            100.0),
    };
    tool.outputs = {OutputSpec{"output", "Inliers", DataKind::Cloud, false}};
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        plugins::OutlierFilterParams params;
        params.neighbours = static_cast<int>(values.integer("k"));
        params.nSigma = values.real("n-sigma");
        plugins::OutlierFilterResult filtered = plugins::statisticalOutliers(input, params, progress);
        ToolResult result;
        // The field is attached to a scratch copy's subset, so the input stays untouched.
        ScalarField meanField("sor_mean_distance", 0);
        meanField.values() = std::move(filtered.meanDistances);
        PointCloud inliers = input.subset(filtered.inliers);
        ScalarField& kept = inliers.addField("sor_mean_distance");
        for (std::size_t j = 0; j < filtered.inliers.size(); ++j)
            kept.values()[j] = meanField.values()[filtered.inliers[j]];
        inliers.name = input.name + "_sor";
        result.add("output", std::move(inliers));
        std::ostringstream summary;
        summary << "kept " << filtered.inliers.size() << " of " << input.size() << " points (removed "
                << input.size() - filtered.inliers.size() << "); mean distance " << filtered.mean << ", sigma "
                << filtered.standardDeviation << ", threshold " << filtered.threshold;
        result.summary = summary.str();
        return result;
    };
    registry.tools.add(std::move(tool));
}
