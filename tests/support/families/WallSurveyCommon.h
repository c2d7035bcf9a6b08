// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Shared pieces of the wall-survey families (FacadeFamily.h, StoneWallFamily.h):
//! seeded Gaussian draws, the wall frame (u along the wall, v up the face,
//! n out of the face towards the scanner), a levelled terrestrial scanner that
//! sweeps a yaw/pitch grid whose angular step gives a chosen median spacing on
//! the wall, the cloud builder with a double origin for Lambert-93/UTM
//! coordinates, and robust 2D polygon metrics (IoU by exact scanline spans,
//! symmetric Hausdorff distance between boundaries) that accept any ring a
//! tool may return, self-intersecting ones included.
//!
//! Written from the data-model headers only, independent of the tools' code.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/SplitMix.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace scandiff::test::family::wallsurvey {

using Polygon2 = std::vector<Eigen::Vector2d>;
using Ring3 = std::vector<Eigen::Vector3d>;

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------- random draws

//! Uniform in [a, b).
inline double uniform(SplitMix64& rng, double a, double b) { return a + (b - a) * rng.uniform(); }

//! Standard normal by Box-Muller (std::normal_distribution differs between
//! standard libraries; this gives the same numbers everywhere).
inline double gaussian(SplitMix64& rng)
{
    const double u1 = 1.0 - rng.uniform(); // (0, 1]: log stays finite
    const double u2 = rng.uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

//! Log-uniform in [a, b): spacings and noises span decades, so each decade is
//! drawn as often as the next.
inline double logUniform(SplitMix64& rng, double a, double b) { return a * std::pow(b / a, rng.uniform()); }

//! A plausible global position for a wall corner: Lambert-93 (EPSG:2154,
//! X 650-700 km, Y 6800-6900 km) or UTM (E 300-700 km, N 4.5-5.5 Mm), ground
//! 20-400 m above sea level. Both need a double origin to keep millimetres.
inline Eigen::Vector3d drawProjectedCorner(SplitMix64& rng)
{
    const double z = uniform(rng, 20.0, 400.0);
    if (rng.uniform() < 0.5)
        return {uniform(rng, 650000.0, 700000.0), uniform(rng, 6800000.0, 6900000.0), z};
    return {uniform(rng, 300000.0, 700000.0), uniform(rng, 4500000.0, 5500000.0), z};
}

// ------------------------------------------------------------------ wall frame

//! The frame of a wall face. Wall coordinates (x, y, z): x along u, y up the
//! face along v, z along the outward normal n (z = 0 on the face, z > 0 in
//! front where the scanner stands, z < 0 behind the face).
struct WallFrame
{
    Eigen::Vector3d origin = Eigen::Vector3d::Zero(); //!< global position of the face's bottom-left corner (m)
    Eigen::Vector3d u = Eigen::Vector3d::UnitX();     //!< unit, horizontal, along the wall (left to right seen from the front)
    Eigen::Vector3d v = Eigen::Vector3d::UnitZ();     //!< unit, in the face, up (leans with the wall)
    Eigen::Vector3d n = -Eigen::Vector3d::UnitY();    //!< unit, u x v, out of the face towards the viewer
    double tiltRad = 0.0; //!< lean of the face from vertical (rad); > 0: top leans towards the viewer

    Eigen::Vector3d toGlobal(const Eigen::Vector3d& w) const { return origin + w.x() * u + w.y() * v + w.z() * n; }
    Eigen::Vector3d toWall(const Eigen::Vector3d& g) const
    {
        const Eigen::Vector3d d = g - origin;
        return {d.dot(u), d.dot(v), d.dot(n)};
    }
    //! 2D wall coordinates (x, y) of a global point (its orthogonal projection on the face).
    Eigen::Vector2d project(const Eigen::Vector3d& g) const
    {
        const Eigen::Vector3d d = g - origin;
        return {d.dot(u), d.dot(v)};
    }
    //! World up (global +Z) expressed in wall coordinates.
    Eigen::Vector3d upInWall() const { return {0.0, std::cos(tiltRad), -std::sin(tiltRad)}; }
    //! Horizontal outward direction (towards the viewer) in wall coordinates.
    Eigen::Vector3d outwardInWall() const { return {0.0, std::sin(tiltRad), std::cos(tiltRad)}; }
};

//! headingDeg: azimuth of u, counter-clockwise from global +X (east);
//! tiltDeg: lean of the face from vertical, positive towards the viewer.
inline WallFrame makeWallFrame(const Eigen::Vector3d& corner, double headingDeg, double tiltDeg)
{
    WallFrame f;
    f.origin = corner;
    f.tiltRad = tiltDeg * kPi / 180.0;
    const double h = headingDeg * kPi / 180.0;
    f.u = Eigen::Vector3d(std::cos(h), std::sin(h), 0.0);
    const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d outward = f.u.cross(up); // horizontal, towards the viewer
    f.v = std::cos(f.tiltRad) * up + std::sin(f.tiltRad) * outward;
    f.n = f.u.cross(f.v);
    return f;
}

// ------------------------------------------------------------------- scanner

//! A levelled terrestrial scanner in wall coordinates sweeping a regular
//! yaw/pitch grid (vertical profiles, as a TLS does). Yaw turns about world
//! up, 0 facing the wall horizontally; pitch is the elevation.
struct ScanGrid
{
    Eigen::Vector3d position = Eigen::Vector3d::Zero(); //!< wall coordinates
    Eigen::Vector3d forward, left, up;                  //!< scanner axes in wall coordinates
    double step = 0.0;                                  //!< angular step, both axes (rad)
    double yawMin = 0, yawMax = 0, pitchMin = 0, pitchMax = 0;

    Eigen::Vector3d direction(double yaw, double pitch) const
    {
        return std::cos(pitch) * (std::cos(yaw) * forward + std::sin(yaw) * left) + std::sin(pitch) * up;
    }
    std::size_t columns() const { return static_cast<std::size_t>(std::floor((yawMax - yawMin) / step)) + 1; }
    std::size_t rows() const { return static_cast<std::size_t>(std::floor((pitchMax - pitchMin) / step)) + 1; }
    //! Calls fn(direction, rayIndex) for every ray, profile by profile.
    template <class Fn> void sweep(Fn&& fn) const
    {
        const std::size_t nc = columns(), nr = rows();
        for (std::size_t c = 0; c < nc; ++c)
            for (std::size_t r = 0; r < nr; ++r)
                fn(direction(yawMin + c * step, pitchMin + r * step), c * nr + r);
    }
};

//! Mean of the ray grid's two step lengths on the plane z = 0 at the point hit
//! by direction d, per radian of step (so spacing = step * this).
inline double stepLengthPerRadian(const ScanGrid& g, double yaw, double pitch)
{
    const Eigen::Vector3d d = g.direction(yaw, pitch);
    if (d.z() >= -1e-9)
        return kInf;
    const double t = -g.position.z() / d.z();
    const Eigen::Vector3d horiz = std::cos(yaw) * g.forward + std::sin(yaw) * g.left;
    const Eigen::Vector3d dYaw = std::cos(pitch) * (-std::sin(yaw) * g.forward + std::cos(yaw) * g.left);
    const Eigen::Vector3d dPitch = -std::sin(pitch) * horiz + std::cos(pitch) * g.up;
    auto along = [&](const Eigen::Vector3d& dd) { return (t * dd - t * dd.z() / d.z() * d).norm(); };
    return 0.5 * (along(dYaw) + along(dPitch));
}

//! The scanner at `position` (wall coordinates, in front: z > 0) aimed at the
//! rectangle [x0,x1] x [y0,y1] of the face: its angular window covers the
//! rectangle plus `extraTargets` (other points to see, e.g. a ground strip),
//! and its step makes the MEDIAN spacing over the rectangle equal `spacing`.
inline ScanGrid makeScanGrid(const WallFrame& frame, const Eigen::Vector3d& position, double x0, double x1, double y0,
                             double y1, double spacing, const std::vector<Eigen::Vector3d>& extraTargets = {})
{
    ScanGrid g;
    g.position = position;
    g.up = frame.upInWall();
    g.forward = -frame.outwardInWall();
    g.left = g.up.cross(g.forward);
    auto angles = [&](const Eigen::Vector3d& target) {
        const Eigen::Vector3d d = (target - position).normalized();
        return Eigen::Vector2d(std::atan2(d.dot(g.left), d.dot(g.forward)), std::asin(std::clamp(d.dot(g.up), -1.0, 1.0)));
    };
    std::vector<Eigen::Vector3d> targets = extraTargets;
    const int edgeSamples = 64; // extremes of pitch lie inside edges, not only at corners
    for (int i = 0; i <= edgeSamples; ++i) {
        const double a = static_cast<double>(i) / edgeSamples;
        targets.emplace_back(x0 + a * (x1 - x0), y0, 0.0);
        targets.emplace_back(x0 + a * (x1 - x0), y1, 0.0);
        targets.emplace_back(x0, y0 + a * (y1 - y0), 0.0);
        targets.emplace_back(x1, y0 + a * (y1 - y0), 0.0);
    }
    g.yawMin = g.pitchMin = kInf;
    g.yawMax = g.pitchMax = -kInf;
    for (const auto& t : targets) {
        const Eigen::Vector2d a = angles(t);
        g.yawMin = std::min(g.yawMin, a.x()), g.yawMax = std::max(g.yawMax, a.x());
        g.pitchMin = std::min(g.pitchMin, a.y()), g.pitchMax = std::max(g.pitchMax, a.y());
    }
    std::vector<double> perRadian;
    const int grid = 24;
    for (int i = 0; i <= grid; ++i)
        for (int j = 0; j <= grid; ++j) {
            const Eigen::Vector2d a = angles({x0 + (x1 - x0) * i / grid, y0 + (y1 - y0) * j / grid, 0.0});
            perRadian.push_back(stepLengthPerRadian(g, a.x(), a.y()));
        }
    std::nth_element(perRadian.begin(), perRadian.begin() + perRadian.size() / 2, perRadian.end());
    g.step = spacing / perRadian[perRadian.size() / 2];
    const double margin = 2.0 * g.step;
    g.yawMin -= margin, g.yawMax += margin, g.pitchMin -= margin, g.pitchMax += margin;
    return g;
}

//! The scanner's pose for the cloud's sensor list (visibility tools need it).
inline SensorPose sensorPose(const WallFrame& frame, const ScanGrid& g)
{
    auto toGlobalDir = [&](const Eigen::Vector3d& w) {
        return Eigen::Vector3d(w.x() * frame.u + w.y() * frame.v + w.z() * frame.n);
    };
    Eigen::Matrix3d r;
    r.col(0) = toGlobalDir(g.forward);
    r.col(1) = toGlobalDir(g.left);
    r.col(2) = toGlobalDir(g.up);
    SensorPose pose;
    pose.position = frame.toGlobal(g.position);
    pose.orientation = Eigen::Quaterniond(r).normalized();
    pose.yawStep = pose.pitchStep = g.step;
    pose.yawMin = g.yawMin, pose.yawMax = g.yawMax, pose.pitchMin = g.pitchMin, pose.pitchMax = g.pitchMax;
    return pose;
}

//! A cloud of global points: origin chosen as suggestOrigin() does (minimum
//! rounded down to 1000 m for large coordinates), local float positions.
inline PointCloud makeCloud(const std::vector<Eigen::Vector3d>& global, const std::string& name)
{
    PointCloud cloud;
    cloud.name = name;
    BoundingBox box;
    for (const auto& p : global) {
        if (box.empty)
            box.min = box.max = p, box.empty = false;
        box.min = box.min.cwiseMin(p), box.max = box.max.cwiseMax(p);
    }
    const Eigen::Vector3d origin = suggestOrigin(box);
    cloud.setOrigin(origin);
    cloud.resize(global.size());
    for (std::size_t i = 0; i < global.size(); ++i)
        cloud.positions()[i] = (global[i] - origin).cast<float>();
    return cloud;
}

// ----------------------------------------------------------- polygon metrics

inline double polygonArea(const Polygon2& p)
{
    double a = 0.0;
    for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++)
        a += p[j].x() * p[i].y() - p[i].x() * p[j].y();
    return 0.5 * std::abs(a);
}

