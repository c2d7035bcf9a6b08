// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Family A: multi-station terrestrial scans of an industrial hall, for tools
//! that register N stations together and return, per station, the pose
//! (station frame -> frame of station 0).
//!
//! Conditions (a survey of a hall with a levelled TLS on a tripod):
//! - the hall: floor, roof slab, four walls 0.3 m thick with doors, man doors
//!   and high windows (rays through them reach the outside ground or the sky),
//!   columns on a grid under roof beams, an optional interior partition with a
//!   wide door that does not reach the roof, and clutter: pallet racking,
//!   machines (a body with a control cabinet on top), tanks, pallet stacks;
//!   optionally objects that moved between two stations (a forklift, a
//!   pallet), the usual trouble of a working site;
//! - each station is simulated as a TLS: rays from the scanner centre
//!   (1.5-1.8 m above the floor) on a regular yaw x pitch grid (full turn,
//!   pitch from about -60 deg to the zenith), nearest surface hit, nothing
//!   beyond the maximum range or below the minimum range, no echo at
//!   incidences beyond 88 deg, Gaussian range noise along the ray. Points are
//!   stored in the scanner's own frame (levelled, heading arbitrary), exactly
//!   as a scanner writes them: global = pose * local;
//! - truth: the poses (station -> world) and trueRelativePose(i) (station i ->
//!   station 0).
//!
//! Issue case: four stations, headings 0, 35, 120, 250 deg, several metres
//! apart, about 60 % of the hall seen by each (partition, racks, machines),
//! 2 mm range noise, about 250-350 k points each (angular step 0.42 deg).
//!
//! Family ranges (drawFamily): hall 25-80 m x 12-40 m x 5-12 m; 3-6
//! stations, headings uniform in 0-360 deg independently; tilt 0 (levelled)
//! or up to 0.03 deg; consecutive stations 4-15 m apart and retried until
//! every consecutive pair overlaps 30-90 % (overlap defined in viewStats());
//! range noise 1-10 mm (log-uniform); survey angular step giving 2 mm - 3 cm
//! spacing at 10 m (log-uniform); maximum range 30-120 m; half of the draws
//! at UTM-like world coordinates (~500000, 5400000, 100-500 m) with the hall
//! turned arbitrarily, the station clouds staying near zero as scanners
//! write them; 0-2 objects moved between stations.
//!
//! Scale: `scale` acts on the linear point density. The simulated angular
//! step is the survey's, coarsened when needed so a station returns at most
//! about max(25 k, 3 M * scale^2) points: scale 0.1 or less gives 25-40 k
//! points per station, scale 0.3 about 270 k, scale 1 up to 3 M (survey
//! steps finer than ~2.3 cm at 10 m are coarsened even at scale 1: a
//! full-dome scan at 2 mm at 10 m would be 400 M points).
//!
//! The hall itself (parameters, solids, coverage and overlap of stations) is
//! in StationsHall.h; this header simulates the scans, draws the family and
//! scores. Namespace scandiff::test::family::stations.
//!
//! Scoring: per station, the rotation error (deg) and the largest
//! displacement (m) of that station's points between the estimated pose and
//! the true one (both relative to station 0). Issue targets: 0.005 deg, 2 mm.


#include "StationsHall.h"

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/SensorPose.h>
#include <scandiff/core/SplitMix.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace scandiff::test::family::stations {

struct StationsScene
{
    StationsParams params;
    std::vector<PointCloud> clouds;         //!< one per station, in its own scanner frame
    std::vector<Eigen::Matrix4d> truePoses; //!< station -> world
    //! Station i -> frame of station 0 (what the tool estimates).
    Eigen::Matrix4d trueRelativePose(std::size_t i) const { return truePoses[0].inverse() * truePoses[i]; }
};

//! The scanner's grid: pitch rows from pitchMin up to just below the zenith.
struct ScanGrid
{
    int columns = 0, rows = 0;
    double yawStep = 0.0, pitchStep = 0.0, pitchMin = 0.0;
};

