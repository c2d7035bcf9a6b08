// SPDX-License-Identifier: GPL-3.0-or-later
// Tools: clone, merge, transform, crop, cross-sections.
#include "processing/tools/ToolGroups.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/processing/CloudEditing.h>
#include <scandiff/core/processing/CrossSections.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace scandiff::detail {

namespace {

//! Numbers separated by commas, semicolons, spaces, tabs or line breaks.
std::vector<double> numbersIn(const std::string& text, const std::string& what)
{
    std::string spaced = text;
    for (char& c : spaced)
        if (c == ',' || c == ';' || c == '\t' || c == '\n' || c == '\r')
            c = ' ';
    std::istringstream in(spaced);
    std::vector<double> out;
    std::string token;
    while (in >> token) {
        const std::vector<double> one = parseNumberList(token, what);
        out.insert(out.end(), one.begin(), one.end());
    }
    return out;
}

Eigen::Vector3d vector3(const std::string& text, const std::string& what)
{
    const std::vector<double> v = parseNumberList(text, what);
    if (v.size() != 3)
        throw Error(ErrorCode::InvalidArgument, what + " is X,Y,Z");
    return {v[0], v[1], v[2]};
}

//! 16 numbers typed or pasted (row by row), or the text file holding them
//! (CloudCompare's layout: four lines of four numbers).
Eigen::Matrix4d parseMatrix(const std::string& text)
{
    std::vector<double> v;
    bool numeric = true;
    try {
        v = numbersIn(text, "the matrix");
    } catch (const Error&) {
        numeric = false;
    }
    if (!numeric || v.size() != 16) {
        std::ifstream file(text);
        if (!numeric && !file)
            throw Error(ErrorCode::InvalidArgument, "transform: '" + text + "' is neither 16 numbers nor a readable matrix file");
        if (file) {
            std::stringstream content;
            content << file.rdbuf();
            v = numbersIn(content.str(), "the matrix file " + text);
        }
    }
    if (v.size() != 16)
        throw Error(ErrorCode::InvalidArgument, "transform: a matrix is 16 numbers (4 rows of 4), not " + std::to_string(v.size()));
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            m(r, c) = v[static_cast<std::size_t>(4 * r + c)];
    return m;
}

Eigen::Vector3d centreOf(const PointCloud& cloud, const std::string& text)
{
    if (text == "centroid") {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (const auto& p : cloud.positions())
            sum += p.cast<double>();
        return cloud.origin() + sum / static_cast<double>(std::max<std::size_t>(1, cloud.size()));
    }
    if (text == "box-centre") {
        const BoundingBox box = cloud.bounds();
        return box.empty ? Eigen::Vector3d::Zero() : Eigen::Vector3d((box.min + box.max) / 2);
    }
    return vector3(text, "the centre");
}

void addCloneTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool("clone", "Clone", "Edit", "A copy of the cloud, with every attribute.", newCloud("Copy"));
    tool.run = [](const ToolInputs& inputs, const ParameterValues&, ProgressObserver*) {
        PointCloud out = inputs.cloud().clone();
        out.name = inputs.cloud().name + "_clone";
        ToolResult result;
        result.summary = describe("copied ", out.size(), " points");
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

// "R,G,B" (each 0-255) or "#rrggbb".
Rgb8 parseColour(const std::string& text)
{
    const auto invalid = [&] {
        return Error(ErrorCode::InvalidArgument, "set-colour: '" + text + "' is not a colour (R,G,B with each 0-255, or #rrggbb)");
    };
    int channels[3] = {0, 0, 0};
    if (!text.empty() && text.front() == '#') {
        if (text.size() != 7 || text.find_first_not_of("0123456789abcdefABCDEF", 1) != std::string::npos)
            throw invalid();
        for (int c = 0; c < 3; ++c)
            channels[c] = std::stoi(text.substr(1 + 2 * c, 2), nullptr, 16);
    } else {
        const std::vector<double> values = parseNumberWords(text, "set-colour");
        if (values.size() != 3)
            throw invalid();
        for (int c = 0; c < 3; ++c) {
            if (!(values[c] >= 0 && values[c] <= 255) || values[c] != std::floor(values[c]))
                throw invalid();
            channels[c] = static_cast<int>(values[c]);
        }
    }
    return Rgb8{static_cast<std::uint8_t>(channels[0]), static_cast<std::uint8_t>(channels[1]), static_cast<std::uint8_t>(channels[2])};
}

// CloudCompare's Edit > Colors > Set unique: one colour for every point,
// e.g. to tell two epochs apart at a glance.
void addSetColourTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool("set-colour", "Set one colour", "Edit",
                                 "Gives every point of the cloud one colour (replacing its colours, if any).",
                                 updatedCloud("Coloured cloud"));
    tool.parameters = {ParameterSpec::text("colour", "Colour", "R,G,B (each 0-255) or #rrggbb", "255,200,0")};
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver*) {
        const Rgb8 colour = parseColour(values.text("colour"));
        PointCloud out = inputs.cloud().clone();
        std::vector<Rgb8>& colours = out.enableColors();
        std::fill(colours.begin(), colours.end(), colour);
        ToolResult result;
        result.summary = describe("coloured ", out.size(), " points ", int(colour.r), ",", int(colour.g), ",", int(colour.b));
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

void addMergeTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool("merge", "Merge clouds", "Edit",
                                 "One cloud holding every point of the inputs, in their order, with the field source_index "
                                 "(0 for the first input). Global shifts are reconciled in double precision; fields are "
                                 "matched by name (no value where a cloud lacks one).",
                                 newCloud("Merged cloud"));
    tool.inputs = {InputSpec{"input", "Clouds", "The clouds to merge, in order", DataKind::Cloud, true, false}};
    tool.run = [](const ToolInputs& inputs, const ParameterValues&, ProgressObserver* progress) {
        std::vector<const PointCloud*> clouds;
        for (std::size_t i = 0; i < inputs.count("input"); ++i)
            clouds.push_back(&inputs.cloud("input", i));
        PointCloud out = mergeClouds(clouds, progress);
        ToolResult result;
        result.summary = describe("merged ", clouds.size(), " clouds into ", out.size(), " points");
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

void addTransformTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool(
        "transform", "Apply a transformation", "Edit",
        "Moves the cloud (or a mesh's vertices) in global coordinates, in double precision: a 4x4 matrix (16 numbers "
        "row by row, or a file of four lines of four numbers), a translation, a rotation about an axis through a "
        "centre, or a uniform scale about it; --inverse applies the inverse. The matrix is kept in the cloud's history.",
        updatedCloud("Moved cloud"));
    tool.outputs.push_back(OutputSpec{"matrix", "Applied matrix", DataKind::Transform, false});
    tool.parameters = {
        ParameterSpec::text("matrix", "Matrix", "16 numbers row by row, or a matrix file").asAlternative("transformation"),
        ParameterSpec::text("translate", "Translation", "X,Y,Z (m)").asAlternative("transformation"),
        ParameterSpec::text("rotate", "Rotation", "AXIS,DEGREES with AXIS x, y, z or DX,DY,DZ (e.g. z,30 or 0,0,1,30)")
            .asAlternative("transformation"),
        ParameterSpec::real("scale", "Scale", "Uniform scale factor", 1.0, 1e-9, 1e9).asAlternative("transformation"),
        ParameterSpec::text("centre", "Centre", "Centre of the rotation or the scale: X,Y,Z, centroid or box-centre", "0,0,0")
            .withSuggestions({"0,0,0", "centroid", "box-centre"}),
        ParameterSpec::boolean("inverse", "Inverse", "Apply the inverse of the transformation", false),
    };
    tool.runsOnClasses = false; // the whole cloud is moved
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        Eigen::Matrix4d m;
        std::string description;
        if (values.has("matrix")) {
            m = parseMatrix(values.text("matrix"));
            description = "matrix";
        } else if (values.has("translate")) {
            m = translation(vector3(values.text("translate"), "the translation"));
            description = "translate " + values.text("translate");
        } else if (values.has("rotate")) {
            const std::string& text = values.text("rotate");
            const auto comma = text.find(',');
            Eigen::Vector3d axis;
            double degrees = 0;
            if (comma == 1 && text[0] >= 'x' && text[0] <= 'z') {
                axis = Eigen::Vector3d::Unit(text[0] - 'x');
                const std::vector<double> angle = parseNumberList(text.substr(2), "the rotation angle");
                if (angle.size() != 1)
                    throw Error(ErrorCode::InvalidArgument, "transform: --rotate is AXIS,DEGREES");
                degrees = angle[0];
            } else {
                const std::vector<double> v = parseNumberList(text, "the rotation");
                if (v.size() != 4)
                    throw Error(ErrorCode::InvalidArgument, "transform: --rotate is AXIS,DEGREES or DX,DY,DZ,DEGREES");
                axis = Eigen::Vector3d(v[0], v[1], v[2]);
                degrees = v[3];
            }
            m = rotationAbout(axis, degrees, centreOf(input, values.text("centre")));
            description = "rotate " + text + " about " + values.text("centre");
        } else if (values.has("scale")) {
            m = scaleAbout(values.real("scale"), centreOf(input, values.text("centre")));
            description = describe("scale ", values.real("scale"), " about ", values.text("centre"));
        } else {
            throw Error(ErrorCode::InvalidArgument, "transform: give one of --matrix, --translate, --rotate, --scale");
        }
        if (values.boolean("inverse")) {
            if (!m.allFinite() || !(std::abs(m.topLeftCorner<3, 3>().determinant()) > 1e-12))
                throw Error(ErrorCode::InvalidArgument, "transform: the matrix has no inverse");
            m = m.inverse().eval();
            description = "inverse of " + description;
        }
        PointCloud out = transformCloud(input, m, description, progress);
        ToolResult result;
        result.summary = describe(description, " on ", out.size(), " points");
        result.add("output", std::move(out));
        result.add("matrix", m);
        return result;
    };
    registry.add(std::move(tool));
}

void addUndoTransformTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool("undo-transform", "Undo the last transformation", "Edit",
                                 "Moves the cloud (or a mesh's vertices) back by the inverse of the last transformation in its "
                                 "history (a registration, a transform) and removes it from the history.",
                                 updatedCloud("Moved cloud"));
    tool.outputs.push_back(OutputSpec{"matrix", "Undone matrix", DataKind::Transform, false});
    tool.runsOnClasses = false; // the whole cloud is moved back
    tool.run = [](const ToolInputs& inputs, const ParameterValues&, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        const AppliedTransform undone = input.transformHistory().empty() ? AppliedTransform{} : input.transformHistory().back();
        PointCloud out = undoLastTransform(input, progress);
        ToolResult result;
        result.summary = describe("undid ", undone.description, " on ", out.size(), " points");
        result.add("output", std::move(out));
        result.add("matrix", undone.matrix);
        return result;
    };
    registry.add(std::move(tool));
}

