// SPDX-License-Identifier: GPL-3.0-or-later
// Normals against analytic surfaces, and every orientation method.
#include "StageWatcher.h"
#include "SyntheticClouds.h"
#include "TestSupport.h"

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/processing/Normals.h>

#include <Eigen/Geometry>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <random>

using namespace scandiff;
using scandiff::test::kPi;

namespace {

double degreesBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
    return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / kPi;
}

//! The largest angle (degrees) between each normal and the analytic one, sign included.
template <typename Analytic>
double worstAngle(const PointCloud& cloud, const std::vector<Eigen::Vector3f>& normals, Analytic&& analytic)
{
    double worst = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        worst = std::max(worst, degreesBetween(normals[i].cast<double>(), analytic(cloud.positions()[i].cast<double>())));
    return worst;
}

} // namespace

TEST(Normals, TiltedPlaneIsExactWithEveryModel)
{
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 0).normalized()).toRotationMatrix();
    const PointCloud plane = test::gridCloud(60, 60, 0.05, tilt, Eigen::Vector3d(512000, 5403000, 100));
    const Eigen::Vector3d expected = tilt * Eigen::Vector3d::UnitZ(); // +z side: its z is positive
    for (NormalModel model : {NormalModel::Plane, NormalModel::Quadric, NormalModel::Triangulation}) {
        for (bool byRadius : {false, true}) {
            NormalParams params;
            params.model = model;
            if (byRadius)
                params.radius = 0.12;
            const NormalResult result = computeNormals(plane, params);
            EXPECT_EQ(result.unfitted, 0u);
            EXPECT_LT(worstAngle(plane, result.normals, [&](const Eigen::Vector3d&) { return expected; }), 1e-3)
                << "model " << static_cast<int>(model) << " radius " << byRadius;
            for (std::size_t i = 0; i < plane.size(); ++i)
                EXPECT_LT(result.surfaceVariation.value(i), 1e-6);
        }
    }
}

TEST(Normals, SphereNormalsAreRadialWithinATenthOfADegree)
{
    // The models that follow curvature (quadric, triangulation) are exact on a
    // sphere to well below the bound; the plane's normal leans towards the
    // centroid of its neighbours, off the point by a fraction of the spacing,
    // so it needs the denser sampling: 0.08 degree at 400,000 points, 0.16 at
    // 100,000 (the lean shrinks with the spacing over the radius).
    const Eigen::Vector3d centre(3, -1, 2);
    const auto radial = [&](const Eigen::Vector3d& p) { return (p - centre).normalized(); };
    NormalParams params;
    params.orientation.kind = NormalOrientation::Kind::AwayFromCentroid;
    const PointCloud sphere = test::sphereCloud(100000, 2.0, centre);
    for (double radius : {0.05, 0.1}) { // about 16 and 63 neighbours
        params.radius = radius;
        for (NormalModel model : {NormalModel::Quadric, NormalModel::Triangulation}) {
            params.model = model;
            const NormalResult result = computeNormals(sphere, params);
            EXPECT_EQ(result.unfitted, 0u);
            EXPECT_LT(worstAngle(sphere, result.normals, radial), 0.1) << "model " << static_cast<int>(model) << " radius " << radius;
        }
    }
    params.radius.reset();
    params.knn = 12;
    for (NormalModel model : {NormalModel::Quadric, NormalModel::Triangulation}) {
        params.model = model;
        EXPECT_LT(worstAngle(sphere, computeNormals(sphere, params).normals, radial), 0.1) << "model " << static_cast<int>(model);
    }
    const PointCloud dense = test::sphereCloud(400000, 2.0, centre);
    params.model = NormalModel::Plane;
    params.radius = 0.03; // about 25 neighbours
    EXPECT_LT(worstAngle(dense, computeNormals(dense, params).normals, radial), 0.1);
}

