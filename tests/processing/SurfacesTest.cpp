// SPDX-License-Identifier: GPL-3.0-or-later
// Primitive fits and distances, unrolling, sampling points on a mesh.
#include "SyntheticClouds.h"
#include "TestSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/geometry/PointTriangleDistance.h>
#include <scandiff/core/geometry/Primitives.h>
#include <scandiff/core/processing/MeshSampling.h>
#include <scandiff/core/processing/Unrolling.h>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace scandiff;
using scandiff::test::kPi;

namespace {

//! Points on a cylinder (axis through `point` along `axis`), over `height`, on a grid of angles, with a global shift.
PointCloud cylinderCloud(const Eigen::Vector3d& point, const Eigen::Vector3d& axis, double radius, double height, int around, int along,
                         const Eigen::Vector3d& origin)
{
    Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.normalized().cross(e1);
    PointCloud c;
    c.setOrigin(origin);
    c.resize(static_cast<std::size_t>(around * along));
    for (int i = 0; i < around; ++i)
        for (int j = 0; j < along; ++j) {
            const double t = 2 * kPi * (i + 0.5 * (j % 2)) / around, h = height * j / (along - 1);
            const Eigen::Vector3d g = point + h * axis.normalized() + radius * (std::cos(t) * e1 + std::sin(t) * e2);
            c.positions()[static_cast<std::size_t>(i * along + j)] = (g - origin).cast<float>();
        }
    return c;
}

PointCloud coneCloud(const Eigen::Vector3d& apex, const Eigen::Vector3d& axis, double halfAngle, double from, double to, int around,
                     int along)
{
    Eigen::Vector3d w = axis.normalized(), e1 = w.unitOrthogonal(), e2 = w.cross(e1);
    PointCloud c;
    c.resize(static_cast<std::size_t>(around * along));
    for (int i = 0; i < around; ++i)
        for (int j = 0; j < along; ++j) {
            const double t = 2 * kPi * (i + 0.5 * (j % 2)) / around, h = from + (to - from) * j / (along - 1);
            const Eigen::Vector3d p = apex + h * w + h * std::tan(halfAngle) * (std::cos(t) * e1 + std::sin(t) * e2);
            c.positions()[static_cast<std::size_t>(i * along + j)] = p.cast<float>();
        }
    return c;
}

} // namespace

TEST(Primitives, FitsRecoverExactSurfaces)
{
    // Plane.
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
    const PointCloud plane = test::gridCloud(40, 40, 0.1, tilt, Eigen::Vector3d(512000, 5403000, 10));
    const PrimitiveFit planeFit = fitPrimitive(plane, PrimitiveKind::Plane);
    EXPECT_LT((planeFit.primitive.direction - tilt * Eigen::Vector3d::UnitZ()).norm(), 1e-6);
    EXPECT_LT(planeFit.rms, 1e-5);

    // Sphere.
    const PointCloud sphere = test::sphereCloud(5000, 1.5, Eigen::Vector3d(4, 5, 6));
    const PrimitiveFit sphereFit = fitPrimitive(sphere, PrimitiveKind::Sphere);
    EXPECT_LT((sphereFit.primitive.point - Eigen::Vector3d(4, 5, 6)).norm(), 1e-5);
    EXPECT_NEAR(sphereFit.primitive.radius, 1.5, 1e-5);

    // A georeferenced, tilted cylinder: axis, radius and the axis' position.
    const Eigen::Vector3d axis = Eigen::Vector3d(0.2, -0.1, 1).normalized(), onAxis(512003, 5403002, 100);
    const PointCloud cylinder = cylinderCloud(onAxis, axis, 2.5, 8, 120, 40, Eigen::Vector3d(512000, 5403000, 100));
    const PrimitiveFit cylinderFit = fitPrimitive(cylinder, PrimitiveKind::Cylinder);
    EXPECT_NEAR(cylinderFit.primitive.radius, 2.5, 1e-5);
    EXPECT_GT(std::abs(cylinderFit.primitive.direction.dot(axis)), 1 - 1e-10);
    const Eigen::Vector3d offset = cylinderFit.primitive.point - onAxis;
    EXPECT_LT((offset - offset.dot(axis) * axis).norm(), 1e-4); // the fitted axis passes through the true one
    EXPECT_LT(cylinderFit.rms, 1e-5);

    // A cone.
    const Eigen::Vector3d apex(1, 2, 3), coneAxis = Eigen::Vector3d(1, 0, 1).normalized();
    const PointCloud cone = coneCloud(apex, coneAxis, 0.35, 1.0, 4.0, 150, 40);
    const PrimitiveFit coneFit = fitPrimitive(cone, PrimitiveKind::Cone);
    EXPECT_LT((coneFit.primitive.point - apex).norm(), 1e-4);
    EXPECT_GT(coneFit.primitive.direction.dot(coneAxis), 1 - 1e-9);
    EXPECT_NEAR(coneFit.primitive.halfAngle, 0.35, 1e-6);

    // Too few or collinear points are a clear error.
    PointCloud line;
    line.resize(10);
    for (std::size_t i = 0; i < 10; ++i)
        line.positions()[i] = Eigen::Vector3f(float(i), 0, 0);
    EXPECT_EQ(test::errorCodeOf([&] { fitPrimitive(line, PrimitiveKind::Cylinder); }), ErrorCode::InvalidData);
}

