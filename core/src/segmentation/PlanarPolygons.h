// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Small exact computations on closed 2D polygons (the region outlines): area,
//! and the area of a polygon inside an axis-aligned rectangle, which weighs
//! each column of the 2.5D volume grid by the part of it inside the footprint.

#include <scandiff/core/geometry/PlanarRings.h>
#include <scandiff/core/segmentation/RegionReport.h>

#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace scandiff::detail {

//! The area of `ring` (a simple polygon, either orientation) inside the
//! rectangle [lo, hi]: the ring clipped by the rectangle's four half-planes
//! (Sutherland-Hodgman, exact for a convex clipping window even when the ring
//! is concave: the cut pieces are joined by zero-area edges along the window).
double areaInRectangle(const Polygon2d& ring, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi);

//! The area of each cell of a grid inside a set of disjoint rings (the
//! footprint), for many cells at once: a cell no ring edge comes near lies
//! wholly inside or outside, decided by its centre against its row's
//! crossings; only the cells along the edges are clipped exactly
//! (areaInRectangle). Linear in cells plus perimeter, where clipping every
//! cell would cost cells x vertices.
class FootprintCells
{
public:
    //! Cells of side `cell`, cell (0, 0) with its low corner at `low`.
    FootprintCells(const std::vector<Polygon2d>& rings, const Eigen::Vector2d& low, double cell);
    double areaIn(std::int64_t cx, std::int64_t cy) const;
    //! The rings' total area.
    double totalArea() const { return total_; }

private:
    bool centreInside(std::int64_t cx, std::int64_t cy) const;
    //! Shifted as unsigned: a left shift of a negative signed value is undefined.
    static std::int64_t key(std::int64_t cx, std::int64_t cy)
    {
        return static_cast<std::int64_t>((static_cast<std::uint64_t>(cy) << 32) ^ (static_cast<std::uint64_t>(cx) & 0xffffffffu));
    }

    const std::vector<Polygon2d>& rings_;
    Eigen::Vector2d low_;
    double cell_;
    double total_ = 0.0;
    std::unordered_set<std::int64_t> nearEdge_;
    mutable std::unordered_map<std::int64_t, std::vector<double>> rowCrossings_;
};

} // namespace scandiff::detail
