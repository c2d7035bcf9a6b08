// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The call into CGAL's region growing on point sets (internal to the
//! plugin): its headers stay in RegionGrowing.cpp.

#include "EfficientRansac.h"

#include <scandiff/octree/Octree.h>

#include <functional>

namespace scandiff::plugins::detail {

struct RegionGrowingSettings
{
    double epsilon = 0.01;         //!< largest distance of a point to its region's plane (m)
    double normalDegrees = 25;     //!< largest angle between a point's normal and its region's plane (deg)
    double neighbourRadius = 0.1;  //!< a region grows to the points within this distance of its points (m)
    std::size_t minPoints = 200;   //!< smallest region kept
};

//! Planar regions grown from the flattest points first (CGAL's
//! Least_squares_plane_fit_sorting: seeds in order of their neighbourhood's
//! planarity), each point joining the region of a neighbour when it lies
//! within epsilon of the region's least-squares plane and its normal within
//! the angle. Deterministic: no random draw. The neighbours (the 32 nearest
//! within the radius at most) come from `tree`, the octree of the same points
//! (its own float coordinates): exact, and already built, where CGAL's sphere query would build a kd-tree of its
//! own (a second of silence on a million points, Cancel unheard). `keepGoing`
//! is asked every few thousand neighbour queries; false stops the run (the
//! result is then empty).
std::vector<RansacShape> growPlanarRegions(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals,
                                           const octree::Octree& tree, const RegionGrowingSettings& settings,
                                           const std::function<bool()>& keepGoing);

} // namespace scandiff::plugins::detail
