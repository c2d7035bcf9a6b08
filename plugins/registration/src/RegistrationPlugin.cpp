// SPDX-License-Identifier: GPL-3.0-or-later
// Registers the registration tools: register (ICP, optionally after a global
// alignment), register-pairs (point pairs), register-stations (several scans).
#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>
#include <scandiff/core/processing/CloudEditing.h>
#include <scandiff/plugins/PluginRegistry.h>
#include <scandiff/plugins/registration/GlobalAlignment.h>
#include <scandiff/plugins/registration/Icp.h>
#include <scandiff/plugins/registration/PointPairs.h>
#include <scandiff/plugins/registration/PrimitiveAlignment.h>
#include <scandiff/plugins/registration/Stations.h>

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

std::vector<ParameterSpec> dofParameters()
{
    return {ParameterSpec::choice("dof", "Degrees of freedom",
                                  "6; 4 (rotation about --axis and translation: levelled scanners); translation",
                                  {"6", "4", "translation"}, "6"),
            ParameterSpec::text("axis", "Rotation axis", "The axis of the 4-DOF rotation, X,Y,Z", "0,0,1").withSuggestions({"0,0,1"})};
}

DofConstraint dofFrom(const ParameterValues& values)
{
    DofConstraint constraint;
    constraint.dof = parseDof(values.text("dof"));
    constraint.axis = axisFrom(values.text("axis"));
    return constraint;
}

std::vector<ParameterSpec> globalParameters()
{
    const GlobalAlignmentParams defaults;
    return {ParameterSpec::real("spacing", "Feature spacing",
                                "Both clouds thinned to this spacing for the descriptors (normals within 2, descriptors within 5 "
                                "spacings); absent: the reference keeps about 10 000 points",
                                0.5, 1e-6, 1e6, "m")
                .asOptional(),
            ParameterSpec::integer("hypotheses", "Hypotheses", "RANSAC hypotheses at most",
                                   static_cast<std::int64_t>(defaults.maxIterations), 100, 100000000)};
}

GlobalAlignmentParams globalFrom(const ParameterValues& values)
{
    GlobalAlignmentParams params;
    params.constraint = dofFrom(values);
    if (values.has("spacing"))
        params.spacing = values.real("spacing");
    params.maxIterations = static_cast<std::size_t>(values.integer("hypotheses"));
    params.seed = static_cast<std::uint64_t>(values.integer("seed"));
    return params;
}

//! The tool's outputs after an optional coarse stage (global alignment,
//! alignment on primitives) and, when `refine`, ICP from the coarse matrix;
//! the coarse stage's notes lead the refined report's, after `notePrefix`.
ToolResult refineAndReport(const ToolInputs& inputs, IcpParams icp, const RegistrationReport* coarse, const std::string& notePrefix,
                           bool refine, ProgressObserver* progress)
{
    const PointCloud& moving = inputs.cloud("moving");
    const Mesh* mesh = inputs.meshOrNull("reference");
    const PointCloud* referenceCloud = mesh ? nullptr : &inputs.cloud("reference");
    RegistrationReport report;
    ScalarField residual, excluded;
    if (refine) {
        if (coarse)
            icp.initial = coarse->matrix;
        IcpResult fine = icpRegister(moving, referenceCloud, mesh, icp, progress);
        report = std::move(fine.report);
        residual = std::move(fine.residual);
        excluded = std::move(fine.excluded);
        if (coarse) {
            report.method = coarse->method + ", then " + report.method;
            std::vector<std::string> notes;
            for (const auto& note : coarse->notes)
                notes.push_back(notePrefix + note);
            report.notes.insert(report.notes.begin(), notes.begin(), notes.end());
        }
    } else if (coarse) {
        report = *coarse;
    }
    ToolResult result;
    result.summary = reportSummary(report);
    if (refine)
        result.add("output", movedCloud(moving, report.matrix, report.method, std::move(residual), std::move(excluded)));
    else
        result.add("output", transformCloud(moving, report.matrix, report.method));
    result.add("matrix", report.matrix);
    result.add("report", reportTable(report));
    if (refine)
        result.add("trace", traceTable(report));
    return result;
}

