// SPDX-License-Identifier: GPL-3.0-or-later
// The registration tools from the command line: the moved cloud, the matrix
// file (4 lines of 4 numbers, world coordinates), the JSON report.
#include "CliRunner.h"
#include "SyntheticSite.h"
#include "TestSupport.h"

#include <scandiff/core/processing/CloudEditing.h>

#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

using namespace scandiff;

namespace {

Eigen::Matrix4d readMatrix(const std::filesystem::path& path)
{
    std::ifstream in(path);
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            in >> m(r, c);
    EXPECT_TRUE(in) << path;
    return m;
}

//! The largest displacement, over the site's corners, between two motions.
double displacement(const Eigen::Matrix4d& a, const Eigen::Matrix4d& b, const Eigen::Vector3d& centre)
{
    double worst = 0;
    for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d p = centre + Eigen::Vector3d((k & 1) ? 30 : -30, (k & 2) ? 30 : -30, (k & 4) ? 12 : 0);
        worst = std::max(worst, ((a - b) * p.homogeneous()).norm());
    }
    return worst;
}

} // namespace

TEST(RegistrationCli, RegisterWritesTheMovedCloudTheMatrixAndTheReport)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const Eigen::Vector3d utm(512000, 5423000, 100);
    test::SiteOptions a{30000, 1, 0.002, false, utm, false};
    test::SiteOptions b = a;
    b.seed = 2;
    const Eigen::Matrix4d truth = test::rigidMotionAbout(12, 2, -1, Eigen::Vector3d(0.7, -0.4, 0.2), utm);
    PointCloud reference = test::syntheticSite(a);
    PointCloud moving = transformCloud(test::syntheticSite(b), truth.inverse(), "test");
    moving.transformHistory().clear();
    io::writePointCloud(registry.formats, reference, dir / "ref.ply");
    io::writePointCloud(registry.formats, moving, dir / "mov.ply");

    test::CliRun r = test::runCliInProcess(registry, {"register", "--reference", (dir / "ref.ply").string(), "--moving", (dir / "mov.ply").string(), "-o",
                              (dir / "out.ply").string(), "--matrix-out", (dir / "m.txt").string(), "--report",
                              (dir / "r.json").string(), "--robust"});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("RMS"), std::string::npos) << r.out;
    EXPECT_LT(displacement(readMatrix(dir / "m.txt"), truth, utm), 0.003);
    const PointCloud out = io::readPointCloud(registry.formats, dir / "out.ply");
    ASSERT_EQ(out.size(), moving.size());
    ASSERT_NE(out.field("registration_residual"), nullptr);
    // The moved cloud lies on the reference: its first point where the truth puts it.
    const Eigen::Vector3d expected = (truth * moving.globalPosition(0).homogeneous()).head<3>();
    EXPECT_LT((out.globalPosition(0) - expected).norm(), 0.003);
    // The JSON report: the matrix by role, the report table's rows.
    std::ifstream json(dir / "r.json");
    const nlohmann::json report = nlohmann::json::parse(json);
    EXPECT_EQ(report["tool"], "register");
    EXPECT_NEAR(report["matrices"]["matrix"][0][3].get<double>(), readMatrix(dir / "m.txt")(0, 3), 1e-9);
    bool sawRms = false;
    for (const auto& row : report["tables"]["report"]["rows"])
        sawRms |= row[0] == "rms_m" && row[1].get<double>() < 0.05; // edges of a sparse reference
    EXPECT_TRUE(sawRms);
    EXPECT_FALSE(report["tables"]["trace"]["rows"].empty());

    // Point pairs: three of the moving cloud's points and where the truth puts them.
    std::ostringstream pairs;
    pairs.precision(17);
    for (std::size_t i : {0u, 1000u, 2000u}) {
        const Eigen::Vector3d m = moving.globalPosition(i);
        const Eigen::Vector3d f = (truth * m.homogeneous()).head<3>();
        pairs << m.x() << ' ' << m.y() << ' ' << m.z() << ' ' << f.x() << ' ' << f.y() << ' ' << f.z() << '\n';
    }
    test::writeText(dir / "pairs.txt", pairs.str());
    r = test::runCliInProcess(registry, {"register-pairs", "--reference", (dir / "ref.ply").string(), "--moving", (dir / "mov.ply").string(), "--pairs",
                       (dir / "pairs.txt").string(), "--matrix-out", (dir / "p.txt").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("pair residuals"), std::string::npos) << r.out;
    EXPECT_LT(displacement(readMatrix(dir / "p.txt"), truth, utm), 1e-4); // pairs from float positions
    r = test::runCliInProcess(registry, {"register-pairs", "--reference", (dir / "ref.ply").string(), "--moving", (dir / "mov.ply").string(), "--pairs",
                       "1,2,3,4,5,6"});
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("at least 3"), std::string::npos) << r.err;
}

