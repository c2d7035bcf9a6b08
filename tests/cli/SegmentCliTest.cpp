// SPDX-License-Identifier: GPL-3.0-or-later
// `segment` and `compare` on the synthetic pair with three known changes.
#include "CliRunner.h"

#include <scandiff/core/Error.h>

#include "../segmentation/SyntheticScene.h"
#include "TestSupport.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <set>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

using namespace scandiff;

namespace {

std::size_t lineCount(const std::filesystem::path& file)
{
    std::ifstream in(file);
    std::size_t n = 0;
    for (std::string line; std::getline(in, line);)
        ++n;
    return n;
}

//! Exit status of tests/io/check_dxf.py (ezdxf's audit) on `file`.
int dxfAudit(const std::filesystem::path& file)
{
    const std::string command = "python3 '" + (std::filesystem::path(SCANDIFF_TEST_SCRIPTS_DIR) / "check_dxf.py").string() + "' '" +
                                file.string() + "' > /dev/null";
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

//! The cells of a CSV file without quoted commas (what regions.csv holds).
std::vector<std::vector<std::string>> csvRows(const std::filesystem::path& file)
{
    std::ifstream in(file);
    std::vector<std::vector<std::string>> rows;
    for (std::string line; std::getline(in, line);) {
        std::vector<std::string> cells(1);
        for (char c : line)
            if (c == ',')
                cells.emplace_back();
            else
                cells.back() += c;
        rows.push_back(std::move(cells));
    }
    return rows;
}

std::size_t columnOf(const std::vector<std::string>& header, const std::string& name)
{
    const auto it = std::find(header.begin(), header.end(), name);
    EXPECT_NE(it, header.end()) << name;
    return static_cast<std::size_t>(it - header.begin());
}

//! The two epochs written as PLY files in `dir`.
std::pair<std::string, std::string> writeEpochs(const PluginRegistry& registry, const std::filesystem::path& dir)
{
    const auto reference = dir / "reference.ply", compared = dir / "compared.ply";
    io::writePointCloud(registry.formats, test::referenceEpoch(), reference);
    io::writePointCloud(registry.formats, test::comparedEpoch(), compared);
    return {reference.string(), compared.string()};
}

} // namespace

TEST(SegmentCli, CompareRunsTheWholeChainAndFindsTheThreeChanges)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const auto [reference, compared] = writeEpochs(registry, dir);
    const auto out = dir / "out";
    const test::CliRun run = test::runCliInProcess(registry, {"compare", "--reference", reference, "--compared", compared, "--model", "plane", "--above", "0.1",
                                   "--components", "--min-points", "50", "--out-dir", out.string()});
    ASSERT_EQ(run.status, 0) << run.err;
    EXPECT_NE(run.out.find("3 regions"), std::string::npos) << run.out;
    for (const char* name : {"regions.ply", "region_0001.ply", "region_0002.ply", "region_0003.ply", "regions.dxf", "regions.csv",
                             "compared.ply"})
        EXPECT_TRUE(std::filesystem::exists(out / name)) << name;
    EXPECT_FALSE(std::filesystem::exists(out / "region_0004.ply"));
    EXPECT_EQ(lineCount(out / "regions.csv"), 4u);
    EXPECT_EQ(dxfAudit(out / "regions.dxf"), 0);
    const PointCloud all = io::readPointCloud(registry.formats, out / "compared.ply");
    ASSERT_NE(all.field("c2c_distance"), nullptr);
    ASSERT_NE(all.field("region_id"), nullptr);
    ASSERT_NE(all.field("changed"), nullptr);
    EXPECT_EQ(all.field("region_id")->range().max, 3.0);
    // The volume column is filled: compare knows the reference.
    const auto rows = csvRows(out / "regions.csv");
    ASSERT_GE(rows.size(), 2u);
    EXPECT_FALSE(rows[1].at(columnOf(rows[0], "volume")).empty());
    EXPECT_TRUE(rows[1].at(columnOf(rows[0], "distance_volume")).empty()); // c2c has no level of detection
}

