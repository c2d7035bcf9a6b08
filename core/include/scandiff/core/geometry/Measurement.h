// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What a surveyor reads off points picked in the view: for two points their
//! distance and its components (ΔX, ΔY, ΔZ, horizontal distance, slope); for
//! three, the angle at the middle one; for three or more, the area and
//! perimeter of the polygon they outline. Global coordinates in, double
//! precision throughout.

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace scandiff {

struct PointMeasurement
{
    std::size_t pointCount = 0;
    //! Length of the path through the points in order (two points: their distance).
    double pathLength = 0.0;
    //! Last point minus first (ΔX, ΔY, ΔZ).
    Eigen::Vector3d delta = Eigen::Vector3d::Zero();
    double horizontalDistance = 0.0; //!< of the first and last points
    //! Slope of first -> last above the horizontal, degrees (-90..90).
    double slopeDegrees = 0.0;
    //! Three points: the angle at the second between the other two, degrees (0..180).
    std::optional<double> angleDegrees;
    //! Three or more: the polygon closed from the last point back to the first.
    //! Its area is that of its projection on its best plane, taken with
    //! Newell's vector (exact for a planar polygon, convex or not), m^2.
    std::optional<double> area;
    std::optional<double> perimeter;
    //! Unit normal of that plane (its Newell vector), when the area is not 0.
    std::optional<Eigen::Vector3d> normal;
};

//! Throws nothing; fewer than two points give only pointCount.
PointMeasurement measurePoints(const std::vector<Eigen::Vector3d>& points);

} // namespace scandiff