CropPolygon parsePolygon(const std::string& text, const std::string& axis)
{
    CropPolygon polygon;
    polygon.axis = axis == "x" ? 0 : axis == "y" ? 1 : 2;
    std::string separated = text;
    std::replace(separated.begin(), separated.end(), ' ', ';');
    for (const std::string& vertex : splitList(separated, ';')) {
        if (vertex.empty())
            continue;
        const std::vector<double> v = parseNumberList(vertex, "a polygon vertex");
        if (v.size() != 2)
            throw Error(ErrorCode::InvalidArgument, "crop: a polygon vertex is A,B (two coordinates), not '" + vertex + "'");
        polygon.vertices.emplace_back(v[0], v[1]);
    }
    return polygon;
}

void addCropTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool(
        "crop", "Crop", "Edit",
        "Keeps the points inside an axis-aligned box, an oriented box, or a polygon seen along an axis (its vertices "
        "are the two other coordinates: x y seen along z, y z along x, z x along y), or with --outside the others. "
        "Coordinates are global.",
        newCloud("Cropped cloud"));
    tool.parameters = {
        ParameterSpec::text("box", "Box", "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX").asAlternative("region"),
        ParameterSpec::text("obox", "Oriented box", "CX,CY,CZ,SX,SY,SZ[,HEADING[,PITCH,ROLL]]: centre, sizes, degrees")
            .asAlternative("region"),
        ParameterSpec::text("polygon", "Polygon", "Vertices A1,B1;A2,B2;... (or separate A,B values)").asAlternative("region"),
        ParameterSpec::choice("axis", "Polygon axis", "The axis the polygon is seen along", {"x", "y", "z"}, "z"),
        ParameterSpec::boolean("outside", "Keep outside", "Keep the points outside instead", false),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver*) {
        const PointCloud& input = inputs.cloud();
        std::vector<std::size_t> inside;
        std::string region;
        if (values.has("box")) {
            const std::vector<double> v = parseNumberList(values.text("box"), "the box");
            if (v.size() != 6)
                throw Error(ErrorCode::InvalidArgument, "crop: --box is XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX");
            CropBox box;
            const Eigen::Vector3d low(v[0], v[1], v[2]), high(v[3], v[4], v[5]);
            if ((high.array() < low.array()).any())
                throw Error(ErrorCode::InvalidArgument, "crop: the box's maximum is below its minimum");
            box.centre = (low + high) / 2;
            box.size = high - low;
            inside = pointsInBox(input, box);
            region = "box";
        } else if (values.has("obox")) {
            inside = pointsInBox(input, parseOrientedBox(values.text("obox")));
            region = "oriented box";
        } else if (values.has("polygon")) {
            const CropPolygon polygon = parsePolygon(values.text("polygon"), values.text("axis"));
            inside = pointsInPolygon(input, polygon);
            region = describe("polygon of ", polygon.vertices.size(), " vertices along ", values.text("axis"));
        } else {
            throw Error(ErrorCode::InvalidArgument, "crop: give one of --box, --obox, --polygon");
        }
        const bool outside = values.boolean("outside");
        const std::vector<std::size_t> kept = outside ? complementOf(inside, input.size()) : inside;
        PointCloud out = input.subset(kept);
        out.name = input.name + "_cropped";
        ToolResult result;
        result.summary = describe("kept ", kept.size(), " of ", input.size(), " points (", outside ? "outside the " : "inside the ", region, ")");
        result.add("output", std::move(out));
        return result;
    };
    registry.add(std::move(tool));
}