TEST(Primitives, ReportedUncertaintiesMatchTheNoiseWhateverTheOrientation)
{
    // A 1.2 m square plate of 800 points with 5 mm of noise, facing each of
    // the six axis directions: the offset's standard uncertainty is
    // sigma / sqrt(n), the normal's (two tilts) sqrt(2) sigma / sqrt(n E[u^2])
    // with E[u^2] = 1.2^2 / 12 for a uniform spread. Numerical derivatives
    // with a step proportional to the parameter once gave 0 for parameters
    // that converged near 0 (the sides facing some axes).
    const double sigma = 0.005, side = 1.2;
    const std::size_t n = 800;
    const double offsetExpected = sigma / std::sqrt(static_cast<double>(n));
    const double tiltExpected = std::sqrt(2.0) * sigma / std::sqrt(static_cast<double>(n) * side * side / 12.0) * 180.0 / kPi;
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> uniform(-0.5, 0.5);
    std::normal_distribution<double> noise(0.0, sigma);
    const Eigen::Vector3d centre(6, 6, 2);
    for (int axis = 0; axis < 3; ++axis)
        for (double sign : {1.0, -1.0}) {
            Eigen::Vector3d normal = Eigen::Vector3d::Zero();
            normal[axis] = sign;
            const Eigen::Vector3d e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
            std::vector<Eigen::Vector3d> points; // relative to `centre`, as refinePrimitive takes them
            Eigen::Vector3d mean = Eigen::Vector3d::Zero();
            for (std::size_t i = 0; i < n; ++i) {
                points.push_back(Eigen::Vector3d(2, 2, -1) + uniform(rng) * side * e1 + uniform(rng) * side * e2 + noise(rng) * normal);
                mean += points.back() / static_cast<double>(n);
            }
            Primitive initial;
            initial.kind = PrimitiveKind::Plane;
            initial.direction = normal;
            initial.point = centre + mean;
            const PrimitiveRefinement fit = refinePrimitive(points, centre, initial);
            double tilt = 0, offset = 0;
            for (const auto& [name, value] : fit.uncertainty) {
                if (name == "direction_deg")
                    tilt = value;
                if (name == "offset")
                    offset = value;
            }
            EXPECT_NEAR(offset, offsetExpected, 0.15 * offsetExpected) << axis << " " << sign;
            EXPECT_NEAR(tilt, tiltExpected, 0.15 * tiltExpected) << axis << " " << sign;
        }
}

TEST(Primitives, SignedDistancesAndText)
{
    Primitive cylinder = parsePrimitive("cylinder:0,0,0,0,0,2,1.5");
    EXPECT_EQ(cylinder.direction, Eigen::Vector3d::UnitZ());
    EXPECT_DOUBLE_EQ(signedDistance(cylinder, Eigen::Vector3d(3, 0, 7)), 1.5);
    EXPECT_DOUBLE_EQ(signedDistance(cylinder, Eigen::Vector3d(0.5, 0, -2)), -1.0);
    const Primitive cone = parsePrimitive("cone:0,0,0,0,0,1,45");
    EXPECT_NEAR(signedDistance(cone, Eigen::Vector3d(2, 0, 1)), std::sqrt(0.5), 1e-12);
    const Primitive plane = parsePrimitive("plane:0,0,5,0,0,1");
    EXPECT_DOUBLE_EQ(signedDistance(plane, Eigen::Vector3d(1, 1, 3)), -2.0);
    const Primitive sphere = parsePrimitive("sphere:1,1,1,2");
    EXPECT_DOUBLE_EQ(signedDistance(sphere, Eigen::Vector3d(1, 1, 4)), 1.0);
    for (const Primitive& p : {cylinder, cone, plane, sphere}) {
        const Primitive again = parsePrimitive(primitiveText(p));
        EXPECT_EQ(again.point, p.point);
        EXPECT_EQ(again.direction, p.direction);
        EXPECT_EQ(again.radius, p.radius);
        EXPECT_NEAR(again.halfAngle, p.halfAngle, 1e-15);
    }
    for (const char* bad : {"cylinder:0,0,0,0,0,1", "torus:1,2", "sphere:0,0,0,-1", "cone:0,0,0,0,0,1,95", "plane:0,0,0,0,0,0"})
        EXPECT_EQ(test::errorCodeOf([&] { parsePrimitive(bad); }), ErrorCode::InvalidArgument) << bad;
}

