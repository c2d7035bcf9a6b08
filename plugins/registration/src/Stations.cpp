// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/plugins/registration/Stations.h>

#include "ReferenceSurface.h"
#include "StationModel.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/RobustStatistics.h>
#include <scandiff/core/distance/Visibility.h>
#include <scandiff/core/processing/Subsampling.h>
#include <scandiff/plugins/registration/GlobalAlignment.h>
#include <scandiff/plugins/registration/Icp.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

namespace scandiff::plugins {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
//! What a point put where another scanner saw through costs a pose, in
//! points brought together: the right pose puts there only what moved
//! between the stations, a wrong one that fits the walls of a hall that
//! repeats itself puts its clutter there.
constexpr double kFreeSpaceWeight = 10;
//! ICP iterations for the start from where the stations are, when the global
//! search offers others.
constexpr std::size_t kWhereTheyAreIterations = 40;
//! Where the stations are is where the surveyor put them: a candidate from
//! there keeps a tenth of its score in hand (scores may be negative).
constexpr double kWhereTheyAreBonus = 0.1;
//! How far a station's own vertical may be from another's: 10 degrees,
//! twice a tripod scanner's compensator range.
constexpr double kMaxStationTilt = 10 * M_PI / 180;
//! Two scanners whose verticals are this close (1 degree: a compensator
//! levels to a few thousandths) are searched for by turns about it.
constexpr double kLevelledSearchTilt = M_PI / 180;

using detail::match;
using detail::Matched;
using detail::motionSize;
using detail::Station;
using JointAdjustmentOutcome = detail::JointAdjustment;

std::vector<Station> prepare(const std::vector<const PointCloud*>& clouds, const StationParams& params, Eigen::Vector3d& worldOrigin,
                             ProgressObserver* progress)
{
    std::vector<Station> stations(clouds.size());
    for (std::size_t k = 0; k < clouds.size(); ++k)
        if (!clouds[k] || clouds[k]->empty())
            throw Error(ErrorCode::InvalidData, "stations: station " + std::to_string(k) + " is empty");
    ProgressTicker ticker(progress, "Stations: octrees", clouds.size());
    for (std::size_t k = 0; k < clouds.size(); ++k) {
        stations[k].cloud = clouds[k];
        stations[k].surface = detail::cloudSurface(*clouds[k], true, 12, progress);
        ticker.step(); // a station's octree takes a while: Cancel is heard between them
    }
    worldOrigin = stations[0].surface->frameOrigin();
    for (std::size_t k = 0; k < clouds.size(); ++k) {
        Station& s = stations[k];
        for (std::size_t i : randomSubsample(*s.cloud, params.sampleCount, params.seed + k))
            if (s.cloud->positions()[i].allFinite())
                s.sample.push_back(s.cloud->globalPosition(i) - worldOrigin);
        if (s.sample.empty())
            throw Error(ErrorCode::InvalidData, "stations: station " + std::to_string(k) + " has no finite point");
        for (const auto& p : s.sample)
            s.centre += p / static_cast<double>(s.sample.size());
    }
    return stations;
}

//! Poses along a breadth-first spanning tree from station 0, composed from the
//! pairwise motions; `parentEdge[k]` is the pair that reached k (none for 0).
std::vector<Eigen::Matrix4d> chainPoses(std::size_t count, const std::vector<StationPair>& pairs, std::vector<std::ptrdiff_t>& parentEdge,
                                        std::vector<std::size_t>& parent)
{
    std::vector<Eigen::Matrix4d> pose(count, Eigen::Matrix4d::Identity());
    std::vector<char> reached(count, 0);
    parentEdge.assign(count, -1);
    parent.assign(count, 0);
    std::deque<std::size_t> queue{0};
    reached[0] = 1;
    while (!queue.empty()) {
        const std::size_t s = queue.front();
        queue.pop_front();
        for (std::size_t e = 0; e < pairs.size(); ++e) {
            const StationPair& p = pairs[e];
            if (p.a != s && p.b != s)
                continue;
            const std::size_t other = p.a == s ? p.b : p.a;
            if (reached[other])
                continue;
            // The pairwise matrix maps b's coordinates to a's.
            pose[other] = p.a == s ? Eigen::Matrix4d(pose[s] * p.pairwise.matrix) : Eigen::Matrix4d(pose[s] * p.pairwise.matrix.inverse());
            reached[other] = 1;
            parentEdge[other] = static_cast<std::ptrdiff_t>(e);
            parent[other] = s;
            queue.push_back(other);
        }
    }
    for (std::size_t k = 0; k < count; ++k)
        if (!reached[k])
            throw Error(ErrorCode::InvalidData, "stations: station " + std::to_string(k) +
                                                    " overlaps no station linked to station 0 (within the maximum distance " +
                                                    "and the minimum overlap): bring it closer first, or raise --max-dist");
    return pose;
}

//! Every edge outside the tree closes a loop: the pairwise motions composed
//! around it, compared with the identity.
std::vector<StationLoop> loopMisclosures(const std::vector<Station>& stations, const std::vector<StationPair>& pairs,
                                         const std::vector<Eigen::Matrix4d>& chain, const std::vector<std::ptrdiff_t>& parentEdge,
                                         const std::vector<std::size_t>& parent, const Eigen::Vector3d& worldOrigin)
{
    std::vector<StationLoop> loops;
    const auto pathToRoot = [&](std::size_t k) {
        std::vector<std::size_t> path{k};
        while (path.back() != 0)
            path.push_back(parent[path.back()]);
        return path;
    };
    for (std::size_t e = 0; e < pairs.size(); ++e) {
        if (std::find(parentEdge.begin(), parentEdge.end(), static_cast<std::ptrdiff_t>(e)) != parentEdge.end())
            continue;
        const StationPair& p = pairs[e];
        // a -> ... -> common ancestor -> ... -> b -> a.
        std::vector<std::size_t> up = pathToRoot(p.a), down = pathToRoot(p.b);
        while (up.size() > 1 && down.size() > 1 && up[up.size() - 2] == down[down.size() - 2]) {
            up.pop_back();
            down.pop_back();
        }
        StationLoop loop;
        loop.stations = up;
        for (auto it = down.rbegin() + 1; it != down.rend(); ++it)
            loop.stations.push_back(*it);
        loop.stations.push_back(p.a);
        // The chain gives b's pose through the tree; the pair's own motion
        // gives it through a: their difference is the loop's misclosure.
        const Eigen::Matrix4d misclosure = chain[p.a] * p.pairwise.matrix * chain[p.b].inverse();
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        for (std::size_t i = 0; i + 1 < loop.stations.size(); ++i)
            centre += (stations[loop.stations[i]].centre + worldOrigin) / static_cast<double>(loop.stations.size() - 1);
        motionSize(misclosure, centre, loop.rotationDegrees, loop.translationMetres);
        loops.push_back(std::move(loop));
    }
    return loops;
}

//! The fraction of `from`'s first points (moved by `fromToOn`) that lie
//! within `tolerance` of the tangent plane of their closest point of `on`,
//! that point within `reach`.
double posedAgreement(const Station& from, const Station& on, const Eigen::Matrix4d& fromToOn, const Eigen::Vector3d& worldOrigin,
                      double tolerance, double reach)
{
    Matched m;
    match(from, toLocal(fromToOn, worldOrigin), on, Eigen::Isometry3d::Identity(), worldOrigin, 4000, m);
    std::size_t agree = 0;
    for (std::size_t i = 0; i < m.x.size(); ++i)
        agree += m.distance[i] <= reach && std::abs(m.residual[i]) <= tolerance;
    return static_cast<double>(agree) / static_cast<double>(std::max<std::size_t>(m.x.size(), 1));
}

//! The fraction of `from`'s first points (moved by `fromToOn`) that lie
//! where `on`'s scanner looked through empty space (0 without its view).
//! The right pose puts a few there (moved objects, depth edges); a pose that
//! fits the walls of a hall that repeats itself puts the clutter of one
//! station in the other's empty aisles.
double freeSpaceShare(const Station& from, const Station& on, const Eigen::Matrix4d& fromToOn, const Eigen::Vector3d& worldOrigin)
{
    if (!on.view)
        return 0;
    const Eigen::Isometry3d pose = toLocal(fromToOn, worldOrigin);
    const std::size_t count = std::min<std::size_t>(4000, from.sample.size());
    std::size_t through = 0;
    for (std::size_t i = 0; i < count; ++i)
        through += on.view->inFreeSpace(pose * from.sample[i] + worldOrigin);
    return static_cast<double>(through) / static_cast<double>(std::max<std::size_t>(count, 1));
}

//! Whether the motions b -> a, c -> a and b -> c agree: b -> a equals going
//! through c, within `degrees` and `metres` (the misclosure's displacement at
//! `at`, b's centre).
bool triangleCloses(const Eigen::Matrix4d& ab, const Eigen::Matrix4d& ac, const Eigen::Matrix4d& cb, const Eigen::Vector3d& at,
                    double degrees, double metres)
{
    double angle = 0, shift = 0;
    motionSize(ab.inverse() * ac * cb, at, angle, shift);
    return angle <= degrees && shift <= metres;
}

//! A pair registered alone: its candidate motions (b -> a), each refined by
//! ICP, with how much of both stations each brings onto the other.
struct PairHypotheses
{
    StationPair pair; //!< pairwise: the candidate chosen
    std::vector<RegistrationReport> candidates;
    std::vector<double> shares;
    std::vector<bool> fromWhereTheyAre; //!< per candidate: refined from the stations' own start
    double tolerance = 0; //!< of the agreement: 3 robust sigmas of the residuals, the smallest over the candidates
};

//! The change-robust ICP that refines a pair's candidates.
IcpParams pairIcp(const StationParams& params, double spacing)
{
    IcpParams icp;
    icp.constraint = params.constraint;
    icp.kernel = RobustKernel::Cauchy;
    icp.changeRobust = true;
    icp.sampleCount = params.sampleCount;
    icp.seed = params.seed;
    // From within about a feature spacing (any start): the ICP needs no more reach.
    icp.maxDistance = params.anyStart ? std::min(params.maxDistance, 4 * spacing) : params.maxDistance;
    // A pair's candidates are weighed by their shares; their residuals over
    // the sample are enough (every station's points are not moved per start).
    icp.residualOfEveryPoint = false;
    return icp;
}

//! A candidate's score: the points of both stations it brings onto the
//! other's surface within `tolerance`, less those it puts where the other
//! scanner saw through. A hall is near symmetric under a half turn: the
//! turned fit lands walls, floor and roof as well, and only the clutter
//! (racks, machines, a partition's door) tells them apart; the ICP's own RMS,
//! over what it kept, preferred the wrong turn that kept less.
double candidateShare(const std::vector<Station>& stations, std::size_t a, std::size_t b, const Eigen::Matrix4d& motion,
                      double tolerance, double spacing, const Eigen::Vector3d& worldOrigin)
{
    const Eigen::Matrix4d back = motion.inverse();
    return posedAgreement(stations[b], stations[a], motion, worldOrigin, tolerance, 2 * spacing) +
           posedAgreement(stations[a], stations[b], back, worldOrigin, tolerance, 2 * spacing) -
           kFreeSpaceWeight * (freeSpaceShare(stations[b], stations[a], motion, worldOrigin) +
                               freeSpaceShare(stations[a], stations[b], back, worldOrigin));
}

//! Whether two motions are the same (within 0.05 deg and `metres`).
bool sameMotion(const Eigen::Matrix4d& p, const Eigen::Matrix4d& q, double metres)
{
    return rotationDegrees(p.topLeftCorner<3, 3>().transpose() * q.topLeftCorner<3, 3>()) < 0.05 &&
           (p.topRightCorner<3, 1>() - q.topRightCorner<3, 1>()).norm() < metres;
}

//! Adds a candidate unless the same motion is there already.
void addCandidate(PairHypotheses& hypotheses, RegistrationReport report, double share, bool fromWhereTheyAre, double spacing)
{
    for (const RegistrationReport& kept : hypotheses.candidates)
        if (sameMotion(kept.matrix, report.matrix, spacing))
            return;
    hypotheses.candidates.push_back(std::move(report));
    hypotheses.shares.push_back(share);
    hypotheses.fromWhereTheyAre.push_back(fromWhereTheyAre);
}

//! The pair's overlap after its motion: within two feature spacings (the
//! joint adjustment's distance at most) of the other station, the larger of
//! both ways; below the minimum, the pair is left out.
void measureOverlap(StationPair& pair, const std::vector<Station>& stations, double spacing, const StationParams& params,
                    const Eigen::Vector3d& worldOrigin)
{
    const double near = std::min(params.maxDistance, 2 * spacing);
    pair.overlap = std::max(posedAgreement(stations[pair.b], stations[pair.a], pair.pairwise.matrix, worldOrigin, kInfinity, near),
                            posedAgreement(stations[pair.a], stations[pair.b], pair.pairwise.matrix.inverse(), worldOrigin, kInfinity, near));
    pair.used = pair.overlap >= params.minOverlap;
    if (!pair.used)
        pair.note = "overlap " + std::to_string(pair.overlap) + " below the minimum";
}

//! The pair's best candidate becomes its motion, with its overlap.
void chooseBestCandidate(PairHypotheses& hypotheses, const std::vector<Station>& stations, double spacing,
                         const StationParams& params, const Eigen::Vector3d& worldOrigin)
{
    StationPair& pair = hypotheses.pair;
    const auto best = static_cast<std::size_t>(std::max_element(hypotheses.shares.begin(), hypotheses.shares.end()) - hypotheses.shares.begin());
    pair.pairwise = hypotheses.candidates[best];
    pair.agreement = hypotheses.shares[best];
    measureOverlap(pair, stations, spacing, params, worldOrigin);
}

//! One pair registered alone: global alignment from the descriptors (any
//! start), then change-robust ICP from it and from where the stations are;
//! or ICP from where the stations are.
PairHypotheses registerPair(const std::vector<Station>& stations, std::size_t a, std::size_t b,
                            const std::vector<std::shared_ptr<const AlignmentFeatures>>& features, double spacing,
                            const StationParams& params, const Eigen::Vector3d& worldOrigin)
{
    PairHypotheses hypotheses;
    StationPair& pair = hypotheses.pair;
    pair.a = a;
    pair.b = b;
    IcpParams icp = pairIcp(params, spacing);
    std::vector<Eigen::Matrix4d> starts{Eigen::Matrix4d::Identity()};
    if (params.anyStart) {
        GlobalAlignmentParams global;
        global.constraint = params.constraint;
        // Two scanners whose verticals agree are levelled tripods: the
        // search turns one about that vertical only (two matches make a
        // motion, and a match whose normals lean differently is no match),
        // which finds the pose where a 6-DOF search among sparse, repeated
        // descriptors settles on a symmetry of the site. The adjustment
        // keeps its own degrees of freedom for the levelling's residue.
        if (params.constraint.dof == Dof::Six && stations[a].scanner && stations[b].scanner &&
            stations[a].up.dot(stations[b].up) >= std::cos(kLevelledSearchTilt))
            global.constraint = DofConstraint{Dof::Four, stations[a].up};
        global.seed = params.seed + 31 * a + b;
        global.alternatives = 4;
        try {
            const GlobalAlignmentResult found = globalAlign(*features[b], *features[a], global);
            // Where the stations already are is a candidate too: stations
            // brought roughly together before (or a survey's own poses) keep
            // that start, which the global search may not rank first in a
            // hall that repeats itself.
            starts = {Eigen::Matrix4d::Identity(), found.report.matrix};
            starts.insert(starts.end(), found.alternatives.begin(), found.alternatives.end());
            // A scan that holds its scanner's pose is a station on a tripod:
            // the scanner's z is up within its levelling (a compensator's
            // few degrees). A fit that tips one station's vertical over (a
            // floor on a roof, a wall on a floor) is a symmetry of the site,
            // not a pose.
            if (stations[a].scanner && stations[b].scanner)
                starts.erase(std::remove_if(starts.begin() + 1, starts.end(),
                                            [&](const Eigen::Matrix4d& m) {
                                                return (m.topLeftCorner<3, 3>() * stations[b].up).dot(stations[a].up) < std::cos(kMaxStationTilt);
                                            }),
                             starts.end());
        } catch (const Error& e) {
            if (e.code() == ErrorCode::Cancelled)
                throw;
            pair.note = std::string("no global alignment (") + e.what() + "): from where the stations are";
        }
    }
    std::vector<RegistrationReport> refined;
    std::vector<bool> fromWhereTheyAre;
    std::string failure;
    double sigma = kInfinity;
    const std::size_t fullIterations = icp.maxIterations;
    for (const Eigen::Matrix4d& start : starts) {
        icp.initial = start;
        // Where the stations are, beside the global search's motions: a
        // station that is there within the ICP's reach converges in a few
        // dozen iterations (12-36 on the hall); one in its own
        // scanner's heading slides for the full hundred (1.5-2 s a pair
        // there) to a pose no score keeps.
        icp.maxIterations = start.isIdentity() && starts.size() > 1 ? std::min<std::size_t>(fullIterations, kWhereTheyAreIterations)
                                                                       : fullIterations;
        try {
            refined.push_back(detail::icpOnSurface(*stations[b].cloud, *stations[a].surface, icp, nullptr).report);
            fromWhereTheyAre.push_back(start.isIdentity());
            const double s = kMadToSigma * refined.back().median;
            if (std::isfinite(s) && s > 0)
                sigma = std::min(sigma, s);
        } catch (const Error& e) {
            if (e.code() == ErrorCode::Cancelled)
                throw;
            failure = e.what();
        }
    }
    hypotheses.tolerance = std::isfinite(sigma) ? 3 * sigma : spacing;
    for (std::size_t k = 0; k < refined.size(); ++k) {
        double share = candidateShare(stations, a, b, refined[k].matrix, hypotheses.tolerance, spacing, worldOrigin);
        // Where the stations are is where the surveyor put them: it keeps
        // a tenth in hand over a fit found elsewhere (a site that repeats
        // itself offers those), which a station in another heading, far
        // from its place, does not come near.
        if (fromWhereTheyAre[k] && params.anyStart)
            share += kWhereTheyAreBonus * std::abs(share);
        addCandidate(hypotheses, std::move(refined[k]), share, fromWhereTheyAre[k] && params.anyStart, spacing);
    }
    if (hypotheses.candidates.empty()) {
        pair.used = false;
        pair.note = "no registration: " + failure;
        return hypotheses;
    }
    chooseBestCandidate(hypotheses, stations, spacing, params, worldOrigin);
    return hypotheses;
}

//! The report of a motion composed through other stations: its residuals
//! over the points of b that land within two feature spacings of a.
RegistrationReport composedReport(const std::vector<Station>& stations, std::size_t a, std::size_t b, const Eigen::Matrix4d& motion,
                                  double spacing, const Eigen::Vector3d& worldOrigin)
{
    RegistrationReport report;
    report.method = "composed through the other stations";
    report.matrix = motion;
    report.centre = stations[b].centre + worldOrigin;
    Matched m;
    match(stations[b], toLocal(motion, worldOrigin), stations[a], Eigen::Isometry3d::Identity(), worldOrigin, stations[b].sample.size(), m);
    std::vector<double> residuals;
    double squares = 0;
    for (std::size_t i = 0; i < m.x.size(); ++i)
        if (m.distance[i] <= 2 * spacing) {
            residuals.push_back(std::abs(m.residual[i]));
            squares += m.residual[i] * m.residual[i];
        }
    report.rms = residuals.empty() ? 0 : std::sqrt(squares / static_cast<double>(residuals.size()));
    report.median = medianOf(residuals);
    report.overlap = static_cast<double>(residuals.size()) / static_cast<double>(std::max<std::size_t>(m.x.size(), 1));
    return report;
}

//! Places the stations one at a time from a starting pair's motion, each
//! where its candidates agree best with every station already placed. A
//! hall is near symmetric under a half turn and repeats along its columns:
//! a pair alone may prefer a turned or shifted fit (two stations that see
//! the hall from far apart share little but its shell), while the stations
//! already placed, together, see the clutter such a fit puts in their empty
//! aisles. Of every candidate of a pair between a placed and an unplaced
//! station, the pose whose summed score (candidateShare) against all placed
//! stations is highest places its station. Poses in the starting pair's
//! frame; a station no pair links stays unplaced.
struct Placement
{
    std::vector<Eigen::Matrix4d> pose;
    std::vector<bool> placed;
    double score = 0; //!< summed over the pairs of placed stations
};

//! The placement's scores (candidateShare at one tolerance), each computed
//! once: the starts of the placement, and each station's candidates scored
//! against the station they were registered with, ask for the same relative
//! motions again (a motion and its inverse score alike), up to rounding.
class PlacementShares
{
public:
    PlacementShares(const std::vector<Station>& stations, double tolerance, double spacing, const Eigen::Vector3d& worldOrigin)
        : stations_(stations), tolerance_(tolerance), spacing_(spacing), worldOrigin_(worldOrigin)
    {
    }

