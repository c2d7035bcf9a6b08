// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/geometry/PlanarRings.h>

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


} // namespace scandiff
