// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Tools contributed by plugins, described once for every front end.
//!
//! A tool declares its parameters (name, label, help, unit, default, valid range
//! or choices) and a run function. The CLI turns the declarations into options
//! (`scandiff-cli run TOOL --name value`), the GUI into a dialog: there is no
//! second copy of any default. Values are checked against their declaration
//! before the tool runs, so a run function only sees valid parameters.

#include <scandiff/core/Drawing.h>
#include <scandiff/core/Entity.h>
#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/Table.h>

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <variant>
#include <utility>
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
    //! Optional parameters sharing a group name are alternatives ("--radius R |
    //! --knn K"): at most one may be given. The GUI lets one be switched on at a
    //! time and proposes the group's first; the tool decides what none means.
    std::string alternativeGroup;
    //! A required parameter has no default the user can rely on (a radius that
    //! depends on the data): the CLI refuses to run without it, the GUI shows
    //! `defaultValue` as a proposal the user confirms.
    bool required = false;
    //! Text only: values a user usually types, offered in a list the GUI lets
    //! the user edit (an orientation "+z", "mst"...); any other text is still accepted.
    std::vector<std::string> suggestions;
    //! Text only: the value names a scalar field of the entity given as this
    //! input role (the GUI lists that entity's fields; ';' joins several).
    std::string fieldOfInput;
    //! Text only: the value is points picked in the view, in turn on the
    //! entity of each of these input roles ("moving", "reference": a pair of
    //! points), their global coordinates as numbers, a group per line (';'
    //! between groups on the command line). The workbench fills it by picking.
    std::vector<std::string> pickedOn;
    //! The parameter matters only with this other one given (an alternative
    //! chosen, an optional value switched on, a switch turned on): "neighbours"
    //! of the statistical test, "alpha" of the propagation; "!name": only
    //! without it; "name=value": only while the choice `name` is `value`
    //! ("method=alpha"). The GUI shows it only then (and gives an optional one only
    //! then); the CLI lists it as usual.
    std::string usedWith;
    //! Integer/Real: what 0 stands for ("automatic"); the GUI writes it in
    //! place of the number.
    std::string zeroMeans;
    //! Real: a threshold on the field named by this other (Text, fieldOfInput)
    //! parameter. The workbench proposes the bound the user dragged on that
    //! field's histogram (its threshold range), so the value tuned live on
    //! the view is the one the tool runs with.
    std::string thresholdOfField;
    //! Text only: how many values the command-line option takes at once
    //! ("--range A B": 2); they arrive joined by ';' as repeated values do.
    int commandLineValues = 1;

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
    //! The same declaration, optional and one of the alternatives of `group`.
    ParameterSpec asAlternative(std::string group) const;
    //! The same declaration, required (see `required`).
    ParameterSpec asRequired() const;
    //! The same declaration with suggestions (see `suggestions`).
    ParameterSpec withSuggestions(std::vector<std::string> values) const;
    //! The same declaration, naming a field of input `role` (see `fieldOfInput`).
    ParameterSpec asFieldOf(std::string role = "input") const;
    //! The same declaration, picked in the view on these roles (see `pickedOn`).
    ParameterSpec pickedAlternatelyOn(std::vector<std::string> roles) const;
    //! The same declaration, used only with `parameter` (see `usedWith`).
    ParameterSpec onlyWith(std::string parameter) const;
    //! The same declaration, 0 standing for `meaning` (see `zeroMeans`).
    ParameterSpec withZeroMeaning(std::string meaning) const;
    //! The same declaration, a threshold on the field `fieldParameter` names (see `thresholdOfField`).
    ParameterSpec asThresholdOf(std::string fieldParameter) const;
    //! The same declaration, its option taking `count` values (see `commandLineValues`).
    ParameterSpec takingValues(int count) const;

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

//! What a tool takes or gives. A Cloud input also accepts a mesh (its
//! vertices); a Mesh input needs triangles. A Document is a text file the tool
//! composes itself (a JSON description of its results).
enum class DataKind { Cloud, Mesh, Table, Transform, Drawing, Document };

//! A Document output: its text and the extension of its file (".json").
struct TextDocument
{
    std::string extension = ".json";
    std::string text;
};

//! One input of a tool: an entity, or several, playing a role. A Drawing
//! input is a CAD drawing file (DXF) on the command line; the workbench has
//! no drawing entities yet and does not list tools that need one.
struct InputSpec
{
    //! "input" is the CLI's positional argument (IN, or IN... when repeated);
    //! any other role is an option "--ROLE FILE". The GUI offers a list of the
    //! open entities of the right kind for each role.
    std::string role = "input";
    std::string label = "Cloud";
    std::string description;
    DataKind kind = DataKind::Cloud;
    bool repeated = false; //!< one or more entities (merge)
    bool optional = false; //!< may be absent
};

//! One output of a tool.
struct OutputSpec
{
    //! The first output is written to the CLI's "-o FILE"; each later one beside
    //! it, as FILE's stem + "_" + role + FILE's extension (".csv" for a table,
    //! ".txt" for a transform).
    std::string role = "output";
    std::string label;
    DataKind kind = DataKind::Cloud;
    //! The output is the first input changed in place (normals or fields added,
    //! points moved): the workbench replaces that entity's data and keeps its
    //! place and display instead of adding a new entity under it. A Cloud
    //! output of the same size replaces a mesh's vertices and keeps its triangles.
    bool updatesInput = false;
    //! Any number of outputs of this role (one per station of a multi-station
    //! registration): the CLI writes them with --out-dir, each under its name.
    bool repeated = false;
    //! The name of its file in --out-dir, without extension (default: the
    //! role): outputs of different kinds may share one ("stones" gives
    //! stones.ply, stones.dxf and stones.csv).
    std::string fileStem = {};
    //! A repeated output whose k-th entity belongs to the k-th of another
    //! repeated output (a shape's surface and its points): the workbench lists
    //! it under that one instead of under the input. Empty: under the input.
    std::string under = {};
    //! The field the workbench shows first on this output's entities (a
    //! shape's points and surface by primitive_id, one colour per shape),
    //! when they have it. Empty: their first field.
    std::string showsField = {};
};

