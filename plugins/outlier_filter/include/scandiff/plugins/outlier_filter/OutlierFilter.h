// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Statistical outlier removal (Rusu et al. 2008, as in PCL's
//! StatisticalOutlierRemoval and CloudCompare's SOR filter): for each point the
//! mean distance to its k nearest neighbours; a point is an outlier when that
//! mean exceeds mu + n_sigma * sigma of all the means. Neighbours come from the
//! scandiff octree, so the result is exact.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>

#include <vector>

namespace scandiff::plugins {

struct OutlierFilterParams
{
    int neighbours = 6;   //!< k, in [1, 1000]: neighbours averaged per point (the point itself excluded)
    double nSigma = 1.0;  //!< in [0, 100]: tolerance in standard deviations of the mean distances
};

struct OutlierFilterResult
{
    std::vector<std::size_t> inliers;     //!< kept point indices, increasing
    std::vector<float> meanDistances;     //!< per input point: mean distance to its k neighbours
    double mean = 0.0;                    //!< mu of the mean distances
    double standardDeviation = 0.0;       //!< sigma of the mean distances
    double threshold = 0.0;               //!< mu + n_sigma * sigma
};

//! Throws Error(InvalidArgument) for parameters out of range, Error(InvalidData)
//! for an empty cloud or non-finite coordinates, Error(Cancelled) if cancelled.
OutlierFilterResult statisticalOutliers(const PointCloud& cloud, const OutlierFilterParams& params,
                                        ProgressObserver* progress = nullptr);

} // namespace scandiff::plugins
