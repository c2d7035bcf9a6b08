// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Local geometric features as scalar fields, each computed on the points
//! within a radius of every point (thesis 000 annex C: "local density;
//! curvature"; CloudCompare's "Compute geometric features").

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>

#include <vector>

namespace scandiff {

enum class DensityKind {
    Count,   //!< neighbour_count: points within the radius, the point itself included
    Surface, //!< surface_density: that count over pi R^2 (points per m^2)
    Volume   //!< volume_density: that count over 4/3 pi R^3 (points per m^3)
};

struct FeatureParams
{
    double radius = 0; //!< > 0 (m)
    //! The features wanted; when none is set, all of them.
    bool density = false;
    bool roughness = false;
    bool curvature = false;
    bool verticality = false;
    DensityKind densityKind = DensityKind::Surface;
};

namespace fields {
inline constexpr const char* kNeighbourCount = "neighbour_count";
inline constexpr const char* kSurfaceDensity = "surface_density";
inline constexpr const char* kVolumeDensity = "volume_density";
//! Distance from the point to the least-squares plane of its neighbours (the
//! point itself left out), unsigned.
inline constexpr const char* kRoughness = "roughness";
//! From a quadric z = a u² + b uv + c v² + d u + e v + f fitted over the
//! neighbourhood's plane, at the point: the mean curvature (positive where the
//! surface bends towards the side its normal faces, so -1/R on a sphere with
//! outward normals) and the Gaussian curvature (1/R² on a sphere). The side is
//! the cloud's normals when it has them, else +Z.
inline constexpr const char* kMeanCurvature = "mean_curvature";
inline constexpr const char* kGaussianCurvature = "gaussian_curvature";
//! 1 - |n . Z| for the least-squares plane's normal n: 0 on a floor, 1 on a wall.
inline constexpr const char* kVerticality = "verticality";
} // namespace fields

struct FeatureResult
{
    //! One field per feature, NaN where the neighbourhood does not fix it: a
    //! plane through 3 points (the point itself counted for verticality, left
    //! out for roughness) not on a line, a quadric through 6.
    std::vector<ScalarField> fields;
};

//! Throws Error(InvalidArgument) for a radius that is not > 0, Error(InvalidData)
//! for an empty cloud or non-finite coordinates, Error(Cancelled).
FeatureResult computeLocalFeatures(const PointCloud& cloud, const FeatureParams& params, ProgressObserver* progress = nullptr);

} // namespace scandiff
