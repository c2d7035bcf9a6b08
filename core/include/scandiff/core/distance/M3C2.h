// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! M3C2: Multiscale Model to Model Cloud Comparison (Lague, Brodu and Leroux,
//! "Accurate 3D comparison of complex topography with terrestrial laser
//! scanner", ISPRS J. 82, 2013). Change is measured along the local normal of
//! the reference, each epoch averaged inside a cylinder, and each distance
//! comes with its level of detection at 95 % (LoD95), so that a user sees
//! where the change is significant given roughness and registration error.
//!
//! For each core point c:
//! - its normal n is the least-squares plane normal of the reference points
//!   within D/2 of c (with several scales D, the scale whose neighbourhood is
//!   the most planar: the smallest surface variation λ0 / (λ0 + λ1 + λ2), as in
//!   the paper's multi-scale mode), oriented by the chosen rule;
//! - each epoch i keeps its points p in the cylinder of axis (c, n), diameter
//!   d and half-length H: |t| <= H and |p - c|² - t² <= (d/2)², t = (p - c)·n;
//! - n_i points, their mean (or median) position t along n, and their spread
//!   σ_i (population standard deviation, ÷ n as CloudCompare; ÷ (n - 1) on
//!   request as py4dgeo; with `robust`, IQR / 1.349, the normal-consistent
//!   spread of the interquartile range);
//! - distance = t̄₂ - t̄₁ when both cylinders hold a point;
//!   LoD95 = 1.96 (√(σ₁²/n₁ + σ₂²/n₂) + registration error) and significant =
//!   |distance| > LoD95 when both hold at least `minPoints`; NaN otherwise.
//!
//! The two clouds may have different origins (global shifts): the compared
//! points are taken into the reference's frame in double first.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/processing/Normals.h>

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace scandiff {

namespace fields {
inline constexpr const char* kM3c2Distance = "m3c2_distance";
inline constexpr const char* kM3c2Uncertainty = "m3c2_uncertainty"; //!< LoD95
inline constexpr const char* kM3c2Significant = "m3c2_significant"; //!< 1 significant, 0 not, NaN untested
inline constexpr const char* kM3c2N1 = "m3c2_n1";
inline constexpr const char* kM3c2N2 = "m3c2_n2";
inline constexpr const char* kM3c2Std1 = "m3c2_std1";
inline constexpr const char* kM3c2Std2 = "m3c2_std2";
inline constexpr const char* kM3c2NormalScale = "m3c2_normal_scale";
} // namespace fields

struct M3c2Params
{
    //! Normal scales D (diameters, m, > 0): one, or several for the
    //! multi-scale normal (the most planar kept).
    std::vector<double> normalScales{1.0};
    double projectionScale = 1.0;   //!< d, the cylinder's diameter (m, > 0)
    double maxDepth = 1.0;          //!< H, the cylinder's half-length (m, > 0)
    double registrationError = 0.0; //!< m, >= 0, added to the LoD before x 1.96
    std::size_t minPoints = 5;      //!< per cylinder, for the LoD and significance (>= 1)
    bool robust = false;            //!< median and IQR / 1.349 instead of mean and σ
    bool sampleStd = false;         //!< σ ÷ (n - 1) (py4dgeo) instead of ÷ n (CloudCompare)
    //! How each normal's side is chosen; TowardsSensor uses the reference's
    //! sensors, Away/TowardsCentroid the core points' centroid.
    NormalOrientation orientation;
};

struct M3c2Result
{
    //! The core points (global positions as given), their normals and the
    //! fields kM3c2*, one value per core point.
    PointCloud corePoints;
    std::size_t significantCount = 0;  //!< core points with m3c2_significant = 1
    std::size_t measuredCount = 0;     //!< core points with a distance
    std::size_t withoutNormal = 0;     //!< core points whose reference neighbourhood fixes no plane
};

//! M3C2 of `compared` against `reference` at `corePoints` (often the reference
//! itself, or a subsample of it). Parallel (TBB), deterministic whatever the
//! number of threads. Throws Error(InvalidData) for an empty or non-finite
//! reference or compared cloud, Error(InvalidArgument) for parameters out of
//! range or an orientation that cannot be applied (no sensor), and
//! Error(Cancelled) (inputs untouched).
M3c2Result m3c2(const PointCloud& reference, const PointCloud& compared, const PointCloud& corePoints,
                const M3c2Params& params, ProgressObserver* progress = nullptr);

//! The same on parts of the epochs (scandiff-mpi's tiles): each part must hold
//! every point of its epoch within the search reach of the core points given
//! (half the largest normal scale, and the cylinder's half-diagonal
//! sqrt((d/2)^2 + H^2)), in the epoch's order; each value is then the one m3c2
//! gives on the whole epochs, to the bit (neighbourhoods are summed in index
//! order). A part may be empty: no normal without reference points, empty
//! cylinders in an empty compared part. With a centroid orientation, give the
//! whole set of core points' centroid in params.orientation.centroid.
M3c2Result m3c2OnParts(const PointCloud& reference, const PointCloud& compared, const PointCloud& corePoints,
                       const M3c2Params& params, ProgressObserver* progress = nullptr);

//! What guessM3c2Scales() aims for (Lague, Brodu and Leroux 2013, §3.2-3.3).
struct M3c2ScaleGuessParams
{
    std::size_t samples = 2000;          //!< reference points the criteria are measured at (every k-th)
    std::size_t pointsPerCylinder = 30;  //!< in the median cylinder, in each epoch
    double roughnessRatio = 25.0;        //!< D / sigma(D) at the median sample
    //! The projection scale when the user gave it: only D is sought, from it.
    std::optional<double> projectionScale;
};

struct M3c2ScaleGuess
{
    double spacing = 0.0;                //!< median distance to the nearest point, the sparser epoch's
    double projectionScale = 0.0;        //!< d: the smallest whose median ball holds pointsPerCylinder in both epochs
    double normalScale = 0.0;            //!< D: the smallest multiple of d with D / sigma(D) >= the ratio
    double medianPointsReference = 0.0;  //!< in a ball of diameter d at the median sample
    double medianPointsCompared = 0.0;
    double medianRoughnessRatio = 0.0;   //!< D / sigma(D) at the median sample
    bool roughnessRatioReached = false;  //!< false: D is the largest tried (5 d), rougher than asked
};

//! M3C2's projection and normal scales from the epochs themselves (CloudCompare's
//! "guess parameters"): d from the point spacing so that a cylinder holds
//! enough points of each epoch for a level of detection, D from the
//! roughness so that the normal is stable; both rounded up to two significant
//! digits. Throws Error(InvalidData) for empty clouds or coinciding points,
//! Error(InvalidArgument) for parameters out of range, Error(Cancelled).
M3c2ScaleGuess guessM3c2Scales(const PointCloud& reference, const PointCloud& compared, const M3c2ScaleGuessParams& params = {},
                               ProgressObserver* progress = nullptr);

} // namespace scandiff