inline ScanGrid scanGridOf(const StationsParams& p)
{
    ScanGrid g;
    const double step = degToRad(p.angularStepDeg);
    g.columns = std::max(1, static_cast<int>(std::lround(2 * kPi / step)));
    g.yawStep = 2 * kPi / g.columns;
    g.pitchStep = step;
    g.pitchMin = degToRad(p.pitchMinDeg);
    const double top = std::min(degToRad(p.pitchMaxDeg), 0.5 * kPi - 0.5 * step);
    g.rows = static_cast<int>(std::floor((top - g.pitchMin) / step)) + 1;
    return g;
}

//! Simulates the scan of station i: local points in the scanner's frame.
inline std::vector<Eigen::Vector3d> scanStation(const StationsParams& p, std::size_t i)
{
    const std::vector<Solid> solids = hallSolids(p, i);
    const Eigen::Matrix4d pose = stationPoseInHall(p, i);
    const Eigen::Matrix3d R = pose.topLeftCorner<3, 3>();
    const Eigen::Vector3d centre = pose.topRightCorner<3, 1>();
    const ScanGrid g = scanGridOf(p);
    const std::uint64_t stationSeed = splitMix(p.seed) ^ splitMix(0xABCDu + i);
    std::vector<Eigen::Vector3d> points;
    points.reserve(static_cast<std::size_t>(g.columns) * g.rows);
    for (int c = 0; c < g.columns; ++c) { // column after column, as a TLS turns
        const double yaw = c * g.yawStep;
        for (int r = 0; r < g.rows; ++r) {
            const Eigen::Vector3d dLocal = directionOf(yaw, g.pitchMin + r * g.pitchStep);
            const Eigen::Vector3d d = R * dLocal;
            RayHit hit;
            if (!firstHit(solids, centre, d, 0.0, p.maxRange, hit) || hit.t < p.minRange)
                continue;
            if (std::abs(hit.normal.dot(d)) < 0.035) // beyond ~88 deg incidence: no echo
                continue;
            SplitMix64 rng(stationSeed, static_cast<std::uint64_t>(c) * g.rows + r);
            points.push_back(dLocal * (hit.t + p.rangeNoise * gaussian(rng)));
        }
    }
    return points;
}

inline StationsScene make(const StationsParams& p)
{
    StationsScene scene;
    scene.params = p;
    const Eigen::Matrix4d toWorld = hallToWorld(p);
    const ScanGrid g = scanGridOf(p);
    for (std::size_t i = 0; i < p.stations.size(); ++i) {
        PointCloud cloud = cloudFromGlobal(scanStation(p, i), "station " + std::to_string(i));
        SensorPose sensor; // the scanner's own frame: centre at 0, identity orientation
        sensor.yawStep = g.yawStep;
        sensor.pitchStep = g.pitchStep;
        sensor.yawMin = -kPi;
        sensor.yawMax = kPi;
        sensor.pitchMin = g.pitchMin;
        sensor.pitchMax = g.pitchMin + (g.rows - 1) * g.pitchStep;
        sensor.maxRange = p.maxRange;
        cloud.sensors().push_back(sensor);
        scene.clouds.push_back(std::move(cloud));
        scene.truePoses.push_back(toWorld * stationPoseInHall(p, i));
    }
    return scene;
}

