// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The call into CGAL's region growing on point sets (internal to the
//! plugin): its headers stay in RegionGrowing.cpp.

#include "EfficientRansac.h"

#include <scandiff/octree/Octree.h>

#include <functional>
#include <optional>

namespace scandiff::plugins::detail {

struct RegionGrowingSettings
{
    double epsilon = 0.01;         //!< largest distance of a point to its region's plane (m)
    double normalDegrees = 25;     //!< largest angle between a point's normal and its region's plane (deg)
    double neighbourRadius = 0.1;  //!< a region grows to the points within this distance of its points (m)
    std::size_t minPoints = 200;   //!< smallest region kept
    //! Smooth regions: largest angle between the normals of two neighbours of a region (deg).
    double smoothnessDegrees = 20;
    //! Smooth regions: a point whose surface variation is above this joins a
    //! region but does not spread it (an edge stops it); absent: 2 x the median.
    std::optional<double> curvature;
    //! Regions on a value (intensity): largest variance of a region's values; absent: 4 x the median of the discs'.
    std::optional<double> tolerance;
};

//! What a grower reports besides its regions: the thresholds it chose.
struct GrowingOutcome
{
    std::vector<RansacShape> regions; //!< members only (initialShape gives each a first shape)
    double curvature = 0, tolerance = 0;
};

//! Smooth regions (Rabbani, van den Heuvel, Vosselman 2006; the rule of PCL's
//! RegionGrowing): seeds in order of increasing surface variation (the
//! smallest eigenvalue of the neighbourhood's covariance over their sum); a
//! neighbour joins when its normal is within the smoothness angle of the
//! point that reached it and it lies within epsilon of that point's tangent
//! plane (PCL's residual test), and spreads the region further only when its own
//! variation is below the curvature threshold, so a region follows a plane, a
//! pipe or a sphere and stops at edges. Unoriented normals. Regions smaller
//! than minPoints are dropped. Deterministic (ties by index). The normals
//! compared are each point's at the growing scale (the least-squares plane of
//! the same neighbours whose variation is its curvature), not the cloud's: on
//! the 15-shape test scene (5 mm of noise, 4 cm spacing) neighbours' normals
//! fitted within 2.5 spacings differ by 8.4° (median; 26° at the 90th
//! percentile), these by 4.9° (12°), so a plane is not broken by its own
//! noise; `normals` serve points with fewer than 3 neighbours. Written here
//! rather than through PCL's RegionGrowing: that one searches each point's
//! neighbours through FLANN one at a time, where the octree's batch query
//! gives them all at once, as for the planar growing.
GrowingOutcome growSmoothRegions(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals,
                                 const octree::Octree& tree, const RegionGrowingSettings& settings, const std::function<bool()>& keepGoing);

//! Thesis 003 §3.2's region growing on a value (the intensity), made
//! deterministic and leak-proof as the stones tool does: seeds in order of
//! increasing variance of the values within `radius` (a seed whose disc
//! varies more than the tolerance starts nothing); a region grows through
//! discs of that radius, a point joining while the region's variance with it
//! stays below the tolerance and its value lies within 3 sqrt(tolerance) of
//! the region's mean. Points without a finite value join nothing.
GrowingOutcome growValueRegions(const std::vector<Eigen::Vector3d>& points, const std::vector<float>& values, const octree::Octree& tree,
                                double radius, const RegionGrowingSettings& settings, const std::function<bool()>& keepGoing);

//! A first shape for a region of any form: a cylinder whose axis is the
//! direction its normals are all across (the smallest eigenvector of the sum
//! of n n^T) and whose section is the circle through the points projected
//! along it, when the normals turn (their second eigenvalue is above 5 % of
//! the sum); else its least-squares plane. The caller refits it and tries a
//! plane and a sphere against it.
Primitive initialShape(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals,
                       const std::vector<std::uint32_t>& members);

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