//! ICP after an optional global alignment: the result and the tool's outputs.
ToolResult registerAndReport(const ToolInputs& inputs, IcpParams icp, const GlobalAlignmentParams* global, bool refine,
                             ProgressObserver* progress)
{
    if (!global)
        return refineAndReport(inputs, icp, nullptr, {}, refine, progress);
    const Mesh* mesh = inputs.meshOrNull("reference");
    const GlobalAlignmentResult coarse =
        globalAlign(inputs.cloud("moving"), mesh ? nullptr : &inputs.cloud("reference"), mesh, *global, progress);
    // From within about a spacing: correspondences much farther are not the
    // same surface (partial overlap).
    if (!icp.maxDistance)
        icp.maxDistance = 3 * coarse.spacing;
    return refineAndReport(inputs, icp, &coarse.report, "global alignment: ", refine, progress);
}

//! With --exclude-changes, what the ICP registers on (StableParts).
ParameterSpec stableParameter()
{
    return ParameterSpec::choice("stable", "Stable parts",
                                 "With Exclude changes, on a cloud without classes: surfaces (every planar part: ground, walls, "
                                 "roofs) or ground (the ground a morphological filter finds and the walls; the other planar "
                                 "parts for the horizontal only: for epochs whose roofs or objects may have been raised)",
                                 {"surfaces", "ground"}, "surfaces");
}

StableParts stablePartsFrom(const ParameterValues& values)
{
    return values.text("stable") == "ground" ? StableParts::Ground : StableParts::Surfaces;
}

std::vector<ParameterSpec> icpParameters()
{
    const IcpParams defaults;
    return {
        ParameterSpec::choice("method", "Method", "Residual minimised", {"point-to-plane", "point-to-point"}, "point-to-plane"),
        ParameterSpec::real("max-dist", "Maximum distance", "Leave out correspondences farther than this", 1.0, 1e-9, 1e9, "m").asOptional(),
        ParameterSpec::real("overlap", "Overlap", "Keep this fraction of the correspondences, the closest", 1.0, 0.01, 1.0),
        ParameterSpec::boolean("robust", "Robust",
                               "Once converged, weigh residuals with a robust kernel (scale from their median) and go on: "
                               "ten times closer on noisy scans",
                               true),
        ParameterSpec::choice("kernel", "Kernel", "The robust kernel", {"cauchy", "huber", "geman-mcclure"}, "cauchy"),
        ParameterSpec::boolean("exclude-changes", "Exclude changes",
                               "Leave out correspondences beyond a threshold that shrinks with the residuals (changed areas)", false),
        stableParameter(),
        ParameterSpec::integer("sample", "Sampled points", "Moving points used per iteration, at random (0: all)",
                               static_cast<std::int64_t>(defaults.sampleCount), 0, 1000000000, "points"),
        ParameterSpec::integer("iterations", "Maximum iterations", "Iterations at most", static_cast<std::int64_t>(defaults.maxIterations),
                               1, 10000),
    };
}

IcpParams icpFrom(const ParameterValues& values)
{
    IcpParams params;
    params.method = parseIcpMethod(values.text("method"));
    params.constraint = dofFrom(values);
    if (values.has("max-dist"))
        params.maxDistance = values.real("max-dist");
    params.overlap = values.real("overlap");
    params.kernel = values.boolean("robust") ? parseRobustKernel(values.text("kernel")) : RobustKernel::None;
    params.changeRobust = values.boolean("exclude-changes");
    params.stableParts = stablePartsFrom(values);
    params.sampleCount = static_cast<std::size_t>(values.integer("sample"));
    params.maxIterations = static_cast<std::size_t>(values.integer("iterations"));
    params.seed = static_cast<std::uint64_t>(values.integer("seed"));
    return params;
}

