// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Stone or joint, point by point, from two measurements a scan of a wall
//! gives: the intensity (thesis 003's only cue) and the relief, each point's
//! offset from the stone faces around it (joints are usually recessed; the
//! thesis's 3DReshaper break-line trial, §III.2.2, relies on it). Internal to
//! the contours plugin; extractStones() calls it.

#include <scandiff/core/Progress.h>
#include <scandiff/plugins/contours/StoneWall.h>

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <vector>

namespace scandiff::plugins {

struct StoneEvidenceParams
{
    StonePolarity polarity = StonePolarity::Auto;
    std::optional<double> threshold; //!< the starting split; absent: inter-means
    //! false: the threshold alone on the whole wall (thesis 003); the rest unused.
    bool localLevels = true;
    //! Use the points' offset from the stone faces (with local levels); with
    //! it, a field of one intensity starts from the relief instead of failing.
    bool relief = true;
    //! Side of the square over which the two classes' levels and the faces'
    //! surface are taken (m); 0: max(0.15 m, 30 point spacings).
    double window = 0.0;
};

struct StoneEvidence
{
    std::vector<std::uint8_t> stone; //!< 1: stone, 0: joint or no value
    //! 1: set back from the faces beyond doubt (relief used, the offset past
    //! the middle between faces and joints and 2.5 noise deviations from the
    //! faces). A stone's side inside a groove seen obliquely (its arris) is
    //! stone by its intensity, yet lies between two stones' faces where the
    //! groove's bottom is hidden: with no joint point there, only the relief
    //! tells the stones apart.
    std::vector<std::uint8_t> recessed;
    double threshold = 0.0;          //!< the starting split of the intensities
    int thresholdIterations = 0;     //!< 0 when the threshold was given
    StonePolarity polarity = StonePolarity::Dark;
    double stoneMean = 0.0, jointMean = 0.0; //!< mean intensity of each class, as classified at the end
    double intensitySeparation = 0.0; //!< (stone - joint level) / the intensity noise, signed by the polarity
    double jointOffset = 0.0;         //!< the joints' median offset from the stone faces (m, along the wall's normal)
    double faceOffset = 0.0;          //!< the stone points' median offset from their faces' surface (m, about 0)
    double reliefNoise = 0.0;         //!< robust standard deviation of the stone points' offsets (m)
    bool reliefUsed = false;          //!< whether the offset took part (asked, and the joints stand apart by half its noise)
    int iterations = 0;               //!< classification rounds until the classes settled
};

//! `uv`: the points in the wall's plane; `height`: their signed distance to
//! it; `spacing`: the median distance between neighbouring points. Throws
//! Error(InvalidData) when neither the intensities nor the relief part the
//! points into two classes (with local levels), or, by the threshold alone,
//! when fewer than two distinct intensities exist and none is given.
StoneEvidence classifyStonePoints(const std::vector<Eigen::Vector2d>& uv, const std::vector<double>& height,
                                  const std::vector<float>& intensity, double spacing, const StoneEvidenceParams& params,
                                  ProgressTicker& ticker);

} // namespace scandiff::plugins
