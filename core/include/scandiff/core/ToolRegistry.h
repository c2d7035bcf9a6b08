// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Tools contributed by plugins, described once for every front end.
//!
//! A tool declares its parameters (name, label, help, unit, default, valid range
//! or choices) and a run function. The CLI turns the declarations into options
//! (`scandiff-cli run TOOL --name value`), the GUI into a dialog: there is no
//! second copy of any default. Values are checked against their declaration
//! before the tool runs, so a run function only sees valid parameters.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <variant>
#include <vector>

namespace scandiff {

//! Text is free text checked by the tool itself (lists of numbers such as a
//! sensor pose "X,Y,Z"); the others are checked against their declaration.
enum class ParameterType { Integer, Real, Boolean, Choice, Text };

using ParameterValue = std::variant<std::int64_t, double, bool, std::string>;

struct ParameterSpec
{
    std::string name;        //!< identifier, CLI option "--name"
    std::string label;       //!< short GUI label
    std::string description; //!< one sentence of help
    std::string unit;        //!< "m", "points", "" ...
    ParameterType type = ParameterType::Real;
    ParameterValue defaultValue = 0.0;
    double minimum = -std::numeric_limits<double>::infinity(); //!< Integer/Real: inclusive
    double maximum = std::numeric_limits<double>::infinity();  //!< Integer/Real: inclusive
    std::vector<std::string> choices;                            //!< Choice only
    //! An optional parameter has no value unless the user gives one (the CLI
    //! option is absent, the GUI's checkbox beside it is off); `defaultValue` is
    //! then only the value a dialog proposes when the user switches it on.
    bool optional = false;

    static ParameterSpec integer(std::string name, std::string label, std::string description, std::int64_t defaultValue,
                                 std::int64_t minimum, std::int64_t maximum, std::string unit = {});
    static ParameterSpec real(std::string name, std::string label, std::string description, double defaultValue,
                              double minimum, double maximum, std::string unit = {});
    static ParameterSpec boolean(std::string name, std::string label, std::string description, bool defaultValue);
    static ParameterSpec choice(std::string name, std::string label, std::string description,
                                std::vector<std::string> choices, std::string defaultValue);
    static ParameterSpec text(std::string name, std::string label, std::string description, std::string defaultValue = {});
    //! The same declaration, made optional (see `optional`).
    ParameterSpec asOptional() const;

    //! Parses user text ("12", "0.5", "true", "plane") into a valid value.
    //! Throws Error(InvalidArgument) naming the parameter and its valid range.
    ParameterValue parse(const std::string& text) const;
    //! Throws Error(InvalidArgument) if `value` has the wrong type or lies outside the range.
    void validate(const ParameterValue& value) const;
    //! "8", "0.5", "true", "plane": the inverse of parse().
    static std::string format(const ParameterValue& value);
};

//! Validated parameter values of one tool run.
class ParameterValues
{
public:
    void set(const std::string& name, ParameterValue value) { values_[name] = std::move(value); }
    //! False for an optional parameter the user left unset.
    bool has(const std::string& name) const { return values_.count(name) != 0; }
    std::int64_t integer(const std::string& name) const;
    double real(const std::string& name) const;
    bool boolean(const std::string& name) const;
    const std::string& text(const std::string& name) const;
    const std::map<std::string, ParameterValue>& all() const { return values_; }

private:
    const ParameterValue& get(const std::string& name) const;
    std::map<std::string, ParameterValue> values_;
};

struct ToolResult
{
    PointCloud cloud;    //!< the tool's output cloud (input untouched)
    std::string summary; //!< one line for the log: what was done, counts
};

struct ToolSpec
{
    std::string name;        //!< CLI name, e.g. "sor-filter"
    std::string title;       //!< menu text, e.g. "Statistical outlier filter"
    std::string description; //!< a paragraph of help, with the method's source
    std::string category;    //!< menu group, e.g. "Filters"
    std::vector<ParameterSpec> parameters;
    std::function<ToolResult(const PointCloud&, const ParameterValues&, ProgressObserver*)> run;

    const ParameterSpec* parameter(const std::string& name) const;
    //! The declared defaults.
    ParameterValues defaults() const;
    //! Defaults overridden by user text, every value parsed and checked.
    //! Throws Error(InvalidArgument) for an unknown name or a bad value.
    ParameterValues resolve(const std::map<std::string, std::string>& userText) const;
};

//! The declared defaults (optional parameters left unset), overridden by user
//! text keyed by parameter name; every value parsed and checked. `owner` names
//! the tool or command in error messages. Throws Error(InvalidArgument) for an
//! unknown name or a bad value.
ParameterValues resolveParameters(const std::vector<ParameterSpec>& parameters,
                                  const std::map<std::string, std::string>& userText, const std::string& owner);

class ToolRegistry
{
public:
    //! Throws Error(Internal) if a tool of that name exists already.
    void add(ToolSpec tool);
    //! Null when unknown.
    const ToolSpec* find(const std::string& name) const;
    const std::vector<ToolSpec>& tools() const { return tools_; }

private:
    std::vector<ToolSpec> tools_;
};

} // namespace scandiff
