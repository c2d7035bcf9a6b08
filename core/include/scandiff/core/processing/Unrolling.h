// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Unrolling a cloud about a cylinder or a cone into a plane (thesis 000
//! annex C and §5.3.2, "développement": the cooling tower compared on its
//! unrolled surface), and rolling it back.
//!
//! The frame: the surface's axis w, a reference direction e1 across it (the
//! global X axis projected across the axis, or Y when X is nearly along it)
//! turned by the start angle, and e2 = w x e1; a point's angle theta runs from
//! 0 to 360 degrees about w from e1.
//! - Cylinder of radius R: x = R theta (the arc length on the surface),
//!   y = the height along the axis, z = the radial deviation (distance to the
//!   axis minus R).
//! - Cone of apex A and half-angle a: the surface develops into a sector of
//!   angle 2 pi sin(a); a point at distance s from the apex along its
//!   generator and angle theta goes to x = s cos(phi), y = s sin(phi) with
//!   phi = theta sin(a), and z = its signed distance to the cone.
//! Rolling back with the same surface and start angle gives the points back
//! (to float rounding).

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/geometry/Primitives.h>

namespace scandiff {

namespace fields {
//! The signed deviation from the surface (outside positive), in metres.
inline constexpr const char* kUnrollDeviation = "unroll_deviation";
//! The angle about the axis from the reference direction, in degrees [0, 360).
inline constexpr const char* kUnrollAngle = "unroll_angle";
} // namespace fields

//! The unrolled cloud (every attribute kept, in input order; normals
//! dropped: they would need unrolling too) with the two fields above. Throws
//! Error(InvalidArgument) for a surface that is not a cylinder or a cone.
PointCloud unrollCloud(const PointCloud& cloud, const Primitive& surface, double startAngleDegrees = 0,
                       ProgressObserver* progress = nullptr);

//! The inverse: an unrolled cloud (x, y, z as above, global) back onto the surface.
PointCloud rollCloud(const PointCloud& unrolled, const Primitive& surface, double startAngleDegrees = 0,
                     ProgressObserver* progress = nullptr);

} // namespace scandiff
