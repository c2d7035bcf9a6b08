// SPDX-License-Identifier: GPL-3.0-or-later
// `scandiff-cli stones` and `scandiff-cli contours` end to end: a synthetic
// wall and façade written as PLY, the commands' files in --out-dir read back.
#include "CliRunner.h"

#include <scandiff/io/DxfWriter.h>
#include <scandiff/io/FileIO.h>

#include "DxfCheck.h"
#include "TestSupport.h"
#include "WallScenes.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <set>

using namespace scandiff;

TEST(ContoursCli, StonesWriteTheLabelledPointsTheDrawingAndTheTable)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    test::StoneWallOptions options;
    options.brightStones = true;
    const test::StoneWallScene scene = test::makeStoneWall(options);
    io::writePointCloud(registry.formats, scene.cloud, dir / "wall.ply");
    const auto out = dir / "out";
    std::filesystem::create_directories(out);
    const test::CliRun r =
        test::runCliInProcess(registry, {"stones", (dir / "wall.ply").string(), "--polarity", "bright", "--out-dir", out.string()});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find(std::to_string(scene.stones.size()) + " stones"), std::string::npos) << r.out;
    // The points, in input order, with stone_id (positions to the float
    // precision of the reader's global shift: float32 local coordinates).
    const PointCloud labelled = io::readPointCloud(registry.formats, out / "stones.ply");
    ASSERT_EQ(labelled.size(), scene.cloud.size());
    ASSERT_NE(labelled.field("stone_id"), nullptr);
    for (std::size_t i = 0; i < labelled.size(); i += 97)
        ASSERT_LT((labelled.globalPosition(i) - scene.cloud.globalPosition(i)).norm(), 1e-4);
    std::set<int> ids;
    for (float v : labelled.field("stone_id")->values())
        ids.insert(static_cast<int>(v));
    EXPECT_EQ(ids.size(), scene.stones.size() + 1);
    // A closed polyline and a label per stone, audited by ezdxf.
    const test::DxfCheck dxf = test::checkDxf(out / "stones.dxf");
    EXPECT_EQ(dxf.exitStatus, 0);
    EXPECT_EQ(dxf.count("POLYLINE@STONES"), static_cast<int>(scene.stones.size()));
    EXPECT_EQ(dxf.count("TEXT@STONE_IDS"), static_cast<int>(scene.stones.size()));
    // The table: a header and a row per stone.
    std::ifstream csv(out / "stones.csv");
    std::string header, line;
    std::getline(csv, header);
    EXPECT_EQ(header.rfind("id,area,perimeter,centroid_x", 0), 0u) << header;
    std::size_t rows = 0;
    while (std::getline(csv, line))
        rows += !line.empty();
    EXPECT_EQ(rows, scene.stones.size());
}

TEST(ContoursCli, ContoursWriteTheDrawingAndTheJsonDocument)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const test::FacadeScene scene = test::makeFacade();
    io::writePointCloud(registry.formats, scene.cloud, dir / "facade.ply");
    const auto out = dir / "out";
    std::filesystem::create_directories(out);
    const test::CliRun r = test::runCliInProcess(registry, {"contours", (dir / "facade.ply").string(), "--vectorise", "--out-dir", out.string()});
    ASSERT_EQ(r.status, 0) << r.err;
    const test::DxfCheck dxf = test::checkDxf(out / "contours.dxf");
    EXPECT_EQ(dxf.exitStatus, 0);
    EXPECT_EQ(dxf.count("POLYLINE"), static_cast<int>(1 + scene.openings.size()));
    std::ifstream file(out / "contours.json");
    const auto json = nlohmann::json::parse(file);
    ASSERT_EQ(json["planes"].size(), 1u);
    const auto& polygon = json["planes"][0]["polygons"][0];
    EXPECT_EQ(polygon["holes"].size(), scene.openings.size());
    // Areas against the scene's truth, within a strip half a point spacing
    // wide along each outline (the outline runs through the outermost points):
    // the façade 6 x 4 m less the door's notch 0.9 x 1.9 m; the openings.
    const double halfSpacing = 0.015 / 2;
    const double outerTruth = 6.0 * 4.0 - 0.9 * 1.9, outerPerimeter = 2 * (6.0 + 4.0) + 2 * 1.9;
    EXPECT_NEAR(polygon["outer"]["area"].get<double>(), outerTruth, outerPerimeter * halfSpacing);
    std::vector<double> holeAreas, truthAreas;
    for (const auto& hole : polygon["holes"])
        holeAreas.push_back(hole["area"].get<double>());
    for (const test::Outline& opening : scene.openings) {
        double twiceArea = 0;
        for (std::size_t k = 0; k < opening.size(); ++k) {
            const Eigen::Vector2d& a = opening[k];
            const Eigen::Vector2d& b = opening[(k + 1) % opening.size()];
            twiceArea += a.x() * b.y() - b.x() * a.y();
        }
        truthAreas.push_back(std::abs(twiceArea) / 2);
    }
    std::sort(holeAreas.begin(), holeAreas.end());
    std::sort(truthAreas.begin(), truthAreas.end());
    ASSERT_EQ(holeAreas.size(), truthAreas.size());
    for (std::size_t k = 0; k < holeAreas.size(); ++k)
        EXPECT_NEAR(holeAreas[k], truthAreas[k], 5.0 * halfSpacing) << "opening " << k; // perimeters of 4-5 m
    EXPECT_TRUE(std::filesystem::exists(out / "contours.csv"));
    // A bad option is the same clear error as anywhere else.
    const test::CliRun bad = test::runCliInProcess(registry, {"contours", (dir / "facade.ply").string(), "--edge-threshold", "-3"});
    EXPECT_NE(bad.status, 0);
    EXPECT_NE(bad.err.find("edge-threshold"), std::string::npos) << bad.err;
}

TEST(ContoursCli, ComparePolygonsReadsTwoDrawings)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    Drawing reference, model;
    reference.polylines.push_back({"R", {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 1, 0}}, true});
    model.polylines.push_back({"M", {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, true}); // half of it
    io::writeDrawingDxf(reference, dir / "reference.dxf");
    io::writeDrawingDxf(model, dir / "model.dxf");
    const test::CliRun r =
        test::runCliInProcess(registry, {"compare-polygons", (dir / "model.dxf").string(), (dir / "reference.dxf").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    // rho_d = 1/2, rho_q = 1/2, branching = |R \ A| / |R ∩ A| = 1, miss = 0, failure = 0.
    EXPECT_NE(r.out.find("0,R,0,2,1,0.5,0.5,1,0,0,0,1,"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("0 of 1 reference polygons found"), std::string::npos) << r.out;
}
