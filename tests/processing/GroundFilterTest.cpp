// SPDX-License-Identifier: GPL-3.0-or-later
// Ground filtering (SMRF) on terrains whose ground is known: seeded synthetic
// terrains (slopes, a ridge, a pit, buildings, trees, bushes, large
// coordinates) and the ISPRS filter-test samples with their reference ground.
#include <scandiff/core/Error.h>
#include <scandiff/core/SplitMix.h>
#include <scandiff/core/processing/GroundFilter.h>
#include <scandiff/io/FileIO.h>

#include "families/EpochSceneCommon.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <set>
#include <tuple>

namespace scandiff {
namespace {

namespace es = test::family::epochscene;
using es::gaussian;
using es::uniform;

//! A terrain with an analytic ground z = ground(x, y) and the objects on it.
struct TerrainScene
{
    PointCloud cloud;
    std::vector<char> isGround; //!< truth per point
    std::string description;
};

struct TerrainParams
{
    std::uint64_t seed = 1;
    double side = 200;          //!< m, square
    double density = 2;         //!< ground pulses per m²
    double slopeX = 0.1;        //!< rise over run of the tilted plane
    double ridgeHeight = 5;     //!< m, amplitude of a ridge across y
    double pitDepth = 3;        //!< m, a round pit of radius 12 m
    int buildings = 6;          //!< boxes 8-25 m wide, 4-15 m high, flat roofs
    int trees = 60;             //!< crowns 3-10 m wide on trunks 2-8 m
    int bushes = 40;            //!< 1.2-2.5 m high, 1-3 m wide
    double noise = 0.03;        //!< m, vertical
    Eigen::Vector3d origin = Eigen::Vector3d::Zero(); //!< added to every point (UTM)
};

double groundHeight(const TerrainParams& p, double x, double y)
{
    const double pit = std::hypot(x - 0.3 * p.side, y - 0.7 * p.side);
    return p.slopeX * x + p.ridgeHeight * std::exp(-std::pow((y - 0.4 * p.side) / 25.0, 2))
           - (pit < 12 ? p.pitDepth * (1 - pit * pit / 144) : 0.0);
}

TerrainScene makeTerrain(const TerrainParams& p)
{
    SplitMix64 rng(p.seed, 7);
    struct Box { double x0, y0, x1, y1, height; };
    struct Crown { double x, y, radius, bottom, top; };
    std::vector<Box> boxes;
    while (static_cast<int>(boxes.size()) < p.buildings) {
        const double w = uniform(rng, 8, 25), d = uniform(rng, 8, 25), x = uniform(rng, 5, p.side - 30), y = uniform(rng, 5, p.side - 30);
        bool apart = std::hypot(x - 0.3 * p.side, y - 0.7 * p.side) > 20;
        for (const Box& b : boxes)
            apart = apart && (x > b.x1 + 5 || x + w < b.x0 - 5 || y > b.y1 + 5 || y + d < b.y0 - 5);
        if (apart)
            boxes.push_back({x, y, x + w, y + d, uniform(rng, 4, 15)});
    }
    const auto inBox = [&](double x, double y) -> const Box* {
        for (const Box& b : boxes)
            if (x >= b.x0 && x <= b.x1 && y >= b.y0 && y <= b.y1)
                return &b;
        return nullptr;
    };
    std::vector<Crown> crowns;
    for (int k = 0; k < p.trees + p.bushes; ++k) {
        const bool bush = k >= p.trees;
        const double x = uniform(rng, 0, p.side), y = uniform(rng, 0, p.side);
        if (inBox(x, y))
            continue;
        const double radius = bush ? uniform(rng, 0.5, 1.5) : uniform(rng, 1.5, 5);
        const double bottom = bush ? 0.3 : uniform(rng, 2, 8);
        crowns.push_back({x, y, radius, bottom, bush ? uniform(rng, 1.2, 2.5) : bottom + 2 * radius});
    }
    TerrainScene s;
    std::vector<Eigen::Vector3d> points;
    const auto pulses = static_cast<std::size_t>(p.density * p.side * p.side);
    for (std::size_t i = 0; i < pulses; ++i) {
        const double x = uniform(rng, 0, p.side), y = uniform(rng, 0, p.side), g = groundHeight(p, x, y);
        if (const Box* b = inBox(x, y)) {
            points.emplace_back(x, y, g + b->height + p.noise * gaussian(rng));
            s.isGround.push_back(0);
            continue;
        }
        // A pulse through a crown returns from it (first) and, half the time, from the ground too.
        bool hitCrown = false;
        for (const Crown& c : crowns) {
            const double r = std::hypot(x - c.x, y - c.y);
            if (r < c.radius) {
                const double h = c.top - (c.top - c.bottom) * (r / c.radius) * uniform(rng, 0.3, 1.0);
                points.emplace_back(x, y, g + h);
                s.isGround.push_back(0);
                hitCrown = true;
                break;
            }
        }
        if (!hitCrown || rng.uniform() < 0.5) {
            points.emplace_back(x, y, g + p.noise * gaussian(rng));
            s.isGround.push_back(1);
        }
    }
    s.cloud.name = "terrain";
    s.cloud.resize(points.size());
    s.cloud.setOrigin(p.origin);
    for (std::size_t i = 0; i < points.size(); ++i)
        s.cloud.positions()[i] = points[i].cast<float>();
    return s;
}

struct Errors
{
    double typeI = 0, typeII = 0, total = 0; //!< ground rejected / objects accepted / both, as shares
};

Errors errorsOf(const std::vector<std::uint8_t>& found, const std::vector<char>& truth)
{
    double groundMissed = 0, objectTaken = 0, grounds = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
        grounds += truth[i];
        groundMissed += truth[i] && !found[i];
        objectTaken += !truth[i] && found[i];
    }
    const double n = static_cast<double>(truth.size());
    return {groundMissed / grounds, objectTaken / (n - grounds), (groundMissed + objectTaken) / n};
}

TEST(GroundFilter, FindsTheAnalyticGroundOnEveryDrawnTerrain)
{
    for (std::uint64_t seed = 1; seed <= 12; ++seed) {
        SplitMix64 rng(seed, 1);
        TerrainParams p;
        p.seed = seed;
        p.density = uniform(rng, 0.5, 8);
        p.side = 120 + 100 * rng.uniform();
        p.slopeX = uniform(rng, 0, 0.3);
        p.ridgeHeight = uniform(rng, 0, 8);
        p.pitDepth = uniform(rng, 0, 4);
        p.buildings = static_cast<int>(rng.below(8));
        p.trees = static_cast<int>(rng.below(150));
        p.bushes = static_cast<int>(rng.below(80));
        p.noise = uniform(rng, 0.01, 0.1);
        if (seed % 3 == 0)
            p.origin = {651234.5, 5432109.25, 312.0};
        const TerrainScene s = makeTerrain(p);
        const GroundFilterResult r = filterGround(s.cloud);
        const Errors e = errorsOf(r.ground, s.isGround);
        SCOPED_TRACE(testing::Message() << "seed " << seed << ": " << s.cloud.size() << " points, density " << p.density
                                        << ", slope " << p.slopeX << ", ridge " << p.ridgeHeight << ", " << p.buildings
                                        << " buildings, " << p.trees << " trees, " << p.bushes << " bushes");
        std::printf("seed %llu: type I %.2f %%, type II %.2f %%, total %.2f %%\n", static_cast<unsigned long long>(seed),
                    100 * e.typeI, 100 * e.typeII, 100 * e.total);
        // Measured: type I 0-0.2 %, type II 0-5.8 % (bushes on a 29 % slope,
        // where the threshold grows with the slope).
        EXPECT_LT(e.typeI, 0.01);
        EXPECT_LT(e.typeII, 0.06);
        // The terrain model lies on the analytic ground away from the pit's rim.
        EXPECT_NEAR(r.terrain.heightAt(0.5 * p.side, 0.1 * p.side), groundHeight(p, 0.5 * p.side, 0.1 * p.side), 0.3);
    }
}

//! The ISPRS filter test's samples (Sithole and Vosselman 2003) in PCL's
//! data: the reference ground is the subset file; a point is ground when the
//! subset holds it.
Errors realSampleErrors(const std::string& sample)
{
    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    const auto dir = std::filesystem::path(SCANDIFF_SAMPLE_DATA_DIR) / "pcl-data";
    const PointCloud all = io::readPointCloud(formats, dir / (sample + ".pcd"));
    const PointCloud ground = io::readPointCloud(formats, dir / (sample + "-ground.pcd"));
    std::set<std::tuple<float, float, float>> reference;
    for (std::size_t i = 0; i < ground.size(); ++i) {
        const Eigen::Vector3d q = ground.globalPosition(i) - all.origin();
        reference.emplace(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()));
    }
    std::vector<char> truth(all.size());
    for (std::size_t i = 0; i < all.size(); ++i)
        truth[i] = reference.count({all.positions()[i].x(), all.positions()[i].y(), all.positions()[i].z()}) > 0;
    const Errors e = errorsOf(filterGround(all).ground, truth);
    std::printf("%s: %zu points, %zu ground: type I %.2f %%, type II %.2f %%, total %.2f %%\n", sample.c_str(), all.size(),
                ground.size(), 100 * e.typeI, 100 * e.typeII, 100 * e.total);
    return e;
}