ParameterSpec seedParameter()
{
    return ParameterSpec::integer("seed", "Seed", "Random sampling seed (the same seed, the same result)", 0, 0,
                                  std::numeric_limits<std::int64_t>::max());
}

void addIcpTool(ToolRegistry& registry)
{
    ToolSpec tool;
    tool.name = "register";
    tool.title = "Fine registration (ICP)";
    tool.category = "Registration";
    tool.description =
        "Moves the moving cloud onto the reference (a cloud or a mesh) by iterative closest points: point-to-plane "
        "(default) or point-to-point, on exact closest points, in double precision; degrees of freedom constrained in "
        "the solver (4: rotation about an axis, levelled scanners); maximum distance, trimmed overlap, robust kernel; "
        "--exclude-changes leaves out what changed between the epochs (thesis 000 §1.4) and marks it in "
        "registration_excluded; --global first finds the motion from any start. Reports the matrix, residuals, "
        "convergence and a degeneracy warning.";
    tool.inputs = movingAndReference();
    tool.outputs = registrationOutputs();
    tool.parameters = icpParameters();
    const std::vector<ParameterSpec> dof = dofParameters();
    tool.parameters.insert(tool.parameters.begin() + 1, dof.begin(), dof.end());
    tool.parameters.push_back(
        ParameterSpec::boolean("global", "Global alignment first", "Find the motion from any start first (FPFH descriptors, RANSAC)", false));
    for (const auto& p : globalParameters())
        tool.parameters.push_back(p);
    tool.parameters.push_back(
        ParameterSpec::text("initial", "Initial matrix", "A starting motion: 16 numbers row by row, or a matrix file").asOptional());
    tool.parameters.push_back(seedParameter());
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        IcpParams params = icpFrom(values);
        const bool global = values.boolean("global");
        if (global && values.has("initial"))
            throw Error(ErrorCode::InvalidArgument, "registration: --global finds the start itself; give it or --initial, not both");
        if (values.has("initial"))
            params.initial = matrixFrom(values.text("initial"));
        const GlobalAlignmentParams globalParams = globalFrom(values);
        return registerAndReport(inputs, params, global ? &globalParams : nullptr, true, progress);
    };
    registry.add(std::move(tool));
}

void addGlobalTool(ToolRegistry& registry)
{
    ToolSpec tool;
    tool.name = "register-global";
    tool.title = "Global alignment";
    tool.category = "Registration";
    tool.description =
        "Finds the motion of the moving cloud onto the reference from any start: both thinned to a feature spacing, a "
        "shape descriptor per point (FPFH, Rusu et al. 2009), descriptors matched, and the motion most matches agree on "
        "found by RANSAC (3 matches a hypothesis; 2 with 4 degrees of freedom, which searches only the heading). Then, "
        "unless --refine is off, point-to-plane ICP with a robust kernel finishes it.";
    tool.inputs = movingAndReference();
    tool.outputs = registrationOutputs();
    tool.parameters = dofParameters();
    for (const auto& p : globalParameters())
        tool.parameters.push_back(p);
    tool.parameters.push_back(ParameterSpec::boolean("refine", "Refine with ICP", "Finish with point-to-plane ICP (robust kernel)", true));
    tool.parameters.push_back(ParameterSpec::boolean(
        "exclude-changes", "Exclude changes", "In the ICP, leave out what changed between the epochs (thesis 000 §1.4)", false));
    tool.parameters.push_back(stableParameter());
    tool.parameters.push_back(seedParameter());
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        IcpParams icp;
        icp.constraint = dofFrom(values);
        icp.kernel = RobustKernel::Cauchy;
        icp.changeRobust = values.boolean("exclude-changes");
        icp.stableParts = stablePartsFrom(values);
        icp.seed = static_cast<std::uint64_t>(values.integer("seed"));
        const GlobalAlignmentParams global = globalFrom(values);
        return registerAndReport(inputs, icp, &global, values.boolean("refine"), progress);
    };
    registry.add(std::move(tool));
}