//! Drops a repeated closing vertex (rings may come closed or open).
inline Polygon2 openRing(Polygon2 p)
{
    while (p.size() > 1 && (p.front() - p.back()).norm() < 1e-9)
        p.pop_back();
    return p;
}

//! A 3D ring projected to wall 2D; *rmsOffset gets the RMS distance of its
//! vertices to the face plane (to tell wall rings from recessed ones).
inline Polygon2 projectRing(const WallFrame& frame, const Ring3& ring, double* rmsOffset = nullptr)
{
    Polygon2 out;
    double sum = 0.0;
    for (const auto& p : ring) {
        const Eigen::Vector3d w = frame.toWall(p);
        out.emplace_back(w.x(), w.y());
        sum += w.z() * w.z();
    }
    if (rmsOffset)
        *rmsOffset = ring.empty() ? 0.0 : std::sqrt(sum / ring.size());
    return openRing(std::move(out));
}

struct Box2
{
    Eigen::Vector2d min = Eigen::Vector2d::Constant(kInf), max = Eigen::Vector2d::Constant(-kInf);
    void add(const Eigen::Vector2d& p) { min = min.cwiseMin(p), max = max.cwiseMax(p); }
    bool overlaps(const Box2& b) const
    {
        return min.x() <= b.max.x() && b.min.x() <= max.x() && min.y() <= b.max.y() && b.min.y() <= max.y();
    }
};
inline Box2 boxOf(const Polygon2& p)
{
    Box2 b;
    for (const auto& q : p)
        b.add(q);
    return b;
}