//! The entities a run gets, by role. It only refers to them: they belong to
//! the caller (the CLI's files, the workbench's document) and must outlive the run.
class ToolInputs
{
public:
    ToolInputs& add(const std::string& role, const PointCloud& cloud);
    ToolInputs& add(const std::string& role, const Mesh& mesh);
    ToolInputs& add(const std::string& role, const Entity& entity);
    ToolInputs& add(const std::string& role, const Drawing& drawing);

    std::size_t count(const std::string& role) const;
    bool has(const std::string& role) const { return count(role) != 0; }
    //! A cloud, or a mesh's vertices. Throws Error(InvalidArgument) naming the role when absent.
    const PointCloud& cloud(const std::string& role = "input", std::size_t index = 0) const;
    //! Throws Error(InvalidArgument) when absent or not a mesh.
    const Mesh& mesh(const std::string& role = "input", std::size_t index = 0) const;
    //! Null when the entity is a cloud.
    const Mesh* meshOrNull(const std::string& role = "input", std::size_t index = 0) const;
    //! Throws Error(InvalidArgument) when absent or not a drawing.
    const Drawing& drawing(const std::string& role, std::size_t index = 0) const;

private:
    using Ref = std::variant<const PointCloud*, const Mesh*, const Drawing*>;
    const Ref& at(const std::string& role, std::size_t index) const;
    std::map<std::string, std::vector<Ref>> entities_;
};

using OutputData = std::variant<PointCloud, Mesh, Table, Eigen::Matrix4d, Drawing, TextDocument>;

//! Named values describing one output (a shape's type, parameters and
//! uncertainties), in order: the workbench lists them in its Properties panel.
using OutputProperties = std::vector<std::pair<std::string, std::string>>;

struct ToolOutput
{
    std::string role;
    OutputData data;
    OutputProperties properties = {};
};

//! A value worth seeing on the histogram of an input's field: a threshold
//! the tool chose, the means of the classes it separated.
struct FieldMark
{
    std::string role = "input"; //!< the input whose field it is
    std::string field;
    double value = 0.0;
    std::string label;          //!< "threshold", "stone mean"...
};

struct ToolResult
{
    std::vector<ToolOutput> outputs; //!< in the order of the tool's OutputSpecs; an output may be absent
    std::string summary;             //!< one line for the log: what was done, counts
    //! Shown by the workbench on the field's histogram (dashed, labelled); the CLI's summary says them.
    std::vector<FieldMark> marks;

    ToolResult& add(std::string role, OutputData data, OutputProperties properties = {});
    //! Null when the run produced no output of that role (the first, for a repeated role).
    const ToolOutput* find(const std::string& role) const;
    ToolOutput* find(const std::string& role);
    //! Every output of the role, in order.
    std::vector<ToolOutput*> findAll(const std::string& role);
    //! The cloud of output `role`. Throws Error(Internal) when absent or not a cloud.
    const PointCloud& cloud(const std::string& role = "output") const;
    const Mesh& mesh(const std::string& role = "output") const;
    const Table& table(const std::string& role = "output") const;
    const Eigen::Matrix4d& transform(const std::string& role = "output") const;
};

struct ToolSpec
{
    std::string name;        //!< CLI name, e.g. "sor-filter"
    std::string title;       //!< menu text, e.g. "Statistical outlier filter"
    std::string description; //!< a paragraph of help, with the method's source
    std::string category;    //!< menu group, e.g. "Filters"
    std::vector<InputSpec> inputs{InputSpec{}};
    std::vector<OutputSpec> outputs{OutputSpec{}};
    std::vector<ParameterSpec> parameters;
    std::function<ToolResult(const ToolInputs&, const ParameterValues&, ProgressObserver*)> run;
    //! Optional: a quick table of what a run would give, for the workbench to
    //! show and refresh while the dialog is open (point pairs: each pair's
    //! residual as the pairs are picked). Fast, no progress; throws
    //! Error(InvalidArgument) with the reason while the values cannot give one.
    std::function<Table(const ToolInputs&, const ParameterValues&)> preview;
    //! The registry gives the tool `--classes` / `--exclude-classes`
    //! (ClassSelection.h) when it takes clouds; false for a tool where a class
    //! means nothing (renaming or deleting a field, moving a whole cloud).
    bool runsOnClasses = true;

    const ParameterSpec* parameter(const std::string& name) const;
    const InputSpec* input(const std::string& role) const;
    const OutputSpec* output(const std::string& role) const;
    //! The declared defaults (a required parameter's proposal included).
    ParameterValues defaults() const;
    //! Defaults overridden by user text, every value parsed and checked.
    //! Throws Error(InvalidArgument) for an unknown name or a bad value.
    ParameterValues resolve(const std::map<std::string, std::string>& userText) const;
    //! Throws Error(InvalidArgument) when a required role is missing, a single
    //! role has several entities, or a Mesh role holds a cloud.
    void checkInputs(const ToolInputs& inputs) const;
    //! checkInputs, then run: what every front end calls.
    ToolResult execute(const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) const;
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