void addPrimitivesTool(ToolRegistry& registry)
{
    ToolSpec tool;
    tool.name = "register-primitives";
    tool.title = "Alignment on planes, pipes or targets";
    tool.category = "Registration";
    tool.description =
        "Moves the moving cloud onto the reference on the shapes both scans hold (thesis 004): the planes (region growing by "
        "default), the sphere targets (--on spheres), the pipes and columns (--on cylinders) or all three (--on all) found in "
        "each; three reference shapes that fix the motion and three moving ones of the same kinds and sizes making the same "
        "angles and distances give a hypothesis, scored by the shapes it brings onto shapes of the other scan, the best "
        "refined on every match. From any start. Then, unless --refine is off, point-to-plane ICP with a robust kernel "
        "finishes it.";
    tool.inputs = movingAndReference();
    tool.outputs = registrationOutputs();
    tool.outputs.push_back(OutputSpec{"matches", "Matched shapes", DataKind::Table, false});
    tool.parameters = {
        ParameterSpec::choice("on", "Align on",
                              "planes: the planes both scans hold (walls, floors, roofs); spheres: sphere targets (found by "
                              "efficient RANSAC), matched by their radii and the distances between them; cylinders: pipes and "
                              "columns (two that are not parallel fix the motion); all: planes, cylinders and spheres together",
                              {"planes", "spheres", "cylinders", "all"}, "planes"),
        ParameterSpec::choice("method", "Plane finder", "How the planes of each scan are found (see primitives)",
                              {"region-growing", "efficient-ransac", "sequential"}, "region-growing")
            .onlyWith("on=planes"),
        ParameterSpec::real("epsilon", "Plane thickness", "Largest distance of a point to its plane; absent: 3 x the noise", 0.01, 1e-9,
                            1e9, "m")
            .asOptional(),
        ParameterSpec::integer("min-points", "Smallest plane", "Smallest number of points of a plane", 500, 10, 1000000000, "points"),
        ParameterSpec::real("angle-tolerance", "Angle tolerance", "Matched pairs of planes make the same angle within this", 2.0, 0.01,
                            30, "deg"),
        ParameterSpec::real("distance-tolerance", "Distance tolerance", "A matched plane's offset after the motion", 0.05, 1e-6, 1e6,
                            "m"),
        ParameterSpec::boolean("refine", "Refine with ICP", "Finish with point-to-plane ICP (robust kernel)", true),
        seedParameter(),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& moving = inputs.cloud("moving");
        const Mesh* mesh = inputs.meshOrNull("reference");
        const PointCloud& reference = mesh ? mesh->vertices : inputs.cloud("reference");
        const std::string on = values.text("on");
        const bool spheres = on == "spheres", planes = on == "planes";
        // The kinds matched; planes are sought in every case, so that a wall
        // is never taken for a huge cylinder or sphere.
        const std::set<PrimitiveKind> matched = on == "cylinders" ? std::set<PrimitiveKind>{PrimitiveKind::Cylinder}
                                                : on == "all"     ? std::set<PrimitiveKind>{PrimitiveKind::Plane, PrimitiveKind::Cylinder, PrimitiveKind::Sphere}
                                                : spheres         ? std::set<PrimitiveKind>{PrimitiveKind::Sphere}
                                                                  : std::set<PrimitiveKind>{PrimitiveKind::Plane};
        PrimitiveDetectionParams detection;
        detection.method = planes ? parsePrimitiveMethod(values.text("method")) : PrimitiveMethod::EfficientRansac;
        detection.kinds = matched;
        detection.kinds.insert(PrimitiveKind::Plane);
        if (values.has("epsilon"))
            detection.epsilon = values.real("epsilon");
        detection.minPoints = static_cast<std::size_t>(values.integer("min-points"));
        detection.seed = static_cast<std::uint64_t>(values.integer("seed"));
        const PrimitiveDetectionResult movingPlanes = detectPrimitives(moving, detection, progress);
        const PrimitiveDetectionResult referencePlanes = detectPrimitives(reference, detection, progress);
        PrimitiveAlignmentParams align;
        align.angleToleranceDegrees = values.real("angle-tolerance");
        align.distanceTolerance = values.real("distance-tolerance");
        const PrimitiveAlignment aligned = alignOnShapes(movingPlanes.primitives, referencePlanes.primitives, matched, align, progress);

        RegistrationReport coarse;
        coarse.method = "alignment on " + std::to_string(aligned.matches.size()) + (spheres ? " spheres" : planes ? " planes" : " shapes");
        coarse.matrix = aligned.matrix;
        const BoundingBox movingBox = moving.bounds();
        coarse.centre = movingBox.empty ? moving.origin() : Eigen::Vector3d((movingBox.min + movingBox.max) / 2);
        coarse.rms = aligned.rmsOffset;
        // The residuals' spread is the shapes' (listed in `matches`), not the points'.
        coarse.median = coarse.p90 = coarse.p95 = coarse.p99 = std::numeric_limits<double>::quiet_NaN();
        coarse.overlap = std::numeric_limits<double>::quiet_NaN();
        coarse.converged = true;
        coarse.degeneracy = aligned.degeneracy;
        coarse.notes = aligned.notes;
        coarse.notes.push_back(spheres ? "spheres: RMS distance of the centres " + std::to_string(aligned.rmsOffset) + " m"
                                       : std::string(planes ? "planes" : "shapes") + ": RMS angle " + std::to_string(aligned.rmsAngleDegrees) +
                                             " deg, RMS offset " + std::to_string(aligned.rmsOffset) + " m");
        IcpParams icp;
        icp.kernel = RobustKernel::Cauchy;
        icp.seed = static_cast<std::uint64_t>(values.integer("seed"));
        // From within a few plane thicknesses and spacings of the planes' motion.
        icp.maxDistance = std::max(movingPlanes.clusterEpsilon, 5.0 * std::max(aligned.rmsOffset, movingPlanes.epsilon));
        ToolResult result = refineAndReport(inputs, icp, &coarse, {}, values.boolean("refine"), progress);
        Table matches;
        matches.columns = {"moving_shape", "reference_shape", "type", "angle_deg", "offset_m"};
        for (const PlaneMatch& m : aligned.matches)
            matches.rows.push_back({static_cast<double>(m.moving), static_cast<double>(m.reference), std::string(primitiveKindName(m.kind)),
                                    m.angleDegrees, m.offset});
        result.add("matches", std::move(matches));
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
                            "by ';', or a text/CSV file of such lines")
            .pickedAlternatelyOn({"moving", "reference"}),
    };
    for (const auto& p : dofParameters())
        tool.parameters.push_back(p);
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver*) {
        const PointCloud& moving = inputs.cloud("moving");
        const RegistrationReport report = fitPointPairs(parsePointPairs(values.text("pairs")), dofFrom(values));
        ToolResult result;
        result.summary = reportSummary(report);
        result.add("output", transformCloud(moving, report.matrix, report.method));
        result.add("matrix", report.matrix);
        result.add("report", reportTable(report));
        return result;
    };
    // Each pair's residual as the pairs are picked: what tells a mistaken pick.
    tool.preview = [](const ToolInputs&, const ParameterValues& values) {
        const RegistrationReport report = fitPointPairs(parsePointPairs(values.text("pairs")), dofFrom(values));
        Table t;
        t.columns = {"pair", "residual_m", "note"};
        for (std::size_t i = 0; i < report.pairResiduals.size(); ++i)
            t.rows.push_back({std::to_string(i + 1), report.pairResiduals[i], std::string()});
        std::string notes;
        for (const auto& note : report.notes)
            notes += (notes.empty() ? "" : "; ") + note;
        t.rows.push_back({std::string("RMS"), report.rms, notes});
        return t;
    };
    registry.add(std::move(tool));
}

