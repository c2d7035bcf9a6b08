// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A detected shape's surface as a mesh, for the workbench to draw: the part
//! of the shape its inliers cover, not the unbounded plane or cylinder.

#include <scandiff/core/Mesh.h>
#include <scandiff/core/PointCloud.h>
#include <scandiff/core/geometry/Primitives.h>

#include <cstdint>
#include <vector>

namespace scandiff::plugins {

//! The surface is unrolled onto a grid of its own coordinates (a plane's two
//! axes; angle and height on a cylinder or a cone; longitude and colatitude on
//! a sphere; the two angles of a torus) whose cells measure about `cellSize`
//! metres on the surface. The cells holding an inlier are kept, one-cell gaps
//! are closed (a dilation then an erosion, as the plane outlines close them),
//! and each cell becomes two triangles whose corners lie exactly on the
//! surface; neighbouring cells share their corners, around a closed surface
//! too. Vertices in `cloud`'s frame (its origin). Grids are capped at 2048
//! cells a side (a coarser cell beyond). Throws Error(InvalidArgument) for
//! cellSize <= 0.
Mesh shapeSurface(const Primitive& primitive, const PointCloud& cloud, const std::vector<std::uint32_t>& inliers, double cellSize);

//! The cell shapeSurface and the plane outlines use for a shape: 1.5 times the
//! median spacing of its inliers (outlineCellFor).
double shapeCellSize(const PointCloud& cloud, const std::vector<std::uint32_t>& inliers);

} // namespace scandiff::plugins