TEST(Normals, EveryOrientationMethodGivesOneConsistentSide)
{
    const PointCloud sphere = test::sphereCloud(20000, 1.0);
    NormalParams params;
    params.knn = 10;
    const auto outward = [](const Eigen::Vector3d& p) { return p.normalized(); };

    params.orientation.kind = NormalOrientation::Kind::AwayFromCentroid;
    std::vector<Eigen::Vector3f> normals = computeNormals(sphere, params).normals;
    for (std::size_t i = 0; i < sphere.size(); ++i)
        ASSERT_GT(normals[i].cast<double>().dot(outward(sphere.positions()[i].cast<double>())), 0.9) << i;

    params.orientation.kind = NormalOrientation::Kind::TowardsCentroid;
    normals = computeNormals(sphere, params).normals;
    for (std::size_t i = 0; i < sphere.size(); ++i)
        ASSERT_LT(normals[i].cast<double>().dot(outward(sphere.positions()[i].cast<double>())), -0.9) << i;

    // Towards a sensor at the centre: inward everywhere.
    params.orientation = parseNormalOrientation("sensor:0,0,0");
    normals = computeNormals(sphere, params).normals;
    for (std::size_t i = 0; i < sphere.size(); ++i)
        ASSERT_LT(normals[i].cast<double>().dot(outward(sphere.positions()[i].cast<double>())), -0.9) << i;

    // The cloud's own scanner position, in global coordinates.
    PointCloud shifted = sphere.clone();
    shifted.setOrigin(Eigen::Vector3d(500000, 4000000, 50));
    SensorPose pose;
    pose.position = Eigen::Vector3d(500000, 4000000, 50 + 10); // above the sphere
    shifted.sensors().push_back(pose);
    params.orientation = parseNormalOrientation("sensor");
    normals = computeNormals(shifted, params).normals;
    for (std::size_t i = 0; i < sphere.size(); ++i)
        ASSERT_GE(normals[i].cast<double>().dot(Eigen::Vector3d(0, 0, 10) - sphere.positions()[i].cast<double>()), 0.0) << i;

    // A direction: +z and a tilted one.
    for (const std::string text : {"+z", "-x", "1,1,0"}) {
        params.orientation = parseNormalOrientation(text);
        normals = computeNormals(sphere, params).normals;
        for (std::size_t i = 0; i < sphere.size(); ++i)
            ASSERT_GE(normals[i].cast<double>().dot(params.orientation.direction), 0.0) << text << " point " << i;
    }

    // flip reverses after orienting.
    params.orientation = parseNormalOrientation("+z");
    params.flip = true;
    normals = computeNormals(sphere, params).normals;
    for (std::size_t i = 0; i < sphere.size(); ++i)
        ASSERT_LE(normals[i].z(), 0.0f) << i;
}

TEST(Normals, MinimumSpanningTreeOrientsAClosedTorusOutward)
{
    // A torus is where orienting by a direction or the centroid fails: half
    // of the inner ring faces the centroid.
    const double major = 2.0, minor = 0.6;
    const PointCloud torus = test::torusCloud(400, 120, major, minor);
    NormalParams params;
    params.knn = 10;
    params.orientation = parseNormalOrientation("mst");
    const NormalResult result = computeNormals(torus, params);
    EXPECT_EQ(result.components, 1u);
    std::size_t inward = 0;
    for (std::size_t i = 0; i < torus.size(); ++i)
        inward += result.normals[i].cast<double>().dot(test::torusOutward(torus.positions()[i].cast<double>(), major)) <= 0;
    EXPECT_EQ(inward, 0u);

    // The centroid method gets the inner half wrong: the test can fail.
    params.orientation.kind = NormalOrientation::Kind::AwayFromCentroid;
    const NormalResult naive = computeNormals(torus, params);
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < torus.size(); ++i)
        wrong += naive.normals[i].cast<double>().dot(test::torusOutward(torus.positions()[i].cast<double>(), major)) <= 0;
    EXPECT_GT(wrong, torus.size() / 10);

    // Orienting existing normals gives the same answer, whatever side they start on.
    std::vector<Eigen::Vector3f> scrambled = naive.normals;
    for (std::size_t i = 0; i < scrambled.size(); i += 3)
        scrambled[i] = -scrambled[i];
    NormalOrientation mst;
    mst.kind = NormalOrientation::Kind::MinimumSpanningTree;
    mst.mstNeighbours = 10;
    orientNormals(torus, scrambled, mst);
    for (std::size_t i = 0; i < torus.size(); ++i)
        ASSERT_GT(scrambled[i].cast<double>().dot(test::torusOutward(torus.positions()[i].cast<double>(), major)), 0.0) << i;
}

