// SPDX-License-Identifier: GPL-3.0-or-later
// Local features against closed forms, subsampling against brute force.
#include "SyntheticClouds.h"
#include "TestSupport.h"

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/processing/LocalFeatures.h>
#include <scandiff/core/processing/Subsampling.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <map>
#include <set>

using namespace scandiff;
using scandiff::test::kPi;

namespace {

const ScalarField& fieldNamed(const FeatureResult& result, const std::string& name)
{
    for (const auto& f : result.fields)
        if (f.name() == name)
            return f;
    throw std::runtime_error("no field " + name);
}

} // namespace

TEST(LocalFeatures, DensityOfARegularGridIsItsCountOverTheDisc)
{
    const double step = 0.1, radius = 2.0; // 20 spacings: the disc holds ~1257 points
    const PointCloud grid = test::gridCloud(101, 101, step);
    FeatureParams params;
    params.radius = radius;
    params.density = true;
    const FeatureResult result = computeLocalFeatures(grid, params);
    ASSERT_EQ(result.fields.size(), 1u);
    const ScalarField& density = fieldNamed(result, fields::kSurfaceDensity);
    // At the centre: the exact count of grid nodes within the radius (brute
    // force), over pi r^2; and within 1 % of the grid's 1/step^2 = 100 per m^2.
    const std::size_t centre = 50 * 101 + 50;
    std::size_t count = 0;
    for (const auto& p : grid.positions())
        count += (p - grid.positions()[centre]).squaredNorm() <= static_cast<float>(radius * radius);
    EXPECT_FLOAT_EQ(density.values()[centre], static_cast<float>(count / (kPi * radius * radius)));
    EXPECT_NEAR(density.value(centre), 1.0 / (step * step), 1.0);

    params.densityKind = DensityKind::Count;
    EXPECT_EQ(computeLocalFeatures(grid, params).fields.front().values()[centre], static_cast<float>(count));
    params.densityKind = DensityKind::Volume;
    EXPECT_FLOAT_EQ(computeLocalFeatures(grid, params).fields.front().values()[centre],
                    static_cast<float>(count / (4.0 / 3.0 * kPi * radius * radius * radius)));
}

TEST(LocalFeatures, CurvatureOfAParaboloidAndASphere)
{
    // z = a x^2 + b y^2 at the apex: K = 4ab, H = a + b (normals up, the
    // surface bends towards them). The quadric fit is exact there.
    const double a = 0.3, b = 0.1;
    PointCloud bowl = test::gridCloud(81, 81, 0.025);
    for (auto& p : bowl.positions()) {
        p.x() -= 1.0f;
        p.y() -= 1.0f;
        p.z() = static_cast<float>(a * p.x() * p.x() + b * p.y() * p.y());
    }
    FeatureParams params;
    params.radius = 0.2;
    params.curvature = true;
    const FeatureResult bowlResult = computeLocalFeatures(bowl, params);
    const std::size_t apex = 40 * 81 + 40;
    EXPECT_NEAR(fieldNamed(bowlResult, fields::kGaussianCurvature).value(apex), 4 * a * b, 1e-3);
    EXPECT_NEAR(fieldNamed(bowlResult, fields::kMeanCurvature).value(apex), a + b, 1e-3);

    // A sphere of radius 2 with outward normals: K = 1/4, H = -1/2 everywhere.
    PointCloud sphere = test::sphereCloud(60000, 2.0);
    auto& normals = sphere.enableNormals();
    for (std::size_t i = 0; i < sphere.size(); ++i)
        normals[i] = sphere.positions()[i].normalized();
    params.radius = 0.15;
    const FeatureResult sphereResult = computeLocalFeatures(sphere, params);
    for (std::size_t i = 0; i < sphere.size(); i += 97) {
        EXPECT_NEAR(fieldNamed(sphereResult, fields::kGaussianCurvature).value(i), 0.25, 0.25 * 0.02) << i;
        EXPECT_NEAR(fieldNamed(sphereResult, fields::kMeanCurvature).value(i), -0.5, 0.5 * 0.02) << i;
    }
}

TEST(LocalFeatures, RoughnessAndVerticality)
{
    // A flat grid with one point lifted by 3 cm: its roughness is 3 cm, the
    // others' (its neighbours') stay near 0 and exactly 0 far from it.
    PointCloud floor = test::gridCloud(41, 41, 0.05);
    const std::size_t lifted = 20 * 41 + 20;
    floor.positions()[lifted].z() = 0.03f;
    FeatureParams params;
    params.radius = 0.16;
    params.roughness = true;
    params.verticality = true;
    const FeatureResult result = computeLocalFeatures(floor, params);
    EXPECT_NEAR(fieldNamed(result, fields::kRoughness).value(lifted), 0.03, 1e-6);
    EXPECT_NEAR(fieldNamed(result, fields::kRoughness).value(0), 0.0, 1e-9);
    EXPECT_NEAR(fieldNamed(result, fields::kVerticality).value(0), 0.0, 1e-9);

    // A wall: verticality 1.
    const PointCloud wall = test::gridCloud(30, 30, 0.05, Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix());
    const FeatureResult wallResult = computeLocalFeatures(wall, params);
    EXPECT_NEAR(fieldNamed(wallResult, fields::kVerticality).value(100), 1.0, 1e-6);

    // No flag: every feature; with curvature the neighbourhoods are listed
    // rather than summed, and the other features come out the same.
    FeatureParams all;
    all.radius = 0.16;
    const FeatureResult everything = computeLocalFeatures(floor, all);
    EXPECT_EQ(everything.fields.size(), 5u);
    params.density = true;
    const FeatureResult summed = computeLocalFeatures(floor, params);
    for (const char* name : {fields::kSurfaceDensity, fields::kRoughness, fields::kVerticality})
        for (std::size_t i = 0; i < floor.size(); ++i)
            ASSERT_NEAR(fieldNamed(everything, name).value(i), fieldNamed(summed, name).value(i), 1e-7) << name << " " << i;
    FeatureParams bad;
    EXPECT_EQ(test::errorCodeOf([&] { computeLocalFeatures(floor, bad); }), ErrorCode::InvalidArgument);
}

