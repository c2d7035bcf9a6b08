// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Drawing.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace scandiff {

std::vector<Eigen::Vector3d> polylineVertices(const DrawingPolyline& polyline, double stepDegrees)
{
    const std::vector<Eigen::Vector3d>& p = polyline.points;
    if (polyline.bulges.size() != p.size() || !(polyline.normal.norm() > 0) || !(stepDegrees > 0))
        return p;
    const Eigen::Vector3d normal = polyline.normal.normalized();
    std::vector<Eigen::Vector3d> out;
    const std::size_t segments = polyline.closed ? p.size() : p.size() - 1;
    for (std::size_t i = 0; i < p.size(); ++i) {
        out.push_back(p[i]);
        const double bulge = polyline.bulges[i];
        if (i >= segments || bulge == 0.0 || !std::isfinite(bulge))
            continue;
        const Eigen::Vector3d& a = p[i];
        const Eigen::Vector3d& b = p[(i + 1) % p.size()];
        const Eigen::Vector3d chord = b - a;
        const double length = chord.norm();
        if (length == 0.0)
            continue;
        // The centre lies on the chord's bisector, on its left for a
        // counter-clockwise arc under a half turn (the signed offset below
        // moves it right past a half turn, or for a clockwise arc).
        const double angle = 4.0 * std::atan(bulge);
        const Eigen::Vector3d left = normal.cross(chord / length);
        const Eigen::Vector3d centre = 0.5 * (a + b) + left * (0.5 * length / std::tan(0.5 * angle));
        const double radius = (a - centre).norm();
        const Eigen::Vector3d u = (a - centre) / radius, v = normal.cross(u);
        const int steps = static_cast<int>(std::clamp(std::ceil(std::abs(angle) * 180.0 / 3.14159265358979323846 / stepDegrees), 1.0, 100000.0));
        for (int s = 1; s < steps; ++s) {
            const double t = angle * s / steps;
            out.push_back(centre + radius * (std::cos(t) * u + std::sin(t) * v));
        }
    }
    return out;
}

} // namespace scandiff
