// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/ClassSelection.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>

#include <cmath>
#include <set>
#include <string>

namespace scandiff {

namespace {

constexpr const char* kClassField = "classification";

std::set<int> classList(const ParameterValues& values, const char* parameter)
{
    if (!values.has(parameter))
        return {};
    const std::vector<int> classes = parseClassList(values.text(parameter), std::string("--") + parameter);
    return {classes.begin(), classes.end()};
}

} // namespace

std::vector<int> parseClassList(const std::string& text, const std::string& what)
{
    std::vector<int> classes;
    for (double c : parseNumberWords(text, what)) {
        if (c != std::round(c) || c < 0 || c > 255)
            throw Error(ErrorCode::InvalidArgument, what + ": a class is an integer in 0..255 (ASPRS), not " + std::to_string(c));
        classes.push_back(static_cast<int>(c));
    }
    if (classes.empty())
        throw Error(ErrorCode::InvalidArgument, what + ": no class given");
    return classes;
}

std::vector<ParameterSpec> classParameters()
{
    return {ParameterSpec::text(kClassesParameter, "Only classes",
                                "Runs on the points of these ASPRS classes only (field classification) of every input cloud, "
                                "e.g. 2 or 2,6; what the tool gives for the input itself keeps every point (new fields empty "
                                "on the others)",
                                "2")
                .asOptional(),
            ParameterSpec::text(kExcludeClassesParameter, "Without classes",
                                "Leaves the points of these ASPRS classes out of every input cloud, e.g. 7,18 (low and high noise)",
                                "7,18")
                .asOptional()};
}

bool restrictsClasses(const ParameterValues& values)
{
    return values.has(kClassesParameter) || values.has(kExcludeClassesParameter);
}

std::optional<std::vector<std::size_t>> pointsOfClasses(const PointCloud& cloud, const ParameterValues& values)
{
    if (!restrictsClasses(values))
        return std::nullopt;
    const std::set<int> only = classList(values, kClassesParameter), excluded = classList(values, kExcludeClassesParameter);
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

ScalarField spreadOver(const ScalarField& part, const std::vector<std::size_t>& kept, std::size_t size)
{
    ScalarField whole(part.name(), size);
    whole.setOffset(part.offset());
    for (std::size_t k = 0; k < kept.size(); ++k)
        whole.setValue(kept[k], part.value(k));
    return whole;
}

} // namespace scandiff