TEST(Subsampling, SpatialKeepsNoTwoPointsWithinTheDistanceAndCoversEveryPoint)
{
    // Local coordinates near 0 and near a kilometre (where a float's step is 60 um).
    for (const auto& [d, offset] : std::vector<std::pair<double, float>>{{0.02, 0.0f}, {0.05, 0.0f}, {0.3, 0.0f}, {0.001, 900.0f}, {0.05, 900.0f}}) {
        PointCloud cloud = test::randomPlaneCloud(4000, 2.0, 7);
        for (auto& p : cloud.positions())
            p += Eigen::Vector3f(offset, offset, 0.0f);
        // Duplicates and a second layer make it harder.
        for (std::size_t i = 0; i < 200; ++i)
            cloud.positions()[3000 + i] = cloud.positions()[i];
        for (std::size_t i = 3500; i < 4000; ++i)
            cloud.positions()[i].z() = 0.01f;
        const std::vector<std::size_t> kept = spatialSubsample(cloud, d);
        ASSERT_TRUE(std::is_sorted(kept.begin(), kept.end()));
        const float d2 = static_cast<float>(d * d);
        std::vector<char> isKept(cloud.size(), 0);
        for (std::size_t i : kept)
            isKept[i] = 1;
        for (std::size_t a = 0; a < kept.size(); ++a)
            for (std::size_t b = a + 1; b < kept.size(); ++b)
                ASSERT_GT((cloud.positions()[kept[a]] - cloud.positions()[kept[b]]).squaredNorm(), d2) << "d " << d;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (isKept[i])
                continue;
            bool covered = false;
            for (std::size_t k : kept)
                covered = covered || (cloud.positions()[i] - cloud.positions()[k]).squaredNorm() <= d2;
            ASSERT_TRUE(covered) << "point " << i << " d " << d;
        }
    }
}

TEST(Subsampling, SpatialGivesTheSamePointsOnOneThreadOrSeveral)
{
    const PointCloud cloud = test::randomPlaneCloud(200000, 20.0, 12);
    const std::vector<std::size_t> parallel = spatialSubsample(cloud, 0.04);
    std::vector<std::size_t> serial;
    {
        const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        serial = spatialSubsample(cloud, 0.04);
    }
    EXPECT_EQ(parallel, serial);
    EXPECT_LT(parallel.size(), cloud.size());
}

TEST(Subsampling, OctreeKeepsExactlyThePointNearestEachCellCentre)
{
    const PointCloud cloud = test::randomPlaneCloud(5000, 3.0, 11);
    const octree::Octree tree = buildOctree(cloud);
    for (int level : {1, 3, 5, 7}) {
        const std::vector<std::size_t> kept = octreeSubsample(cloud, level);
        // Brute force: each point's cell, and the nearest to each cell's centre.
        const double size = tree.cellSize(level);
        std::map<std::array<long, 3>, std::size_t> best;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            std::array<long, 3> cell;
            for (int a = 0; a < 3; ++a) {
                const double offset = (cloud.positions()[i][a] - tree.box().min[a]) / size;
                cell[static_cast<std::size_t>(a)] = std::min(static_cast<long>(offset), (1L << level) - 1);
            }
            const auto distance = [&](std::size_t j) {
                Eigen::Vector3d centre;
                for (int a = 0; a < 3; ++a)
                    centre[a] = tree.box().min[a] + (cell[static_cast<std::size_t>(a)] + 0.5) * size;
                return (cloud.positions()[j].cast<double>() - centre).squaredNorm();
            };
            const auto it = best.find(cell);
            if (it == best.end() || distance(i) < distance(it->second))
                best[cell] = i;
        }
        std::vector<std::size_t> expected;
        for (const auto& [cell, i] : best)
            expected.push_back(i);
        std::sort(expected.begin(), expected.end());
        EXPECT_EQ(kept, expected) << "level " << level;
        EXPECT_EQ(kept.size(), tree.levelStatistics(level).nonEmptyCells);
    }
    EXPECT_EQ(test::errorCodeOf([&] { octreeSubsample(cloud, 0); }), ErrorCode::InvalidArgument);
}

TEST(Subsampling, RandomKeepsTheCountAndRepeatsWithTheSeed)
{
    const PointCloud cloud = test::randomPlaneCloud(10000, 1.0, 3);
    const std::vector<std::size_t> a = randomSubsample(cloud, 1234, 42), b = randomSubsample(cloud, 1234, 42),
                                   c = randomSubsample(cloud, 1234, 43);
    EXPECT_EQ(a.size(), 1234u);
    EXPECT_EQ(a, b);
    EXPECT_NE(a, c);
    EXPECT_TRUE(std::is_sorted(a.begin(), a.end()));
    EXPECT_EQ(std::set<std::size_t>(a.begin(), a.end()).size(), a.size());
    EXPECT_EQ(randomSubsample(cloud, 20000).size(), cloud.size());
}
