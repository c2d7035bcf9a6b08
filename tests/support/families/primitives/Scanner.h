// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A terrestrial scanner station simulated by ray casting: a full turn in yaw
//! (or a horizontal scan window) and pitchMin..pitchMax in pitch at one angular step, the first surface met
//! by each ray (so nearer surfaces hide farther ones), Gaussian range noise
//! along the ray, no return at grazing incidence, and the depth jumps between
//! neighbouring rays where a real scanner produces mixed pixels (a footprint
//! straddling an edge returns a range in between).

#include "Surfaces.h"

#include <cstdint>
#include <vector>

namespace scandiff::test::family::primitives {

struct StationSpec
{
    Vector3d position = Vector3d::Zero(); //!< scanner centre, scene frame (m)
    double pitchMin = -55.0 * kPi / 180;  //!< below it the tripod hides the ground (rad)
    double pitchMax = 90.0 * kPi / 180;   //!< rad
    //! Horizontal scan window: yaw within yawCentre +- yawHalfWidth (rad); pi: a full turn.
    double yawCentre = 0;
    double yawHalfWidth = kPi;
};

struct ScanSettings
{
    double angularStep = 0.004;    //!< yaw and pitch step (rad)
    double rangeNoise = 0.005;     //!< 1 sigma along the ray (m)
    double maxRange = 120;         //!< m
    double minCosIncidence = 0.05; //!< no return beyond ~87 degrees of incidence
    double mixedPixelJump = 0.10;  //!< range jump between neighbouring rays that makes an edge (m)
};

struct ScanHit
{
    Vector3d position = Vector3d::Zero(); //!< measured (noisy), scene frame
    double range = 0;                     //!< measured range (m)
    float cosIncidence = 1;
    int target = 0;  //!< true shape index (>= 0) or -(1 + clutter object index)
    int station = 0;
};

//! Two neighbouring rays of a row whose ranges jump: a mixed pixel may come back
//! along `direction` anywhere between the two ranges.
struct EdgeCandidate
{
    Vector3d direction = Vector3d::UnitX();
    double nearRange = 0, farRange = 0;
    int station = 0;
};

struct StationScan
{
    std::vector<ScanHit> hits;
    std::vector<EdgeCandidate> edges;
};

namespace detail {

//! The directions from a station in which a bounding sphere can be met, as a
//! pitch interval and a yaw interval (everywhere when the station is inside).
struct AngularWindow
{
    bool everywhere = false;
    double pitchLo = 0, pitchHi = 0;
    double yawCentre = 0, yawHalf = kPi;
};

inline AngularWindow angularWindow(const BoundingSphere& b, const Vector3d& station)
{
    AngularWindow w;
    const Vector3d v = b.centre - station;
    const double dist = v.norm();
    if (dist <= b.radius * 1.0001 + 1e-9) {
        w.everywhere = true;
        return w;
    }
    const double beta = std::asin(b.radius / dist);
    const double pitch = std::asin(std::clamp(v.z() / dist, -1.0, 1.0));
    w.pitchLo = pitch - beta;
    w.pitchHi = pitch + beta;
    w.yawCentre = std::atan2(v.y(), v.x());
    const double steepest = std::abs(pitch) + beta;
    if (steepest >= 0.5 * kPi - 1e-6) {
        w.yawHalf = kPi;
    } else {
        const double s = std::sin(beta) / std::cos(steepest);
        w.yawHalf = s >= 1 ? kPi : std::asin(s) + 1e-6;
    }
    return w;
}

inline bool yawInside(const AngularWindow& w, double yaw)
{
    if (w.everywhere || w.yawHalf >= kPi)
        return true;
    double diff = std::remainder(yaw - w.yawCentre, 2 * kPi);
    return std::abs(diff) <= w.yawHalf;
}

//! The nearest surface along a ray among the row's candidates.
struct RayResult
{
    double t = kNoHit;
    int target = 0;
};

inline RayResult castRay(const std::vector<ShapeSpec>& shapes, const std::vector<ClutterObject>& clutter,
                         const std::vector<int>& candidates, const std::vector<AngularWindow>& windows,
                         const Vector3d& o, const Vector3d& d, double yaw, double maxRange)
{
    RayResult best;
    best.t = maxRange;
    const int shapeCount = static_cast<int>(shapes.size());
    for (int id : candidates) {
        if (!yawInside(windows[id], yaw))
            continue;
        const double t = id < shapeCount ? intersect(shapes[id], o, d, 1e-3)
                                         : intersectClutter(clutter[id - shapeCount], o, d, 1e-3);
        if (t < best.t) {
            best.t = t;
            best.target = id < shapeCount ? id : -(1 + (id - shapeCount));
        }
    }
    if (best.t >= maxRange)
        best.t = kNoHit;
    return best;
}

} // namespace detail

//! Scans every ray of one station. `seed` and the station index fix the noise.
//! With `noisy` false, ranges are exact and no edges are kept (pilot scans).
inline StationScan scanStation(const std::vector<ShapeSpec>& shapes, const std::vector<ClutterObject>& clutter,
                               const StationSpec& station, int stationIndex, const ScanSettings& settings,
                               std::uint64_t seed, bool noisy = true)
{
    StationScan scan;
    SplitMix64 rng(seed, 0x5CA11ULL + static_cast<std::uint64_t>(stationIndex));
    const Vector3d& o = station.position;
    std::vector<detail::AngularWindow> windows;
    for (const ShapeSpec& s : shapes)
        windows.push_back(detail::angularWindow(boundingSphere(s), o));
    for (const ClutterObject& c : clutter)
        windows.push_back(detail::angularWindow(boundingSphere(c), o));

    const double step = settings.angularStep;
    const int columns = std::max(8, static_cast<int>(std::lround(2 * kPi / step)));
    const double yawStep = 2 * kPi / columns;
    const int rows = std::max(1, static_cast<int>(std::floor((station.pitchMax - station.pitchMin) / step)) + 1);
    std::vector<int> candidates;
    for (int row = 0; row < rows; ++row) {
        const double pitch = station.pitchMin + row * step;
        candidates.clear();
        for (int id = 0; id < static_cast<int>(windows.size()); ++id)
            if (windows[id].everywhere || (pitch >= windows[id].pitchLo && pitch <= windows[id].pitchHi))
                candidates.push_back(id);
        if (candidates.empty())
            continue;
        const double cp = std::cos(pitch), sp = std::sin(pitch);
        double previousRange = kNoHit;
        for (int col = 0; col < columns; ++col) {
            const double yaw = -kPi + (col + 0.5) * yawStep;
            if (station.yawHalfWidth < kPi && std::abs(std::remainder(yaw - station.yawCentre, 2 * kPi)) > station.yawHalfWidth) {
                previousRange = kNoHit;
                continue;
            }
            const Vector3d d(cp * std::cos(yaw), cp * std::sin(yaw), sp);
            const detail::RayResult r = detail::castRay(shapes, clutter, candidates, windows, o, d, yaw, settings.maxRange);
            if (r.t == kNoHit) {
                previousRange = kNoHit;
                continue;
            }
            const Vector3d exact = o + r.t * d;
            const Vector3d normal = r.target >= 0 ? outwardNormal(shapes[r.target], exact)
                                                  : outwardNormal(clutter[-r.target - 1], exact);
            const double cosIncidence = std::abs(normal.dot(d));
            if (cosIncidence < settings.minCosIncidence) {
                previousRange = kNoHit; // no return: the beam glances off
                continue;
            }
            const double range = noisy ? r.t + settings.rangeNoise * gaussian(rng) : r.t;
            if (noisy && previousRange != kNoHit && std::abs(range - previousRange) > settings.mixedPixelJump) {
                const double prevYaw = yaw - yawStep;
                const Vector3d prevDir(cp * std::cos(prevYaw), cp * std::sin(prevYaw), sp);
                scan.edges.push_back({(d + prevDir).normalized(), std::min(range, previousRange),
                                      std::max(range, previousRange), stationIndex});
            }
            previousRange = range;
            scan.hits.push_back({o + range * d, range, static_cast<float>(cosIncidence), r.target, stationIndex});
        }
    }
    return scan;
}

} // namespace scandiff::test::family::primitives
