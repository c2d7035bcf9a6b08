// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Small exact computations on closed 2D polygons (the region outlines): area,
//! and the area of a polygon inside an axis-aligned rectangle, which weighs
//! each column of the 2.5D volume grid by the part of it inside the footprint.

#include <scandiff/core/segmentation/RegionReport.h>

namespace scandiff::detail {

//! Shoelace area: positive when counter-clockwise.
double signedArea(const Polygon2d& ring);

//! The area of `ring` (a simple polygon, either orientation) inside the
//! rectangle [lo, hi]: the ring clipped by the rectangle's four half-planes
//! (Sutherland-Hodgman, exact for a convex clipping window even when the ring
//! is concave: the cut pieces are joined by zero-area edges along the window).
double areaInRectangle(const Polygon2d& ring, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi);

} // namespace scandiff::detail