TEST(Normals, MinimumSpanningTreeStartsEachPartFromItsHighestPoint)
{
    // Two separate spheres: two parts, both outward.
    PointCloud a = test::sphereCloud(3000, 1.0), b = test::sphereCloud(3000, 1.0, Eigen::Vector3d(10, 0, 0));
    PointCloud both;
    both.resize(a.size() + b.size());
    std::copy(a.positions().begin(), a.positions().end(), both.positions().begin());
    std::copy(b.positions().begin(), b.positions().end(), both.positions().begin() + static_cast<std::ptrdiff_t>(a.size()));
    NormalParams params;
    params.knn = 8;
    params.orientation = parseNormalOrientation("mst");
    const NormalResult result = computeNormals(both, params);
    EXPECT_EQ(result.components, 2u);
    for (std::size_t i = 0; i < both.size(); ++i) {
        const Eigen::Vector3d centre = i < a.size() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(10, 0, 0);
        ASSERT_GT(result.normals[i].cast<double>().dot(both.positions()[i].cast<double>() - centre), 0.0) << i;
    }
}

TEST(Normals, DegenerateNeighbourhoodsAndBadInput)
{
    // A line of points fixes no plane: no normal, no surface variation.
    PointCloud line;
    line.resize(50);
    for (std::size_t i = 0; i < 50; ++i)
        line.positions()[i] = Eigen::Vector3f(float(i), 0, 0);
    const NormalResult result = computeNormals(line, NormalParams{});
    EXPECT_EQ(result.unfitted, 50u);
    for (std::size_t i = 0; i < 50; ++i) {
        EXPECT_EQ(result.normals[i], Eigen::Vector3f::Zero());
        EXPECT_FALSE(result.surfaceVariation.hasValue(i));
    }
    // Isolated points with a small radius: no normal either.
    NormalParams small;
    small.radius = 0.1;
    EXPECT_EQ(computeNormals(line, small).unfitted, 50u);

    PointCloud empty;
    EXPECT_EQ(test::errorCodeOf([&] { computeNormals(empty, NormalParams{}); }), ErrorCode::InvalidData);
    PointCloud withNan = line.clone();
    withNan.positions()[3].x() = std::nanf("");
    EXPECT_EQ(test::errorCodeOf([&] { computeNormals(withNan, NormalParams{}); }), ErrorCode::InvalidData);
    NormalParams badK;
    badK.knn = 2;
    EXPECT_EQ(test::errorCodeOf([&] { computeNormals(line, badK); }), ErrorCode::InvalidArgument);
    NormalParams sensorless;
    sensorless.orientation = parseNormalOrientation("sensor");
    EXPECT_EQ(test::errorCodeOf([&] { computeNormals(line, sensorless); }), ErrorCode::InvalidArgument);
    for (const char* bad : {"up", "1,2", "0,0,0", "sensor:1,2", ""})
        EXPECT_EQ(test::errorCodeOf([&] { parseNormalOrientation(bad); }), ErrorCode::InvalidArgument) << bad;
}

TEST(Normals, CancelStopsTheFit)
{
    test::CancelAtOnce cancel;
    const PointCloud sphere = test::sphereCloud(200000, 1.0);
    EXPECT_EQ(test::errorCodeOf([&] { computeNormals(sphere, NormalParams{}, &cancel); }), ErrorCode::Cancelled);
    NormalParams byRadius;
    byRadius.radius = 0.02;
    EXPECT_EQ(test::errorCodeOf([&] { computeNormals(sphere, byRadius, &cancel); }), ErrorCode::Cancelled);
    // The octree build itself hears it (it is linear but takes a second on ten million points).
    EXPECT_EQ(test::errorCodeOf([&] { buildOctree(sphere, std::nullopt, &cancel); }), ErrorCode::Cancelled);
}

TEST(Normals, TheSpanningTreeHearsCancelWhileSortingItsEdges)
{
    // 300 000 points, 10 neighbours: 3 M edges whose sort and Kruskal pass
    // took 1.3 s on 2 M points with only two polls, at their ends. Now the
    // sort asks before each partition and each small sort, the pass every
    // 2^20 edges.
    const PointCloud sphere = test::sphereCloud(300000, 1.0);
    std::vector<Eigen::Vector3f> normals = computeNormals(sphere, NormalParams{}).normals;
    NormalOrientation mst = parseNormalOrientation("mst");
    test::StageWatcher watch("spanning tree", 0);
    std::vector<Eigen::Vector3f> oriented = normals;
    orientNormals(sphere, oriented, mst, &watch);
    EXPECT_GE(watch.polls(), 5u);
    test::StageWatcher cancel("spanning tree", 3);
    oriented = normals;
    EXPECT_EQ(test::errorCodeOf([&] { orientNormals(sphere, oriented, mst, &cancel); }), ErrorCode::Cancelled);
    // Stopped there: the sort's other branch, on the other core, may ask once
    // more before the exception stops it, nothing after.
    EXPECT_GE(cancel.polls(), 3u);
    EXPECT_LE(cancel.polls(), 3u + static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()) - 1);
}

