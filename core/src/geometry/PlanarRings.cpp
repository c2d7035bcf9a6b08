// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/geometry/PlanarRings.h>

#include <algorithm>

namespace scandiff {

double signedArea(const std::vector<Eigen::Vector2d>& ring)
{
    double twice = 0.0;
    for (std::size_t i = 0, n = ring.size(); i < n; ++i) {
        const Eigen::Vector2d a = ring[i] - ring[0], b = ring[(i + 1) % n] - ring[0];
        twice += a.x() * b.y() - b.x() * a.y();
    }
    return 0.5 * twice;
}

bool containsPoint(const std::vector<Eigen::Vector2d>& ring, const Eigen::Vector2d& p)
{
    bool inside = false;
    for (std::size_t i = 0, n = ring.size(), j = n - 1; i < n; j = i++) {
        const Eigen::Vector2d& a = ring[i];
        const Eigen::Vector2d& b = ring[j];
        if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < b.x() + (p.y() - b.y()) * (a.x() - b.x()) / (a.y() - b.y()))
            inside = !inside;
    }
    return inside;
}

namespace {

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b)
{
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

bool withinBox(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& q)
{
    return q.x() >= std::min(a.x(), b.x()) && q.x() <= std::max(a.x(), b.x()) && q.y() >= std::min(a.y(), b.y()) &&
           q.y() <= std::max(a.y(), b.y());
}

//! Closed segments ab and cd share a point (orientation tests; collinear
//! pieces that overlap or touch count).
bool segmentsMeet(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, const Eigen::Vector2d& d)
{
    const double d1 = cross(c, d, a), d2 = cross(c, d, b), d3 = cross(a, b, c), d4 = cross(a, b, d);
    if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
        return true;
    return (d1 == 0 && withinBox(c, d, a)) || (d2 == 0 && withinBox(c, d, b)) || (d3 == 0 && withinBox(a, b, c)) ||
           (d4 == 0 && withinBox(a, b, d));
}

} // namespace

bool crossesItself(const std::vector<Eigen::Vector2d>& ring)
{
    const std::size_t n = ring.size();
    if (n < 3)
        return false;
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector2d &a = ring[i], &b = ring[(i + 1) % n], &c = ring[(i + 2) % n];
        // Neighbouring edges share b; they fold back when c turns straight back along ab.
        if (cross(a, b, c) == 0 && (b - a).dot(c - b) < 0)
            return true;
        for (std::size_t j = i + 2; j < n; ++j) {
            if (i == 0 && j == n - 1)
                continue; // the closing edge neighbours the first
            if (segmentsMeet(a, b, ring[j], ring[(j + 1) % n]))
                return true;
        }
    }
    return false;
}

} // namespace scandiff