//! The issue's condition: four stations, headings 0, 35, 120, 250 deg.
inline StationsParams issueCase()
{
    StationsParams p; // hall 40 x 20 x 8 m, columns every 6.5 m in two rows
    p.partitionX = 20.0; // two rooms joined by a 6 m gap in a 4 m partition
    p.partitionHeight = 4.0;
    p.partitionDoorCentreY = 14.0;
    p.partitionDoorWidth = 6.0;
    p.partitionDoorHeight = 4.0;
    p.beamDepth = 0.5;
    p.racks = 2;
    p.palletStacks = 6;
    p.openings = {{0, 30.0, 4.5, 0.0, 4.5}, {0, 8.0, 1.0, 0.0, 2.1}, {1, 10.0, 4.0, 0.0, 4.2},
                  {2, 6.0, 4.0, 3.0, 4.5},  {2, 14.0, 4.0, 3.0, 4.5}, {2, 30.0, 4.0, 3.0, 4.5}, {3, 15.0, 1.0, 0.0, 2.1}};
    p.clutterSeed = 20240611;
    p.stations = {{{9.0, 6.0}, 1.65, 0.0}, {{15.0, 13.0}, 1.60, 35.0}, {{27.0, 11.0}, 1.70, 120.0}, {{32.0, 13.0}, 1.55, 250.0}};
    p.seed = 7;
    return p;
}

namespace detail {

//! A random hall: size, doors, windows, columns, partition, clutter counts.
inline void drawHall(SplitMix64& rng, StationsParams& p)
{
    p.hallLength = uniformIn(rng, 25.0, 80.0);
    p.hallWidth = uniformIn(rng, 12.0, std::min(40.0, p.hallLength));
    p.hallHeight = uniformIn(rng, 5.0, 12.0);
    p.openings.clear();
    auto wallLength = [&](int wall) { return wall % 2 == 0 ? p.hallLength : p.hallWidth; };
    auto addOpenings = [&](int count, double wMin, double wMax, double bottomMin, double bottomMax, double hMin, double hMax) {
        for (int i = 0; i < count; ++i) {
            HallOpening o;
            o.wall = static_cast<int>(rng.below(4));
            o.width = uniformIn(rng, wMin, wMax);
            o.along = uniformIn(rng, o.width, wallLength(o.wall) - o.width);
            o.bottom = uniformIn(rng, bottomMin, bottomMax);
            o.top = std::min(o.bottom + uniformIn(rng, hMin, hMax), p.hallHeight - 0.5);
            bool clash = false; // openings of a wall never overlap
            for (const HallOpening& q : p.openings)
                clash = clash || (q.wall == o.wall && std::abs(q.along - o.along) < 0.5 * (q.width + o.width) + 0.5);
            if (!clash)
                p.openings.push_back(o);
        }
    };
    addOpenings(1 + static_cast<int>(rng.below(3)), 3.0, 5.0, 0.0, 0.0, 3.5, 5.0); // roll-up doors
    addOpenings(1 + static_cast<int>(rng.below(3)), 0.9, 1.2, 0.0, 0.0, 2.1, 2.1); // man doors
    addOpenings(static_cast<int>(rng.below(7)), 2.0, 5.0, 2.5, 4.0, 1.0, 2.0);     // high windows
    p.columnSpacing = uniformIn(rng, 5.0, 9.0);
    p.columnRows = p.hallWidth < 15 ? static_cast<int>(rng.below(2)) : 1 + static_cast<int>(rng.below(2));
    p.columnSize = uniformIn(rng, 0.4, 0.6);
    p.roundColumns = rng.uniform() < 0.3;
    p.beamDepth = uniformIn(rng, 0.5, 1.0);
    p.partitionHeight = rng.uniform() < 0.75 ? uniformIn(rng, 3.0, p.hallHeight) : 0.0;
    p.partitionX = p.hallLength * uniformIn(rng, 0.35, 0.65);
    p.partitionDoorWidth = uniformIn(rng, 3.0, 6.0);
    p.partitionDoorCentreY = uniformIn(rng, 0.5 * p.partitionDoorWidth + 0.5, p.hallWidth - 0.5 * p.partitionDoorWidth - 0.5);
    p.partitionDoorHeight = std::min(uniformIn(rng, 3.0, 5.0), p.partitionHeight);
    const double floorArea = p.hallLength * p.hallWidth;
    p.racks = static_cast<int>(floorArea / uniformIn(rng, 120.0, 300.0));
    p.machines = static_cast<int>(floorArea / uniformIn(rng, 60.0, 150.0));
    p.tanks = static_cast<int>(rng.below(3));
    p.palletStacks = static_cast<int>(floorArea / uniformIn(rng, 30.0, 80.0));
    p.clutterSeed = rng.next();
}

//! Whether a tripod can stand at xy: inside, clear of columns, partition and walls by 0.8 m.
inline bool tripodSpotFree(const StationsParams& p, const Eigen::Vector2d& xy)
{
    if (xy.x() < 1.0 || xy.y() < 1.0 || xy.x() > p.hallLength - 1.0 || xy.y() > p.hallWidth - 1.0)
        return false;
    for (const Solid& s : structure(p))
        if ((s.tag == TagColumn || s.tag == TagPartition) && s.contains({xy.x(), xy.y(), 0.5}, 0.8))
            return false;
    return true;
}

//! A walk of n stations, 4-15 m apart, each on a free spot.
inline bool drawStations(SplitMix64& rng, StationsParams& p, int n, double maxTiltDeg)
{
    p.stations.clear();
    for (int i = 0; i < n; ++i) {
        StationSetup st;
        bool placed = false;
        for (int attempt = 0; attempt < 200 && !placed; ++attempt) {
            if (i == 0)
                st.position = {uniformIn(rng, 1.0, p.hallLength - 1.0), uniformIn(rng, 1.0, p.hallWidth - 1.0)};
            else {
                const double a = uniformIn(rng, 0.0, 2 * kPi), d = uniformIn(rng, 4.0, 15.0);
                st.position = p.stations.back().position + d * Eigen::Vector2d(std::cos(a), std::sin(a));
            }
            placed = tripodSpotFree(p, st.position);
            for (const StationSetup& other : p.stations)
                placed = placed && (other.position - st.position).norm() > 3.0;
        }
        if (!placed)
            return false;
        st.height = uniformIn(rng, 1.5, 1.8);
        st.headingDeg = uniformIn(rng, 0.0, 360.0);
        st.tiltDeg = uniformIn(rng, 0.0, maxTiltDeg);
        st.tiltAzimuthDeg = uniformIn(rng, 0.0, 360.0);
        p.stations.push_back(st);
    }
    return true;
}

} // namespace detail