Table posesTable(const std::vector<Eigen::Matrix4d>& poses)
{
    Table t;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            t.columns.push_back("m" + std::to_string(r) + std::to_string(c));
    t.plainNumbers = true; // poses.txt: one line of 16 numbers per station, row by row
    for (const auto& m : poses) {
        std::vector<TableCell> row;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c)
                row.emplace_back(m(r, c));
        t.rows.push_back(std::move(row));
    }
    return t;
}

Table stationsReportTable(const StationResult& s)
{
    Table t;
    t.columns = {"metric", "value"};
    const auto add = [&](const std::string& name, TableCell value) { t.rows.push_back({name, std::move(value)}); };
    const RegistrationReport& r = s.report;
    add("method", r.method);
    add("stations", static_cast<double>(s.poses.size()));
    add("pairs", static_cast<double>(s.pairs.size()));
    add("loops", static_cast<double>(s.loops.size()));
    add("rms_m", r.rms);
    add("median_m", r.median);
    add("p90_m", r.p90);
    add("p95_m", r.p95);
    add("p99_m", r.p99);
    add("iterations", static_cast<double>(r.iterations));
    add("converged", r.converged ? 1.0 : 0.0);
    for (std::size_t k = 0; k < s.poses.size(); ++k) {
        add("station_" + std::to_string(k) + "_rotation_deg", rotationDegrees(s.poses[k].topLeftCorner<3, 3>()));
    }
    add("warning", r.degeneracy);
    for (const auto& note : r.notes)
        add("note", note);
    return t;
}

