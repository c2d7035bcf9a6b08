// SPDX-License-Identifier: GPL-3.0-or-later
// scandiff-mpi against scandiff-cli, value for value: the same comparison on
// 1, 2 and 4 ranks (oversubscribed), on a pair built so that tile borders cut
// through a change and through a hole of the reference, where a compared
// point's nearest reference point lies far outside its tile's halo.
#include <scandiff/core/Error.h>
#include <scandiff/core/Mesh.h>
#include <scandiff/io/FileIO.h>

#include "BuiltinFormats.h"
#include "TestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>

namespace scandiff::test {
namespace {

namespace fs = std::filesystem;

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

//! A mesh of the surface on a grid of `step` metres over the 60 m square,
//! without the triangles of a hole across the tile borders x = 20 and y = 40
//! (compared points there have their nearest triangle metres away).
Mesh sampleMesh(double step)
{
    Mesh mesh;
    mesh.name = "surface";
    mesh.vertices.setOrigin(Eigen::Vector3d(500000.0, 5400000.0, 100.0));
    const int n = static_cast<int>(60.0 / step);
    std::vector<Eigen::Vector3f> vertices;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
            const double x = i * step, y = j * step;
            vertices.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(surface(x, y)));
        }
    const auto at = [n](int i, int j) { return static_cast<std::uint32_t>(i * (n + 1) + j); };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double x = (i + 0.5) * step, y = (j + 0.5) * step;
            if (x > 14 && x < 27 && y > 33 && y < 47)
                continue;
            mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    mesh.vertices.resize(vertices.size());
    mesh.vertices.positions() = vertices;
    return mesh;
}

class ScaleOut : public ::testing::Test
{
protected:
    void SetUp() override
    {
        dir_ = tempDir();
        const auto registry = builtinFormats();
        const PointCloud reference = sampleSite(1, 4.0, true, false);
        io::writePointCloud(registry, reference, dir_ / "reference.ply");
        io::writePointCloud(registry, sampleSite(2, 3.0, false, true), dir_ / "compared.ply");
        io::writeMesh(registry, sampleMesh(1.5), dir_ / "mesh.ply");
        std::vector<std::size_t> every7th;
        for (std::size_t i = 0; i < reference.size(); i += 7)
            every7th.push_back(i);
        io::writePointCloud(registry, reference.subset(every7th), dir_ / "cores.ply");
    }

    std::string file(const char* name) const { return (dir_ / name).string(); }

