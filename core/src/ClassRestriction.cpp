// SPDX-License-Identifier: GPL-3.0-or-later
#include "ClassRestriction.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/processing/CloudEditing.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <set>

namespace scandiff::detail {

namespace {

constexpr const char* kClassField = "classification";

std::set<int> classList(const ParameterValues& values, const char* parameter)
{
    std::set<int> classes;
    if (!values.has(parameter))
        return classes;
    for (double c : parseNumberWords(values.text(parameter), std::string("--") + parameter)) {
        if (c != std::round(c) || c < 0 || c > 255)
            throw Error(ErrorCode::InvalidArgument,
                        std::string("--") + parameter + ": a class is an integer in 0..255 (ASPRS), not " + std::to_string(c));
        classes.insert(static_cast<int>(c));
    }
    if (classes.empty())
        throw Error(ErrorCode::InvalidArgument, std::string("--") + parameter + ": no class given");
    return classes;
}

//! The points of `cloud` the classes keep: in `only` (when given), not in
//! `excluded`. A point without a class (NaN) is in no class.
std::vector<std::size_t> keptPoints(const PointCloud& cloud, const std::set<int>& only, const std::set<int>& excluded)
{
    const ScalarField* classes = cloud.field(kClassField);
    if (!classes)
        throw Error(ErrorCode::InvalidArgument, "'" + cloud.name + "' has no field " + kClassField + " to choose classes in");
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const double v = classes->value(i);
        const bool known = std::isfinite(v);
        const int c = known ? static_cast<int>(std::lround(v)) : -1;
        const bool in = only.empty() || (known && only.count(c));
        if (in && !(known && excluded.count(c)))
            kept.push_back(i);
    }
    if (kept.empty())
        throw Error(ErrorCode::InvalidArgument, "no point of '" + cloud.name + "' is in the classes asked for");
    return kept;
}

bool samePositions(const PointCloud& a, const PointCloud& b)
{
    if (a.size() != b.size())
        return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if ((a.exactGlobalPosition(i) - b.exactGlobalPosition(i)).norm() > 1e-9 * (1 + a.exactGlobalPosition(i).norm()))
            return false;
    return true;
}

//! `whole` with what the tool gave for its points `kept` (`part`, in the
//! same order) laid over it: fields and normals; the tool's new fields empty
//! elsewhere.
void layOver(PointCloud& whole, const PointCloud& part, const std::vector<std::size_t>& kept)
{
    for (const ScalarField& field : part.fields()) {
        ScalarField* target = whole.field(field.name());
        if (!target) {
            ScalarField added(field.name(), whole.size());
            added.setOffset(field.offset());
            target = &whole.addField(std::move(added));
        }
        for (std::size_t k = 0; k < kept.size(); ++k)
            target->setValue(kept[k], field.value(k));
    }
    if (part.hasNormals()) {
        std::vector<Eigen::Vector3f>& normals = whole.enableNormals();
        for (std::size_t k = 0; k < kept.size(); ++k)
            normals[kept[k]] = part.normals()[k];
    }
}

} // namespace

void addClassParameters(ToolSpec& tool)
{
    const bool takesClouds =
        std::any_of(tool.inputs.begin(), tool.inputs.end(), [](const InputSpec& in) { return in.kind == DataKind::Cloud; });
    const bool repeatedInPlace =
        std::any_of(tool.outputs.begin(), tool.outputs.end(), [](const OutputSpec& out) { return out.updatesInput && out.repeated; });
    if (!takesClouds || repeatedInPlace || tool.parameter(kClassesParameter) || tool.parameter(kExcludeClassesParameter))
        return;
    tool.parameters.push_back(ParameterSpec::text(kClassesParameter, "Only classes",
                                                  "Runs on the points of these ASPRS classes only (field classification) of "
                                                  "every input cloud, e.g. 2 or 2,6; what the tool gives for the input itself "
                                                  "keeps every point (new fields empty on the others)",
                                                  "2")
                                  .asOptional());
    tool.parameters.push_back(ParameterSpec::text(kExcludeClassesParameter, "Without classes",
                                                  "Leaves the points of these ASPRS classes out of every input cloud, e.g. "
                                                  "7,18 (low and high noise)",
                                                  "7,18")
                                  .asOptional());
}

bool restrictsClasses(const ParameterValues& values)
{
    return values.has(kClassesParameter) || values.has(kExcludeClassesParameter);
}

ToolResult runOnClasses(const ToolSpec& tool, const ToolInputs& given, const ParameterValues& values, ProgressObserver* progress)
{
    const std::set<int> only = classList(values, kClassesParameter), excluded = classList(values, kExcludeClassesParameter);
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
                std::vector<std::size_t> kept = keptPoints(cloud, only, excluded);
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
        if (samePositions(*part, firstPart))
            whole = first->clone();
        else if (matrix && std::holds_alternative<Eigen::Matrix4d>(matrix->data))
            whole = transformCloud(*first, std::get<Eigen::Matrix4d>(matrix->data), "moved as its classes " + spec.role);
        else
            continue; // moved without a matrix: the output holds the chosen points only
        whole.name = part->name;
        layOver(whole, *part, firstKept);
        *part = std::move(whole);
    }
    result.summary += " (on " + std::to_string(firstKept.size()) + " of " + std::to_string(first->size()) +
                      " points of '" + first->name + "' by class)";
    return result;
}

} // namespace scandiff::detail
