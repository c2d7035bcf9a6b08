// SPDX-License-Identifier: GPL-3.0-or-later
// Measurements of picked points against closed forms, at UTM magnitudes.

#include <scandiff/core/geometry/Measurement.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace scandiff;

namespace {
const Eigen::Vector3d kUtm(512345.678, 5403210.987, 312.5); // where survey data lives
}

TEST(Measurement, TwoPointsGiveTheDistanceAndItsComponents)
{
    const PointMeasurement m = measurePoints({kUtm, kUtm + Eigen::Vector3d(3, 4, 12)});
    EXPECT_EQ(m.pointCount, 2u);
    EXPECT_NEAR(m.pathLength, 13.0, 1e-9); // 3-4-12-13
    EXPECT_NEAR(m.delta.x(), 3.0, 1e-9);
    EXPECT_NEAR(m.delta.y(), 4.0, 1e-9);
    EXPECT_NEAR(m.delta.z(), 12.0, 1e-9);
    EXPECT_NEAR(m.horizontalDistance, 5.0, 1e-9);
    EXPECT_NEAR(m.slopeDegrees, std::atan2(12.0, 5.0) * 180.0 / M_PI, 1e-9);
    EXPECT_FALSE(m.angleDegrees.has_value());
    EXPECT_FALSE(m.area.has_value());
    // A millimetre at UTM magnitudes is a millimetre.
    EXPECT_NEAR(measurePoints({kUtm, kUtm + Eigen::Vector3d(0.001, 0, 0)}).pathLength, 0.001, 1e-9);
}

TEST(Measurement, ThreePointsGiveTheAngleAtTheMiddleOne)
{
    const Eigen::Vector3d corner = kUtm;
    const PointMeasurement right = measurePoints({corner + Eigen::Vector3d(2, 0, 0), corner, corner + Eigen::Vector3d(0, 0, 5)});
    ASSERT_TRUE(right.angleDegrees.has_value());
    EXPECT_NEAR(*right.angleDegrees, 90.0, 1e-6);
    const PointMeasurement sixty =
        measurePoints({corner + Eigen::Vector3d(1, 0, 0), corner, corner + Eigen::Vector3d(0.5, std::sqrt(3.0) / 2, 0)});
    // The coordinates themselves hold about 1e-9 m at UTM magnitudes, which is
    // 6e-8 degrees over a metre: the tolerance.
    EXPECT_NEAR(*sixty.angleDegrees, 60.0, 1e-6);
    // Nearly straight: still accurate (acos would lose it).
    const PointMeasurement straight = measurePoints({corner - Eigen::Vector3d(1, 0, 0), corner, corner + Eigen::Vector3d(1, 1e-5, 0)});
    EXPECT_NEAR(*straight.angleDegrees, 180.0 - std::atan(1e-5) * 180.0 / M_PI, 1e-6);
    // The triangle's area and perimeter come with it.
    EXPECT_NEAR(*right.area, 5.0, 1e-9);
    EXPECT_NEAR(*right.perimeter, 2.0 + 5.0 + std::sqrt(29.0), 1e-9);
}

TEST(Measurement, APolygonGetsItsAreaInItsOwnPlane)
{
    // An L-shaped window outline (concave) on a vertical façade at 30 degrees to X:
    // 4 x 3 m minus 2 x 1.5 m = 9 m^2.
    const Eigen::Vector3d u(std::cos(M_PI / 6), std::sin(M_PI / 6), 0), v(0, 0, 1);
    const double outline[6][2] = {{0, 0}, {4, 0}, {4, 1.5}, {2, 1.5}, {2, 3}, {0, 3}};
    std::vector<Eigen::Vector3d> points;
    for (const auto& q : outline)
        points.push_back(kUtm + q[0] * u + q[1] * v);
    const PointMeasurement m = measurePoints(points);
    ASSERT_TRUE(m.area && m.perimeter && m.normal);
    EXPECT_NEAR(*m.area, 9.0, 1e-9);
    EXPECT_NEAR(*m.perimeter, 4 + 1.5 + 2 + 1.5 + 2 + 3, 1e-9);
    EXPECT_NEAR(std::abs(m.normal->dot(u.cross(v))), 1.0, 1e-12);
    // The same points in the other order: the same area.
    std::reverse(points.begin(), points.end());
    EXPECT_NEAR(*measurePoints(points).area, 9.0, 1e-9);
    // Collinear points enclose nothing; fewer than two measure nothing.
    EXPECT_NEAR(*measurePoints({kUtm, kUtm + u, kUtm + 2 * u}).area, 0.0, 1e-9);
    EXPECT_EQ(measurePoints({kUtm}).pathLength, 0.0);
    EXPECT_EQ(measurePoints({}).pointCount, 0u);
}
