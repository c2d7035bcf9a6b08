// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Closed 2D rings (outlines, footprints, polygons drawn on screen): their
//! signed area and whether a point lies inside. The last vertex joins the first.

#include <Eigen/Core>

#include <vector>

namespace scandiff {

//! Shoelace area, positive when counter-clockwise; summed about the first
//! vertex, so rings far from the origin keep their precision.
double signedArea(const std::vector<Eigen::Vector2d>& ring);

//! Even-odd crossing test; a point on the boundary may go either way.
bool containsPoint(const std::vector<Eigen::Vector2d>& ring, const Eigen::Vector2d& p);

} // namespace scandiff
