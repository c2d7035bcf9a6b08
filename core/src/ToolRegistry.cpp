// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/ToolRegistry.h>

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

ParameterValues ToolSpec::defaults() const
{
    return resolveParameters(parameters, {}, name);
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
    for (const auto& [key, text] : userText) {
        const auto spec = std::find_if(parameters.begin(), parameters.end(), [&](const ParameterSpec& p) { return p.name == key; });
        if (spec == parameters.end())
            throw Error(ErrorCode::InvalidArgument, owner + " has no parameter '" + key + "'");
        values.set(key, spec->parse(text));
    }
    return values;
}

void ToolRegistry::add(ToolSpec tool)
{
    if (find(tool.name))
        throw Error(ErrorCode::Internal, "two tools are named '" + tool.name + "'");
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