TEST(Unrolling, ACylinderUnrollsToARectangleAndRollsBack)
{
    const double radius = 3.0;
    const Eigen::Vector3d origin(600000, 4000000, 0), onAxis(600010, 4000010, 0);
    PointCloud cylinder = cylinderCloud(onAxis, Eigen::Vector3d::UnitZ(), radius, 10, 200, 30, origin);
    // One point bulges out by 7 cm.
    const std::size_t bump = 55 * 30 + 12;
    const Eigen::Vector3d radial = (cylinder.globalPosition(bump) - onAxis).cwiseProduct(Eigen::Vector3d(1, 1, 0)).normalized();
    cylinder.positions()[bump] += (0.07 * radial).cast<float>();
    Primitive surface;
    surface.kind = PrimitiveKind::Cylinder;
    surface.point = onAxis;
    surface.direction = Eigen::Vector3d::UnitZ();
    surface.radius = radius;
    const PointCloud flat = unrollCloud(cylinder, surface, 0);
    double minX = 1e300, maxX = -1e300, minY = 1e300, maxY = -1e300;
    for (std::size_t i = 0; i < flat.size(); ++i) {
        const Eigen::Vector3d p = flat.globalPosition(i);
        minX = std::min(minX, p.x());
        maxX = std::max(maxX, p.x());
        minY = std::min(minY, p.y());
        maxY = std::max(maxY, p.y());
        if (i != bump) {
            ASSERT_NEAR(p.z(), 0.0, 1e-5) << i;
        }
    }
    // The rectangle is 2 pi R wide (less one angular step) and as high as the cylinder.
    EXPECT_NEAR(maxX - minX, 2 * kPi * radius * (1 - 1.0 / 400), 2 * kPi * radius / 400 + 1e-4);
    EXPECT_NEAR(maxY - minY, 10.0, 1e-5);
    EXPECT_NEAR(flat.field(fields::kUnrollDeviation)->value(bump), 0.07, 1e-5);
    EXPECT_NEAR(flat.globalPosition(bump).z(), 0.07, 1e-5);
    // Rolled back with the same surface: the points come back.
    const PointCloud back = rollCloud(flat, surface, 0);
    for (std::size_t i = 0; i < cylinder.size(); ++i)
        ASSERT_LT((back.globalPosition(i) - cylinder.globalPosition(i)).norm(), 1e-4) << i;
    // A point without finite coordinates stays so and moves nothing else.
    PointCloud withNan = cylinder.clone();
    withNan.positions()[0] = Eigen::Vector3f(std::nanf(""), 0, 0);
    const PointCloud flatNan = unrollCloud(withNan, surface, 0);
    EXPECT_FALSE(flatNan.positions()[0].allFinite());
    EXPECT_LT((flatNan.globalPosition(5) - flat.globalPosition(5)).norm(), 1e-4);
    // Unrolling about a plane is refused.
    EXPECT_EQ(test::errorCodeOf([&] { unrollCloud(cylinder, parsePrimitive("plane:0,0,0,0,0,1")); }), ErrorCode::InvalidArgument);
}

TEST(Unrolling, AConeDevelopsIntoASectorAndRollsBack)
{
    const double halfAngle = 0.4;
    const PointCloud cone = coneCloud(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d::UnitZ(), halfAngle, 1.0, 3.0, 120, 20);
    Primitive surface;
    surface.kind = PrimitiveKind::Cone;
    surface.point = Eigen::Vector3d(1, 1, 1);
    surface.direction = Eigen::Vector3d::UnitZ();
    surface.halfAngle = halfAngle;
    const PointCloud flat = unrollCloud(cone, surface, 15);
    for (std::size_t i = 0; i < cone.size(); ++i) {
        const Eigen::Vector3d p = flat.globalPosition(i);
        // Distance from the apex along the generator is preserved; on the surface z = 0.
        const double along = (cone.globalPosition(i) - surface.point).norm();
        ASSERT_NEAR(std::hypot(p.x(), p.y()), along, 1e-5) << i;
        ASSERT_NEAR(p.z(), 0.0, 1e-5) << i;
        // The sector's angle is 2 pi sin(a).
        double phi = std::atan2(p.y(), p.x());
        if (phi < 0)
            phi += 2 * kPi;
        ASSERT_LE(phi, 2 * kPi * std::sin(halfAngle) + 1e-9) << i;
    }
    const PointCloud back = rollCloud(flat, surface, 15);
    for (std::size_t i = 0; i < cone.size(); ++i)
        ASSERT_LT((back.globalPosition(i) - cone.globalPosition(i)).norm(), 1e-4) << i;
}

