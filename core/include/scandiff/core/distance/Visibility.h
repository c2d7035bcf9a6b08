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
    //! How far behind the reference's surface a point may lie and still count
    //! as seen, >= 0, measured across the surface: along the ray it is this
    //! divided by the sine of the angle the ray meets the surface at (ground
    //! met at 2.6 degrees 40 m from a 1.8 m tripod: 22 times this). It absorbs
    //! sensor and registration errors ([ISPRS05] §4.1.1: 3-10 cm indoors,
    //! 0.1-1 m outdoors at long range). Default 0.05 m.
    double tolerance = 0.05;
    //! A direction whose own cell holds no sample but which lies within about
    //! half a step of the reference's samples gets the surface through them
    //! (the scan's grid and the map's need not line up). Off: only directions
    //! in a cell holding a sample. Default on.
    bool fillHoles = true;
    //! Name of the reference field giving each point's scan (0, 1, ...), when
    //! the reference merges several viewpoints; without it every viewpoint's map
    //! is built from all reference points.
    std::string scanIndexField = "scan_index";
};

//! The depth map of one viewpoint in its angular coordinates: yaw = atan2(y,
//! x), pitch = atan2(z, hypot(x, y)) in the sensor frame (x forward, z up).
//! Each cell keeps the reference samples that fall in it; a direction gets
//! the range of the surface through the samples around it (1/r, linear in
//! the direction on a plane, fitted over the nearest samples of one surface:
//! a jump in 1/r larger than any surface 0.25 m or more from the scanner
//! makes between two samples is an edge, and the samples beyond it are left
//! out). The thesis's map keeps one range per cell, the smallest: at grazing
//! incidence the range changes by metres across a cell, and the ground the
//! scanner saw was found behind that range. Steps come from the pose, or,
//! when 0, from the reference itself (the square root of the covered solid
//! angle per point). A scan all around wraps at the back.
class DepthMap
{
public:
    //! `pointsOfScan` selects the reference points of this viewpoint; null: every
    //! reference point (a pointer, so that "none" can never be read as "all").
    DepthMap(const PointCloud& reference, const SensorPose& pose, const VisibilityParams& params,
             const std::vector<std::uint32_t>* pointsOfScan = nullptr);

    //! Out of field outside the map, out of range beyond the pose's range;
    //! else hidden when the point lies farther than the surface along its
    //! direction plus the tolerance taken along the ray, visible otherwise
    //! (also where no sample is near: the ray met nothing the scanner saw).
    VisibilityLabel classify(const Eigen::Vector3d& globalPoint) const;

    //! Whether the scanner looked through the point: it lies in the field,
    //! within range, and nearer than the surface along its direction by more
    //! than the tolerance taken along the ray. Something there now was not
    //! there when the scanner passed (or is misplaced): the free-space
    //! contradiction a pose that puts a station's clutter in another's empty
    //! room makes.
    bool inFreeSpace(const Eigen::Vector3d& globalPoint) const;

    int width() const { return width_; }
    int height() const { return height_; }
    double yawStep() const { return yawStep_; }
    double pitchStep() const { return pitchStep_; }

private:
    struct Sample
    {
        double yaw, pitch;
        float inverseRange;
    };
    struct SurfaceAlong
    {
        bool seen = false;
        double range = 0;
        double alongRay = 1; //!< 1 / sin of the grazing angle, capped
    };
    std::vector<Sample> collectSamples(const PointCloud& reference, const std::vector<std::uint32_t>* pointsOfScan) const;
    void layOutGrid(const std::vector<Sample>& samples);
    void bucketSamples(const std::vector<Sample>& samples);
    int column(double yaw) const;
    int row(double pitch) const;
    SurfaceAlong surfaceAlong(double yaw, double pitch, int u, int v) const;

    SensorPose pose_;
    Eigen::Matrix3d worldToSensor_;
    double tolerance_;
    bool interpolate_ = true;
    bool wraps_ = false;
    double yawMin_ = 0, pitchMin_ = 0, yawStep_ = 0, pitchStep_ = 0;
    int width_ = 0, height_ = 0;
    std::vector<std::uint32_t> cellStart_; //!< cell c's samples: samples_[cellStart_[c]..cellStart_[c + 1])
    std::vector<Sample> samples_;
};

//! Labels of every compared point against every viewpoint: visible as soon as
//! one map sees it, else the most favourable of hidden < out of range < out of
//! field (Algorithm 3). Throws Error(InvalidArgument) without viewpoints.
std::vector<VisibilityLabel> visibilityLabels(const PointCloud& compared, const PointCloud& reference,
                                              const std::vector<SensorPose>& viewpoints, const VisibilityParams& params,
                                              ProgressObserver* progress = nullptr);

} // namespace scandiff
