// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Shared pieces of the terrestrial-scanner families (StationsFamily.h,
//! GrazingVisibilityFamily.h): seeded Gaussian draws that give the same
//! numbers on every standard library, ray casting against a small set of
//! solids (boxes turned about the vertical, vertical cylinders), and the
//! construction of a PointCloud from global double coordinates with the
//! library's origin convention.
//!
//! Independent of the code under test: only the data-model headers are used.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/SplitMix.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace scandiff::test::family::tls {

constexpr double kPi = 3.14159265358979323846;
inline double degToRad(double deg) { return deg * kPi / 180.0; }
inline double radToDeg(double rad) { return rad * 180.0 / kPi; }

//! Uniform in [a, b).
inline double uniformIn(SplitMix64& rng, double a, double b) { return a + (b - a) * rng.uniform(); }

//! Log-uniform in [a, b) (for quantities spanning a decade: noise, spacing).
inline double logUniformIn(SplitMix64& rng, double a, double b)
{
    return std::exp(uniformIn(rng, std::log(a), std::log(b)));
}

//! Standard normal by Box-Muller (std::normal_distribution differs between
//! standard libraries; this does not).
inline double gaussian(SplitMix64& rng)
{
    const double u1 = 1.0 - rng.uniform(); // (0, 1]: log stays finite
    const double u2 = rng.uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

//! Rotation about the vertical axis.
inline Eigen::Matrix3d rotationZ(double angleRad)
{
    return Eigen::AngleAxisd(angleRad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

//! Unit direction of scanner angles (yaw from +x towards +y, pitch above the
//! horizontal plane), the usual spherical convention of scanner files.
inline Eigen::Vector3d directionOf(double yaw, double pitch)
{
    return {std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch)};
}

//! A solid of the scene. A box is centred at `centre`, of half extents
//! `halfSize` in its own axes, turned by `yaw` about the vertical. A vertical
//! cylinder has its axis through centre.xy, radius halfSize.x, and spans
//! centre.z +- halfSize.z.
struct Solid
{
    enum class Kind { Box, VerticalCylinder };
    Kind kind = Kind::Box;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    Eigen::Vector3d halfSize = Eigen::Vector3d::Constant(0.5);
    double yaw = 0.0; //!< set with setYaw() (keeps its cosine and sine)
    double cosYaw = 1.0, sinYaw = 0.0;
    int tag = 0; //!< caller's label (what the solid is)

    void setYaw(double angle)
    {
        yaw = angle;
        cosYaw = std::cos(angle);
        sinYaw = std::sin(angle);
    }
    //! Radius of the sphere about `centre` that holds the solid (quick rejection of rays).
    double boundingRadius() const
    {
        return kind == Kind::Box ? halfSize.norm() : std::hypot(halfSize.x(), halfSize.z());
    }

    static Solid box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int tag = 0)
    {
        Solid s;
        s.centre = 0.5 * (lo + hi);
        s.halfSize = 0.5 * (hi - lo);
        s.tag = tag;
        return s;
    }
    static Solid turnedBox(const Eigen::Vector3d& centre, const Eigen::Vector3d& half, double yaw, int tag = 0)
    {
        Solid s;
        s.centre = centre;
        s.halfSize = half;
        s.setYaw(yaw);
        s.tag = tag;
        return s;
    }
    static Solid cylinder(double x, double y, double radius, double zMin, double zMax, int tag = 0)
    {
        Solid s;
        s.kind = Kind::VerticalCylinder;
        s.centre = {x, y, 0.5 * (zMin + zMax)};
        s.halfSize = {radius, radius, 0.5 * (zMax - zMin)};
        s.tag = tag;
        return s;
    }

    //! Point or vector expressed in the solid's axes (about its centre for points).
    Eigen::Vector3d toLocalPoint(const Eigen::Vector3d& p) const { return toLocalVector(p - centre); }
    Eigen::Vector3d toLocalVector(const Eigen::Vector3d& v) const
    {
        return {cosYaw * v.x() + sinYaw * v.y(), -sinYaw * v.x() + cosYaw * v.y(), v.z()};
    }
    Eigen::Vector3d toWorldVector(const Eigen::Vector3d& v) const
    {
        return {cosYaw * v.x() - sinYaw * v.y(), sinYaw * v.x() + cosYaw * v.y(), v.z()};
    }

    //! Whether p lies inside the solid grown by `margin` (negative: shrunk).
    bool contains(const Eigen::Vector3d& p, double margin = 0.0) const
    {
        if (kind == Kind::Box) {
            const Eigen::Vector3d q = toLocalPoint(p);
            return std::abs(q.x()) <= halfSize.x() + margin && std::abs(q.y()) <= halfSize.y() + margin
                && std::abs(q.z()) <= halfSize.z() + margin;
        }
        const double r = halfSize.x() + margin;
        return (p.head<2>() - centre.head<2>()).squaredNorm() <= r * r && std::abs(p.z() - centre.z()) <= halfSize.z() + margin;
    }
};

struct RayHit
{
    double t = std::numeric_limits<double>::infinity();
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ(); //!< outward normal of the surface hit
    int solid = -1;
};

//! First entry of the ray o + t d (t in (tMin, tMax)) into a box grown by
//! `margin`; false when the ray misses it or starts inside.
inline bool intersectBox(const Solid& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tMin, double tMax,
                         double margin, RayHit& hit)
{
    const Eigen::Vector3d lo = s.toLocalPoint(o), ld = s.toLocalVector(d);
    double tEnter = -std::numeric_limits<double>::infinity(), tExit = std::numeric_limits<double>::infinity();
    int enterAxis = -1;
    for (int a = 0; a < 3; ++a) {
        const double h = s.halfSize[a] + margin;
        if (std::abs(ld[a]) < 1e-15) {
            if (std::abs(lo[a]) > h)
                return false;
            continue;
        }
        double t0 = (-h - lo[a]) / ld[a], t1 = (h - lo[a]) / ld[a];
        if (t0 > t1)
            std::swap(t0, t1);
        if (t0 > tEnter) {
            tEnter = t0;
            enterAxis = a;
        }
        tExit = std::min(tExit, t1);
        if (tEnter > tExit)
            return false;
    }
    if (enterAxis < 0 || tEnter <= tMin || tEnter >= tMax)
        return false;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    n[enterAxis] = ld[enterAxis] > 0 ? -1.0 : 1.0;
    hit.t = tEnter;
    hit.normal = s.toWorldVector(n);
    return true;
}

//! First entry of the ray into a vertical cylinder (side or caps).
inline bool intersectCylinder(const Solid& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tMin, double tMax,
                              double margin, RayHit& hit)
{
    const double r = s.halfSize.x() + margin, zLo = s.centre.z() - s.halfSize.z() - margin,
                 zHi = s.centre.z() + s.halfSize.z() + margin;
    double best = tMax;
    Eigen::Vector3d bestNormal;
    const Eigen::Vector2d oc = o.head<2>() - s.centre.head<2>();
    const Eigen::Vector2d dxy = d.head<2>();
    const double a = dxy.squaredNorm();
    if (a > 1e-18) {
        const double b = oc.dot(dxy), c = oc.squaredNorm() - r * r;
        const double disc = b * b - a * c;
        if (disc >= 0) {
            const double t = (-b - std::sqrt(disc)) / a; // entry through the side
            const double z = o.z() + t * d.z();
            if (t > tMin && t < best && z >= zLo && z <= zHi) {
                best = t;
                bestNormal << (oc + t * dxy) / r, 0.0;
            }
        }
    }
    if (std::abs(d.z()) > 1e-15) {
        for (const double zc : {zLo, zHi}) {
            const double t = (zc - o.z()) / d.z();
            const bool entering = (zc == zHi) ? d.z() < 0 : d.z() > 0;
            if (!entering || t <= tMin || t >= best)
                continue;
            if ((oc + t * dxy).squaredNorm() <= r * r) {
                best = t;
                bestNormal = Eigen::Vector3d(0, 0, zc == zHi ? 1.0 : -1.0);
            }
        }
    }
    if (best >= tMax)
        return false;
    hit.t = best;
    hit.normal = bestNormal;
    return true;
}

inline bool intersectSolid(const Solid& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tMin, double tMax,
                           double margin, RayHit& hit)
{
    // Quick rejection by the bounding sphere (d is a unit vector).
    const Eigen::Vector3d oc = s.centre - o;
    const double along = oc.dot(d), r = s.boundingRadius() + std::max(margin, 0.0) + 1e-9;
    const double r2 = r * r, dist2 = oc.squaredNorm();
    if (dist2 - along * along > r2 || (along < 0 && dist2 > r2) || along - r > tMax)
        return false;
    return s.kind == Solid::Kind::Box ? intersectBox(s, o, d, tMin, tMax, margin, hit)
                                      : intersectCylinder(s, o, d, tMin, tMax, margin, hit);
}

//! Nearest entry among `solids` of the ray o + t d, t in (tMin, tMax); d unit.
inline bool firstHit(const std::vector<Solid>& solids, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tMin,
                     double tMax, RayHit& hit)
{
    hit = RayHit{};
    double limit = tMax;
    for (std::size_t i = 0; i < solids.size(); ++i) {
        RayHit h;
        if (intersectSolid(solids[i], o, d, tMin, limit, 0.0, h)) {
            limit = h.t;
            hit = h;
            hit.solid = static_cast<int>(i);
        }
    }
    return hit.solid >= 0;
}

//! Whether the segment a -> b enters a solid of `solids` shrunk by
//! `tolerance` (so a point lying on a surface does not hide itself). A
//! segment ending inside a solid counts as blocked; one starting inside a
//! solid is not blocked by that solid (a scanner is never inside one).
inline bool segmentBlocked(const std::vector<Solid>& solids, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           double tolerance)
{
    const Eigen::Vector3d ab = b - a;
    const double len = ab.norm();
    if (len <= 0)
        return false;
    const Eigen::Vector3d d = ab / len;
    for (const Solid& s : solids) {
        RayHit h;
        if (intersectSolid(s, a, d, 0.0, len, -tolerance, h))
            return true;
    }
    return false;
}

//! The cloud of the given global coordinates, with the library's origin
//! convention (zero for small coordinates, the box minimum rounded down to
//! 1000 m otherwise), positions stored relative to it.
inline PointCloud cloudFromGlobal(const std::vector<Eigen::Vector3d>& global, const std::string& name)
{
    PointCloud cloud;
    cloud.name = name;
    BoundingBox box;
    for (const Eigen::Vector3d& p : global) {
        if (box.empty) {
            box.min = box.max = p;
            box.empty = false;
        } else {
            box.min = box.min.cwiseMin(p);
            box.max = box.max.cwiseMax(p);
        }
    }
    const Eigen::Vector3d origin = box.empty ? Eigen::Vector3d::Zero() : suggestOrigin(box);
    cloud.setOrigin(origin);
    cloud.resize(global.size());
    std::vector<Eigen::Vector3f>& pos = cloud.positions();
    for (std::size_t i = 0; i < global.size(); ++i)
        pos[i] = (global[i] - origin).cast<float>();
    return cloud;
}

//! Rotation angle (degrees) of R_a^T R_b: the angle between two orientations.
inline double rotationAngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b)
{
    const Eigen::Matrix3d r = a.transpose() * b;
    // atan2 of the rotation axis length and the trace: accurate for tiny angles,
    // where acos((trace - 1) / 2) loses everything below ~1e-4 degrees.
    const Eigen::Vector3d axis(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));
    return radToDeg(std::atan2(0.5 * axis.norm(), 0.5 * (r.trace() - 1.0)));
}

} // namespace scandiff::test::family::tls