//! Inside intervals of the horizontal line at y (even-odd rule, so any ring,
//! even a self-intersecting one, has a defined inside): sorted crossings, pairs.
inline std::vector<double> crossingsAt(const Polygon2& p, double y)
{
    std::vector<double> xs;
    for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++) {
        const Eigen::Vector2d &a = p[j], &b = p[i];
        if ((a.y() <= y) != (b.y() <= y))
            xs.push_back(a.x() + (y - a.y()) / (b.y() - a.y()) * (b.x() - a.x()));
    }
    std::sort(xs.begin(), xs.end());
    return xs;
}

//! Lengths of A, B, A and B, A or B along one line, from their crossings.
inline void spanLengths(const std::vector<double>& a, const std::vector<double>& b, double out[4])
{
    std::vector<std::pair<double, int>> ev; // +-1 for A (bit 0), +-2 for B (bit 1) entering/leaving
    for (std::size_t i = 0; i + 1 < a.size(); i += 2)
        ev.push_back({a[i], 1}), ev.push_back({a[i + 1], -1});
    for (std::size_t i = 0; i + 1 < b.size(); i += 2)
        ev.push_back({b[i], 2}), ev.push_back({b[i + 1], -2});
    std::sort(ev.begin(), ev.end());
    int inA = 0, inB = 0;
    double last = 0.0;
    for (const auto& e : ev) {
        const double len = e.first - last;
        if (inA > 0) out[0] += len;
        if (inB > 0) out[1] += len;
        if (inA > 0 && inB > 0) out[2] += len;
        if (inA > 0 || inB > 0) out[3] += len;
        if (e.second == 1 || e.second == -1) inA += e.second;
        else inB += e.second / 2;
        last = e.first;
    }
}

