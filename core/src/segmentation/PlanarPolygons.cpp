// SPDX-License-Identifier: GPL-3.0-or-later
#include "PlanarPolygons.h"

#include <cmath>

namespace scandiff::detail {

double signedArea(const Polygon2d& ring)
{
    double twice = 0.0;
    for (std::size_t i = 0; i < ring.size(); ++i) {
        const Eigen::Vector2d& p = ring[i];
        const Eigen::Vector2d& q = ring[(i + 1) % ring.size()];
        twice += p.x() * q.y() - q.x() * p.y();
    }
    return 0.5 * twice;
}

namespace {

//! Keeps the part of `in` where coordinate `axis` is >= bound (keepAbove) or <= bound.
Polygon2d clipHalfPlane(const Polygon2d& in, int axis, double bound, bool keepAbove)
{
    Polygon2d out;
    if (in.empty())
        return out;
    auto inside = [&](const Eigen::Vector2d& p) { return keepAbove ? p[axis] >= bound : p[axis] <= bound; };
    Eigen::Vector2d previous = in.back();
    bool previousInside = inside(previous);
    for (const Eigen::Vector2d& current : in) {
        const bool currentInside = inside(current);
        if (currentInside != previousInside) {
            const double t = (bound - previous[axis]) / (current[axis] - previous[axis]);
            Eigen::Vector2d crossing = previous + t * (current - previous);
            crossing[axis] = bound; // exactly on the line, whatever the rounding
            out.push_back(crossing);
        }
        if (currentInside)
            out.push_back(current);
        previous = current;
        previousInside = currentInside;
    }
    return out;
}

} // namespace

double areaInRectangle(const Polygon2d& ring, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi)
{
    Polygon2d clipped = clipHalfPlane(ring, 0, lo.x(), true);
    clipped = clipHalfPlane(clipped, 0, hi.x(), false);
    clipped = clipHalfPlane(clipped, 1, lo.y(), true);
    clipped = clipHalfPlane(clipped, 1, hi.y(), false);
    return std::abs(signedArea(clipped));
}

} // namespace scandiff::detail
