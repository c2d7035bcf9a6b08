// SPDX-License-Identifier: GPL-3.0-or-later
#include "ClassRestriction.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/ClassSelection.h>
#include <scandiff/core/processing/CloudEditing.h>

#include <algorithm>
#include <cmath>
#include <deque>

namespace scandiff::detail {

namespace {

//! An in-place output that did not move its points is a copy of them: the
//! same coordinates to the last digit (a registration's correction of a
//! millimetre is a move, at any distance from the origin).
bool samePositions(const PointCloud& a, const PointCloud& b)
{
    if (a.size() != b.size())
        return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (a.exactGlobalPosition(i) != b.exactGlobalPosition(i))
            return false;
    return true;
}

//! Whether `matrix` takes the points of `before` to those of `after` (to a
//! millimetre: what float coordinates about two origins agree to), so that it
//! may move the points left out too.
bool movesOnto(const Eigen::Matrix4d& matrix, const PointCloud& before, const PointCloud& after)
{
    for (std::size_t i = 0; i < before.size(); ++i) {
        const Eigen::Vector3d moved = (matrix * before.exactGlobalPosition(i).homogeneous()).head<3>();
        if (!((moved - after.exactGlobalPosition(i)).norm() <= 1e-3))
            return false;
    }
    return true;
}

//! `whole` with what the tool gave for its points `kept` (`part`, in the
//! same order) laid over it: fields, normals and colours; the tool's new
//! fields empty elsewhere, normals zero (none) and colours black where the
//! cloud had none; a field the tool removed (`before` had it, `part` not) is
//! removed.
void layOver(PointCloud& whole, const PointCloud& before, const PointCloud& part, const std::vector<std::size_t>& kept)
{
    for (const ScalarField& field : before.fields())
        if (!part.field(field.name()))
            whole.removeField(field.name());
    for (const ScalarField& field : part.fields()) {
        ScalarField* target = whole.field(field.name());
        if (!target) {
            whole.addField(spreadOver(field, kept, whole.size()));
            continue;
        }
        for (std::size_t k = 0; k < kept.size(); ++k)
            target->setValue(kept[k], field.value(k));
    }
    if (part.hasNormals()) {
        std::vector<Eigen::Vector3f>& normals = whole.enableNormals();
        for (std::size_t k = 0; k < kept.size(); ++k)
            normals[kept[k]] = part.normals()[k];
    }
    if (part.hasColors()) {
        std::vector<Rgb8>& colours = whole.enableColors();
        for (std::size_t k = 0; k < kept.size(); ++k)
            colours[kept[k]] = part.colors()[k];
    }
}

} // namespace

void addClassParameters(ToolSpec& tool)
{
    const bool takesClouds =
        std::any_of(tool.inputs.begin(), tool.inputs.end(), [](const InputSpec& in) { return in.kind == DataKind::Cloud; });
    const bool repeatedInPlace =
        std::any_of(tool.outputs.begin(), tool.outputs.end(), [](const OutputSpec& out) { return out.updatesInput && out.repeated; });
    if (!tool.runsOnClasses || !takesClouds || repeatedInPlace || tool.parameter(kClassesParameter) ||
        tool.parameter(kExcludeClassesParameter))
        return;
    for (ParameterSpec& spec : classParameters())
        tool.parameters.push_back(std::move(spec));
}

ToolResult runOnClasses(const ToolSpec& tool, const ToolInputs& given, const ParameterValues& values, ProgressObserver* progress)
{
    ToolInputs restricted;
    std::deque<PointCloud> parts; // stable addresses for `restricted`
    std::vector<std::size_t> firstKept;
    const PointCloud* first = nullptr;
    for (const InputSpec& spec : tool.inputs)
        for (std::size_t i = 0; i < given.count(spec.role); ++i) {
            if (spec.kind == DataKind::Drawing) {
                restricted.add(spec.role, given.drawing(spec.role, i));
            } else if (const Mesh* mesh = given.meshOrNull(spec.role, i)) {
                restricted.add(spec.role, *mesh); // a mesh's triangles are not chosen by class
            } else {
                const PointCloud& cloud = given.cloud(spec.role, i);
                if (spec.optional && !cloud.field("classification")) {
                    restricted.add(spec.role, cloud); // core points without classes: all of them
                    continue;
                }
                std::vector<std::size_t> kept = *pointsOfClasses(cloud, values);
                parts.push_back(cloud.subset(kept));
                restricted.add(spec.role, parts.back());
                if (!first && &spec == &tool.inputs.front()) {
                    first = &cloud;
                    firstKept = std::move(kept);
                }
            }
        }
    ToolResult result = tool.run(restricted, values, progress);
    if (!first)
        return result;
    const PointCloud& firstPart = parts.front();
    const ToolOutput* matrix = nullptr;
    for (const OutputSpec& spec : tool.outputs)
        if (spec.kind == DataKind::Transform && !matrix)
            matrix = result.find(spec.role);
    for (const OutputSpec& spec : tool.outputs) {
        if (!spec.updatesInput)
            continue;
        ToolOutput* output = result.find(spec.role);
        auto* part = output ? std::get_if<PointCloud>(&output->data) : nullptr;
        if (!part || part->size() != firstKept.size())
            continue;
        PointCloud whole;
        if (samePositions(*part, firstPart)) {
            whole = first->clone();
        } else {
            const Eigen::Matrix4d* m = matrix ? std::get_if<Eigen::Matrix4d>(&matrix->data) : nullptr;
            if (!m || !movesOnto(*m, firstPart, *part))
                throw Error(ErrorCode::InvalidArgument, tool.name + " moves the points without one motion for all of them: it "
                                                                    "does not run on some classes only");
            whole = transformCloud(*first, *m, "");
            whole.transformHistory() = part->transformHistory(); // the tool's own entry
        }
        whole.name = part->name;
        layOver(whole, firstPart, *part, firstKept);
        *part = std::move(whole);
    }
    result.summary += " (on " + std::to_string(firstKept.size()) + " of " + std::to_string(first->size()) +
                      " points of '" + first->name + "' by class)";
    return result;
}

} // namespace scandiff::detail
