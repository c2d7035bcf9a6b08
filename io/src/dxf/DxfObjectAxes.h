// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The object coordinate system of a DXF entity from its extrusion direction
// (DXF Reference, "Arbitrary Axis Algorithm"): what the writer puts a
// polyline with arcs in, and what the reader rebuilds from 210/220/230.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>

namespace scandiff::io::detail {

//! Columns: the object x, y and z axes in world coordinates; `normal` unit.
inline Eigen::Matrix3d dxfObjectAxes(const Eigen::Vector3d& normal)
{
    const bool nearZ = std::abs(normal.x()) < 1.0 / 64 && std::abs(normal.y()) < 1.0 / 64;
    const Eigen::Vector3d ax = (nearZ ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ()).cross(normal).normalized();
    Eigen::Matrix3d axes;
    axes.col(0) = ax;
    axes.col(1) = normal.cross(ax).normalized();
    axes.col(2) = normal;
    return axes;
}

} // namespace scandiff::io::detail
