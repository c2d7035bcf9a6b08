// SPDX-License-Identifier: GPL-3.0-or-later
// The tools on the scene families of tests/support/families: the issue's case
// at full size and a number of seeded draws, one line of figures each
// (docs/benchmarks.md quotes them; the family tests assert the same figures).
//
//   scandiff-family-trials FAMILY [--issue] [--verbose] [--cloudcompare DIR] [--draws N] [--first-seed S] [--scale F] [--set KEY=VALUE ...]
#include "families/ChangeTrials.h"
#include "families/PrimitiveTrials.h"
#include "families/RegistrationTrials.h"
#include "families/WallTrials.h"

#include <scandiff/core/Log.h>
#include <scandiff/core/processing/CloudEditing.h>

#include <scandiff/io/FileIO.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <tuple>
#include <fstream>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

using namespace scandiff;
using namespace scandiff::test::family;

namespace {

struct Options
{
    std::string family;
    bool issue = false;
    int draws = 0;
    std::uint64_t firstSeed = 1;
    double scale = 0.1;
    std::map<std::string, std::string> set;
    std::string svgDir; //!< --svg DIR: the wall families' rings over their truth, one SVG per run
    std::string dataDir = "data"; //!< --data DIR: where pcl-data/ lies (the real samples)
    bool verbose = false;         //!< --verbose: the tool's report and, for primitives, how each shape was split
    std::string cloudCompareDir;  //!< --cloudcompare DIR: primitives also through CloudCompare's RANSAC plugin, files in DIR
};

double seconds(std::chrono::steady_clock::time_point since)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

bool facadeRow(const facade::FacadeParams& p, const Options& o, const std::string& label)
{
    const auto start = std::chrono::steady_clock::now();
    const facade::FacadeScene scene = facade::make(p);
    std::map<std::string, std::string> prim{{"method", "region-growing"}}, cont;
    for (const auto& [k, v] : o.set)
        (k.rfind("p.", 0) == 0 ? prim : cont)[k.rfind("p.", 0) == 0 ? k.substr(2) : k] = v;
    const FacadeTrial t = o.set.count("wall-only") ? runFacadeContours(scene, {}) : runFacade(scene, prim, cont);
    if (!o.svgDir.empty()) {
        std::vector<wallsurvey::Polygon2> truth = scene.openingTruth;
        truth.push_back(scene.outlineTruth);
        writeWallSvg(o.svgDir + "/facade-" + label + ".svg", scene.frame, truth, t.rings, &scene.cloud);
    }
    std::printf("%s %s | %zu pts, %zu rings, most vertices %zu, rectangles not 4 corners %zu | %s | %.1f s%s\n", label.c_str(),
                facade::describe(p).c_str(), t.points, t.rings.size(), t.largestRingVertices, t.rectanglesNotFourCorners, t.score.summary().c_str(), seconds(start),
                t.score.meetsIssueTarget ? "" : "  FAIL");
    for (std::size_t k = 0; k < t.score.openings.size() && !t.score.meetsIssueTarget; ++k) {
        const auto& s = t.score.openings[k];
        if (!s.right)
            std::printf("    opening %zu at %.2f,%.2f (%.2f x %.2f m%s): IoU %.3f, Hausdorff %.1f mm, %zu vertices, %d rings\n", k,
                        p.openings[k].x0, p.openings[k].y0, p.openings[k].width, p.openings[k].height,
                        p.openings[k].arched ? ", arched" : "", s.iou, s.hausdorff * 1e3, s.vertices, s.ringsMatching);
    }
    std::fflush(stdout);
    return t.score.meetsIssueTarget;
}

bool stonesRow(const stonewall::StoneWallParams& p, const Options& o, const std::string& label)
{
    const auto start = std::chrono::steady_clock::now();
    const stonewall::StoneWallScene scene = stonewall::make(p);
    std::map<std::string, std::string> options = o.set;
    options.erase("svg-joints"); // the SVG's points coloured by stone_joint, not by stone
    const StoneTrial t = runStones(scene, options);
    if (!o.svgDir.empty())
        writeWallSvg(o.svgDir + "/stones-" + label + ".svg", scene.frame, scene.stoneTruth, t.rings, &scene.cloud, 400,
                     o.set.count("svg-joints") && t.jointOfPoint.size() == scene.cloud.size() ? &t.jointOfPoint : t.stoneOfPoint.size() == scene.cloud.size() ? &t.stoneOfPoint : nullptr);
    std::size_t merged = 0, jagged = 0, several = 0;
    for (const auto& m : t.score.stones) {
        merged += m.iou < 0.8;
        jagged += m.iou >= 0.8 && m.polygonsAbove == 1 && m.hausdorff > 0.03;
        several += m.polygonsAbove > 1;
    }
    std::printf("    wrong stones: %zu with IoU < 0.8, %zu within IoU but beyond 3 cm, %zu in several polygons\n", merged, jagged, several);
    if (o.verbose)
        std::printf("    %s\n", t.report.c_str());
    if (o.verbose)
        std::printf("    called stone: faces %.2f %% of %zu, arrises %.2f %% of %zu, joints %.2f %% of %zu\n",
                    100.0 * t.calledStone[0] / std::max<std::size_t>(1, t.truthParts[0]), t.truthParts[0],
                    100.0 * t.calledStone[1] / std::max<std::size_t>(1, t.truthParts[1]), t.truthParts[1],
                    100.0 * t.calledStone[2] / std::max<std::size_t>(1, t.truthParts[2]), t.truthParts[2]);
    if (o.verbose)
        for (int part = 0; part < 3; ++part)
            std::printf("    %s: parting off the joint lines %.2f %%, on a joint line %.2f %%\n", part == 0 ? "faces" : part == 1 ? "arrises" : "joints",
                        100.0 * t.calledParting[part] / std::max<std::size_t>(1, t.truthParts[part]),
                        100.0 * t.calledJoint[part] / std::max<std::size_t>(1, t.truthParts[part]));
    std::printf("%s %s | %zu pts, %zu polygons | %s | %.1f s%s\n", label.c_str(), stonewall::describe(p).c_str(), t.points,
                t.polygons, t.score.summary().c_str(), seconds(start), t.score.meetsIssueTarget ? "" : "  FAIL");
    std::fflush(stdout);
    return t.score.meetsIssueTarget;
}

bool changeRow(const terrainchange::TerrainChangeParams& p, const Options& o, const std::string& label)
{
    const auto start = std::chrono::steady_clock::now();
    const terrainchange::TerrainChangeScene scene = terrainchange::make(p);
    std::map<std::string, std::string> c2c, segment{{"stat-test", "weibull"}, {"components", "true"}};
    for (const auto& [k, v] : o.set)
        (k.rfind("c.", 0) == 0 ? c2c : segment)[k.rfind("c.", 0) == 0 ? k.substr(2) : k] = v;
    const ChangeTrial t = runChangeSegmentation(scene, c2c, segment);
    std::printf("%s %s | %s | %s | %.1f s%s\n", label.c_str(), terrainchange::describe(p).c_str(), t.summary.c_str(),
                terrainchange::describe(t.score).c_str(), seconds(start), t.met ? "" : "  FAIL");
    std::fflush(stdout);
    return t.met;
}

bool visibilityRow(const grazing::GrazingParams& p, const Options& o, const std::string& label)
{
    const auto start = std::chrono::steady_clock::now();
    const grazing::GrazingScene scene = grazing::make(p);
    const grazing::VisibilityScore s = runVisibility(scene, o.set);
    std::printf("%s %s | %zu ref, %zu cmp | agreement %.4f (ground %.4f wall %.4f cube %.4f), visible->hidden %.4f (ground %.4f), "
                "cube visible %.4f | %.1f s%s\n",
                label.c_str(), grazing::describe(p).c_str(), scene.reference.size(), scene.compared.size(), s.agreement,
                s.agreementByPart[0], s.agreementByPart[1], s.agreementByPart[2], s.visibleLabelledHidden,
                s.visibleGroundLabelledHidden, s.cubeLabelledVisible, seconds(start), s.meetsIssueTargets() ? "" : "  FAIL");
    std::printf("    confusion [truth][label]:");
    for (const auto& row : s.confusion)
        std::printf(" [%zu %zu %zu %zu]", row[0], row[1], row[2], row[3]);
    std::printf("\n");
    std::fflush(stdout);
    return s.meetsIssueTargets();
}

bool airborneRow(const airborne::AirborneEpochsScene& scene, const Options& o, const std::string& label, bool real)
{
    const auto start = std::chrono::steady_clock::now();
    std::map<std::string, std::string> options = o.set;
    // --set start-at-truth=1: ICP starts at the true motion; whether it stays
    // tells an objective whose minimum lies elsewhere from a search that stops short.
    if (options.erase("start-at-truth")) {
        std::string numbers;
        for (int k = 0; k < 16; ++k)
            numbers += epochscene::format(k ? " %.17g" : "%.17g", scene.trueLaterToEarlier(k / 4, k % 4));
        options["initial"] = numbers;
    }
    const AirborneTrial t = runAirborneRegistration(scene, options);
    const bool met = real ? airborne::meetsRealPairTarget(t.error) : airborne::meetsParkTarget(t.error);
    std::printf("%s %s | %zu/%zu pts | %s | %s | %.1f s%s\n", label.c_str(), scene.description.c_str(), scene.earlier.size(),
                scene.later.size(), airborne::describe(t.error).c_str(), t.report.c_str(), seconds(start), met ? "" : "  FAIL");
    std::fflush(stdout);
    return met;
}

bool stationsRow(const stations::StationsParams& p, const Options& o, const std::string& label)
{
    const auto start = std::chrono::steady_clock::now();
    stations::StationsScene scene = stations::make(p);
    const double made = seconds(start);
    std::map<std::string, std::string> options = o.set;
    if (options.count("verbose"))
        for (const auto& st : p.stations)
            std::printf("    station at (%.2f, %.2f) m, %.2f m high, heading %.1f deg, tilt %.3f deg; partition at x %.1f m, door at y %.1f m, "
                        "%.1f m wide\n",
                        st.position.x(), st.position.y(), st.height, st.headingDeg, st.tiltDeg, p.partitionX, p.partitionDoorCentreY,
                        p.partitionDoorWidth);
    options.erase("verbose");
    // --set start-at-truth=1: every station already where it belongs. Whether
    // the tool keeps the truth tells a search that missed it from a score
    // that prefers another pose.
    if (options.erase("start-at-truth")) {
        for (std::size_t i = 1; i < scene.clouds.size(); ++i) {
            scene.clouds[i] = transformCloud(scene.clouds[i], scene.trueRelativePose(i), "truth");
            scene.truePoses[i] = scene.truePoses[0];
        }
    }
    const StationsTrial t = runStations(scene, options);
    const bool met = stations::withinTolerance(t.errors, scene.clouds.size());
    std::size_t points = 0;
    for (const PointCloud& c : scene.clouds)
        points += c.size();
    std::printf("%s %s | %zu stations, %zu pts | errors:", label.c_str(), stations::describe(p).c_str(), scene.clouds.size(), points);
    for (const auto& e : t.errors)
        std::printf(" %.4f deg/%.1f mm", e.rotationDeg, e.maxDisplacement * 1e3);
    std::printf(" | %s | scene %.1f s, tool %.1f s%s\n", t.report.c_str(), made, seconds(start) - made, met ? "" : "  FAIL");
    if (o.set.count("verbose"))
        for (const auto& row : t.pairs.rows) {
            std::printf("    pair");
            for (const auto& cell : row)
                std::visit([](const auto& v) {
                    if constexpr (std::is_same_v<std::decay_t<decltype(v)>, double>)
                        std::printf(" %.4g", v);
                    else
                        std::printf(" %s", v.c_str());
                }, cell);
            std::printf("\n");
        }
    std::fflush(stdout);
    return met;
}

//! The scene through CloudCompare 2.11's RANSAC plugin (given our epsilon and
//! normal radius, its other settings its own), its shapes scored as ours: the
//! scene is written in local coordinates (CloudCompare's global shift stays
//! out of it), each subcloud's points found back by their coordinates, each
//! subcloud's type read from its file name.
std::string cloudCompareRow(const primitives::PrimitivesScene& scene, const std::string& report, const std::string& dir)
{
    const auto number = [&](const std::string& before) {
        const auto at = report.find(before);
        return at == std::string::npos ? 0.0 : std::atof(report.c_str() + at + before.size());
    };
    const double epsilon = number("epsilon "), normalRadius = number("fitted within ");
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir + "/shapes");
    PointCloud local = scene.cloud.clone();
    local.setOrigin(Eigen::Vector3d::Zero());
    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    io::writePointCloud(formats, local, dir + "/scene.ply");
    char command[1024];
    std::snprintf(command, sizeof command,
                  "cd %s && QT_QPA_PLATFORM=offscreen CloudCompare -SILENT -NO_TIMESTAMP -AUTO_SAVE OFF -C_EXPORT_FMT PLY -O scene.ply "
                  "-OCTREE_NORMALS %.6f -RANSAC EPSILON_ABSOLUTE %.6f SUPPORT_POINTS 200 ENABLE_PRIMITIVE PLANE SPHERE CYLINDER CONE TORUS "
                  "OUTPUT_INDIVIDUAL_SUBCLOUDS OUT_CLOUD_DIR shapes > cloudcompare.log 2>&1",
                  dir.c_str(), normalRadius, epsilon);
    const auto start = std::chrono::steady_clock::now();
    const int status = std::system(command);
    const double wall = seconds(start);
    std::map<std::tuple<float, float, float>, std::size_t> index;
    for (std::size_t i = 0; i < local.size(); ++i)
        index.emplace(std::make_tuple(local.positions()[i].x(), local.positions()[i].y(), local.positions()[i].z()), i);
    std::vector<int> assignment(local.size(), -1);
    std::vector<Primitive> detected;
    std::size_t unmatched = 0;
    std::vector<std::filesystem::path> files;
    for (const auto& entry : std::filesystem::directory_iterator(dir + "/shapes"))
        files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    for (const std::filesystem::path& file : files) {
        std::string name = file.filename().string();
        std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        Primitive shape;
        if (name.find("plane") != std::string::npos)
            shape.kind = PrimitiveKind::Plane;
        else if (name.find("sphere") != std::string::npos)
            shape.kind = PrimitiveKind::Sphere;
        else if (name.find("cylinder") != std::string::npos)
            shape.kind = PrimitiveKind::Cylinder;
        else if (name.find("cone") != std::string::npos)
            shape.kind = PrimitiveKind::Cone;
        else if (name.find("torus") != std::string::npos)
            shape.kind = PrimitiveKind::Torus;
        else
            continue;
        const PointCloud part = io::readPointCloud(formats, file);
        for (std::size_t k = 0; k < part.size(); ++k) {
            const Eigen::Vector3d g = part.globalPosition(k);
            const auto found = index.find(std::make_tuple(static_cast<float>(g.x()), static_cast<float>(g.y()), static_cast<float>(g.z())));
            if (found == index.end())
                ++unmatched;
            else
                assignment[found->second] = static_cast<int>(detected.size());
        }
        detected.push_back(shape);
    }
    const primitives::DetectionScore score = primitives::score(scene, detected, assignment);
    char line[512];
    std::snprintf(line, sizeof line, "  CloudCompare (exit %d, %.1f s, %zu subclouds, %zu points not found back): %s%s", status, wall, detected.size(),
                  unmatched, score.summary().c_str(), score.meetsTarget() ? "" : "  FAIL");
    return line;
}

