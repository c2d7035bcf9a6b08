// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Pose and angular grid of a terrestrial scanner station, as needed to build its
//! depth map (thesis 000 §2.3.3). Angles in radians, positions in global coordinates.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <limits>

namespace scandiff {

struct SensorPose
{
    Eigen::Vector3d position = Eigen::Vector3d::Zero();        //!< scanner centre (global)
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity(); //!< scanner frame -> world
    double yawStep = 0.0;   //!< horizontal angular step (rad), 0 = unknown
    double pitchStep = 0.0; //!< vertical angular step (rad), 0 = unknown
    double yawMin = -M_PI, yawMax = M_PI;           //!< horizontal field of view
    double pitchMin = -M_PI / 2, pitchMax = M_PI / 2; //!< vertical field of view
    double maxRange = std::numeric_limits<double>::infinity(); //!< metres
};

} // namespace scandiff