//! Largest number of points a station returns at this scale (see the header comment).
inline double stationPointBudget(double scale) { return std::max(25000.0, 3.0e6 * scale * scale); }

//! A draw over the ranges of real hall surveys (header comment).
inline StationsParams drawFamily(std::uint64_t seed, double scale)
{
    using namespace detail;
    StationsParams p;
    SplitMix64 rng(seed, 0xA11u);
    const int n = 3 + static_cast<int>(rng.below(4));
    const double maxTilt = rng.uniform() < 0.5 ? 0.0 : 0.03;
    p.rangeNoise = logUniformIn(rng, 0.001, 0.010);
    p.maxRange = uniformIn(rng, 30.0, 120.0);
    p.pitchMinDeg = uniformIn(rng, -65.0, -55.0);
    const double surveyStep = radToDeg(logUniformIn(rng, 0.002, 0.03) / 10.0); // spacing at 10 m
    const double rays = 2 * kPi * degToRad(p.pitchMaxDeg - p.pitchMinDeg) * 0.9; // x 1/step^2, ~90 % return
    p.angularStepDeg = std::max(surveyStep, radToDeg(std::sqrt(rays / stationPointBudget(scale))));
    p.movingObjects = static_cast<int>(rng.below(3));
    if (rng.uniform() < 0.5) {
        p.worldOffset = {uniformIn(rng, 400000.0, 600000.0), uniformIn(rng, 5300000.0, 5500000.0), uniformIn(rng, 100.0, 500.0)};
        p.hallAzimuthDeg = uniformIn(rng, 0.0, 360.0);
    }
    p.seed = rng.next();
    for (int hall = 0; hall < 30; ++hall) {
        drawHall(rng, p);
        for (int walk = 0; walk < 15; ++walk) {
            if (!drawStations(rng, p, n, maxTilt))
                break;
            const ViewStats v = viewStats(p, 0.8);
            bool ok = true;
            for (int i = 0; i + 1 < n; ++i)
                ok = ok && v.overlap(i, i + 1) >= 0.3 && v.overlap(i, i + 1) <= 0.9;
            if (ok)
                return p;
        }
    }
    return p; // not reached in practice: the last walk drawn
}