TEST(MeshSampling, PointsLieOnTheirTrianglesInProportionToArea)
{
    Mesh mesh;
    mesh.vertices.setOrigin(Eigen::Vector3d(512000, 5403000, 0));
    mesh.vertices.resize(5);
    mesh.vertices.positions() = {{0, 0, 0}, {4, 0, 0}, {4, 3, 0}, {0, 3, 2}, {4, 0, 0}};
    ScalarField& h = mesh.vertices.addField("h");
    for (std::size_t i = 0; i < 5; ++i)
        h.setValue(i, static_cast<double>(i));
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}}; // the last is degenerate (two equal vertices)
    MeshSamplingParams params;
    params.count = 10001;
    params.seed = 5;
    const PointCloud cloud = sampleMesh(mesh, params);
    ASSERT_EQ(cloud.size(), 10001u);
    const double area0 = 6.0, area1 = 0.5 * (Eigen::Vector3d(4, 3, 0).cross(Eigen::Vector3d(0, 3, 2))).norm();
    std::array<std::size_t, 3> counts{};
    const ScalarField& triangle = *cloud.field(fields::kTriangleIndex);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto t = static_cast<std::size_t>(triangle.value(i));
        ++counts[t];
        const auto& tri = mesh.triangles[t];
        const Eigen::Vector3d p = cloud.positions()[i].cast<double>();
        const Eigen::Vector3d a = mesh.vertices.positions()[tri[0]].cast<double>(), b = mesh.vertices.positions()[tri[1]].cast<double>(),
                              c = mesh.vertices.positions()[tri[2]].cast<double>();
        ASSERT_LT(std::sqrt(geometry::pointTriangleDistance(p, a, b, c).squaredDistance), 1e-5) << i;
        // The interpolated field is linear: exact at any point of the triangle.
        const Eigen::Vector3d n = (b - a).cross(c - a);
        const double wa = (b - p).cross(c - p).dot(n) / n.squaredNorm(), wb = (c - p).cross(a - p).dot(n) / n.squaredNorm();
        const double expected = wa * tri[0] + wb * tri[1] + (1 - wa - wb) * tri[2];
        ASSERT_NEAR(cloud.field("h")->value(i), expected, 1e-4) << i;
        ASSERT_NEAR(std::abs(cloud.normals()[i].cast<double>().dot(n.normalized())), 1.0, 1e-6);
    }
    EXPECT_EQ(counts[2], 0u);
    EXPECT_LE(std::abs(static_cast<double>(counts[0]) - 10001 * area0 / (area0 + area1)), 1.0);
    EXPECT_LE(std::abs(static_cast<double>(counts[1]) - 10001 * area1 / (area0 + area1)), 1.0);
    // The same seed, the same points; other seeds, unrelated points (not the
    // same draws shifted by one).
    EXPECT_EQ(sampleMesh(mesh, params).positions(), cloud.positions());
    for (std::uint64_t other : {6u, 7u, 9u}) {
        MeshSamplingParams reseeded = params;
        reseeded.seed = other;
        const PointCloud again = sampleMesh(mesh, reseeded);
        std::size_t shared = 0;
        for (const auto& p : again.positions())
            shared += std::find(cloud.positions().begin(), cloud.positions().end(), p) != cloud.positions().end();
        EXPECT_EQ(shared, 0u) << "seed " << other;
    }
    MeshSamplingParams byDensity;
    byDensity.density = 100;
    EXPECT_EQ(sampleMesh(mesh, byDensity).size(), static_cast<std::size_t>(std::llround(100 * (area0 + area1))));
    EXPECT_EQ(test::errorCodeOf([&] { sampleMesh(mesh, MeshSamplingParams{}); }), ErrorCode::InvalidArgument);
    MeshSamplingParams huge;
    huge.count = std::size_t(100000000000); // refused before anything is allocated
    EXPECT_EQ(test::errorCodeOf([&] { sampleMesh(mesh, huge); }), ErrorCode::InvalidArgument);
}
