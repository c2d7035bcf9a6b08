// SPDX-License-Identifier: GPL-3.0-or-later
// Tools: field (expressions), field-gradient, field-smooth, field-rename,
// field-delete, field-to-colours, colours-to-field, field-histogram, filter.
#include "processing/tools/ToolGroups.h"

#include <scandiff/core/ColourScale.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/processing/FieldOperations.h>
#include <scandiff/core/segmentation/FastMarching.h>


namespace scandiff::detail {

namespace {

const ScalarField& fieldOf(const PointCloud& cloud, const std::string& name, const std::string& tool)
{
    const ScalarField* field = cloud.field(name);
    if (!field) {
        std::string names;
        for (const auto& f : cloud.fields())
            names += (names.empty() ? "" : ", ") + f.name();
        throw Error(ErrorCode::InvalidArgument, tool + ": cloud '" + cloud.name + "' has no field '" + name + "'" +
                                                    (names.empty() ? " (it has none)" : " (it has: " + names + ")"));
    }
    return *field;
}

ParameterSpec fieldParameter(const std::string& description)
{
    return ParameterSpec::text("field", "Field", description).asRequired().asFieldOf("input");
}

//! The tool result of a cloud with one more (or a replaced) field.
ToolResult withField(const PointCloud& input, ScalarField field, std::string summary)
{
    PointCloud out = input.clone();
    out.addField(std::move(field));
    ToolResult result;
    result.summary = std::move(summary);
    result.add("output", std::move(out));
    return result;
}

void addExpressionTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool(
        "field", "Field calculator", "Scalar fields",
        "Computes a field from the others with an expression, NAME = EXPRESSION: + - * / ^, comparisons and && || "
        "(1 or 0), c ? a : b, abs sqrt exp ln log10 min max sin cos ...; fields by name (characters other than letters, "
        "digits and _ written _), x y z (global), nx ny nz, r g b. A point without a value in a used field gets none.",
        updatedCloud("Cloud with the new field"));
    tool.parameters = {ParameterSpec::text("expr", "Expression", "NAME = EXPRESSION, e.g. change = c2c_distance > 0.1 ? 1 : 0").asRequired()};
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        const auto [name, expression] = parseFieldAssignment(values.text("expr"));
        ScalarField field = evaluateFieldExpression(input, expression, name, progress);
        const ValueRange range = field.range();
        return withField(input, std::move(field),
                         describe(name, " = ", expression, ": ", range.validCount, " values in [", range.min, ", ", range.max, "]"));
    };
    registry.add(std::move(tool));
}

void addGradientTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool("field-gradient", "Gradient norm", "Scalar fields",
                                 "The norm of a field's gradient, by least squares over the points within a radius (thesis "
                                 "000 §3.3.2; a radius, not k neighbours, so it does not depend on the density).",
                                 updatedCloud("Cloud with the gradient field"));
    tool.parameters = {
        fieldParameter("The field to differentiate"),
        ParameterSpec::real("radius", "Radius", "Neighbourhood radius (absent: about 16 points per octree cell)", 0.1, 1e-9, 1e9, "m")
            .asOptional(),
        ParameterSpec::boolean("clamp", "Clamp to 1", "Clamp norms above 1 (a distance field cannot vary faster)", false),
        ParameterSpec::text("name", "Result name", "Name of the new field (default: FIELD_gradient)"),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        const std::string& fieldName = values.text("field");
        fieldOf(input, fieldName, "field-gradient");
        GradientParams params;
        if (values.has("radius"))
            params.radius = values.real("radius");
        params.clampToOne = values.boolean("clamp");
        GradientResult gradient = gradientNorm(input, fieldName, params, progress);
        gradient.norm.rename(values.text("name").empty() ? fieldName + "_gradient" : values.text("name"));
        return withField(input, std::move(gradient.norm), describe("gradient of ", fieldName, " in a radius of ", gradient.radius, " m"));
    };
    registry.add(std::move(tool));
}

void addSmoothTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool("field-smooth", "Gaussian smoothing", "Scalar fields",
                                 "The Gaussian-weighted mean of a field over the points within 3 sigma (thesis 000 eq. 3.10).",
                                 updatedCloud("Cloud with the smoothed field"));
    tool.parameters = {
        fieldParameter("The field to smooth"),
        ParameterSpec::real("sigma", "Sigma", "Standard deviation of the Gaussian", 0.1, 1e-9, 1e9, "m").asRequired(),
        ParameterSpec::text("name", "Result name", "Name of the new field (default: FIELD_smoothed)"),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        const std::string& fieldName = values.text("field");
        fieldOf(input, fieldName, "field-smooth");
        const std::string name = values.text("name").empty() ? fieldName + "_smoothed" : values.text("name");
        ScalarField smoothed = gaussianSmoothing(input, fieldName, values.real("sigma"), name, progress);
        return withField(input, std::move(smoothed), describe(fieldName, " smoothed with sigma ", values.real("sigma"), " m"));
    };
    registry.add(std::move(tool));
}

void addRenameTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool("field-rename", "Rename a field", "Scalar fields", "Gives a field another name.",
                                 updatedCloud("Cloud with the renamed field"));
    tool.parameters = {fieldParameter("The field to rename"), ParameterSpec::text("to", "New name", "The new name").asRequired()};
    tool.runsOnClasses = false; // a field is renamed or deleted on every point
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver*) {
        const PointCloud& input = inputs.cloud();
        const std::string &from = values.text("field"), &to = values.text("to");
        fieldOf(input, from, "field-rename");
        if (to.empty())
            throw Error(ErrorCode::InvalidArgument, "field-rename: the new name is empty");
        if (to != from && input.field(to))
            throw Error(ErrorCode::InvalidArgument, "field-rename: cloud '" + input.name + "' already has a field '" + to + "'");
        PointCloud out = input.clone();
        out.field(from)->rename(to);
        ToolResult result;
        result.summary = describe("renamed ", from, " to ", to);
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

void addDeleteTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool("field-delete", "Delete fields", "Scalar fields", "Removes fields from the cloud.",
                                 updatedCloud("Cloud without the fields"));
    tool.parameters = {fieldParameter("The fields to delete (NAME;NAME... or the option repeated)")};
    tool.runsOnClasses = false; // a field is renamed or deleted on every point
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver*) {
        const PointCloud& input = inputs.cloud();
        PointCloud out = input.clone();
        std::size_t removed = 0;
        for (const std::string& name : splitList(values.text("field"), ';')) {
            if (name.empty())
                continue;
            fieldOf(input, name, "field-delete");
            removed += out.removeField(name) ? 1 : 0;
        }
        ToolResult result;
        result.summary = describe("deleted ", removed, " field", removed == 1 ? "" : "s");
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

void addToColoursTool(ToolRegistry& registry)
{
    std::vector<std::string> scales;
    for (const auto& scale : ColourScale::presets())
        scales.push_back(scale.name());
    ToolSpec tool = oneCloudTool("field-to-colours", "Field to colours", "Scalar fields",
                                 "Replaces the cloud's colours by a field through a colour scale over a range (the field's "
                                 "own by default; values outside are saturated, points without a value grey).",
                                 updatedCloud("Cloud with the colours"));
    tool.parameters = {
        fieldParameter("The field to colour by"),
        ParameterSpec::choice("scale", "Colour scale", "The scale", scales, ColourScale::defaultScale().name()),
        ParameterSpec::real("min", "Minimum", "Value of the scale's first colour (default: the field's minimum)", 0, -1e300, 1e300)
            .asOptional(),
        ParameterSpec::real("max", "Maximum", "Value of the scale's last colour (default: the field's maximum)", 1, -1e300, 1e300)
            .asOptional(),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver*) {
        const PointCloud& input = inputs.cloud();
        const ScalarField& field = fieldOf(input, values.text("field"), "field-to-colours");
        const ValueRange range = field.range();
        if (range.validCount == 0 && !(values.has("min") && values.has("max")))
            throw Error(ErrorCode::InvalidArgument, "field-to-colours: field '" + field.name() + "' has no value to colour by");
        const double low = values.has("min") ? values.real("min") : range.min;
        const double high = values.has("max") ? values.real("max") : range.max;
        PointCloud out = input.clone();
        out.enableColors() = coloursFromField(field, *ColourScale::preset(values.text("scale")), low, high);
        ToolResult result;
        result.summary = describe(field.name(), " coloured with ", values.text("scale"), " over [", low, ", ", high, "]");
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

void addFromColoursTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool("colours-to-field", "Colours to field", "Scalar fields",
                                 "A field from the colours: luminance (0.2126 R + 0.7152 G + 0.0722 B, ITU-R BT.709), one "
                                 "channel, or their mean, in 0..255.",
                                 updatedCloud("Cloud with the colour field"));
    tool.parameters = {
        ParameterSpec::choice("channel", "Channel", "What the field holds", {"luminance", "red", "green", "blue", "mean"}, "luminance"),
        ParameterSpec::text("name", "Result name", "Name of the new field (default: the channel's)"),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver*) {
        const PointCloud& input = inputs.cloud();
        const std::string& channel = values.text("channel");
        const std::string name = values.text("name").empty() ? channel : values.text("name");
        return withField(input, fieldFromColours(input, parseColourChannel(channel), name), describe(name, " from the colours"));
    };
    registry.add(std::move(tool));
}

void addHistogramTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool("field-histogram", "Field histogram", "Scalar fields",
                                 "The histogram of a field as a table (bin_min, bin_max, count), over the field's range or a "
                                 "given one; saved as CSV.",
                                 OutputSpec{"output", "Histogram", DataKind::Table, false});
    tool.parameters = {
        fieldParameter("The field"),
        ParameterSpec::integer("bins", "Bins", "Number of bins", 256, 1, 10000000),
        ParameterSpec::real("min", "Minimum", "Start of the first bin (with --max; default: the field's minimum)", 0, -1e300, 1e300)
            .asOptional(),
        ParameterSpec::real("max", "Maximum", "End of the last bin (with --min; default: the field's maximum)", 1, -1e300, 1e300)
            .asOptional(),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver*) {
        const PointCloud& input = inputs.cloud();
        const ScalarField& field = fieldOf(input, values.text("field"), "field-histogram");
        if (values.has("min") != values.has("max"))
            throw Error(ErrorCode::InvalidArgument, "field-histogram: give both --min and --max, or neither");
        std::optional<std::pair<double, double>> range;
        if (values.has("min"))
            range = std::make_pair(values.real("min"), values.real("max"));
        const int bins = static_cast<int>(values.integer("bins"));
        Table table = fieldHistogram(field, bins, range);
        ToolResult result;
        result.summary = describe(bins, " bins of ", field.name(), " over [", std::get<double>(table.rows.front()[0]), ", ",
                                  std::get<double>(table.rows.back()[1]), "]");
        result.add("output", std::move(table));
        return result;
    };
    registry.add(std::move(tool));
}

void addFilterTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool("filter", "Filter by value", "Scalar fields",
                                 "Keeps the points whose value of a field lies in [A, B] (bounds included), or with --outside "
                                 "the points outside it (CloudCompare's Filter by value). Points without a value are left out "
                                 "either way.",
                                 newCloud("Filtered cloud"));
    tool.parameters = {
        fieldParameter("The field"),
        ParameterSpec::text("range", "Range", "A B: the bounds, in the field's units (also 'A,B')").asRequired().takingValues(2),
        ParameterSpec::boolean("outside", "Keep outside", "Keep the points outside [A, B] instead", false),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver*) {
        const PointCloud& input = inputs.cloud();
        const std::vector<double> bounds = parseNumberWords(values.text("range"), "the range");
        if (bounds.size() != 2)
            throw Error(ErrorCode::InvalidArgument, "filter: --range takes two values A B");
        FilterByValueParams params;
        params.field = fieldOf(input, values.text("field"), "filter").name();
        params.low = bounds[0];
        params.high = bounds[1];
        params.outside = values.boolean("outside");
        const FilterByValueResult filtered = filterByValue(input, params);
        PointCloud out = input.subset(filtered.kept);
        out.name = input.name + "_filtered";
        ToolResult result;
        result.summary = describe("kept ", filtered.kept.size(), " of ", input.size(), " points with ", params.field,
                                  params.outside ? " outside [" : " in [", params.low, ", ", params.high, "]",
                                  filtered.withoutValue ? describe(" (", filtered.withoutValue, " without a value left out)") : "");
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

} // namespace

void registerFieldTools(ToolRegistry& registry)
{
    addExpressionTool(registry);
    addGradientTool(registry);
    addSmoothTool(registry);
    addRenameTool(registry);
    addDeleteTool(registry);
    addToColoursTool(registry);
    addFromColoursTool(registry);
    addHistogramTool(registry);
    addFilterTool(registry);
}

} // namespace scandiff::detail
