// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Depth maps of reference scans and the visibility test of thesis 000 §2.3.3
//! (Algorithm 3): is a compared point something the reference scanner could
//! have seen? A point in a zone the reference never saw (behind a wall that
//! has since gone, outside the scan's angular crop) has no meaningful
//! nearest-neighbour distance.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/SensorPose.h>

#include <cstdint>
#include <vector>

namespace scandiff {

//! Values of the "visibility" field (Algorithm 3's codes).
enum class VisibilityLabel : std::uint8_t { Visible = 0, Hidden = 1, OutOfRange = 2, OutOfField = 3 };

struct VisibilityParams
{
    //! Metres added to the depth-map range before comparing, >= 0. It absorbs
    //! sensor and registration errors ([ISPRS05] §4.1.1: 3-10 cm indoors,
    //! 0.1-1 m outdoors at long range). Default 0.05 m.
    double tolerance = 0.05;
    //! Fill empty depth-map cells with the mean of their non-empty neighbours
    //! when at least 4 of the 8 are filled ([ISPRS05]). Default on.
    bool fillHoles = true;
    //! Name of the reference field giving each point's scan (0, 1, ...), when
    //! the reference merges several viewpoints; without it every viewpoint's map
    //! is built from all reference points.
    std::string scanIndexField = "scan_index";
};

//! The Z-buffer of one viewpoint in its angular coordinates: yaw = atan2(y, x),
//! pitch = atan2(z, hypot(x, y)) in the sensor frame (x forward, z up); each
//! cell keeps the smallest range seen. Steps come from the pose, or, when 0,
//! from the reference itself (the square root of the covered solid angle per point).
class DepthMap
{
public:
    //! `pointsOfScan` selects the reference points of this viewpoint; null: every
    //! reference point (a pointer, so that "none" can never be read as "all").
    DepthMap(const PointCloud& reference, const SensorPose& pose, const VisibilityParams& params,
             const std::vector<std::uint32_t>* pointsOfScan = nullptr);

    VisibilityLabel classify(const Eigen::Vector3d& globalPoint) const;

    int width() const { return width_; }
    int height() const { return height_; }
    double yawStep() const { return yawStep_; }
    double pitchStep() const { return pitchStep_; }

private:
    SensorPose pose_;
    Eigen::Matrix3d worldToSensor_;
    double tolerance_;
    double yawMin_ = 0, pitchMin_ = 0, yawStep_ = 0, pitchStep_ = 0;
    int width_ = 0, height_ = 0;
    std::vector<float> range_;
};

//! Labels of every compared point against every viewpoint: visible as soon as
//! one map sees it, else the most favourable of hidden < out of range < out of
//! field (Algorithm 3). Throws Error(InvalidArgument) without viewpoints.
std::vector<VisibilityLabel> visibilityLabels(const PointCloud& compared, const PointCloud& reference,
                                              const std::vector<SensorPose>& viewpoints, const VisibilityParams& params,
                                              ProgressObserver* progress = nullptr);

} // namespace scandiff
