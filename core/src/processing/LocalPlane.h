// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The least-squares plane of a point's neighbourhood given as offsets from
//! the point (internal to core: normals and local features).

#include "geometry/PrincipalAxes.h"

#include <vector>

namespace scandiff::detail {

//! A neighbourhood whose second principal variance is below this fraction of
//! the largest is a line (spread across it under a thousandth of its length):
//! it fixes no plane. Well above the rounding of the closed-form eigenvalues
//! (about 1e-8 of the largest on a rank-one matrix).
constexpr double kLineThreshold = 1e-6;

struct LocalPlane
{
    Eigen::Vector3d normal;  //!< unit, its side arbitrary
    Eigen::Vector3d mean;    //!< the offsets' centroid
    Eigen::Vector3d values;  //!< principal variances (sums of squares), increasing
};

//! The plane of offsets[first..]; false when they fix none (fewer than 3, or a
//! line). Offsets from the point keep the cloud's magnitude out of the squares.
inline bool fitLocalPlane(const std::vector<Eigen::Vector3d>& offsets, std::size_t first, LocalPlane& plane)
{
    if (offsets.size() < first + 3)
        return false;
    const auto n = static_cast<double>(offsets.size() - first);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d products = Eigen::Matrix3d::Zero();
    for (std::size_t j = first; j < offsets.size(); ++j) {
        sum += offsets[j];
        products.noalias() += offsets[j] * offsets[j].transpose();
    }
    plane.mean = sum / n;
    Eigen::Vector3d smallest, largest;
    principalAxes(products - sum * plane.mean.transpose(), plane.values, smallest, largest);
    if (!(plane.values[2] > 0) || !(plane.values[1] > kLineThreshold * plane.values[2]) || !smallest.allFinite())
        return false;
    plane.normal = smallest.normalized();
    return true;
}

} // namespace scandiff::detail
