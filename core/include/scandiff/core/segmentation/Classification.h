// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Global two-class classification of a scalar field (thesis 000 §3.2.1-3.2.2):
//! a manual threshold, or K-means on the values. Both return per-point fields
//! so the result flows through PLY files and the GUI like any other field.
//!
//! Label convention shared by every classifier of this folder: the field
//! `changed` holds 1 (changed), 0 (unchanged) or NaN (the input had no value).

#include <scandiff/core/Progress.h>
#include <scandiff/core/ScalarField.h>

#include <cstdint>
#include <limits>
#include <vector>

namespace scandiff {

//! Names of the per-point fields written by the segmentation algorithms.
namespace fields {
inline constexpr const char* kChanged = "changed";          //!< 1 / 0 / NaN
inline constexpr const char* kKMeansClass = "kmeans_class"; //!< 0..k-1, by increasing centre
inline constexpr const char* kChiSquare = "chi2";           //!< local chi-square distance d_k
inline constexpr const char* kRegionId = "region_id";       //!< 1..R, NaN outside every region
inline constexpr const char* kGradient = "gradient_norm";   //!< |grad f|
inline constexpr const char* kArrivalTime = "arrival_time"; //!< fast-marching time (metres at unit speed)
} // namespace fields

//! Points whose value lies in [low, high] are changed. Either bound may be
//! infinite ("above X" is [X, +inf]). Throws Error(InvalidArgument) if a bound
//! is NaN or low > high.
ScalarField classifyByRange(const ScalarField& field, double low, double high);

//! |value| per point (NaN stays NaN): unsigned distances, as the thesis uses them.
ScalarField absoluteValues(const ScalarField& field);

struct KMeansParams
{
    //! Number of classes, in [2, 64]. Thesis default: 2.
    int classes = 2;
    //! Iteration cap, in [1, 10000]; Lloyd's iterations usually stop far sooner,
    //! when no value changes class.
    int maxIterations = 100;
};

struct KMeansResult
{
    ScalarField classes;                //!< "kmeans_class": 0..k-1 ordered by increasing centre; NaN for NaN inputs
    ScalarField changed;                //!< "changed": 0 for the class whose centre is nearest 0, 1 for the others
    std::vector<double> centres;        //!< increasing
    std::vector<std::size_t> counts;    //!< values per class
    int iterations = 0;
    bool converged = false;             //!< false if maxIterations was reached
    //! Boundaries between consecutive classes (the mid-points of the centres),
    //! k-1 values: a first guess for a manual threshold (thesis §3.2.2).
    std::vector<double> thresholds;
};

//! K-means of the field's values (Algorithm 4 of the thesis): initial centres
//! spread evenly over [min, max], then assignment to the nearest centre and
//! re-centring until no assignment changes. A class that empties keeps its centre.
//! Throws Error(InvalidData) if the field has fewer valid values than classes,
//! Error(InvalidArgument) for parameters out of range, Error(Cancelled).
KMeansResult kMeans(const ScalarField& field, const KMeansParams& params = {}, ProgressObserver* progress = nullptr);

//! Per-point selection from a label field: true where the value is finite and
//! greater than 0.5 (so the `changed` field gives the changed points).
std::vector<std::uint8_t> selectionFromLabels(const ScalarField& labels);

} // namespace scandiff