void addSectionsTool(ToolRegistry& registry)
{
    ToolSpec tool = oneCloudTool(
        "sections", "Cross-sections", "Edit",
        "Cuts slabs of a given thickness across the cloud, perpendicular to an axis, one every step (CloudCompare's "
        "cross-sections): each slab's points as a cloud, the outline of each section in its plane as a drawing (DXF), "
        "and a table of the sections.",
        OutputSpec{"sections", "Sections", DataKind::Drawing, false});
    OutputSpec slabs{"slab", "Slab", DataKind::Cloud, false};
    slabs.repeated = true;
    tool.outputs.push_back(slabs);
    tool.outputs.push_back(OutputSpec{"table", "Sections", DataKind::Table, false});
    const CrossSectionParams defaults;
    tool.parameters = {
        ParameterSpec::choice("axis", "Axis", "The slabs are perpendicular to this axis", {"x", "y", "z"}, "x"),
        ParameterSpec::real("thickness", "Thickness", "Of each slab", defaults.thickness, 1e-9, 1e9, "m").asRequired(),
        ParameterSpec::real("step", "Step", "Between the slabs' middles", defaults.step, 1e-9, 1e9, "m").asRequired(),
        ParameterSpec::real("first", "First", "The first slab's middle (global coordinate on the axis); default: the cloud's start",
                            0.0, -1e12, 1e12, "m")
            .asOptional(),
        ParameterSpec::real("last", "Last", "The last slab's middle; default: the cloud's end", 0.0, -1e12, 1e12, "m").asOptional(),
        ParameterSpec::real("outline-cell", "Outline cell", "Cell of the section outlines", 0.0, 0.0, 1e9, "m")
            .withZeroMeaning("automatic"),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& input = inputs.cloud();
        CrossSectionParams params;
        params.axis = values.text("axis")[0] - 'x';
        params.thickness = values.real("thickness");
        params.step = values.real("step");
        if (values.has("first"))
            params.first = values.real("first");
        if (values.has("last"))
            params.last = values.real("last");
        params.outlineCell = values.real("outline-cell");
        const std::vector<CrossSection> sections = crossSections(input, params, progress);
        ToolResult result;
        Drawing drawing;
        Table table;
        table.columns = {"section", "position", "points", "area", "rings"};
        for (std::size_t k = 0; k < sections.size(); ++k) {
            const CrossSection& s = sections[k];
            char layer[32];
            std::snprintf(layer, sizeof layer, "SECTION_%04zu", k + 1);
            for (const auto& ring : s.outlines)
                drawing.polylines.push_back({layer, ring, true});
            table.rows.push_back({static_cast<double>(k + 1), s.position, static_cast<double>(s.indices.size()), s.area,
                                  static_cast<double>(s.outlines.size())});
        }
        result.add("sections", std::move(drawing));
        for (std::size_t k = 0; k < sections.size(); ++k) {
            PointCloud slab = input.subset(sections[k].indices);
            slab.name = describe(input.name.empty() ? "section" : input.name, "_section_", k + 1);
            result.add("slab", std::move(slab));
        }
        result.add("table", std::move(table));
        result.summary = describe(sections.size(), " sections across ", values.text("axis"), " every ", params.step, " m, ",
                                  params.thickness, " m thick");
        return result;
    };
    registry.add(std::move(tool));
}

} // namespace

void registerEditTools(ToolRegistry& registry)
{
    addCloneTool(registry);
    addMergeTool(registry);
    addSetColourTool(registry);
    addTransformTool(registry);
    addUndoTransformTool(registry);
    addCropTool(registry);
    addSectionsTool(registry);
}

} // namespace scandiff::detail
