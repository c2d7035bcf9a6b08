// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Multi-station adjustment: N scans of one site, each in its own scanner
//! frame (any heading, any place), registered jointly. Every pair is first
//! registered alone: global alignment (FPFH and RANSAC on descriptors made
//! once per station, 4 DOF for levelled scanners) then ICP from it; a pair is
//! kept when enough of it overlaps and it agrees with the loops it closes
//! (pairs that disagree with the rest are left out, most doubtful first);
//! those pairwise motions give the starting poses (along a spanning tree from
//! station 0) and the misclosure of every loop of the overlap graph. Then all
//! poses are estimated together in one least-squares problem over the
//! point-to-plane residuals of every overlapping pair, station 0 fixed: six
//! unknowns per other station, or four for levelled scanners (thesis 004
//! §III-2.2.1: "add 4 columns per extra station"), re-matched at each
//! iteration like ICP.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/plugins/registration/RegistrationReport.h>
#include <scandiff/plugins/registration/RigidMotion.h>

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace scandiff::plugins {

struct StationParams
{
    DofConstraint constraint;
    //! Correspondences farther than this (m) are left out of the joint
    //! adjustment; also the distance within which points count as overlapping.
    double maxDistance = 1.0;
    //! True: the stations arrive in any heading and place (a global alignment
    //! per pair); false: roughly in one frame already (ICP from where they are).
    bool anyStart = true;
    //! The global alignment's feature spacing (m); absent: chosen so the
    //! median station keeps about 10 000 points.
    std::optional<double> featureSpacing;
    //! A pair overlaps when at least this fraction of one station's sampled
    //! points lies within maxDistance of the other.
    double minOverlap = 0.1;
    std::size_t sampleCount = 20000; //!< points of each station used, at random
    std::size_t maxIterations = 50;
    std::uint64_t seed = 0;
};

struct StationPair
{
    std::size_t a = 0, b = 0;
    double overlap = 0;            //!< the larger of the two directions' fractions (after the pair's own registration)
    //! How well the pair's motion brings both stations together: the shares
    //! of each station's points within 3 robust sigmas of the other's surface,
    //! summed (0 to 2), less ten times the shares put where the other scanner
    //! saw through empty space (when both carry their scanner's pose).
    double agreement = 0;
    //! Left out of the adjustment: it disagrees with the loops it closes
    //! (why in `note`), or its alignment failed.
    bool used = true;
    std::string note;
    RegistrationReport pairwise;   //!< b registered alone on a (matrix: b -> a)
    double adjustedRms = 0;        //!< point-to-plane RMS of the pair under the adjusted poses (m)
    //! How far the adjusted relative pose is from the pairwise one: angle
    //! (degrees) and displacement at the pair's centre (m).
    double disagreementDegrees = 0, disagreementMetres = 0;
};

struct StationLoop
{
    std::vector<std::size_t> stations; //!< around the loop, the first repeated at the end
    //! The pairwise motions composed around the loop, which would be the
    //! identity without error: its angle (degrees) and the displacement it
    //! gives the loop's centre (m).
    double rotationDegrees = 0, translationMetres = 0;
};

struct StationResult
{
    //! Per station: station coordinates (global) -> station 0's (global);
    //! the identity for station 0.
    std::vector<Eigen::Matrix4d> poses;
    std::vector<StationPair> pairs;
    std::vector<StationLoop> loops;
    //! The joint adjustment: RMS and percentiles of every pair's residuals,
    //! iterations and trace, notes (pairwise warnings).
    RegistrationReport report;
};

//! Throws Error(InvalidArgument) for fewer than 2 stations or bad parameters,
//! Error(InvalidData) for an empty station or one that overlaps no other
//! connected to station 0, Error(Cancelled).
StationResult adjustStations(const std::vector<const PointCloud*>& stations, const StationParams& params,
                             ProgressObserver* progress = nullptr);

} // namespace scandiff::plugins
