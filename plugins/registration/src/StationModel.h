// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What the multi-station adjustment's two halves share (Stations.cpp finds
//! and checks the pairs, StationAdjustment.cpp adjusts every pose jointly):
//! a station, its points matched on another's surface, the size of a motion.

#include "ReferenceSurface.h"

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/distance/Visibility.h>
#include <scandiff/plugins/registration/Stations.h>

#include <Eigen/Geometry>

#include <memory>
#include <optional>
#include <vector>

namespace scandiff::plugins::detail {

//! One station: its cloud, the surface others are matched on, and its
//! sampled points in station coordinates relative to the world origin.
struct Station
{
    const PointCloud* cloud = nullptr;
    std::unique_ptr<ReferenceSurface> surface;
    std::vector<Eigen::Vector3d> sample;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero(); //!< of the sample, world-relative station coordinates
    std::unique_ptr<DepthMap> view; //!< what the scanner saw, when the cloud holds its one sensor pose
    std::optional<Eigen::Vector3d> scanner; //!< its centre, world-relative station coordinates, with the view
    Eigen::Vector3d up = Eigen::Vector3d::UnitZ(); //!< the scanner's vertical in the station's coordinates
};

//! A pair's correspondences one way: points of `from` matched on `on`'s surface.
struct Matched
{
    std::vector<Eigen::Vector3d> x, q, n; //!< world-relative, station 0's frame
    std::vector<double> residual, distance;
};

//! The first `limit` sampled points of `from` (posed) matched on the surface
//! of `on` (posed), each on the side its scanner saw.
void match(const Station& from, const Eigen::Isometry3d& fromPose, const Station& on, const Eigen::Isometry3d& onPose,
           const Eigen::Vector3d& worldOrigin, std::size_t limit, Matched& m);

//! The displacement a motion gives a point, and its angle.
void motionSize(const Eigen::Matrix4d& m, const Eigen::Vector3d& at, double& degrees, double& metres);

//! What the joint adjustment leaves: every pose (world-relative, station 0's
//! frame), each used pair's sums of squared residuals, the last iteration's
//! residuals.
struct JointAdjustment
{
    std::vector<Eigen::Isometry3d> pose;
    std::vector<double> pairSquares, pairCount;
    std::vector<double> finalResiduals;
};

//! Every pose adjusted at once on the used pairs' point-to-plane residuals,
//! from the chained poses: Gauss-Newton with Cauchy weights whose scale
//! narrows from a third of the maximum distance to the residuals' own.
//! Fills the report's trace, iterations, convergence and the directions a
//! station's overlaps leave free (its degeneracy).
JointAdjustment adjustJointly(const std::vector<Station>& stations, const std::vector<StationPair>& pairs,
                              const std::vector<Eigen::Matrix4d>& chain, const StationParams& params,
                              const Eigen::Vector3d& worldOrigin, RegistrationReport& report, ProgressObserver* progress);

} // namespace scandiff::plugins::detail
