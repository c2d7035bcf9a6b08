// SPDX-License-Identifier: GPL-3.0-or-later
// scandiff-mpi against scandiff-cli, value for value: the same comparison on
// 1, 2 and 4 ranks (oversubscribed), on a pair built so that tile borders cut
// through a change and through a hole of the reference, where a compared
// point's nearest reference point lies far outside its tile's halo.
#include <scandiff/core/Error.h>
#include <scandiff/io/FileIO.h>

#include "TestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <sstream>

namespace scandiff::test {
namespace {

namespace fs = std::filesystem;

io::FormatRegistry formats()
{
    io::FormatRegistry registry;
    io::registerBuiltinFormats(registry);
    return registry;
}

double surface(double x, double y)
{
    return 0.3 * std::sin(x / 7.0) + 0.2 * std::cos(y / 5.0);
}

//! A 60 m square at UTM coordinates sampled at random, `perSquareMetre`
//! points, z on a gentle surface with 3 mm of noise; `change` lifts a block.
PointCloud sampleSite(unsigned seed, double perSquareMetre, bool withHole, bool withChange)
{
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> along(0.0, 60.0);
    std::normal_distribution<double> noise(0.0, 0.003);
    PointCloud cloud;
    const Eigen::Vector3d origin(500000.0, 5400000.0, 100.0);
    cloud.setOrigin(origin);
    const auto n = static_cast<std::size_t>(perSquareMetre * 3600);
    std::vector<Eigen::Vector3f> points;
    for (std::size_t i = 0; i < n; ++i) {
        const double x = along(random), y = along(random);
        // The hole spans the tile border x = 30 and y = 20 (tiles of 10 m).
        if (withHole && x > 22 && x < 38 && y > 16 && y < 27)
            continue;
        double z = surface(x, y) + noise(random);
        if (withChange && x > 25 && x < 35 && y > 35 && y < 45)
            z += 0.5;
        points.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
    }
    cloud.resize(points.size());
    cloud.positions() = points;
    ScalarField& intensity = cloud.addField(ScalarField("intensity", points.size()));
    for (std::size_t i = 0; i < points.size(); ++i)
        intensity.values()[i] = static_cast<float>(i % 4096);
    return cloud;
}

//! The command's output with its errors.
CommandOutcome run(const std::string& command)
{
    return runCommand(command + " 2>&1");
}

std::string mpirun(int ranks)
{
    // Root in CI; more ranks than cores here.
    return std::string(SCANDIFF_MPIEXEC) + " --allow-run-as-root --oversubscribe -np " + std::to_string(ranks) + " " +
           SCANDIFF_MPI_PATH;
}

bool sameValue(float a, float b)
{
    return std::memcmp(&a, &b, sizeof a) == 0 || (std::isnan(a) && std::isnan(b));
}

class ScaleOut : public ::testing::Test
{
protected:
    void SetUp() override
    {
        dir_ = tempDir();
        const auto registry = formats();
        io::writePointCloud(registry, sampleSite(1, 4.0, true, false), dir_ / "reference.ply");
        io::writePointCloud(registry, sampleSite(2, 3.0, false, true), dir_ / "compared.ply");
    }

