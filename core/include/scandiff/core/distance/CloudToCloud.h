// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Cloud-to-cloud distance (thesis 000 §2.3): for every point of the compared
//! cloud, its distance to the reference cloud.
//!
//! - Nearest-neighbour distance (§2.3.1), exact, through the octree's batch
//!   query on a cube shared by both clouds.
//! - Optional local model of the reference near each compared point (§2.3.2):
//!   least-squares plane, 2.5D Delaunay triangulation on that plane, or a
//!   quadric height function over it, fitted on the point's k nearest reference
//!   points (the first being its nearest neighbour) or on the reference points
//!   within a radius of its nearest neighbour. Two samplings of one surface are at
//!   NN distance ~1/sqrt(pi*lambda) RMS (eq. 2.5); a local model removes that bias.
//! - Optional visibility (§2.3.3, Algorithm 3): with reference viewpoints, each
//!   compared point is labelled visible / hidden / out of range / out of field,
//!   and only visible points get a distance.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/SensorPose.h>
#include <scandiff/core/distance/DistanceStatistics.h>
#include <scandiff/core/distance/Visibility.h>

#include <optional>
#include <string>
#include <vector>

namespace scandiff {

enum class LocalModel { None, Plane, Delaunay, Quadric };

//! "none", "plane", "delaunay", "quadric"; throws Error(InvalidArgument) otherwise.
LocalModel parseLocalModel(const std::string& name);
const char* localModelName(LocalModel model);

struct CloudToCloudParams
{
    //! Metres, > 0. Points farther than this get NaN, or maxDistance itself with clampBeyondMax.
    std::optional<double> maxDistance;
    bool clampBeyondMax = false;
    //! Local model of the reference near each compared point. Default: none.
    LocalModel model = LocalModel::None;
    //! k, in [3, 500]: the model is fitted on the compared point's k nearest reference points. Default 12.
    int neighbours = 12;
    //! Metres, > 0: fit on the reference points within this radius of the nearest neighbour instead.
    std::optional<double> radius;
    //! Also output the X, Y, Z components of the vector to the nearest neighbour.
    bool splitComponents = false;
    //! Signed distances: needs reference normals (sign of n . (p - nn)) or a
    //! local model, whose normal is oriented by the reference normals when they
    //! exist, else towards the first reference sensor, else towards +Z.
    bool signedDistances = false;
    //! Also output the closest reference point of every compared point.
    bool closestPoints = false;
    //! Octree level 1..21; 0 chooses it from the reference's cell populations.
    int octreeLevel = 0;
    //! Also output CloudToCloudResult::reach (for tiled runs that must know
    //! whether their part of the reference was enough).
    bool reportReach = false;
    //! Reference viewpoints for the visibility test; empty = no test.
    std::vector<SensorPose> viewpoints;
    VisibilityParams visibility;
};

struct CloudToCloudResult
{
    ScalarField distance;                  //!< "c2c_distance", one value per compared point (NaN: none)
    std::optional<ScalarField> dx, dy, dz; //!< "c2c_dx", "c2c_dy", "c2c_dz" with splitComponents
    std::optional<ScalarField> visibility; //!< "visibility" (VisibilityLabel values) with viewpoints
    std::optional<PointCloud> closest;     //!< with closestPoints: the matched reference points
    DistanceStatistics statistics;
    int level = 0;                         //!< the octree level used
    std::size_t modelFallbacks = 0;        //!< neighbourhoods too small or degenerate: plain NN used
    //! With reportReach, per compared point: the radius around it that holds
    //! every reference point its value depends on (the nearest neighbour's
    //! distance, capped at maxDistance; the k-th neighbour's; the nearest's
    //! plus the model radius), +inf when the reference has fewer points than
    //! the model asks for, 0 for a point without a value to compute. A run on
    //! any part of the reference that holds the ball of that radius around the
    //! point gives the point the same value as the whole reference.
    std::vector<float> reach;
};

//! Throws Error(InvalidData) for an empty reference or non-finite reference
//! points, Error(InvalidArgument) for parameters out of range,
//! Error(Cancelled) if cancelled (inputs untouched). Non-finite compared points get NaN.
CloudToCloudResult cloudToCloud(const PointCloud& compared, const PointCloud& reference, const CloudToCloudParams& params,
                                ProgressObserver* progress = nullptr);

//! Adds the result's fields to `cloud` (the compared cloud), replacing fields of the same name.
void attachFields(PointCloud& cloud, CloudToCloudResult&& result);

} // namespace scandiff