struct Overlap
{
    double areaA = 0, areaB = 0, intersection = 0, unionArea = 0;
    double iou() const { return unionArea > 0 ? intersection / unionArea : 0.0; }
};

//! Areas of A, B, their intersection and union, integrated row by row (rows
//! of height <= 1/1000 of the extent, at most 2 mm): exact along x, midpoint
//! rule along y; robust to self-intersecting or badly oriented rings.
inline Overlap polygonOverlap(const Polygon2& a, const Polygon2& b)
{
    Overlap o;
    if (a.size() < 3 && b.size() < 3)
        return o;
    Box2 box = boxOf(a);
    for (const auto& q : b)
        box.add(q);
    const double extent = box.max.y() - box.min.y();
    if (!(extent > 0))
        return o;
    const double dy = std::clamp(extent / 1000.0, 2e-4, 2e-3);
    const int rows = static_cast<int>(std::ceil(extent / dy));
    const double h = extent / rows;
    for (int r = 0; r < rows; ++r) {
        const double y = box.min.y() + (r + 0.5) * h;
        double len[4] = {0, 0, 0, 0};
        spanLengths(a.size() >= 3 ? crossingsAt(a, y) : std::vector<double>{},
                    b.size() >= 3 ? crossingsAt(b, y) : std::vector<double>{}, len);
        o.areaA += len[0] * h, o.areaB += len[1] * h, o.intersection += len[2] * h, o.unionArea += len[3] * h;
    }
    return o;
}