    //! scandiff-cli's output, then scandiff-mpi's on 1, 2 and 4 ranks, each
    //! compared field by field, value by value.
    void expectSameAsCli(const std::string& options, const std::string& tiling, std::vector<std::string> fields)
    {
        const std::string inputs = " --reference " + (dir_ / "reference.ply").string() + " --compared " +
                                   (dir_ / "compared.ply").string() + " " + options;
        const CommandOutcome cli = run(std::string(SCANDIFF_CLI_PATH) + " c2c" + inputs + " -o " + (dir_ / "cli.ply").string());
        ASSERT_EQ(cli.status, 0) << cli.output;
        const auto registry = formats();
        const PointCloud expected = io::readPointCloud(registry, dir_ / "cli.ply");
        fields.push_back("intensity");
        for (const int ranks : {1, 2, 4}) {
            const fs::path output = dir_ / ("mpi" + std::to_string(ranks) + ".ply");
            const CommandOutcome mpi = run(mpirun(ranks) + " c2c" + inputs + " " + tiling + " -o " + output.string());
            ASSERT_EQ(mpi.status, 0) << mpi.output;
            const PointCloud got = io::readPointCloud(registry, output);
            ASSERT_EQ(got.size(), expected.size()) << ranks << " ranks";
            for (std::size_t i = 0; i < got.size(); ++i)
                ASSERT_EQ(got.globalPosition(i), expected.globalPosition(i)) << "point " << i;
            ASSERT_EQ(got.fields().size(), expected.fields().size());
            for (const std::string& name : fields) {
                const ScalarField* a = got.field(name);
                const ScalarField* b = expected.field(name);
                ASSERT_TRUE(a && b) << name;
                std::size_t valid = 0;
                for (std::size_t i = 0; i < got.size(); ++i) {
                    ASSERT_TRUE(sameValue(static_cast<float>(a->value(i)), static_cast<float>(b->value(i))))
                        << ranks << " ranks, " << name << " of point " << i << ": " << a->value(i) << " vs " << b->value(i)
                        << "\n" << mpi.output;
                    valid += b->hasValue(i);
                }
                EXPECT_GT(valid, got.size() / 2) << name; // a comparison that compared something
            }
            lastReport_ = mpi.output;
        }
    }

    fs::path dir_;
    std::string lastReport_;
};

TEST_F(ScaleOut, NearestNeighbourOnSmallTilesWidensAroundTheHole)
{
    expectSameAsCli("", "--tile-size 10 --chunk-points 5000", {"c2c_distance"});
    // Points in the hole have their nearest reference point metres away, far
    // beyond the default 1 m halo: they were widened, not given a wrong value.
    EXPECT_EQ(lastReport_.find(" 0 points widened"), std::string::npos) << lastReport_;
}

TEST_F(ScaleOut, MaximumDistanceAndComponents)
{
    expectSameAsCli("--max-dist 0.4 --split-xyz", "--tile-size 10", {"c2c_distance", "c2c_dx", "c2c_dy", "c2c_dz"});
}

TEST_F(ScaleOut, PlaneModelOnTwelveNeighbours)
{
    expectSameAsCli("--model plane --knn 12 --signed", "--tile-size 10 --halo 0.2", {"c2c_distance"});
}

TEST_F(ScaleOut, QuadricModelWithinARadius)
{
    expectSameAsCli("--model quadric --radius 0.8", "--tile-size 7.5", {"c2c_distance"});
}

TEST_F(ScaleOut, OneTileLeavesRanksWithout)
{
    expectSameAsCli("", "--tile-size 1000", {"c2c_distance"});
    EXPECT_NE(lastReport_.find("rank 3: 0 tiles, 0 compared points"), std::string::npos) << lastReport_;
}

TEST_F(ScaleOut, BadOptionsGiveTheCliErrors)
{
    const std::string inputs =
        " c2c --reference " + (dir_ / "reference.ply").string() + " --compared " + (dir_ / "compared.ply").string();
    for (const std::string& bad : {std::string(" --clamp"), std::string(" --knn 2 --model plane"),
                                   std::string(" --max-dist -1")}) {
        const CommandOutcome cli = run(std::string(SCANDIFF_CLI_PATH) + inputs + bad);
        const CommandOutcome mpi = run(mpirun(2) + inputs + bad);
        EXPECT_NE(cli.status, 0) << bad;
        EXPECT_EQ(mpi.status, cli.status) << bad << "\n" << mpi.output;
        EXPECT_NE(mpi.output.find(cli.output), std::string::npos) << bad << "\ncli: " << cli.output << "\nmpi: " << mpi.output;
    }
    const CommandOutcome missing = run(mpirun(2) + " c2c --reference " + (dir_ / "nothing.ply").string() + " --compared " +
                                (dir_ / "compared.ply").string());
    EXPECT_NE(missing.status, 0);
    EXPECT_NE(missing.output.find("nothing.ply: no such file"), std::string::npos) << missing.output;
    const CommandOutcome tiles = run(mpirun(1) + inputs + " --tile-size 0");
    EXPECT_NE(tiles.output.find("--tile-size must be a positive number"), std::string::npos) << tiles.output;
}

} // namespace
} // namespace scandiff::test