TEST(SegmentCli, CompareByM3c2WritesRegionsCorePointsAndRaster)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const auto [reference, compared] = writeEpochs(registry, dir);
    const auto out = dir / "out";
    const test::CliRun run = test::runCliInProcess(
        registry, {"compare", "--method", "m3c2", "--reference", reference, "--compared", compared, "--normal-scale", "1",
                   "--projection-scale", "0.5", "--max-depth", "1.5", "--registration-error", "0.005", "--core-spacing", "0.25",
                   "--min-points", "20", "--m3c2-min-points", "5", "--raster-cell", "1", "--out-dir", out.string()});
    ASSERT_EQ(run.status, 0) << run.err;
    for (const char* name : {"regions.ply", "region_0001.ply", "regions.dxf", "regions.csv", "core_points.ply", "m3c2_raster.tif"})
        EXPECT_TRUE(std::filesystem::exists(out / name)) << name;
    EXPECT_FALSE(std::filesystem::exists(out / "compared.ply"));
    const PointCloud cores = io::readPointCloud(registry.formats, out / "core_points.ply");
    for (const char* field : {"m3c2_distance", "m3c2_uncertainty", "m3c2_significant", "region_id"})
        EXPECT_NE(cores.field(field), nullptr) << field;
    EXPECT_NE(run.out.find("volume along the distances"), std::string::npos) << run.out;

    // The raised block (3 x 3 m, +0.5 m: 4.5 m3) and the pit (3 x 3 m, -0.4 m:
    // -3.6 m3) are regions whose volume along the distances is near theirs.
    const auto rows = csvRows(out / "regions.csv");
    const std::size_t volume = columnOf(rows[0], "distance_volume"), uncertainty = columnOf(rows[0], "distance_volume_uncertainty");
    bool block = false, pit = false;
    for (std::size_t r = 1; r < rows.size(); ++r) {
        const double v = std::stod(rows[r].at(volume)), u = std::stod(rows[r].at(uncertainty));
        EXPECT_GT(u, 0.0);
        block = block || (v > 3.5 && v < 6.0);
        pit = pit || (v < -2.6 && v > -4.8);
    }
    EXPECT_TRUE(block) << run.out;
    EXPECT_TRUE(pit) << run.out;

    // Options of the other method are refused, naming them.
    test::CliRun bad = test::runCliInProcess(registry, {"compare", "--method", "m3c2", "--reference", reference, "--compared", compared,
                                                         "--normal-scale", "1", "--projection-scale", "0.5", "--max-depth", "1",
                                                         "--model", "plane", "--out-dir", out.string()});
    EXPECT_NE(bad.status, 0);
    EXPECT_NE(bad.err.find("--model"), std::string::npos) << bad.err;
    bad = test::runCliInProcess(registry, {"compare", "--reference", reference, "--compared", compared, "--normal-scale", "1", "--above",
                                           "0.1", "--out-dir", out.string()});
    EXPECT_NE(bad.status, 0);
    EXPECT_NE(bad.err.find("--method m3c2"), std::string::npos) << bad.err;
    // M3C2's required maximum depth is still required with --method m3c2 (its scales may be guessed).
    bad = test::runCliInProcess(registry, {"compare", "--method", "m3c2", "--reference", reference, "--compared", compared,
                                           "--out-dir", out.string()});
    EXPECT_NE(bad.status, 0);
    EXPECT_NE(bad.err.find("max-depth"), std::string::npos) << bad.err;
}