Table stationPairsTable(const StationResult& s)
{
    Table t;
    t.columns = {"station_a", "station_b", "used", "overlap", "agreement", "pairwise_rms_m", "adjusted_rms_m", "disagreement_deg", "disagreement_m",
                 "note", "warning"};
    for (const auto& p : s.pairs)
        t.rows.push_back({static_cast<double>(p.a), static_cast<double>(p.b), p.used ? 1.0 : 0.0, p.overlap, p.agreement, p.pairwise.rms, p.adjustedRms,
                          p.disagreementDegrees, p.disagreementMetres, p.note, p.pairwise.degeneracy});
    return t;
}

Table stationLoopsTable(const StationResult& s)
{
    Table t;
    t.columns = {"loop", "stations", "misclosure_deg", "misclosure_m"};
    for (std::size_t i = 0; i < s.loops.size(); ++i) {
        std::string path;
        for (std::size_t k : s.loops[i].stations)
            path += (path.empty() ? "" : "-") + std::to_string(k);
        t.rows.push_back({static_cast<double>(i + 1), path, s.loops[i].rotationDegrees, s.loops[i].translationMetres});
    }
    return t;
}

void addStationsTool(ToolRegistry& registry)
{
    const StationParams defaults;
    ToolSpec tool;
    tool.name = "register-stations";
    tool.title = "Multi-station adjustment";
    tool.category = "Registration";
    tool.description =
        "Registers several scans of a site together, each in its own scanner frame (any heading and place): every pair "
        "alone by global alignment then ICP, pairs that overlap too little or disagree with the loops they close left out "
        "(the misclosure of every loop of pairs is reported), then every pose at once in one least-squares problem "
        "over the point-to-plane residuals of all pairs, the first station fixed (6 unknowns per other station, 4 for "
        "levelled scanners: thesis 004 §III-2.2.1). Writes each station moved and poses.txt (16 numbers a line, row by "
        "row: station -> first station).";
    tool.inputs = {InputSpec{"input", "Stations", "The stations' scans; the first one stays where it is", DataKind::Cloud, true, false}};
    tool.outputs = {OutputSpec{"station", "Moved station", DataKind::Cloud, true, true},
                    OutputSpec{"poses", "Poses (station -> first station)", DataKind::Table, false},
                    OutputSpec{"report", "Adjustment report", DataKind::Table, false},
                    OutputSpec{"pairs", "Pairs", DataKind::Table, false},
                    OutputSpec{"loops", "Loop misclosures", DataKind::Table, false},
                    OutputSpec{"trace", "Convergence trace", DataKind::Table, false}};
    tool.parameters = dofParameters();
    tool.parameters.push_back(ParameterSpec::choice("start", "Stations start",
                                                    "any: each station in its own scanner frame, any heading and place (each "
                                                    "pair aligned globally first); near: roughly in one frame already (within "
                                                    "the maximum distance)",
                                                    {"any", "near"}, defaults.anyStart ? "any" : "near"));
    tool.parameters.push_back(ParameterSpec::real("max-dist", "Maximum distance",
                                                  "Correspondences farther are left out of the adjustment; with start near, "
                                                  "the stations must start within it",
                                                  defaults.maxDistance, 1e-9, 1e9, "m"));
    tool.parameters.push_back(ParameterSpec::real("spacing", "Feature spacing",
                                                  "start any: the spacing the stations are thinned to for their shape "
                                                  "descriptors; absent: the median station keeps about 10 000 points",
                                                  0.1, 1e-6, 1e6, "m")
                                  .asOptional()
                                  .onlyWith("start=any"));
    tool.parameters.push_back(ParameterSpec::real("min-overlap", "Minimum overlap",
                                                  "Pairs whose overlap (fraction of a station's points near the other) is "
                                                  "smaller are not registered",
                                                  defaults.minOverlap, 0.001, 1.0));
    tool.parameters.push_back(ParameterSpec::integer("sample", "Sampled points", "Points of each station used, at random",
                                                     static_cast<std::int64_t>(defaults.sampleCount), 10, 1000000000, "points"));
    tool.parameters.push_back(ParameterSpec::integer("iterations", "Maximum iterations", "Joint iterations at most",
                                                     static_cast<std::int64_t>(defaults.maxIterations), 1, 10000));
    tool.parameters.push_back(seedParameter());
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        StationParams params;
        params.constraint = dofFrom(values);
        params.maxDistance = values.real("max-dist");
        params.anyStart = values.text("start") == "any";
        if (values.has("spacing"))
            params.featureSpacing = values.real("spacing");
        params.minOverlap = values.real("min-overlap");
        params.sampleCount = static_cast<std::size_t>(values.integer("sample"));
        params.maxIterations = static_cast<std::size_t>(values.integer("iterations"));
        params.seed = static_cast<std::uint64_t>(values.integer("seed"));
        std::vector<const PointCloud*> stations;
        for (std::size_t k = 0; k < inputs.count("input"); ++k)
            stations.push_back(&inputs.cloud("input", k));
        const StationResult adjusted = adjustStations(stations, params, progress);
        ToolResult result;
        std::ostringstream summary;
        double worstLoop = 0;
        for (const auto& loop : adjusted.loops)
            worstLoop = std::max(worstLoop, loop.translationMetres);
        summary << adjusted.report.method << ": RMS " << adjusted.report.rms << " m (median " << adjusted.report.median << "); "
                << adjusted.loops.size() << " loops";
        if (!adjusted.loops.empty())
            summary << ", worst misclosure " << worstLoop << " m";
        summary << "; " << adjusted.report.iterations << " iterations" << (adjusted.report.converged ? "" : " (not converged)");
        if (!adjusted.report.degeneracy.empty())
            summary << "; WARNING " << adjusted.report.degeneracy;
        for (const std::string& note : adjusted.report.notes)
            if (note.find("ambiguous") != std::string::npos)
                summary << "; WARNING " << note;
        result.summary = summary.str();
        for (std::size_t k = 0; k < stations.size(); ++k)
            result.add("station", transformCloud(*stations[k], adjusted.poses[k], adjusted.report.method));
        result.add("poses", posesTable(adjusted.poses));
        result.add("report", stationsReportTable(adjusted));
        result.add("pairs", stationPairsTable(adjusted));
        result.add("loops", stationLoopsTable(adjusted));
        result.add("trace", traceTable(adjusted.report));
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
    scandiff::plugins::addGlobalTool(registry.tools);
    scandiff::plugins::addPointPairsTool(registry.tools);
    scandiff::plugins::addPrimitivesTool(registry.tools);
    scandiff::plugins::addStationsTool(registry.tools);
}
