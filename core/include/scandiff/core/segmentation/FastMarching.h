// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Scalar-field gradient and front propagation (thesis 000 §3.3).
//!
//! - gradientNorm(): |grad f| per point from the points within a fixed radius
//!   (§3.3.2: a radius, not k neighbours, so the result does not depend on the
//!   density), optionally smoothed by a Gaussian (eq. 3.10) and clamped to 1
//!   (the bound of a distance field, Fig. 3.16).
//! - fastMarching(): arrival times of a front leaving seed points at unit speed,
//!   computed on the occupied cells of one octree level (§3.3.1, after Mémoli &
//!   Sapiro: only cells near the cloud are nodes; a point takes its cell's time).
//! - propagationSegmentation(): the gradient-constrained propagation of §3.3.2
//!   (eq. 3.11): from the largest remaining value, a front whose speed from cell
//!   i to cell j is exp(alpha (|grad|_j - |grad|_i)); it does not cross where that
//!   speed falls below a stop value; what it reaches is one region, removed
//!   before the next seed, until no value above the minimum remains.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/ScalarField.h>

#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace scandiff {

struct GradientParams
{
    //! Neighbourhood radius (m), > 0; 0 = automatic: the cell size of the octree
    //! level whose cells hold ~16 points on average (a few point spacings).
    double radius = 0.0;
    //! Gaussian smoothing of the norm (eq. 3.10), sigma in metres, > 0; neighbours
    //! beyond 3 sigma are ignored. Absent: no smoothing.
    std::optional<double> smoothingSigma;
    //! Clamp norms above 1: a distance field cannot vary faster than 1 m/m, so
    //! larger values are estimation artefacts. Turn off for other fields.
    bool clampToOne = true;
};

struct GradientResult
{
    ScalarField norm;     //!< "gradient_norm"; NaN without a value or with < 3 valid neighbours
    double radius = 0.0;  //!< the radius used
};

//! |grad f| by least squares: the g minimising sum_i (g . (P_i - P) - (f_i - f))^2
//! over the neighbours, solved in the span of their offsets (on a surface the
//! normal direction is not observable and is left out). Unlike eq. 3.9 as
//! printed, this is unbiased: a linear field g.x gives |g| exactly.
//! Throws Error(InvalidArgument) for a missing field or bad parameters,
//! Error(InvalidData) for an empty cloud or non-finite coordinates, Error(Cancelled).
GradientResult gradientNorm(const PointCloud& cloud, const std::string& fieldName, const GradientParams& params = {},
                            ProgressObserver* progress = nullptr);

struct FastMarchingParams
{
    //! Octree level of the grid, in [1, 21], on the cube enclosing the cloud;
    //! 0 = automatic: cells holding ~4 points on average.
    int level = 0;
};

struct FastMarchingResult
{
    //! "arrival_time": distance travelled at unit speed along the cloud (m),
    //! NaN where the front never arrived (a part not connected to a seed).
    ScalarField arrivalTime;
    int level = 0;
    double cellSize = 0.0;
    std::size_t cellCount = 0; //!< nodes of the grid (occupied cells)
};

//! Arrival times at unit speed from the seed points (indices into the cloud).
//! Throws Error(InvalidArgument) for no seed or a seed index out of range,
//! Error(InvalidData) for an empty cloud or non-finite coordinates, Error(Cancelled).
FastMarchingResult fastMarching(const PointCloud& cloud, const std::vector<std::size_t>& seeds,
                                const FastMarchingParams& params = {}, ProgressObserver* progress = nullptr);

struct PropagationParams
{
    //! Exaggeration of gradient changes in the speed (eq. 3.11), >= 0. Thesis: 50.
    double alpha = 50.0;
    //! A region starts only from a value >= this (the "really mobile" seed of
    //! §3.3.2); required, finite.
    double minSeedValue = std::numeric_limits<double>::quiet_NaN();
    //! The front does not enter a cell from a neighbour when the speed between
    //! them is below this, in (0, 1]: equivalently, when crossing one cell would
    //! take more than 1/stopSpeed times as long as at unit speed (the "time jump"
    //! stop rule). With alpha = 50, 0.1 stops at a drop of the gradient norm of 0.046.
    double stopSpeed = 0.1;
    //! Let the front enter any cell whose value is at least minSeedValue, even
    //! against the stop rule. The thesis applies the rule everywhere, which cuts
    //! an object whose top is a plateau (zero gradient) into its faces when the
    //! seed falls on an edge; with this (our default) the stop rule only decides
    //! how far a region extends below the seed value, down its slopes.
    bool enterAboveSeedValue = true;
    //! Octree level of the grid, 0 = automatic (cells holding ~8 points).
    int level = 0;
    GradientParams gradient;
    //! Regions with fewer points are dropped (points left without a region), >= 1.
    std::size_t minPoints = 1;
    //! Keep the regions whose values are the field's noise (see
    //! PropagationResult::backgroundRegions) instead of leaving them out.
    bool keepBackground = false;
};

struct PropagationResult
{
    ScalarField regionId;     //!< "region_id": 1..regionCount by decreasing size, NaN elsewhere
    ScalarField arrivalTime;  //!< "arrival_time" within each region, from its seed
    ScalarField gradient;     //!< "gradient_norm" used
    std::size_t regionCount = 0;
    std::vector<std::size_t> regionSizes; //!< points of region id r at index r-1
    std::size_t droppedRegions = 0;       //!< smaller than minPoints
    //! Regions that are background, not change: one noise value above the
    //! seed value starts a region, and on a flat field the front then crosses
    //! the whole unchanged surface. A region is background when its median
    //! value is below the seed value and within the field's noise: at most
    //! the field's median + 3 sigma (sigma = 1.4826 x the median absolute
    //! deviation, robust while changes are a minority). Left out (their
    //! points without a region) unless keepBackground.
    std::size_t backgroundRegions = 0;
    std::size_t backgroundPoints = 0;
    double noiseCeiling = 0.0; //!< the field's median + 3 sigma
    int level = 0;
    double cellSize = 0.0;
};

//! Throws Error(InvalidArgument) for a missing field or bad parameters,
//! Error(InvalidData) for an empty cloud or non-finite coordinates, Error(Cancelled).
PropagationResult propagationSegmentation(const PointCloud& cloud, const std::string& fieldName,
                                          const PropagationParams& params, ProgressObserver* progress = nullptr);

} // namespace scandiff