inline double pointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b)
{
    const Eigen::Vector2d ab = b - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (a + t * ab - p).norm();
}

inline double distanceToBoundary(const Eigen::Vector2d& p, const Polygon2& ring)
{
    double best = kInf;
    for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++)
        best = std::min(best, pointSegmentDistance(p, ring[j], ring[i]));
    return best;
}

//! Points along the closed boundary of `ring`, at most `step` apart, vertices included.
inline std::vector<Eigen::Vector2d> sampleBoundary(const Polygon2& ring, double step)
{
    std::vector<Eigen::Vector2d> out;
    for (std::size_t i = 0; i < ring.size(); ++i) {
        const Eigen::Vector2d &a = ring[i], &b = ring[(i + 1) % ring.size()];
        const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
        for (int k = 0; k < n; ++k)
            out.push_back(a + (b - a) * (static_cast<double>(k) / n));
    }
    return out;
}

//! Largest distance from the boundary of `from` to the boundary of `to`
//! (sampled every 1 mm: error <= 0.5 mm), optionally only for samples of
//! `from` inside `zone`.
inline double directedHausdorff(const Polygon2& from, const Polygon2& to, const Box2* zone = nullptr)
{
    if (from.empty() || to.empty())
        return kInf;
    double worst = 0.0;
    for (const auto& p : sampleBoundary(from, 1e-3)) {
        if (zone && !(p.x() >= zone->min.x() && p.x() <= zone->max.x() && p.y() >= zone->min.y() && p.y() <= zone->max.y()))
            continue;
        worst = std::max(worst, distanceToBoundary(p, to));
    }
    return worst;
}

//! Symmetric Hausdorff distance between two polygon boundaries (m).
inline double boundaryHausdorff(const Polygon2& a, const Polygon2& b)
{
    return std::max(directedHausdorff(a, b), directedHausdorff(b, a));
}

inline std::string format(const char* fmt, double a = 0, double b = 0, double c = 0, double d = 0, double e = 0,
                          double f = 0, double g = 0, double h = 0)
{
    char buf[512];
    std::snprintf(buf, sizeof buf, fmt, a, b, c, d, e, f, g, h);
    return buf;
}

} // namespace scandiff::test::family::wallsurvey
