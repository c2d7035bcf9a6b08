// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/geometry/Measurement.h>

#include <Eigen/Geometry>

#include <cmath>

namespace scandiff {

namespace {
constexpr double kDegrees = 180.0 / 3.14159265358979323846;
} // namespace

PointMeasurement measurePoints(const std::vector<Eigen::Vector3d>& points)
{
    PointMeasurement m;
    m.pointCount = points.size();
    if (points.size() < 2)
        return m;
    // Differences are taken from the first point, so UTM magnitudes cancel before any product.
    const Eigen::Vector3d origin = points.front();
    for (std::size_t i = 1; i < points.size(); ++i)
        m.pathLength += (points[i] - points[i - 1]).norm();
    m.delta = points.back() - origin;
    m.horizontalDistance = m.delta.head<2>().norm();
    m.slopeDegrees = std::atan2(m.delta.z(), m.horizontalDistance) * kDegrees;
    if (points.size() == 3) {
        const Eigen::Vector3d a = points[0] - points[1], b = points[2] - points[1];
        // atan2 of |a x b| and a . b: accurate for angles near 0 and 180 as well.
        m.angleDegrees = std::atan2(a.cross(b).norm(), a.dot(b)) * kDegrees;
    }
    if (points.size() >= 3) {
        Eigen::Vector3d newell = Eigen::Vector3d::Zero();
        double perimeter = 0.0;
        for (std::size_t i = 0; i < points.size(); ++i) {
            const Eigen::Vector3d p = points[i] - origin, q = points[(i + 1) % points.size()] - origin;
            newell += p.cross(q);
            perimeter += (q - p).norm();
        }
        m.area = 0.5 * newell.norm();
        m.perimeter = perimeter;
        if (newell.norm() > 0)
            m.normal = newell.normalized();
    }
    return m;
}

} // namespace scandiff
