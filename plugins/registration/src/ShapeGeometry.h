// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What the alignments on shapes (PrimitiveAlignment.cpp, ShapeAlignment.cpp)
//! share: angles between unsigned directions, and the rotation taking
//! directions onto directions.

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <vector>

namespace scandiff::plugins::detail {

//! The angle between two lines (radians, 0 to pi/2): a direction's sign does not count.
inline double lineAngle(const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
    return std::acos(std::min(1.0, std::abs(a.dot(b))));
}

//! The proper rotation taking the `from` directions onto the `to` ones, each
//! weighted by `w` (all 1 when empty): Kabsch's SVD solution.
inline Eigen::Matrix3d rotationBetween(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to,
                                       const std::vector<double>& w = {})
{
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    for (std::size_t k = 0; k < from.size(); ++k)
        h += (w.empty() ? 1.0 : w[k]) * from[k] * to[k].transpose();
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
    d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
    return svd.matrixV() * d * svd.matrixU().transpose();
}

} // namespace scandiff::plugins::detail