TEST(Normals, SomePointsOnlyGiveTheNormalsOfTheWholeCloud)
{
    // planeNormalsOf (the registration's normals where closest points land)
    // equals computeNormals with the same neighbours and +Z, bit for bit, in
    // turns of a few points each.
    std::mt19937 rng(8);
    std::uniform_real_distribution<float> u(-5.0f, 5.0f);
    PointCloud cloud;
    cloud.resize(4000);
    for (auto& p : cloud.positions()) {
        const float x = u(rng), y = u(rng);
        p = {x, y, 0.3f * std::sin(x) * std::cos(y) + 0.01f * u(rng)};
    }
    NormalParams params;
    params.knn = 12;
    const NormalResult all = computeNormals(cloud, params);
    const octree::Octree tree = buildOctree(cloud);
    std::vector<Eigen::Vector3f> some(cloud.size(), Eigen::Vector3f::Zero());
    std::vector<std::uint32_t> first, second;
    for (std::uint32_t i = 0; i < cloud.size(); ++i)
        (i % 3 == 0 ? first : second).push_back(i);
    planeNormalsOf(cloud, tree, first, 12, some);
    for (std::uint32_t i : second)
        EXPECT_EQ(some[i], Eigen::Vector3f::Zero()); // untouched until asked for
    planeNormalsOf(cloud, tree, second, 12, some);
    for (std::size_t i = 0; i < cloud.size(); ++i)
        ASSERT_EQ(some[i], all.normals[i]) << i;
    EXPECT_THROW(planeNormalsOf(cloud, tree, first, 2, some), Error);
}

TEST(Normals, ARadiusWidensToTheNearestPointsWhereTheScanIsSparse)
{
    // One tilted plane sampled at 1 cm near the scanner and at 10 cm far from
    // it: a 3 cm radius holds the near points' neighbours and none of the far
    // ones'. With at least 12 neighbours, the far points are fitted on their
    // 12 nearest: every normal exact; the near ones keep their radius (the
    // same normals as without the minimum).
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.3, Eigen::Vector3d(2, 1, 0).normalized()).toRotationMatrix();
    const Eigen::Vector3d origin(512000, 5403000, 100);
    PointCloud near = test::gridCloud(40, 40, 0.01, tilt, origin);
    const PointCloud far = test::gridCloud(20, 20, 0.10, tilt, origin + tilt * Eigen::Vector3d(5, 0, 0));
    const std::size_t nearCount = near.size();
    for (std::size_t i = 0; i < far.size(); ++i)
        near.positions().push_back((far.globalPosition(i) - near.origin()).cast<float>());
    const PointCloud& cloud = near;
    const Eigen::Vector3d expected = tilt * Eigen::Vector3d::UnitZ();
    NormalParams params;
    params.radius = 0.03;
    const NormalResult radiusOnly = computeNormals(cloud, params);
    EXPECT_EQ(radiusOnly.unfitted, far.size());
    params.minNeighbours = 12;
    const NormalResult widened = computeNormals(cloud, params);
    EXPECT_EQ(widened.unfitted, 0u);
    EXPECT_LT(worstAngle(cloud, widened.normals, [&](const Eigen::Vector3d&) { return expected; }), 1e-3);
    for (std::size_t i = 0; i < nearCount; ++i)
        ASSERT_LT(degreesBetween(widened.normals[i].cast<double>(), radiusOnly.normals[i].cast<double>()), 1e-4) << i;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        EXPECT_LT(widened.surfaceVariation.value(i), 1e-6) << i;
    // A minimum goes with a radius and the plane model, and is at least 3.
    NormalParams bad = params;
    bad.minNeighbours = 2;
    EXPECT_EQ(test::errorCodeOf([&] { computeNormals(cloud, bad); }), ErrorCode::InvalidArgument);
    bad.minNeighbours = 12;
    bad.radius.reset();
    EXPECT_EQ(test::errorCodeOf([&] { computeNormals(cloud, bad); }), ErrorCode::InvalidArgument);
    bad.radius = 0.03;
    bad.model = NormalModel::Quadric;
    EXPECT_EQ(test::errorCodeOf([&] { computeNormals(cloud, bad); }), ErrorCode::InvalidArgument);
}