    double operator()(std::size_t a, std::size_t b, const Eigen::Matrix4d& motion)
    {
        const Eigen::Matrix4d m = a < b ? motion : Eigen::Matrix4d(motion.inverse());
        if (b < a)
            std::swap(a, b);
        for (const Known& known : known_)
            if (known.a == a && known.b == b && (known.motion - m).cwiseAbs().maxCoeff() <= kSameWithinRounding)
                return known.share;
        known_.push_back({a, b, m, candidateShare(stations_, a, b, m, tolerance_, spacing_, worldOrigin_)});
        return known_.back().share;
    }

private:
    //! Two motions apart by this (rotation entries, metres) are one.
    static constexpr double kSameWithinRounding = 1e-9;
    struct Known
    {
        std::size_t a, b;
        Eigen::Matrix4d motion;
        double share;
    };
    const std::vector<Station>& stations_;
    double tolerance_, spacing_;
    Eigen::Vector3d worldOrigin_;
    std::vector<Known> known_;
};

Placement placeFrom(const std::vector<PairHypotheses>& pairs, const std::vector<std::vector<std::ptrdiff_t>>& index, std::size_t startPair,
                    std::size_t startCandidate, std::size_t count, PlacementShares& share)
{
    Placement placement{std::vector<Eigen::Matrix4d>(count, Eigen::Matrix4d::Identity()), std::vector<bool>(count, false), 0};
    std::vector<Eigen::Matrix4d>& pose = placement.pose;
    std::vector<bool>& placed = placement.placed;
    const PairHypotheses& first = pairs[startPair];
    placed[first.pair.a] = placed[first.pair.b] = true;
    pose[first.pair.b] = first.candidates[startCandidate].matrix;
    placement.score = share(first.pair.a, first.pair.b, pose[first.pair.b]);
    for (;;) {
        double bestScore = -kInfinity;
        std::size_t bestStation = 0;
        Eigen::Matrix4d bestPose = Eigen::Matrix4d::Identity();
        for (std::size_t k = 0; k < count; ++k) {
            if (placed[k])
                continue;
            for (std::size_t p = 0; p < count; ++p) {
                if (!placed[p] || index[p][k] < 0)
                    continue;
                const PairHypotheses& h = pairs[static_cast<std::size_t>(index[p][k])];
                for (std::size_t c = 0; c < h.candidates.size(); ++c) {
                    const Eigen::Matrix4d& m = h.candidates[c].matrix; // b -> a
                    const Eigen::Matrix4d candidate = pose[p] * (h.pair.a == p ? m : Eigen::Matrix4d(m.inverse()));
                    double score = 0;
                    for (std::size_t q = 0; q < count; ++q)
                        if (placed[q])
                            score += share(q, k, pose[q].inverse() * candidate);
                    if (h.fromWhereTheyAre[c])
                        score += kWhereTheyAreBonus * std::abs(score);
                    if (score > bestScore) {
                        bestScore = score;
                        bestStation = k;
                        bestPose = candidate;
                    }
                }
            }
        }
        if (!std::isfinite(bestScore))
            return placement;
        placed[bestStation] = true;
        pose[bestStation] = bestPose;
        placement.score += bestScore;
    }
}

//! The placement that scores best over a few starts: the best candidate of
//! each of the three pairs that agree best (a wrong start, a pair turned by
//! the hall's symmetry, turns every station placed from it). Each station's
//! pose is station -> station 0 (global coordinates); none is placed when
//! station 0 is not (the stations fall apart in groups: the spanning tree
//! says so later).
Placement placeStations(const std::vector<PairHypotheses>& pairs, const std::vector<Station>& stations, double spacing,
                                           const Eigen::Vector3d& worldOrigin)
{
    const std::size_t count = stations.size();
    std::vector<std::vector<std::ptrdiff_t>> index(count, std::vector<std::ptrdiff_t>(count, -1));
    std::vector<double> tolerances;
    std::vector<std::size_t> starts;
    for (std::size_t e = 0; e < pairs.size(); ++e)
        if (pairs[e].pair.used && !pairs[e].candidates.empty()) {
            index[pairs[e].pair.a][pairs[e].pair.b] = index[pairs[e].pair.b][pairs[e].pair.a] = static_cast<std::ptrdiff_t>(e);
            tolerances.push_back(pairs[e].tolerance);
            starts.push_back(e);
        }
    Placement best{std::vector<Eigen::Matrix4d>(count, Eigen::Matrix4d::Identity()), std::vector<bool>(count, false), -kInfinity};
    if (starts.empty())
        return best;
    const double tolerance = medianOf(tolerances);
    std::sort(starts.begin(), starts.end(), [&](std::size_t p, std::size_t q) { return pairs[p].pair.agreement > pairs[q].pair.agreement; });
    starts.resize(std::min<std::size_t>(3, starts.size()));
    PlacementShares share(stations, tolerance, spacing, worldOrigin);
    for (std::size_t e : starts) {
        const auto candidate = static_cast<std::size_t>(std::max_element(pairs[e].shares.begin(), pairs[e].shares.end()) - pairs[e].shares.begin());
        Placement placement = placeFrom(pairs, index, e, candidate, count, share);
        if (placement.score > best.score)
            best = std::move(placement);
    }
    if (!best.placed[0])
        return Placement{std::vector<Eigen::Matrix4d>(count, Eigen::Matrix4d::Identity()), std::vector<bool>(count, false), -kInfinity};
    const Eigen::Matrix4d toStation0 = best.pose[0].inverse();
    for (std::size_t k = 0; k < count; ++k)
        best.pose[k] = best.placed[k] ? Eigen::Matrix4d(toStation0 * best.pose[k]) : Eigen::Matrix4d::Identity();
    return best;
}

//! Each pair between placed stations takes the candidate the placement
//! implies (within `degrees` and `metres` at b's centre), or, when its own
//! search missed that motion, the motion composed through the other
//! stations; its overlap is measured again at that motion (a pair whose own
//! best fit, turned, overlapped too little, comes back).
void chooseImpliedCandidates(std::vector<PairHypotheses>& pairs, const std::vector<Station>& stations, const Placement& placement,
                             double spacing, const StationParams& params, const Eigen::Vector3d& worldOrigin, double degrees, double metres)
{
    const std::vector<Eigen::Matrix4d>& pose = placement.pose;
    std::vector<std::size_t> choice(pairs.size(), 0);
    for (std::size_t e = 0; e < pairs.size(); ++e) {
        PairHypotheses& h = pairs[e];
        if (h.candidates.empty()) {
            continue;
        }
        if (!placement.placed[h.pair.a] || !placement.placed[h.pair.b]) {
            choice[e] = static_cast<std::size_t>(std::max_element(h.shares.begin(), h.shares.end()) - h.shares.begin());
            continue;
        }
        const Eigen::Matrix4d implied = pose[h.pair.a].inverse() * pose[h.pair.b];
        const Eigen::Vector3d at = stations[h.pair.b].centre + worldOrigin;
        double nearest = kInfinity;
        for (std::size_t k = 0; k < h.candidates.size(); ++k) {
            double angle = 0, shift = 0;
            motionSize(implied.inverse() * h.candidates[k].matrix, at, angle, shift);
            if (angle <= degrees && shift <= metres && shift < nearest) {
                nearest = shift;
                choice[e] = k;
            }
        }
        if (!std::isfinite(nearest)) {
            RegistrationReport report = composedReport(stations, h.pair.a, h.pair.b, implied, spacing, worldOrigin);
            h.candidates.push_back(std::move(report));
            h.shares.push_back(candidateShare(stations, h.pair.a, h.pair.b, implied, h.tolerance, spacing, worldOrigin));
            h.fromWhereTheyAre.push_back(false);
            choice[e] = h.candidates.size() - 1;
            h.pair.note = "its own search missed the motion the other stations place it at";
        } else if (h.pair.note.rfind("overlap", 0) == 0) {
            h.pair.note.clear();
        }
        h.pair.pairwise = h.candidates[choice[e]];
        h.pair.agreement = h.shares[choice[e]];
        measureOverlap(h.pair, stations, spacing, params, worldOrigin);
    }
    // A site that repeats itself (a hall under a half or a quarter turn, a
    // row of columns) fits a turned or shifted pair nearly as well: said,
    // not hidden. Nearly: within 5 % of the chosen candidate's share.
    for (PairHypotheses& h : pairs) {
        if (h.candidates.size() < 2 || !h.pair.used)
            continue;
        const std::size_t chosen = choice[static_cast<std::size_t>(&h - pairs.data())];
        if (!h.pair.note.empty() || !(h.shares[chosen] > 0))
            continue;
        for (std::size_t k = 0; k < h.candidates.size(); ++k) {
            if (k == chosen || h.shares[k] < 0.95 * h.shares[chosen])
                continue;
            const Eigen::Matrix4d between = h.candidates[chosen].matrix.inverse() * h.candidates[k].matrix;
            double angle = 0, shift = 0;
            motionSize(between, stations[h.pair.b].centre + worldOrigin, angle, shift);
            std::ostringstream note;
            note.precision(3);
            note << "ambiguous: another fit, turned " << angle << " deg and moved " << shift << " m, brings "
                 << 100 * h.shares[k] / h.shares[chosen] << " % as many points together (the site repeats itself); check this pose";
            h.pair.note = note.str();
            break;
        }
    }
}

//! Leaves out the pairs that disagree with the loops they close. A pair's
//! motion b -> a should equal any path a -> c -> b's; each triangle of used
//! pairs is a vote for (closes within `degrees` and `metres` at b's centre)
//! or against each of its three pairs. While a pair has more votes against
//! than for, the worst such pair (most against, then least agreement) is left
//! out and the votes are counted again: a wrong pair, from a symmetric hall
//! or a repeated rack, disagrees with every triangle it is in, while a right
//! one is outvoted only where wrong ones meet.
void leaveOutInconsistentPairs(std::vector<StationPair>& pairs, const std::vector<Station>& stations, const Eigen::Vector3d& worldOrigin,
                               double degrees, double metres)
{
    const std::size_t count = stations.size();
    for (;;) {
        // index[a][b]: the used pair between a and b, or none.
        std::vector<std::vector<std::ptrdiff_t>> index(count, std::vector<std::ptrdiff_t>(count, -1));
        for (std::size_t e = 0; e < pairs.size(); ++e)
            if (pairs[e].used)
                index[pairs[e].a][pairs[e].b] = index[pairs[e].b][pairs[e].a] = static_cast<std::ptrdiff_t>(e);
        const auto motion = [&](std::size_t to, std::size_t from) { // from -> to
            const StationPair& p = pairs[static_cast<std::size_t>(index[to][from])];
            return p.a == to ? Eigen::Matrix4d(p.pairwise.matrix) : Eigen::Matrix4d(p.pairwise.matrix.inverse());
        };
        std::vector<int> against(pairs.size(), 0), support(pairs.size(), 0);
        for (std::size_t a = 0; a < count; ++a)
            for (std::size_t b = a + 1; b < count; ++b)
                for (std::size_t c = b + 1; c < count; ++c) {
                    if (index[a][b] < 0 || index[a][c] < 0 || index[b][c] < 0)
                        continue;
                    const bool closes = triangleCloses(motion(a, b), motion(a, c), motion(c, b), stations[b].centre + worldOrigin,
                                                       degrees, metres);
                    for (const std::ptrdiff_t e : {index[a][b], index[a][c], index[b][c]})
                        (closes ? support : against)[static_cast<std::size_t>(e)] += 1;
                }
        std::ptrdiff_t worst = -1;
        for (std::size_t e = 0; e < pairs.size(); ++e) {
            if (!pairs[e].used || against[e] <= support[e])
                continue;
            if (worst < 0 || against[e] > against[static_cast<std::size_t>(worst)] ||
                (against[e] == against[static_cast<std::size_t>(worst)] && pairs[e].agreement < pairs[static_cast<std::size_t>(worst)].agreement))
                worst = static_cast<std::ptrdiff_t>(e);
        }
        if (worst < 0)
            return;
        StationPair& p = pairs[static_cast<std::size_t>(worst)];
        p.used = false;
        p.note = "disagrees with " + std::to_string(against[static_cast<std::size_t>(worst)]) + " of the loops it closes (agrees with " +
                 std::to_string(support[static_cast<std::size_t>(worst)]) + ")";
    }
}

} // namespace