    //! scandiff-cli's output, then scandiff-mpi's on 1, 2 and 4 ranks, each
    //! compared point by point (position, normal) and field by field, value
    //! by value.
    void expectSameAsCli(const std::string& command, const std::string& inputs, const std::string& options,
                         const std::string& tiling, std::vector<std::string> fields)
    {
        const std::string arguments = " " + command + " " + inputs + " " + options;
        const CommandOutcome cli = run(std::string(SCANDIFF_CLI_PATH) + arguments + " -o " + file("cli.ply"));
        ASSERT_EQ(cli.status, 0) << cli.output;
        const auto registry = builtinFormats();
        const PointCloud expected = io::readPointCloud(registry, dir_ / "cli.ply");
        fields.push_back("intensity");
        for (const int ranks : {1, 2, 4}) {
            const fs::path output = dir_ / ("mpi" + std::to_string(ranks) + ".ply");
            const CommandOutcome mpi = run(mpirun(ranks) + arguments + " " + tiling + " -o " + output.string());
            ASSERT_EQ(mpi.status, 0) << mpi.output;
            const PointCloud got = io::readPointCloud(registry, output);
            ASSERT_EQ(got.size(), expected.size()) << ranks << " ranks";
            ASSERT_EQ(got.hasNormals(), expected.hasNormals());
            for (std::size_t i = 0; i < got.size(); ++i) {
                ASSERT_EQ(got.globalPosition(i), expected.globalPosition(i)) << "point " << i;
                if (got.hasNormals()) {
                    ASSERT_EQ(got.normals()[i], expected.normals()[i]) << ranks << " ranks, normal of point " << i;
                }
            }
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

    //! c2c of the compared cloud against the reference.
    void expectSameAsCli(const std::string& options, const std::string& tiling, std::vector<std::string> fields)
    {
        expectSameAsCli("c2c", "--reference " + file("reference.ply") + " --compared " + file("compared.ply"), options, tiling,
                        std::move(fields));
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

// LAZ is read by ranges too: each rank decodes the LASzip chunks holding its
// ranges (5,000 records, so ranges begin and end inside chunks of 50,000).
TEST_F(ScaleOut, LazInputsAreStreamedByRanges)
{
    const auto registry = builtinFormats();
    for (const char* name : {"reference", "compared"})
        io::writePointCloud(registry, io::readPointCloud(registry, dir_ / (std::string(name) + ".ply")),
                            dir_ / (std::string(name) + ".laz"));
    expectSameAsCli("c2c", "--reference " + file("reference.laz") + " --compared " + file("compared.laz"), "",
                    "--tile-size 10 --chunk-points 5000", {"c2c_distance"});
    EXPECT_EQ(lastReport_.find("read whole"), std::string::npos) << lastReport_;
}

// A rank takes a chunk's geometry from the coordinates it read to choose the
// origin, except where the file has normals (a reference for signed
// distances): both must read as scandiff-cli reads, non-finite points dropped.
TEST_F(ScaleOut, NonFinitePointsAndReferenceNormalsReadAsTheCliReadsThem)
{
    const auto registry = builtinFormats();
    PointCloud reference = sampleSite(1, 4.0, true, false);
    auto& normals = reference.enableNormals();
    for (std::size_t i = 0; i < reference.size(); ++i)
        normals[i] = Eigen::Vector3f(0.1f * static_cast<float>(i % 3), 0.05f, 1.0f).normalized();
    // Its first record non-finite: the normals must be seen all the same.
    reference.positions()[0].x() = std::numeric_limits<float>::quiet_NaN();
    PointCloud compared = sampleSite(2, 3.0, false, true);
    for (std::size_t i = 0; i < compared.size(); i += 997)
        compared.positions()[i].y() = std::numeric_limits<float>::quiet_NaN();
    io::writePointCloud(registry, reference, dir_ / "reference_normals.ply");
    io::writePointCloud(registry, compared, dir_ / "compared_nan.ply");
    expectSameAsCli("c2c", "--reference " + file("reference_normals.ply") + " --compared " + file("compared_nan.ply"),
                    "--signed", "--tile-size 10 --chunk-points 5000", {"c2c_distance"});
}

TEST_F(ScaleOut, OneTileLeavesRanksWithout)
{
    expectSameAsCli("", "--tile-size 1000", {"c2c_distance"});
    EXPECT_NE(lastReport_.find("rank 3: 0 tiles, 0 compared points"), std::string::npos) << lastReport_;
}

// Binary PLY is written by every rank at once, each chunk at its place;
// text, whose records vary in size, by rank 0 alone: either way the file is
// scandiff-cli's, byte for byte (several rounds of chunks on 4 ranks, and a
// rank past the last chunk).
TEST_F(ScaleOut, TheOutputIsTheCliFileByteForByte)
{
    const std::string arguments = " c2c --reference " + file("reference.ply") + " --compared " + file("compared.ply");
    for (const std::string encoding : {"binary", "ascii"}) {
        const std::string written = " --encoding " + encoding + " -o ";
        const CommandOutcome cli = run(std::string(SCANDIFF_CLI_PATH) + arguments + written + file("cli.ply"));
        ASSERT_EQ(cli.status, 0) << cli.output;
        for (const int ranks : {1, 2, 4}) {
            for (const char* chunk : {"3001", "2000000"}) {
                const CommandOutcome mpi = run(mpirun(ranks) + arguments + " --tile-size 10 --chunk-points " + chunk +
                                               written + file("mpi.ply"));
                ASSERT_EQ(mpi.status, 0) << mpi.output;
                EXPECT_EQ(readBytes(dir_ / "mpi.ply"), readBytes(dir_ / "cli.ply"))
                    << encoding << ", " << ranks << " ranks, chunks of " << chunk;
            }
        }
    }
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

const std::vector<std::string> kM3c2Fields{"m3c2_distance", "m3c2_uncertainty", "m3c2_significant", "m3c2_n1",
                                           "m3c2_n2",       "m3c2_std1",        "m3c2_std2",        "m3c2_normal_scale"};

TEST_F(ScaleOut, CloudToMeshSignedWidensAroundTheMeshHole)
{
    expectSameAsCli("c2m", "--reference " + file("mesh.ply") + " --compared " + file("compared.ply"), "--signed",
                    "--tile-size 10 --chunk-points 5000", {"c2m_distance"});
    // The hole of the mesh is metres wide, the default halo 1 m.
    EXPECT_EQ(lastReport_.find(" 0 points widened"), std::string::npos) << lastReport_;
}

TEST_F(ScaleOut, CloudToMeshWithinAClampedMaximumDistance)
{
    expectSameAsCli("c2m", "--reference " + file("mesh.ply") + " --compared " + file("compared.ply"), "--max-dist 0.3 --clamp",
                    "--tile-size 7", {"c2m_distance"});
}

TEST_F(ScaleOut, M3c2AtCorePointsAcrossTileBordersAndTheHole)
{
    // Tiles of 10 m cut through the raised block and the reference's hole
    // (core points at its rim see a one-sided neighbourhood).
    expectSameAsCli("m3c2",
                    "--reference " + file("reference.ply") + " --compared " + file("compared.ply") + " --core-points " +
                        file("cores.ply"),
                    "--normal-scale 1 --normal-scales 0.6,1.2,2 --projection-scale 2 --max-depth 1", "--tile-size 10",
                    kM3c2Fields);
}

TEST_F(ScaleOut, M3c2OnEveryReferencePointRobustTowardsTheCentroid)
{
    expectSameAsCli("m3c2", "--reference " + file("reference.ply") + " --compared " + file("compared.ply"),
                    "--normal-scale 1.5 --projection-scale 2 --max-depth 0.8 --min-points 4 --robust --orientation -centroid",
                    "--tile-size 12 --chunk-points 4000", kM3c2Fields);
}

TEST_F(ScaleOut, M3c2AndC2mBadOptionsGiveTheCliErrors)
{
    const std::string m3c2 = " m3c2 --reference " + file("reference.ply") + " --compared " + file("compared.ply");
    const std::string c2m = " c2m --reference " + file("mesh.ply") + " --compared " + file("compared.ply");
    for (const std::string& bad : {m3c2 + " --normal-scale -1 --projection-scale 1 --max-depth 1", // a negative scale
                                   m3c2 + " --normal-scale 1 --projection-scale 1 --max-depth 1 --orientation mst",
                                   m3c2 + " --normal-scale 1 --normal-scales 1,x --projection-scale 1 --max-depth 1",
                                   c2m + " --clamp", c2m + " --octree-level 40",
                                   " c2m --reference " + file("nothing.ply") + " --compared " + file("compared.ply")}) {
        const CommandOutcome cli = run(std::string(SCANDIFF_CLI_PATH) + bad);
        const CommandOutcome mpi = run(mpirun(2) + bad);
        EXPECT_NE(cli.status, 0) << bad;
        EXPECT_EQ(mpi.status, cli.status) << bad << "\n" << mpi.output;
        EXPECT_NE(mpi.output.find(cli.output), std::string::npos) << bad << "\ncli: " << cli.output << "\nmpi: " << mpi.output;
    }
    // A halo shorter than M3C2's search could only give other values: refused.
    const CommandOutcome shortHalo = run(mpirun(1) + m3c2 + " --normal-scale 2 --projection-scale 1 --max-depth 1 --halo 0.5");
    EXPECT_NE(shortHalo.status, 0);
    EXPECT_NE(shortHalo.output.find("--halo 0.5 is shorter than M3C2's search (1.11803 m"), std::string::npos) << shortHalo.output;
}

} // namespace
} // namespace scandiff::test
