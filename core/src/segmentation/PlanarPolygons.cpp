// SPDX-License-Identifier: GPL-3.0-or-later
#include "PlanarPolygons.h"

#include <algorithm>
#include <cmath>

namespace scandiff::detail {

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

FootprintCells::FootprintCells(const std::vector<Polygon2d>& rings, const Eigen::Vector2d& low, double cell)
    : rings_(rings), low_(low), cell_(cell)
{
    // Every cell an edge passes through, found by walking the edge in quarter
    // cells and marking the 3 x 3 cells around each step (a step never skips
    // a cell the segment crosses).
    for (const Polygon2d& ring : rings_) {
        total_ += std::abs(signedArea(ring));
        for (std::size_t i = 0; i < ring.size(); ++i) {
            const Eigen::Vector2d a = ring[i], b = ring[(i + 1) % ring.size()];
            const int steps = 1 + static_cast<int>(4.0 * (b - a).norm() / cell_);
            for (int k = 0; k <= steps; ++k) {
                const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(k) / steps);
                const auto cx = static_cast<std::int64_t>(std::floor((p.x() - low_.x()) / cell_));
                const auto cy = static_cast<std::int64_t>(std::floor((p.y() - low_.y()) / cell_));
                for (std::int64_t dy = -1; dy <= 1; ++dy)
                    for (std::int64_t dx = -1; dx <= 1; ++dx)
                        nearEdge_.insert(key(cx + dx, cy + dy));
            }
        }
    }
}

bool FootprintCells::centreInside(std::int64_t cx, std::int64_t cy) const
{
    auto [it, fresh] = rowCrossings_.try_emplace(cy);
    std::vector<double>& xs = it->second;
    const double y = low_.y() + (static_cast<double>(cy) + 0.5) * cell_;
    if (fresh) {
        for (const Polygon2d& ring : rings_)
            for (std::size_t j = 0, k = ring.size() - 1; j < ring.size(); k = j++)
                if ((ring[j].y() > y) != (ring[k].y() > y))
                    xs.push_back(ring[k].x() + (y - ring[k].y()) * (ring[j].x() - ring[k].x()) / (ring[j].y() - ring[k].y()));
        std::sort(xs.begin(), xs.end());
    }
    const double x = low_.x() + (static_cast<double>(cx) + 0.5) * cell_;
    // Even-odd: inside when an odd number of crossings lie to the left.
    return (std::lower_bound(xs.begin(), xs.end(), x) - xs.begin()) % 2 == 1;
}

double FootprintCells::areaIn(std::int64_t cx, std::int64_t cy) const
{
    if (nearEdge_.count(key(cx, cy)) == 0)
        return centreInside(cx, cy) ? cell_ * cell_ : 0.0;
    const Eigen::Vector2d cellLow = low_ + cell_ * Eigen::Vector2d(static_cast<double>(cx), static_cast<double>(cy));
    const Eigen::Vector2d cellHigh = cellLow + Eigen::Vector2d::Constant(cell_);
    double area = 0.0;
    for (const Polygon2d& ring : rings_)
        area += areaInRectangle(ring, cellLow, cellHigh);
    return area;
}

} // namespace scandiff::detail