namespace {

void checkStationParams(const std::vector<const PointCloud*>& clouds, const StationParams& params)
{
    if (clouds.size() < 2)
        throw Error(ErrorCode::InvalidArgument, "stations: at least 2 stations");
    if (!(params.maxDistance > 0 && std::isfinite(params.maxDistance)) || !(params.minOverlap > 0 && params.minOverlap <= 1) ||
        params.sampleCount < 10 || params.maxIterations < 1)
        throw Error(ErrorCode::InvalidArgument,
                    "stations: the maximum distance is > 0, the minimum overlap in (0, 1], at least 10 points and 1 iteration");
}

//! The shape descriptors of every station for the global search (when the
//! stations may start anywhere); returns the feature spacing the pairs use.
double describeStations(const std::vector<Station>& stations, const StationParams& params,
                        std::vector<std::shared_ptr<const AlignmentFeatures>>& features, ProgressObserver* progress)
{
    if (!params.anyStart)
        return params.maxDistance / 2;
    double spacing = params.featureSpacing.value_or(0.0);
    if (!params.featureSpacing) {
        std::vector<double> spacings;
        for (const Station& s : stations)
            spacings.push_back(alignmentSpacing(*s.cloud, 10000));
        spacing = medianOf(spacings);
    }
    ProgressTicker describeTicker(progress, "Stations: shape descriptors", stations.size());
    for (std::size_t k = 0; k < stations.size(); ++k) {
        features[k] = describeForAlignment(*stations[k].cloud, spacing, nullptr);
        describeTicker.step();
    }
    return spacing;
}

//! Each scanner's view, for the free-space test: a point nearer than what
//! it saw by a feature spacing (at least 5 cm) contradicts a pose.
void giveStationsTheirViews(std::vector<Station>& stations, double spacing, const Eigen::Vector3d& worldOrigin)
{
    VisibilityParams seeing;
    seeing.tolerance = std::max(0.05, spacing);
    for (Station& s : stations)
        if (s.cloud->sensors().size() == 1) {
            s.view = std::make_unique<DepthMap>(*s.cloud, s.cloud->sensors().front(), seeing);
            s.scanner = s.cloud->sensors().front().position - worldOrigin;
            s.up = s.cloud->sensors().front().orientation * Eigen::Vector3d::UnitZ();
        }
}

//! Every pair registered alone, placed together, and those that disagree
//! with their loops left out: the used pairs go to result.pairs, the others
//! are returned.
std::vector<StationPair> chooseStationPairs(const std::vector<Station>& stations,
                                            const std::vector<std::shared_ptr<const AlignmentFeatures>>& features, double spacing,
                                            const StationParams& params, const Eigen::Vector3d& worldOrigin, StationResult& result,
                                            ProgressObserver* progress)
{
    const std::size_t count = stations.size();
    std::vector<PairHypotheses> hypotheses;
    ProgressTicker pairTicker(progress, "Stations: pairwise registration", count * (count - 1) / 2);
    for (std::size_t a = 0; a < count; ++a)
        for (std::size_t b = a + 1; b < count; ++b) {
            hypotheses.push_back(registerPair(stations, a, b, features, spacing, params, worldOrigin));
            pairTicker.step();
        }
    const Placement placement = placeStations(hypotheses, stations, spacing, worldOrigin);
    chooseImpliedCandidates(hypotheses, stations, placement, spacing, params, worldOrigin, 0.5, std::max(0.05, 2 * spacing));
    std::vector<StationPair> allPairs;
    for (PairHypotheses& h : hypotheses) {
        if (h.pair.note.rfind("ambiguous", 0) == 0)
            result.report.notes.push_back("pair " + std::to_string(h.pair.a) + "-" + std::to_string(h.pair.b) + " " + h.pair.note);
        allPairs.push_back(std::move(h.pair));
    }
    leaveOutInconsistentPairs(allPairs, stations, worldOrigin, 0.5, std::max(0.05, 2 * spacing));
    std::vector<StationPair> leftOut;
    for (StationPair& p : allPairs)
        (p.used ? result.pairs : leftOut).push_back(std::move(p));
    return leftOut;
}

//! The adjusted poses in global coordinates, each used pair's residual and
//! disagreement with its own registration, the left-out pairs with their
//! reasons, and the residuals' statistics.
void reportAdjustment(const std::vector<Station>& stations, const JointAdjustmentOutcome& adjusted, std::vector<StationPair> leftOut,
                      const StationParams& params, const Eigen::Vector3d& worldOrigin, StationResult& result)
{
    RegistrationReport& report = result.report;
    result.poses.resize(stations.size());
    for (std::size_t k = 0; k < stations.size(); ++k)
        result.poses[k] = toGlobal(adjusted.pose[k], worldOrigin);
    result.poses[0] = Eigen::Matrix4d::Identity();
    for (std::size_t e = 0; e < result.pairs.size(); ++e) {
        StationPair& p = result.pairs[e];
        p.adjustedRms = adjusted.pairCount[e] > 0 ? std::sqrt(adjusted.pairSquares[e] / adjusted.pairCount[e])
                                                  : std::numeric_limits<double>::quiet_NaN();
        const Eigen::Matrix4d motion = result.poses[p.a].inverse() * result.poses[p.b];
        motionSize(p.pairwise.matrix.inverse() * motion, stations[p.b].centre + worldOrigin, p.disagreementDegrees,
                   p.disagreementMetres);
        if (!p.pairwise.degeneracy.empty())
            report.notes.push_back("pair " + std::to_string(p.a) + "-" + std::to_string(p.b) + ": " + p.pairwise.degeneracy);
    }
    for (StationPair& p : leftOut) {
        report.notes.push_back("pair " + std::to_string(p.a) + "-" + std::to_string(p.b) + " left out: " + p.note);
        p.adjustedRms = p.disagreementDegrees = p.disagreementMetres = std::numeric_limits<double>::quiet_NaN();
        result.pairs.push_back(std::move(p));
    }
    const std::vector<double>& residuals = adjusted.finalResiduals;
    double sum2 = 0;
    for (double r : residuals)
        sum2 += r * r;
    report.rms = std::sqrt(sum2 / static_cast<double>(std::max<std::size_t>(residuals.size(), 1)));
    report.median = percentileOf(residuals, 0.5);
    report.p90 = percentileOf(residuals, 0.9);
    report.p95 = percentileOf(residuals, 0.95);
    report.p99 = percentileOf(residuals, 0.99);
    report.overlap = std::numeric_limits<double>::quiet_NaN();
    if (!report.converged)
        report.notes.push_back("not converged after " + std::to_string(params.maxIterations) + " iterations");
}

} // namespace

