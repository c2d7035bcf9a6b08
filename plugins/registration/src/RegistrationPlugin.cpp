// SPDX-License-Identifier: GPL-3.0-or-later
// Registers the registration tools: register (ICP, optionally after a global
// alignment), register-pairs (point pairs), register-stations (several scans).
#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/processing/CloudEditing.h>
#include <scandiff/plugins/PluginRegistry.h>
#include <scandiff/plugins/registration/Icp.h>
#include <scandiff/plugins/registration/PointPairs.h>

#include <fstream>
#include <sstream>

namespace scandiff::plugins {

namespace {

Eigen::Vector3d axisFrom(const std::string& text)
{
    const std::vector<double> v = parseNumberList(text, "the rotation axis");
    if (v.size() != 3 || !(Eigen::Vector3d(v[0], v[1], v[2]).norm() > 0))
        throw Error(ErrorCode::InvalidArgument, "registration: the axis is a non-zero direction X,Y,Z");
    return Eigen::Vector3d(v[0], v[1], v[2]).normalized();
}

//! 16 numbers row by row, or a file of them (as the transform tool reads).
Eigen::Matrix4d matrixFrom(const std::string& text)
{
    std::string content = text;
    if (std::ifstream file{text}) {
        std::stringstream all;
        all << file.rdbuf();
        content = all.str();
    }
    for (char& c : content)
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == ';')
            c = ',';
    std::vector<double> v;
    for (const std::string& part : splitList(content, ','))
        if (!part.empty())
            v.push_back(parseNumberList(part, "the initial matrix").front());
    if (v.size() != 16)
        throw Error(ErrorCode::InvalidArgument, "registration: the initial matrix is 16 numbers (or a file of them), not " +
                                                    std::to_string(v.size()));
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            m(r, c) = v[static_cast<std::size_t>(4 * r + c)];
    return m;
}

//! The moving cloud moved by the result, with the residual fields.
PointCloud movedCloud(const PointCloud& moving, const Eigen::Matrix4d& matrix, const std::string& how, ScalarField residual,
                      ScalarField excluded)
{
    PointCloud out = transformCloud(moving, matrix, how);
    out.addField(std::move(residual));
    if (excluded.size() == out.size())
        out.addField(std::move(excluded));
    return out;
}

std::vector<InputSpec> movingAndReference()
{
    return {InputSpec{"moving", "Moving", "The cloud that is moved (its points keep their order)", DataKind::Cloud, false, false},
            InputSpec{"reference", "Reference", "The cloud or mesh it is registered on", DataKind::Cloud, false, false}};
}

std::vector<OutputSpec> registrationOutputs()
{
    return {OutputSpec{"output", "Moved cloud", DataKind::Cloud, true},
            OutputSpec{"matrix", "Matrix moving -> reference", DataKind::Transform, false},
            OutputSpec{"report", "Registration report", DataKind::Table, false},
            OutputSpec{"trace", "Convergence trace", DataKind::Table, false}};
}

void addIcpTool(ToolRegistry& registry)
{
    const IcpParams defaults;
    ToolSpec tool;
    tool.name = "register";
    tool.title = "Fine registration (ICP)";
    tool.category = "Registration";
    tool.description =
        "Moves the moving cloud onto the reference (a cloud or a mesh) by iterative closest points: point-to-plane "
        "(default) or point-to-point, on exact closest points, in double precision; degrees of freedom constrained in "
        "the solver (4: rotation about an axis, levelled scanners); maximum distance, trimmed overlap, robust kernel; "
        "--exclude-changes leaves out what changed between the epochs (thesis 000 §1.4) and marks it in "
        "registration_excluded. Reports the matrix, residuals, convergence and a degeneracy warning.";
    tool.inputs = movingAndReference();
    tool.outputs = registrationOutputs();
    tool.parameters = {
        ParameterSpec::choice("method", "Method", "Residual minimised", {"point-to-plane", "point-to-point"}, "point-to-plane"),
        ParameterSpec::choice("dof", "Degrees of freedom", "6; 4 (rotation about --axis and translation: levelled scanners); translation",
                              {"6", "4", "translation"}, "6"),
        ParameterSpec::text("axis", "Rotation axis", "The axis of the 4-DOF rotation, X,Y,Z", "0,0,1").withSuggestions({"0,0,1"}),
        ParameterSpec::real("max-dist", "Maximum distance", "Leave out correspondences farther than this", 1.0, 1e-9, 1e9, "m").asOptional(),
        ParameterSpec::real("overlap", "Overlap", "Keep this fraction of the correspondences, the closest", 1.0, 0.01, 1.0),
        ParameterSpec::boolean("robust", "Robust", "Weigh residuals with a robust kernel (scale from their median)", false),
        ParameterSpec::choice("kernel", "Kernel", "The robust kernel", {"cauchy", "huber", "geman-mcclure"}, "cauchy"),
        ParameterSpec::boolean("exclude-changes", "Exclude changes",
                               "Leave out correspondences beyond a threshold that shrinks with the residuals (changed areas)", false),
        ParameterSpec::integer("sample", "Sampled points", "Moving points used per iteration, at random (0: all)",
                               static_cast<std::int64_t>(defaults.sampleCount), 0, 1000000000, "points"),
        ParameterSpec::integer("iterations", "Maximum iterations", "Iterations at most", static_cast<std::int64_t>(defaults.maxIterations),
                               1, 10000),
        ParameterSpec::text("initial", "Initial matrix", "A starting motion: 16 numbers row by row, or a matrix file").asOptional(),
        ParameterSpec::integer("seed", "Seed", "Random sampling seed", 0, 0, std::numeric_limits<std::int64_t>::max()),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& moving = inputs.cloud("moving");
        const Mesh* mesh = inputs.meshOrNull("reference");
        IcpParams params;
        params.method = parseIcpMethod(values.text("method"));
        params.constraint.dof = parseDof(values.text("dof"));
        params.constraint.axis = axisFrom(values.text("axis"));
        if (values.has("max-dist"))
            params.maxDistance = values.real("max-dist");
        params.overlap = values.real("overlap");
        params.kernel = values.boolean("robust") ? parseRobustKernel(values.text("kernel")) : RobustKernel::None;
        params.changeRobust = values.boolean("exclude-changes");
        params.sampleCount = static_cast<std::size_t>(values.integer("sample"));
        params.maxIterations = static_cast<std::size_t>(values.integer("iterations"));
        params.seed = static_cast<std::uint64_t>(values.integer("seed"));
        if (values.has("initial"))
            params.initial = matrixFrom(values.text("initial"));
        IcpResult icp = icpRegister(moving, mesh ? nullptr : &inputs.cloud("reference"), mesh, params, progress);
        ToolResult result;
        result.summary = reportSummary(icp.report);
        result.add("output", movedCloud(moving, icp.report.matrix, icp.report.method, std::move(icp.residual), std::move(icp.excluded)));
        result.add("matrix", icp.report.matrix);
        result.add("report", reportTable(icp.report));
        result.add("trace", traceTable(icp.report));
        return result;
    };
    registry.add(std::move(tool));
}

void addPointPairsTool(ToolRegistry& registry)
{
    ToolSpec tool;
    tool.name = "register-pairs";
    tool.title = "Point pairs";
    tool.category = "Registration";
    tool.description =
        "Moves the moving cloud onto the reference from pairs of the same points picked in both (targets, corners): the "
        "motion in closed form (Horn 1987, Umeyama 1991, without scale; 4 DOF: rotation about the axis only), each "
        "pair's residual reported. At least 3 pairs not on a line (2 for 4 DOF, 1 for a translation).";
    tool.inputs = movingAndReference();
    tool.outputs = {OutputSpec{"output", "Moved cloud", DataKind::Cloud, true},
                    OutputSpec{"matrix", "Matrix moving -> reference", DataKind::Transform, false},
                    OutputSpec{"report", "Registration report", DataKind::Table, false}};
    tool.parameters = {
        ParameterSpec::text("pairs", "Point pairs",
                            "MX,MY,MZ,RX,RY,RZ per pair (moving point, then the same point on the reference), pairs separated "
                            "by ';', or a text/CSV file of such lines"),
        ParameterSpec::choice("dof", "Degrees of freedom", "6; 4 (rotation about --axis and translation); translation",
                              {"6", "4", "translation"}, "6"),
        ParameterSpec::text("axis", "Rotation axis", "The axis of the 4-DOF rotation, X,Y,Z", "0,0,1").withSuggestions({"0,0,1"}),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver*) {
        const PointCloud& moving = inputs.cloud("moving");
        DofConstraint constraint;
        constraint.dof = parseDof(values.text("dof"));
        constraint.axis = axisFrom(values.text("axis"));
        const RegistrationReport report = fitPointPairs(parsePointPairs(values.text("pairs")), constraint);
        ToolResult result;
        result.summary = reportSummary(report);
        result.add("output", transformCloud(moving, report.matrix, report.method));
        result.add("matrix", report.matrix);
        result.add("report", reportTable(report));
        return result;
    };
    registry.add(std::move(tool));
}

} // namespace

} // namespace scandiff::plugins

void scandiff_register_plugin_registration(scandiff::PluginRegistry& registry)
{
    registry.plugins.push_back({"registration", "Fine, change-robust, constrained, global and multi-station registration", ""});
    scandiff::plugins::addIcpTool(registry.tools);
    scandiff::plugins::addPointPairsTool(registry.tools);
}
