// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The change segmentation as every front end runs it, with its parameters
//! declared once: `scandiff-cli segment` and `compare` turn them into options,
//! the workbench into its segmentation dialog.
//!
//! A run is: a classification of the field (exactly one of range, above,
//! kmeans, stat-test) optionally grouped by connected components, or the
//! gradient-constrained propagation (propagate), which needs no classification.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/ToolRegistry.h>
#include <scandiff/core/segmentation/RegionReport.h>
#include <scandiff/core/segmentation/StatisticalTest.h>

#include <optional>
#include <string>
#include <vector>

namespace scandiff {

//! field, absolute, range, above, kmeans, stat-test, neighbours, confidence, calibration,
//! chi2-threshold, fit-box, noise, components, level, connectivity, min-points,
//! propagate, alpha, min-seed, keep-background, stop-speed, gradient-radius, smoothing,
//! report-field, outline-cell, region-epoch, column-height, volume-cell.
const std::vector<ParameterSpec>& segmentationParameters();

//! The default of min-points: regions of fewer points are dropped.
inline constexpr std::int64_t kDefaultMinRegionPoints = 10;

//! What one run produced. `fields` are ready to be added to the cloud
//! (replacing fields of the same name): always "region_id"; with a
//! classification "changed" (and "kmeans_class" or "chi2"); with propagation
//! "arrival_time" and "gradient_norm".
struct SegmentationRun
{
    std::vector<ScalarField> fields;
    std::size_t regionCount = 0;
    std::vector<std::size_t> regionSizes;  //!< points of region id r at index r-1
    std::size_t changedCount = 0;          //!< points labelled changed (classification only)
    std::optional<NoiseDistribution> noise; //!< the model of stat-test
    double threshold = 0.0;                 //!< the chi-square cut of stat-test
    std::vector<double> centres;            //!< the K-means centres
    int level = 0;                          //!< octree level of the components / propagation grid
    //! One line for logs: method, counts, thresholds.
    std::string summary;
};

//! Runs the segmentation described by `values` (resolved against
//! segmentationParameters()) on `cloud`, which is not modified.
//! Throws Error(InvalidArgument) for a missing field, no method or two
//! methods, a propagation without min-seed, malformed fit-box/noise/range
//! text, a fit-box holding no value; Error(InvalidData) for an empty cloud or
//! non-finite coordinates; Error(Cancelled).
SegmentationRun runSegmentation(const PointCloud& cloud, const ParameterValues& values, ProgressObserver* progress = nullptr);

//! Adds the run's fields to `cloud`, replacing fields of the same name.
void attachFields(PointCloud& cloud, SegmentationRun&& run);

//! The region-report settings of `values`: the distance field is `field`,
//! the outline cell `outline-cell`; `reference` (may be null) gives the volume.
RegionReportParams regionReportSettings(const ParameterValues& values, const PointCloud* reference);

} // namespace scandiff