StationResult adjustStations(const std::vector<const PointCloud*>& clouds, const StationParams& params, ProgressObserver* progress)
{
    checkStationParams(clouds, params);
    Eigen::Vector3d worldOrigin;
    std::vector<Station> stations = prepare(clouds, params, worldOrigin, progress);
    const std::size_t count = stations.size();
    StationResult result;

    std::vector<std::shared_ptr<const AlignmentFeatures>> features(count);
    const double spacing = describeStations(stations, params, features, progress);
    giveStationsTheirViews(stations, spacing, worldOrigin);
    std::vector<StationPair> leftOut = chooseStationPairs(stations, features, spacing, params, worldOrigin, result, progress);

    // The joint adjustment, from the poses chained along a spanning tree of the used pairs.
    std::vector<std::ptrdiff_t> parentEdge;
    std::vector<std::size_t> parent;
    const std::vector<Eigen::Matrix4d> chain = chainPoses(count, result.pairs, parentEdge, parent);
    result.loops = loopMisclosures(stations, result.pairs, chain, parentEdge, parent, worldOrigin);
    result.report.method = "multi-station adjustment, " + std::to_string(count) + " stations, " + std::to_string(result.pairs.size()) +
                           " pairs, " + dofName(params.constraint.dof) + " DOF";
    const JointAdjustmentOutcome adjusted = detail::adjustJointly(stations, result.pairs, chain, params, worldOrigin, result.report, progress);
    reportAdjustment(stations, adjusted, std::move(leftOut), params, worldOrigin, result);
    return result;
}

} // namespace scandiff::plugins