TEST(RegistrationCli, StationsWritePosesAndEveryStationMoved)
{
    // Three stations along the site (overlapping neighbours, one pair and a
    // second, no loop), the last two moved by known errors.
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const Eigen::Vector3d utm(512000, 5423000, 100);
    const std::vector<Eigen::Matrix4d> errors = {Eigen::Matrix4d::Identity(),
                                                 test::rigidMotionAbout(1.5, 0.3, 0, Eigen::Vector3d(0.2, -0.1, 0.05), utm),
                                                 test::rigidMotionAbout(-1.0, 0, 0.4, Eigen::Vector3d(-0.15, 0.2, 0), utm)};
    std::vector<std::string> args = {"register-stations"};
    for (std::size_t k = 0; k < 3; ++k) {
        test::SiteOptions o{40000, static_cast<unsigned>(20 + k), 0.002, false, utm, false};
        const PointCloud site = test::syntheticSite(o);
        std::vector<std::size_t> seen;
        const double low = -30 + 15.0 * static_cast<double>(k);
        for (std::size_t i = 0; i < site.size(); ++i) {
            const double x = site.globalPosition(i).x() - utm.x();
            if (x >= low && x <= low + 30)
                seen.push_back(i);
        }
        PointCloud station = transformCloud(site.subset(seen), errors[k], "test");
        station.name = "scan" + std::to_string(k);
        const auto path = dir / (station.name + ".ply");
        io::writePointCloud(registry.formats, station, path);
        args.push_back(path.string());
    }
    std::filesystem::create_directories(dir / "out");
    args.insert(args.end(), {"--out-dir", (dir / "out").string(), "--report", (dir / "out" / "run.json").string()});
    test::CliRun r = test::runCliInProcess(registry, args);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("3 stations"), std::string::npos) << r.out;
    // poses.txt: 3 lines of 16 numbers; the first the identity, the others undo the errors.
    std::ifstream poses(dir / "out" / "poses.txt");
    for (std::size_t k = 0; k < 3; ++k) {
        Eigen::Matrix4d pose;
        for (int i = 0; i < 16; ++i)
            poses >> pose(i / 4, i % 4);
        ASSERT_TRUE(poses) << "line " << k;
        if (k == 0)
            EXPECT_EQ(pose, Eigen::Matrix4d::Identity());
        else
            EXPECT_LT(displacement(pose, errors[k].inverse(), utm), 0.005) << "station " << k;
    }
    std::string extra;
    EXPECT_FALSE(poses >> extra);
    for (std::size_t k = 0; k < 3; ++k)
        EXPECT_TRUE(std::filesystem::exists(dir / "out" / ("scan" + std::to_string(k) + "_" + std::to_string(k) + ".ply")));
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / "pairs.csv"));
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / "loops.csv"));
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / "run.json"));

    // Global alignment from the command line, without its ICP.
    r = test::runCliInProcess(registry, {"register-global", "--reference", args[1], "--moving", args[2], "--no-refine", "--matrix-out",
                       (dir / "g.txt").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.out.find("ICP"), std::string::npos) << r.out;
    EXPECT_LT(displacement(readMatrix(dir / "g.txt"), errors[1].inverse(), utm), 1.5);
}