TEST(GroundFilter, RealIsprsSamplesWithDefaults)
{
    // Measured with the defaults: samp11 (steep, buildings, vegetation) 10.2 %
    // total (13.1 % type I, 6.4 % type II), samp53 (terraces) 8.9 % (9.0 %,
    // 5.7 %); the published SMRF figures are per-sample tuned (mean 2.97 %).
    const Errors steep = realSampleErrors("samp11-utm");
    const Errors terraced = realSampleErrors("samp53-utm");
    EXPECT_LT(steep.total, 0.11);
    EXPECT_LT(terraced.total, 0.095);
}

TEST(GroundFilter, DegenerateCloudsHaveADocumentedAnswer)
{
    const auto cloudOf = [](const std::vector<Eigen::Vector3f>& points) {
        PointCloud c;
        c.resize(points.size());
        c.positions() = points;
        return c;
    };
    // A flat parking lot: every point ground.
    std::vector<Eigen::Vector3f> lot;
    for (int i = 0; i < 60; ++i)
        for (int j = 0; j < 60; ++j)
            lot.emplace_back(0.5f * i, 0.5f * j, 0.01f * static_cast<float>((i * 7 + j * 3) % 5));
    EXPECT_EQ(filterGround(cloudOf(lot)).groundCount, lot.size());
    // A façade alone (a vertical wall 10 m high): its foot is the terrain,
    // nothing more than the threshold above it is ground.
    std::vector<Eigen::Vector3f> wall;
    for (int i = 0; i < 100; ++i)
        for (int k = 0; k <= 100; ++k)
            wall.emplace_back(0.2f * i, 0.0f, 0.1f * k);
    const GroundFilterResult facade = filterGround(cloudOf(wall));
    for (std::size_t i = 0; i < wall.size(); ++i) {
        if (wall[i].z() > 1.0f) {
            ASSERT_EQ(facade.ground[i], 0) << "point " << i << " at " << wall[i].z() << " m";
        }
    }
    // Non-finite points are never ground; a cloud with no finite point, an
    // empty cloud and parameters out of range are errors.
    lot.emplace_back(std::numeric_limits<float>::quiet_NaN(), 1.f, 1.f);
    EXPECT_EQ(filterGround(cloudOf(lot)).ground.back(), 0);
    EXPECT_THROW(filterGround(cloudOf({})), Error);
    EXPECT_THROW(filterGround(cloudOf({Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity())})), Error);
    GroundFilterParams bad;
    bad.cell = 0;
    EXPECT_THROW(filterGround(cloudOf(lot), bad), Error);
    // A grid too large for memory is refused before it is allocated.
    GroundFilterParams tiny;
    tiny.cell = 1e-4;
    EXPECT_THROW(filterGround(cloudOf(lot), tiny), Error);
}

} // namespace
} // namespace scandiff