TEST(SegmentCli, SegmentWithEachMethodOnTheDistances)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const auto [reference, compared] = writeEpochs(registry, dir);
    ASSERT_EQ(test::runCliInProcess(registry, {"c2c", "--reference", reference, "--compared", compared, "--model", "plane", "-o",
                             (dir / "distances.ply").string()})
                  .status,
              0);
    const std::string input = (dir / "distances.ply").string();
    const std::vector<std::vector<std::string>> methods = {
        {"--range", "0.1", "100", "--components", "--level", "6", "--connectivity", "26"},
        {"--stat-test", "weibull", "--fit-box", "16,10,-1,20,20,1", "--confidence", "0.999", "--components"},
        {"--propagate", "--min-seed", "0.15"},
    };
    for (const auto& method : methods) {
        std::vector<std::string> args{"segment", input, "--field", "c2c_distance", "--min-points", "50", "--reference", reference,
                                      "--dxf-points", "--out-dir", (dir / method[0].substr(2)).string()};
        args.insert(args.end(), method.begin(), method.end());
        const test::CliRun run = test::runCliInProcess(registry, args);
        ASSERT_EQ(run.status, 0) << method[0] << ": " << run.err;
        EXPECT_NE(run.out.find("3 regions"), std::string::npos) << method[0] << ": " << run.out;
        EXPECT_EQ(lineCount(dir / method[0].substr(2) / "regions.csv"), 4u) << method[0];
        EXPECT_EQ(dxfAudit(dir / method[0].substr(2) / "regions.dxf"), 0) << method[0];
        // What the files hold, against the scene's truth: each region one
        // change (its points >= 90 % of that change; propagation keeps a
        // fringe of ground), every change found once, and the volume between
        // the epochs of each within 10 %: block +4.5 m3, pit -3.6 m3, cube +1 m3.
        const PointCloud regions = io::readPointCloud(registry.formats, dir / method[0].substr(2) / "regions.ply");
        const ScalarField& region = *regions.field("region_id");
        const ScalarField& truth = *regions.field("truth");
        std::map<int, std::map<int, std::size_t>> votes;
        for (std::size_t i = 0; i < regions.size(); ++i)
            ++votes[static_cast<int>(region.value(i))][static_cast<int>(truth.value(i))];
        ASSERT_EQ(votes.size(), 3u) << method[0];
        std::map<int, int> changeOfRegion;
        for (const auto& [id, counts] : votes) {
            std::size_t total = 0, best = 0;
            for (const auto& [change, count] : counts) {
                total += count;
                if (count > best) {
                    best = count;
                    changeOfRegion[id] = change;
                }
            }
            EXPECT_NE(changeOfRegion[id], 0) << method[0] << " region " << id;
            EXPECT_GE(static_cast<double>(best), (method[0] == "--propagate" ? 0.8 : 0.9) * static_cast<double>(total))
                << method[0] << " region " << id;
        }
        std::set<int> changes;
        for (const auto& [id, change] : changeOfRegion)
            changes.insert(change);
        EXPECT_EQ(changes, (std::set<int>{1, 2, 3})) << method[0];
        std::ifstream csv(dir / method[0].substr(2) / "regions.csv");
        std::string line;
        std::getline(csv, line);
        const std::map<int, double> volumeOfChange{{1, 4.5}, {2, -3.6}, {3, 1.0}};
        while (std::getline(csv, line)) {
            std::vector<std::string> cells;
            std::stringstream row(line);
            for (std::string cell; std::getline(row, cell, ',');)
                cells.push_back(cell);
            ASSERT_GT(cells.size(), 20u);
            const int id = std::stoi(cells[0]);
            const double expected = volumeOfChange.at(changeOfRegion.at(id));
            // A propagated region keeps a fringe of ground around its object:
            // the columns along the object's edge then count at its top
            // (the highest point of a column), about +17 % for the block and
            // +32 % for the cube here. The classifications stop at the edge.
            const double tolerance = method[0] == "--propagate" ? 0.35 : 0.1;
            EXPECT_NEAR(std::stod(cells[20]), expected, tolerance * std::abs(expected)) << method[0] << " region " << id;
            if (method[0] == "--propagate")
                EXPECT_GE(std::abs(std::stod(cells[20])), 0.9 * std::abs(expected)) << "region " << id;
        }
    }
    // Without --components the changed points form one region.
    const test::CliRun one = test::runCliInProcess(registry, {"segment", input, "--kmeans", "2", "--out-dir", (dir / "kmeans").string()});
    ASSERT_EQ(one.status, 0) << one.err;
    EXPECT_NE(one.out.find("one region"), std::string::npos) << one.out;
}

TEST(SegmentCli, BadInputGivesAnErrorAndAStatus)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    PointCloud cloud;
    cloud.resize(20);
    for (std::size_t i = 0; i < 20; ++i)
        cloud.positions()[i] = {static_cast<float>(i), 0.0f, 0.0f};
    ScalarField& d = cloud.addField("d");
    for (std::size_t i = 0; i < 20; ++i)
        d.values()[i] = i % 3 == 0 ? std::nanf("") : static_cast<float>(i) * 0.1f; // NaN values are not an error
    io::writePointCloud(registry.formats, cloud, dir / "in.ply");
    const std::string in = (dir / "in.ply").string(), out = (dir / "out").string();
    EXPECT_EQ(test::runCliInProcess(registry, {"segment", in, "--field", "d", "--above", "1", "--components", "--out-dir", out}).status, 0);
    test::CliRun run = test::runCliInProcess(registry, {"segment", in, "--field", "d", "--out-dir", out});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::InvalidArgument));
    EXPECT_NE(run.err.find("choose a method"), std::string::npos) << run.err;
    run = test::runCliInProcess(registry, {"segment", in, "--field", "missing", "--above", "1", "--out-dir", out});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::InvalidArgument));
    EXPECT_NE(run.err.find("missing"), std::string::npos) << run.err;
    EXPECT_NE(test::runCliInProcess(registry, {"segment", in, "--field", "d", "--above", "1", "--kmeans", "2", "--out-dir", out}).status, 0);
    run = test::runCliInProcess(registry, {"segment", in, "--field", "d", "--propagate", "--out-dir", out});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::InvalidArgument));
    EXPECT_NE(run.err.find("min-seed"), std::string::npos) << run.err;
    run = test::runCliInProcess(registry, {"segment", in, "--field", "d", "--stat-test", "weibull", "--fit-box", "1,2,3", "--out-dir", out});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::InvalidArgument));
    run = test::runCliInProcess(registry, {"segment", (dir / "none.ply").string(), "--field", "d", "--above", "1", "--out-dir", out});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::Io));
}