bool primitivesRow(const primitives::PrimitivesParams& p, const Options& o, const std::string& label)
{
    const auto start = std::chrono::steady_clock::now();
    const primitives::PrimitivesScene scene = primitives::make(p);
    const double made = seconds(start);
    const PrimitivesTrial t = runPrimitives(scene, o.set);
    std::printf("%s %s | %zu pts | %s | scene %.1f s, tool %.1f s%s\n", label.c_str(), primitives::describe(p).c_str(), scene.cloud.size(),
                t.score.summary().c_str(), made, seconds(start) - made, t.score.meetsTarget() ? "" : "  FAIL");
    if (!t.score.meetsTarget())
        std::printf("%s\n", t.score.table().c_str());
    if (o.verbose)
        std::printf("%s\n%s\n", t.report.c_str(), spread(scene, t).c_str());
    if (!o.cloudCompareDir.empty()) {
        std::string dir = o.cloudCompareDir + "/" + label;
        std::replace(dir.begin(), dir.end(), ' ', '-');
        std::printf("%s\n", cloudCompareRow(scene, t.report, dir).c_str());
    }
    std::fflush(stdout);
    return t.score.meetsTarget();
}

} // namespace

int main(int argc, char** argv)
{
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--issue")
            o.issue = true;
        else if (a == "--verbose")
            o.verbose = true;
        else if (a == "--cloudcompare" && i + 1 < argc)
            o.cloudCompareDir = argv[++i];
        else if (a == "--draws" && i + 1 < argc)
            o.draws = std::atoi(argv[++i]);
        else if (a == "--first-seed" && i + 1 < argc)
            o.firstSeed = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--scale" && i + 1 < argc)
            o.scale = std::atof(argv[++i]);
        else if (a == "--data" && i + 1 < argc)
            o.dataDir = argv[++i];
        else if (a == "--svg" && i + 1 < argc)
            o.svgDir = argv[++i];
        else if (a == "--set" && i + 1 < argc) {
            const std::string kv = argv[++i];
            const auto eq = kv.find('=');
            o.set[kv.substr(0, eq)] = eq == std::string::npos ? "true" : kv.substr(eq + 1);
        } else if (o.family.empty())
            o.family = a;
        else {
            std::cerr << "unknown argument " << a << "\n";
            return 2;
        }
    }
    setLogSink([](LogLevel, const std::string&) {});
    int passed = 0, run = 0;
    auto tally = [&](bool ok) { passed += ok, ++run; };
    // The issue's case (with --issue), then the draws, each through `row`.
    const auto family = [&](const auto& issueCase, const auto& drawFamily, const auto& row) {
        if (o.issue)
            tally(row(issueCase(), o, "issue"));
        for (int d = 0; d < o.draws; ++d)
            tally(row(drawFamily(o.firstSeed + d, o.scale), o, "seed " + std::to_string(o.firstSeed + d)));
    };
    if (o.family == "facade") {
        family([] { return facade::issueCase(); }, [](std::uint64_t seed, double scale) { return facade::drawFamily(seed, scale); }, facadeRow);
    } else if (o.family == "stones") {
        family([] { return stonewall::issueCase(); }, [](std::uint64_t seed, double scale) { return stonewall::drawFamily(seed, scale); }, stonesRow);
    } else if (o.family == "change") {
        family([] { return terrainchange::issueCase(); }, [](std::uint64_t seed, double scale) { return terrainchange::drawFamily(seed, scale); }, changeRow);
    } else if (o.family == "visibility") {
        family([] { return grazing::issueCase(); }, [](std::uint64_t seed, double scale) { return grazing::drawFamily(seed, scale); }, visibilityRow);
    } else if (o.family == "primitives") {
        family([] { return primitives::issueCase(); }, [](std::uint64_t seed, double scale) { return primitives::drawFamily(seed, scale); }, primitivesRow);
    } else if (o.family == "stations-pair") {
        // One pair of the issue's stations by ICP from the true pose: what the data allow.
        const stations::StationsScene scene = stations::make(stations::issueCase());
        const PluginRegistry registry = makePluginRegistry();
        const ToolSpec& tool = *registry.tools.find("register");
        const std::size_t a = std::stoul(o.set.count("a") ? o.set.at("a") : "0"), b = std::stoul(o.set.count("b") ? o.set.at("b") : "1");
        const Eigen::Matrix4d truth = scene.trueRelativePose(a).inverse() * scene.trueRelativePose(b);
        std::string initial;
        for (int k = 0; k < 16; ++k)
            initial += (k ? " " : "") + std::to_string(truth(k / 4, k % 4));
        std::map<std::string, std::string> options{{"initial", initial}, {"exclude-changes", "true"}, {"kernel", "cauchy"}};
        ToolResult r = tool.execute(ToolInputs().add("reference", scene.clouds[a]).add("moving", scene.clouds[b]), tool.resolve(options), nullptr);
        const Eigen::Matrix4d m = r.transform("matrix");
        std::printf("pair %zu-%zu from the truth: %s\n  moved %.5f deg, %.5f m\n", a, b, r.summary.c_str(),
                    Eigen::AngleAxisd(Eigen::Matrix3d((m * truth.inverse()).topLeftCorner<3, 3>())).angle() * 57.2958,
                    (m * truth.inverse()).topRightCorner<3, 1>().norm());
    } else if (o.family == "stations") {
        family([] { return stations::issueCase(); }, [](std::uint64_t seed, double scale) { return stations::drawFamily(seed, scale); }, stationsRow);
    } else if (o.family == "airborne") {
        if (o.issue)
            tally(airborneRow(airborne::make(airborne::issueCase()), o, "issue", false));
        for (int d = 0; d < o.draws; ++d)
            tally(airborneRow(airborne::make(airborne::drawFamily(o.firstSeed + d, o.scale)), o, "seed " + std::to_string(o.firstSeed + d),
                              false));
    } else if (o.family == "airborne-real") {
        io::FormatRegistry formats;
        io::registerBuiltinFormats(formats);
        const std::string dir = o.dataDir + "/pcl-data/";
        for (const char* sample : {"samp11-utm", "samp53-utm"}) {
            if (!std::ifstream(dir + sample + ".pcd"))
                continue;
            const PointCloud real = io::readPointCloud(formats, dir + sample + ".pcd");
            const PointCloud ground = io::readPointCloud(formats, dir + sample + "-ground.pcd");
            // Trials of the real pair's make-up, on the issue's pair and the draws alike:
            // r.growth=M (the largest growth; a fifth of it the least), r.class=0|1,
            // r.bias=B (m, the later survey's vertical disagreement), r.loss=F (ground lost under crowns).
            Options rest = o;
            auto remade = [&](airborne::RealPairParams p) {
                if (o.set.count("r.growth"))
                    p.growthMax = std::atof(o.set.at("r.growth").c_str()), p.growthMin = 0.2 * p.growthMax;
                if (o.set.count("r.class"))
                    p.withClassification = o.set.at("r.class") == "1";
                if (o.set.count("r.bias"))
                    p.verticalBiasLater = std::atof(o.set.at("r.bias").c_str());
                if (o.set.count("r.loss"))
                    p.groundLossUnderCanopy = std::atof(o.set.at("r.loss").c_str());
                return airborne::makeRealPair(real, ground, p);
            };
            for (const char* key : {"r.growth", "r.class", "r.bias", "r.loss"})
                rest.set.erase(key);
            if (o.issue)
                tally(airborneRow(remade(airborne::realIssueCase()), rest, std::string(sample) + " issue", true));
            for (int d = 0; d < o.draws; ++d)
                tally(airborneRow(remade(airborne::drawRealPair(o.firstSeed + d, o.scale)), rest,
                                  std::string(sample) + " seed " + std::to_string(o.firstSeed + d), true));
        }
    } else {
        std::cerr << "families: facade, stones, change, visibility, airborne, airborne-real\n";
        return 2;
    }
    std::printf("%d of %d met the target\n", passed, run);
    return passed == run ? 0 : 1;
}