//! Error of one estimated pose (station i -> station 0) against the truth.
struct PoseError
{
    double rotationDeg = 0.0;     //!< angle of the rotation between the estimated and true orientations
    double maxDisplacement = 0.0; //!< largest distance between a station point placed by each pose (m)
};

inline PoseError scorePose(const StationsScene& scene, std::size_t i, const Eigen::Matrix4d& estimatedToStation0)
{
    const Eigen::Matrix4d truth = scene.trueRelativePose(i);
    PoseError e;
    e.rotationDeg = rotationAngleDeg(truth.topLeftCorner<3, 3>(), estimatedToStation0.topLeftCorner<3, 3>());
    const Eigen::Matrix3d dR = estimatedToStation0.topLeftCorner<3, 3>() - truth.topLeftCorner<3, 3>();
    const Eigen::Vector3d dt = estimatedToStation0.topRightCorner<3, 1>() - truth.topRightCorner<3, 1>();
    const PointCloud& cloud = scene.clouds[i];
    for (std::size_t k = 0; k < cloud.size(); ++k)
        e.maxDisplacement = std::max(e.maxDisplacement, (dR * cloud.globalPosition(k) + dt).norm());
    return e;
}

//! Scores every station; `estimated[i]` is the tool's pose of station i in station 0's frame.
inline std::vector<PoseError> scorePoses(const StationsScene& scene, const std::vector<Eigen::Matrix4d>& estimated)
{
    std::vector<PoseError> errors;
    for (std::size_t i = 0; i < scene.clouds.size() && i < estimated.size(); ++i)
        errors.push_back(scorePose(scene, i, estimated[i]));
    return errors;
}

//! Whether every station is within the tolerances (issue: 0.005 deg, 2 mm).
inline bool withinTolerance(const std::vector<PoseError>& errors, std::size_t stationCount, double maxDeg = 0.005,
                            double maxMetres = 0.002)
{
    if (errors.size() != stationCount)
        return false;
    for (const PoseError& e : errors)
        if (!(e.rotationDeg <= maxDeg && e.maxDisplacement <= maxMetres))
            return false;
    return true;
}

inline std::string describe(const StationsParams& p)
{
    std::string headings;
    for (const StationSetup& s : p.stations)
        headings += (headings.empty() ? "" : "/") + std::to_string(static_cast<int>(std::lround(s.headingDeg)));
    char buf[400];
    std::snprintf(buf, sizeof buf,
                  "stations: %zu in hall %.0fx%.0fx%.0f m (partition %.1f m, %d racks, %d machines, %d moved), headings %s deg, "
                  "step %.3f deg (%.1f cm at 10 m), noise %.1f mm, range %.0f m, world (%.0f, %.0f), seed %llu",
                  p.stations.size(), p.hallLength, p.hallWidth, p.hallHeight, p.partitionHeight, p.racks, p.machines,
                  p.movingObjects, headings.c_str(), p.angularStepDeg, 100.0 * 10.0 * degToRad(p.angularStepDeg),
                  1000.0 * p.rangeNoise, p.maxRange, p.worldOffset.x(), p.worldOffset.y(), static_cast<unsigned long long>(p.seed));
    return buf;
}

} // namespace scandiff::test::family::stations
