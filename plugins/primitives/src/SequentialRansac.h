// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Sequential RANSAC for façades (thesis 001 §3.4, internal to the plugin):
//! planes extracted one after the other, each class of orientation in the
//! thesis's order, each plane kept as the largest connected region of its
//! inliers (the rest re-injected), refitted by PCA.

#include "EfficientRansac.h"

#include <scandiff/octree/Octree.h>

#include <functional>
#include <string>

namespace scandiff::plugins::detail {

struct SequentialSettings
{
    double distance = 0.025;          //!< ds: largest distance of an inlier to its plane (m)
    double pixel = 0.05;              //!< side of the connectivity raster's pixels (m)
    double toleranceDegrees = 1.0;    //!< a plane's normal within this angle of its class's axis (thesis: 1°)
    std::size_t minPoints = 200;      //!< smallest plane kept (points)
    double probability = 0.99;        //!< P: chance of drawing at least one sample of inliers
    std::uint64_t seed = 0;
};

struct SequentialOutcome
{
    std::vector<RansacShape> planes;  //!< in the order found
    Eigen::Vector3d facadeNormal = Eigen::Vector3d::UnitY(); //!< horizontal, the Y axis of the thesis's frame
    std::vector<std::string> notes;
};

//! `points` in a local frame whose z is up (world z); `tree` the octree of the
//! same points (float). Classes, in the thesis's order (§3.4.5.2): vertical
//! planes perpendicular to the façade (normal along X), horizontal planes
//! (normal along Z), every other orientation, then planes parallel to the
//! façade (normal along Y); the façade's direction is the normal of the
//! largest vertical plane. Deterministic for a seed, whatever the threads.
//! `keepGoing` is asked between batches of hypotheses; false stops (the result is then empty).
SequentialOutcome sequentialPlanes(const std::vector<Eigen::Vector3d>& points, const octree::Octree& tree,
                                   const SequentialSettings& settings, const std::function<bool()>& keepGoing);

} // namespace scandiff::plugins::detail
