// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The least-squares plane of a point's neighbourhood given as offsets from
//! the point (internal to core: normals and local features).

#include "geometry/PrincipalAxes.h"

#include <scandiff/octree/Octree.h>

#include <algorithm>

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

//! The plane of a neighbourhood given by its moments (offsets from its point);
//! `excludeCentre` leaves the point itself out (its offset is zero: one fewer
//! point). False when they fix none (fewer than 3 points, or a line).
inline bool fitLocalPlane(const octree::NeighbourhoodMoments& m, bool excludeCentre, LocalPlane& plane)
{
    const double n = static_cast<double>(m.count) - (excludeCentre ? 1.0 : 0.0);
    if (n < 3)
        return false;
    const Eigen::Vector3d& sum = m.sum;
    plane.mean = sum / n;
    Eigen::Matrix3d covariance;
    covariance(0, 0) = m.products[0] - sum.x() * plane.mean.x();
    covariance(1, 0) = covariance(0, 1) = m.products[1] - sum.x() * plane.mean.y();
    covariance(2, 0) = covariance(0, 2) = m.products[2] - sum.x() * plane.mean.z();
    covariance(1, 1) = m.products[3] - sum.y() * plane.mean.y();
    covariance(2, 1) = covariance(1, 2) = m.products[4] - sum.y() * plane.mean.z();
    covariance(2, 2) = m.products[5] - sum.z() * plane.mean.z();
    Eigen::Vector3d smallest, largest;
    principalAxes(covariance, plane.values, smallest, largest);
    if (!(plane.values[2] > 0) || !(plane.values[1] > kLineThreshold * plane.values[2]) || !smallest.allFinite())
        return false;
    plane.normal = smallest.normalized();
    return true;
}

//! The plane of offsets[first..]. Offsets from the point keep the cloud's
//! magnitude out of the squares.
inline bool fitLocalPlane(const std::vector<Eigen::Vector3d>& offsets, std::size_t first, LocalPlane& plane)
{
    octree::NeighbourhoodMoments m;
    for (std::size_t j = first; j < offsets.size(); ++j)
        m.add(offsets[j]);
    return fitLocalPlane(m, false, plane);
}

//! The plane of the listed points (the centre among them), from their offsets
//! to `centre`, without copying them first.
inline bool fitLocalPlane(const Eigen::Vector3f* positions, const Eigen::Vector3f& centre, const octree::Neighbour* list,
                          std::size_t count, LocalPlane& plane)
{
    octree::NeighbourhoodMoments m;
    for (std::size_t j = 0; j < count; ++j)
        m.add((positions[list[j].index] - centre).cast<double>());
    return fitLocalPlane(m, false, plane);
}

} // namespace scandiff::detail
