// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Global (coarse) alignment from any start: both clouds thinned to a
//! feature spacing, a shape descriptor per point (FPFH, Rusu et al. 2009),
//! descriptors matched (mutual nearest neighbours), and the motion that the
//! most matches agree on found by RANSAC (Fischler and Bolles 1981) on
//! minimal sets: 3 matches for 6 degrees of freedom, 2 for 4 (only the
//! heading is searched: a levelled scanner's tilt is kept exactly), 1 for a
//! translation. Sets whose edge lengths differ between the clouds are
//! rejected before the motion is scored (the prerejection of Buch et al. 2013).
//! The result is a start for ICP (icpRegister's `initial`), within about the
//! feature spacing.

#include <scandiff/core/Mesh.h>
#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/plugins/registration/RegistrationReport.h>
#include <scandiff/plugins/registration/RigidMotion.h>

#include <cstdint>
#include <memory>
#include <optional>

namespace scandiff::plugins {

struct GlobalAlignmentParams
{
    DofConstraint constraint;
    //! The spacing both clouds are thinned to (m); absent: chosen so the
    //! reference keeps about `targetPoints` points. Normals are fitted within
    //! 2 spacings and descriptors within 5 (the proportions of Open3D's
    //! global registration pipeline, Zhou et al. 2018).
    std::optional<double> spacing;
    std::size_t targetPoints = 10000;
    //! A match agrees with a motion when it brings the points within this many
    //! spacings of each other.
    double inlierSpacings = 1.5;
    //! Hypotheses drawn (minimal sets of mutually consistent matches).
    std::size_t maxIterations = 100000;
    std::uint64_t seed = 0;
    //! Motions returned in all, the best and the next distinct ones.
    std::size_t alternatives = 1;
};

struct GlobalAlignmentResult
{
    RegistrationReport report; //!< matrix moving -> reference (global), RMS of the agreeing matches
    double spacing = 0;
    std::size_t matches = 0;   //!< descriptor matches tried
    std::size_t inliers = 0;   //!< matches that agree with the motion
    //! The next distinct motions (rotations 2 degrees or 2 spacings apart),
    //! best first, each landing at least half as many points as the best
    //! (GlobalAlignmentParams::alternatives - 1 at most).
    std::vector<Eigen::Matrix4d> alternatives;
};

//! A cloud prepared for global alignment at a spacing (thinned, normals,
//! descriptors): built once, aligned with many others (the stations of a
//! survey, pair by pair).
struct AlignmentFeatures;

//! The spacing at which `reference` keeps about `targetPoints` points (the
//! automatic spacing of globalAlign).
double alignmentSpacing(const PointCloud& reference, std::size_t targetPoints);
std::shared_ptr<const AlignmentFeatures> describeForAlignment(const PointCloud& cloud, double spacing,
                                                              ProgressObserver* progress = nullptr);
//! globalAlign on clouds described at one spacing (params.spacing and
//! targetPoints are not used).
GlobalAlignmentResult globalAlign(const AlignmentFeatures& moving, const AlignmentFeatures& reference,
                                  const GlobalAlignmentParams& params, ProgressObserver* progress = nullptr);

//! The motion moving -> reference. A mesh reference is sampled on its
//! surface. Throws Error(InvalidData) for empty clouds or when no motion is
//! agreed on by enough matches (too little overlap or shape), Error(Cancelled).
GlobalAlignmentResult globalAlign(const PointCloud& moving, const PointCloud* referenceCloud, const Mesh* referenceMesh,
                                  const GlobalAlignmentParams& params, ProgressObserver* progress = nullptr);

} // namespace scandiff::plugins
