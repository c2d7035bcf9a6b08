// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/ToolRegistry.h>

#include "ClassRestriction.h"

#include <algorithm>
#include <charconv>
#include <cmath>

namespace scandiff {

namespace {

//! The shortest text that parses back to the same double.
std::string formatNumber(double v)
{
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
    return std::string(buffer, result.ptr);
}

std::string rangeText(const ParameterSpec& spec)
{
    std::string lo = std::isinf(spec.minimum) ? "-inf" : formatNumber(spec.minimum);
    std::string hi = std::isinf(spec.maximum) ? "inf" : formatNumber(spec.maximum);
    return "[" + lo + ", " + hi + "]";
}

[[noreturn]] void reject(const ParameterSpec& spec, const std::string& why)
{
    throw Error(ErrorCode::InvalidArgument, "parameter '" + spec.name + "': " + why);
}

} // namespace

ParameterSpec ParameterSpec::integer(std::string name, std::string label, std::string description,
                                     std::int64_t defaultValue, std::int64_t minimum, std::int64_t maximum,
                                     std::string unit)
{
    ParameterSpec s;
    s.name = std::move(name);
    s.label = std::move(label);
    s.description = std::move(description);
    s.unit = std::move(unit);
    s.type = ParameterType::Integer;
    s.defaultValue = defaultValue;
    s.minimum = static_cast<double>(minimum);
    s.maximum = static_cast<double>(maximum);
    s.validate(s.defaultValue);
    return s;
}

ParameterSpec ParameterSpec::real(std::string name, std::string label, std::string description, double defaultValue,
                                  double minimum, double maximum, std::string unit)
{
    ParameterSpec s;
    s.name = std::move(name);
    s.label = std::move(label);
    s.description = std::move(description);
    s.unit = std::move(unit);
    s.type = ParameterType::Real;
    s.defaultValue = defaultValue;
    s.minimum = minimum;
    s.maximum = maximum;
    s.validate(s.defaultValue);
    return s;
}

ParameterSpec ParameterSpec::boolean(std::string name, std::string label, std::string description, bool defaultValue)
{
    ParameterSpec s;
    s.name = std::move(name);
    s.label = std::move(label);
    s.description = std::move(description);
    s.type = ParameterType::Boolean;
    s.defaultValue = defaultValue;
    return s;
}

ParameterSpec ParameterSpec::choice(std::string name, std::string label, std::string description,
                                    std::vector<std::string> choices, std::string defaultValue)
{
    ParameterSpec s;
    s.name = std::move(name);
    s.label = std::move(label);
    s.description = std::move(description);
    s.type = ParameterType::Choice;
    s.choices = std::move(choices);
    s.defaultValue = std::move(defaultValue);
    s.validate(s.defaultValue);
    return s;
}

ParameterSpec ParameterSpec::text(std::string name, std::string label, std::string description, std::string defaultValue)
{
    ParameterSpec s;
    s.name = std::move(name);
    s.label = std::move(label);
    s.description = std::move(description);
    s.type = ParameterType::Text;
    s.defaultValue = std::move(defaultValue);
    return s;
}

ParameterSpec ParameterSpec::asOptional() const
{
    ParameterSpec s = *this;
    s.optional = true;
    return s;
}

ParameterSpec ParameterSpec::asRequired() const
{
    ParameterSpec s = *this;
    s.required = true;
    return s;
}

ParameterSpec ParameterSpec::takingValues(int count) const
{
    ParameterSpec s = *this;
    s.commandLineValues = count;
    return s;
}

ParameterSpec ParameterSpec::withSuggestions(std::vector<std::string> values) const
{
    ParameterSpec s = *this;
    s.suggestions = std::move(values);
    return s;
}

ParameterSpec ParameterSpec::pickedAlternatelyOn(std::vector<std::string> roles) const
{
    ParameterSpec s = *this;
    s.pickedOn = std::move(roles);
    return s;
}

ParameterSpec ParameterSpec::asFieldOf(std::string role) const
{
    ParameterSpec s = *this;
    s.fieldOfInput = std::move(role);
    return s;
}

ParameterSpec ParameterSpec::onlyWith(std::string parameter) const
{
    ParameterSpec s = *this;
    s.usedWith = std::move(parameter);
    return s;
}

ParameterSpec ParameterSpec::withZeroMeaning(std::string meaning) const
{
    ParameterSpec s = *this;
    s.zeroMeans = std::move(meaning);
    return s;
}

ParameterSpec ParameterSpec::asThresholdOf(std::string fieldParameter) const
{
    ParameterSpec s = *this;
    s.thresholdOfField = std::move(fieldParameter);
    return s;
}

ParameterSpec ParameterSpec::asAlternative(std::string group) const
{
    ParameterSpec s = asOptional();
    s.alternativeGroup = std::move(group);
    return s;
}

ParameterValue ParameterSpec::parse(const std::string& text) const
{
    ParameterValue value;
    switch (type) {
    case ParameterType::Integer: {
        std::int64_t v = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (ec != std::errc() || end != text.data() + text.size())
            reject(*this, "'" + text + "' is not an integer");
        value = v;
        break;
    }
    case ParameterType::Real: {
        double v = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (ec != std::errc() || end != text.data() + text.size())
            reject(*this, "'" + text + "' is not a number");
        value = v;
        break;
    }
    case ParameterType::Boolean:
        if (text == "true" || text == "1" || text == "yes" || text == "on")
            value = true;
        else if (text == "false" || text == "0" || text == "no" || text == "off")
            value = false;
        else
            reject(*this, "'" + text + "' is not true or false");
        break;
    case ParameterType::Choice:
    case ParameterType::Text:
        value = text;
        break;
    }
    validate(value);
    return value;
}

void ParameterSpec::validate(const ParameterValue& value) const
{
    switch (type) {
    case ParameterType::Integer: {
        const auto* v = std::get_if<std::int64_t>(&value);
        if (!v)
            reject(*this, "an integer is expected");
        if (static_cast<double>(*v) < minimum || static_cast<double>(*v) > maximum)
            reject(*this, std::to_string(*v) + " is outside " + rangeText(*this));
        break;
    }
    case ParameterType::Real: {
        const auto* v = std::get_if<double>(&value);
        if (!v)
            reject(*this, "a number is expected");
        if (!std::isfinite(*v) || *v < minimum || *v > maximum)
            reject(*this, formatNumber(*v) + " is outside " + rangeText(*this));
        break;
    }
    case ParameterType::Boolean:
        if (!std::holds_alternative<bool>(value))
            reject(*this, "true or false is expected");
        break;
    case ParameterType::Choice: {
        const auto* v = std::get_if<std::string>(&value);
        if (!v || std::find(choices.begin(), choices.end(), *v) == choices.end()) {
            std::string list;
            for (const auto& c : choices)
                list += (list.empty() ? "" : ", ") + c;
            reject(*this, "expected one of: " + list);
        }
        break;
    }
    case ParameterType::Text:
        if (!std::holds_alternative<std::string>(value))
            reject(*this, "text is expected");
        break;
    }
}

std::string ParameterSpec::format(const ParameterValue& value)
{
    if (const auto* i = std::get_if<std::int64_t>(&value))
        return std::to_string(*i);
    if (const auto* d = std::get_if<double>(&value))
        return formatNumber(*d);
    if (const auto* b = std::get_if<bool>(&value))
        return *b ? "true" : "false";
    return std::get<std::string>(value);
}

const ParameterValue& ParameterValues::get(const std::string& name) const
{
    const auto it = values_.find(name);
    if (it == values_.end())
        throw Error(ErrorCode::Internal, "parameter '" + name + "' was not declared by the tool");
    return it->second;
}

std::int64_t ParameterValues::integer(const std::string& name) const { return std::get<std::int64_t>(get(name)); }
double ParameterValues::real(const std::string& name) const { return std::get<double>(get(name)); }
bool ParameterValues::boolean(const std::string& name) const { return std::get<bool>(get(name)); }
const std::string& ParameterValues::text(const std::string& name) const { return std::get<std::string>(get(name)); }

const ParameterSpec* ToolSpec::parameter(const std::string& parameterName) const
{
    for (const auto& p : parameters)
        if (p.name == parameterName)
            return &p;
    return nullptr;
}

const InputSpec* ToolSpec::input(const std::string& role) const
{
    for (const auto& i : inputs)
        if (i.role == role)
            return &i;
    return nullptr;
}

const OutputSpec* ToolSpec::output(const std::string& role) const
{
    for (const auto& o : outputs)
        if (o.role == role)
            return &o;
    return nullptr;
}

void ToolSpec::checkInputs(const ToolInputs& given) const
{
    for (const auto& spec : inputs) {
        const std::size_t n = given.count(spec.role);
        if (n == 0 && !spec.optional)
            throw Error(ErrorCode::InvalidArgument, "tool '" + name + "' needs " +
                                                        (spec.kind == DataKind::Mesh      ? "a mesh"
                                                         : spec.kind == DataKind::Drawing ? "a drawing"
                                                                                          : "a point cloud") +
                                                        " as '" + spec.role + "' (" + spec.label + ")");
        if (n > 1 && !spec.repeated)
            throw Error(ErrorCode::InvalidArgument,
                        "tool '" + name + "' takes one entity as '" + spec.role + "', not " + std::to_string(n));
        if (spec.kind == DataKind::Mesh)
            for (std::size_t i = 0; i < n; ++i)
                if (!given.meshOrNull(spec.role, i))
                    throw Error(ErrorCode::InvalidArgument, "tool '" + name + "' needs a mesh as '" + spec.role +
                                                                "', and '" + given.cloud(spec.role, i).name + "' is a point cloud");
    }
}

ToolResult ToolSpec::execute(const ToolInputs& given, const ParameterValues& values, ProgressObserver* progress) const
{
    checkInputs(given);
    if (restrictsClasses(values))
        return detail::runOnClasses(*this, given, values, progress);
    return run(given, values, progress);
}

ToolInputs& ToolInputs::add(const std::string& role, const PointCloud& cloud)
{
    entities_[role].emplace_back(&cloud);
    return *this;
}

ToolInputs& ToolInputs::add(const std::string& role, const Mesh& mesh)
{
    entities_[role].emplace_back(&mesh);
    return *this;
}

ToolInputs& ToolInputs::add(const std::string& role, const Entity& entity)
{
    if (const auto* mesh = std::get_if<Mesh>(&entity))
        return add(role, *mesh);
    return add(role, std::get<PointCloud>(entity));
}

ToolInputs& ToolInputs::add(const std::string& role, const Drawing& drawing)
{
    entities_[role].emplace_back(&drawing);
    return *this;
}

const Drawing& ToolInputs::drawing(const std::string& role, std::size_t index) const
{
    const auto* drawing = std::get_if<const Drawing*>(&at(role, index));
    if (!drawing)
        throw Error(ErrorCode::InvalidArgument, "a drawing is needed as '" + role + "'");
    return **drawing;
}

std::size_t ToolInputs::count(const std::string& role) const
{
    const auto it = entities_.find(role);
    return it == entities_.end() ? 0 : it->second.size();
}

const ToolInputs::Ref& ToolInputs::at(const std::string& role, std::size_t index) const
{
    const auto it = entities_.find(role);
    if (it == entities_.end() || index >= it->second.size())
        throw Error(ErrorCode::InvalidArgument, "no entity was given as '" + role + "'");
    return it->second[index];
}

const PointCloud& ToolInputs::cloud(const std::string& role, std::size_t index) const
{
    const Ref& ref = at(role, index);
    if (const auto* mesh = std::get_if<const Mesh*>(&ref))
        return (*mesh)->vertices;
    if (const auto* cloud = std::get_if<const PointCloud*>(&ref))
        return **cloud;
    throw Error(ErrorCode::InvalidArgument, "a point cloud is needed as '" + role + "', not a drawing");
}

const Mesh& ToolInputs::mesh(const std::string& role, std::size_t index) const
{
    const Mesh* mesh = meshOrNull(role, index);
    if (!mesh)
        throw Error(ErrorCode::InvalidArgument, "'" + cloud(role, index).name + "' is a point cloud, a mesh is needed as '" + role + "'");
    return *mesh;
}

const Mesh* ToolInputs::meshOrNull(const std::string& role, std::size_t index) const
{
    const Ref& ref = at(role, index);
    const auto* mesh = std::get_if<const Mesh*>(&ref);
    return mesh ? *mesh : nullptr;
}

ToolResult& ToolResult::add(std::string role, OutputData data, OutputProperties properties)
{
    outputs.push_back({std::move(role), std::move(data), std::move(properties)});
    return *this;
}

const ToolOutput* ToolResult::find(const std::string& role) const
{
    for (const auto& o : outputs)
        if (o.role == role)
            return &o;
    return nullptr;
}

std::vector<ToolOutput*> ToolResult::findAll(const std::string& role)
{
    std::vector<ToolOutput*> all;
    for (auto& o : outputs)
        if (o.role == role)
            all.push_back(&o);
    return all;
}

ToolOutput* ToolResult::find(const std::string& role)
{
    for (auto& o : outputs)
        if (o.role == role)
            return &o;
    return nullptr;
}

namespace {

template <typename T>
const T& outputAs(const ToolResult& result, const std::string& role, const char* what)
{
    const ToolOutput* output = result.find(role);
    const T* data = output ? std::get_if<T>(&output->data) : nullptr;
    if (!data)
        throw Error(ErrorCode::Internal, "the tool gave no " + std::string(what) + " as output '" + role + "'");
    return *data;
}

} // namespace

const PointCloud& ToolResult::cloud(const std::string& role) const { return outputAs<PointCloud>(*this, role, "point cloud"); }
const Mesh& ToolResult::mesh(const std::string& role) const { return outputAs<Mesh>(*this, role, "mesh"); }
const Table& ToolResult::table(const std::string& role) const { return outputAs<Table>(*this, role, "table"); }
const Eigen::Matrix4d& ToolResult::transform(const std::string& role) const
{
    return outputAs<Eigen::Matrix4d>(*this, role, "transformation");
}

ParameterValues ToolSpec::defaults() const
{
    ParameterValues values;
    for (const auto& p : parameters)
        if (!p.optional)
            values.set(p.name, p.defaultValue);
    return values;
}

ParameterValues ToolSpec::resolve(const std::map<std::string, std::string>& userText) const
{
    return resolveParameters(parameters, userText, "tool '" + name + "'");
}

ParameterValues resolveParameters(const std::vector<ParameterSpec>& parameters,
                                  const std::map<std::string, std::string>& userText, const std::string& owner)
{
    ParameterValues values;
    for (const auto& p : parameters)
        if (!p.optional)
            values.set(p.name, p.defaultValue);
    for (const auto& entry : userText) {
        const std::string& key = entry.first; // a named variable: a lambda may not capture a structured binding before C++20
        const std::string& text = entry.second;
        const auto spec = std::find_if(parameters.begin(), parameters.end(), [&](const ParameterSpec& p) { return p.name == key; });
        if (spec == parameters.end())
            throw Error(ErrorCode::InvalidArgument, owner + " has no parameter '" + key + "'");
        values.set(key, spec->parse(text));
    }
    for (const auto& p : parameters)
        if (p.required && !userText.count(p.name))
            throw Error(ErrorCode::InvalidArgument, owner + " needs --" + p.name + " (" + p.description + ")");
    // Alternatives: at most one of a group may be given.
    std::map<std::string, std::string> givenInGroup;
    for (const auto& p : parameters) {
        if (p.alternativeGroup.empty() || !userText.count(p.name))
            continue;
        auto [it, first] = givenInGroup.emplace(p.alternativeGroup, p.name);
        if (!first)
            throw Error(ErrorCode::InvalidArgument,
                        owner + ": give only one of --" + it->second + " and --" + p.name + " (they are alternatives)");
    }
    return values;
}

void ToolRegistry::add(ToolSpec tool)
{
    if (find(tool.name))
        throw Error(ErrorCode::Internal, "two tools are named '" + tool.name + "'");
    for (std::size_t k = 0; k < tool.outputs.size(); ++k) {
        const OutputSpec& o = tool.outputs[k];
        if (o.under.empty())
            continue;
        // Its entities go under those of an earlier repeated output, one for one.
        const auto owner = std::find_if(tool.outputs.begin(), tool.outputs.begin() + static_cast<std::ptrdiff_t>(k),
                                        [&](const OutputSpec& other) { return other.role == o.under; });
        if (!o.repeated || owner == tool.outputs.begin() + static_cast<std::ptrdiff_t>(k) || !owner->repeated)
            throw Error(ErrorCode::Internal, tool.name + ": output '" + o.role + "' goes under '" + o.under +
                                                 "', which must be an earlier repeated output, and be repeated itself");
    }
    detail::addClassParameters(tool);
    tools_.push_back(std::move(tool));
}

const ToolSpec* ToolRegistry::find(const std::string& name) const
{
    for (const auto& t : tools_)
        if (t.name == name)
            return &t;
    return nullptr;
}

} // namespace scandiff
