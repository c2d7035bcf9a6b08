// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The parameters of the cloud-to-cloud, cloud-to-mesh and M3C2 distances, declared
//! once for every front end: `scandiff-cli c2c`/`c2m` turn them into options,
//! the workbench into its distance dialogs. The defaults are those of
//! CloudToCloudParams / CloudToMeshParams, read from the structs themselves.

#include <scandiff/core/ToolRegistry.h>
#include <scandiff/core/distance/CloudToCloud.h>
#include <scandiff/core/distance/CloudToMesh.h>
#include <scandiff/core/distance/M3C2.h>

#include <vector>

namespace scandiff {

//! max-dist, clamp, model, knn, radius, split-xyz, signed, closest-points,
//! both-ways, visibility, sensor, sensor-step, sensor-fov, sensor-range,
//! visibility-tolerance, octree-level.
const std::vector<ParameterSpec>& cloudToCloudParameters();

//! The computation's settings from resolved values. `reference` provides the
//! sensor poses stored in its file when `visibility` is on and no `sensor` is
//! given. Throws Error(InvalidArgument) for inconsistent values (clamp without
//! max-dist, visibility without any viewpoint, a malformed sensor text).
//! When `radius` is given it replaces `knn`.
CloudToCloudParams cloudToCloudSettings(const ParameterValues& values, const PointCloud& reference);

//! Whether the run also computes reference -> compared (`both-ways`).
bool cloudToCloudBothWays(const ParameterValues& values);

//! One run of `c2c` as every front end does it: compared -> reference and, with
//! `both-ways`, reference -> compared (with the compared scan's own sensor
//! poses for the visibility test, and no closest points).
struct CloudToCloudRun
{
    CloudToCloudParams params;
    CloudToCloudResult forward;                //!< fields for the compared cloud
    std::optional<CloudToCloudResult> reverse; //!< fields for the reference, with both-ways
};
CloudToCloudRun runCloudToCloud(const PointCloud& compared, const PointCloud& reference, const ParameterValues& values,
                                ProgressObserver* progress = nullptr);

//! signed, max-dist, clamp, octree-level.
const std::vector<ParameterSpec>& cloudToMeshParameters();
CloudToMeshParams cloudToMeshSettings(const ParameterValues& values);

//! normal-scale, normal-scales, projection-scale, max-depth,
//! registration-error, min-points, core-spacing, orientation, robust,
//! sample-std, raster-cell: the m3c2 tool's, and scandiff-mpi m3c2's.
const std::vector<ParameterSpec>& m3c2Parameters();
//! The computation's settings (core-spacing and raster-cell are the tool's:
//! which core points, and what it makes of the result). Throws
//! Error(InvalidArgument) for a malformed normal-scales or orientation.
M3c2Params m3c2Settings(const ParameterValues& values);

//! A viewpoint from "X,Y,Z[,HEADING,PITCH,ROLL]" (degrees; heading about Z, then
//! pitch about Y, then roll about X) with optional angular step "DEG" or
//! "YAWDEG,PITCHDEG", field of view "YAWMIN,YAWMAX,PITCHMIN,PITCHMAX" (degrees)
//! and maximum range (m, <= 0: none). Throws Error(InvalidArgument).
SensorPose parseSensorPose(const std::string& pose, const std::string& step, const std::string& fieldOfView, double range);

} // namespace scandiff
