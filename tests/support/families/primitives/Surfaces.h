// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Surfaces of the primitives family: the bounded pieces of primitives that are
//! the true shapes of a plant-like scene (a rectangle of a plane, a length of a
//! cylinder, a sphere, a frustum of a cone, a sector of a torus) and the lumpy
//! clutter objects (valves, bags, junction boxes: no primitive), with what a
//! simulated scanner needs from them: the first intersection of a ray, the
//! outward normal, a bounding sphere, a point drawn on the surface.
//!
//! Everything is in the scene frame (metres, z up) before the scene is turned to
//! its heading and moved to its global coordinates. Independent of the code
//! under test: nothing here comes from scandiff's shape detection.

#include <scandiff/core/SplitMix.h>
#include <scandiff/core/geometry/Primitives.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace scandiff::test::family::primitives {

using Eigen::Vector3d;

constexpr double kPi = 3.14159265358979323846;
constexpr double kNoHit = std::numeric_limits<double>::infinity();

//! Standard normal draw by Box-Muller: std::normal_distribution differs between
//! standard libraries, this gives the same numbers everywhere.
inline double gaussian(SplitMix64& rng)
{
    const double u1 = std::max(rng.uniform(), 1e-300);
    const double u2 = rng.uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

inline double uniformIn(SplitMix64& rng, double lo, double hi) { return lo + (hi - lo) * rng.uniform(); }

inline Vector3d randomUnitVector(SplitMix64& rng)
{
    const double z = uniformIn(rng, -1.0, 1.0);
    const double phi = uniformIn(rng, 0.0, 2.0 * kPi);
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {s * std::cos(phi), s * std::sin(phi), z};
}

//! A unit vector perpendicular to the unit vector n.
inline Vector3d perpendicularTo(const Vector3d& n)
{
    const Vector3d helper = std::abs(n.z()) < 0.9 ? Vector3d::UnitZ() : Vector3d::UnitX();
    return n.cross(helper).normalized();
}

//! One true shape: a bounded piece of a primitive, scene frame.
struct ShapeSpec
{
    std::string name;                                //!< "floor", "long pipe", "elbow torus"...
    PrimitiveKind kind = PrimitiveKind::Plane;
    //! Plane: the rectangle's centre. Cylinder: the start of its axis. Sphere,
    //! torus: the centre. Cone: the apex (m).
    Vector3d centre = Vector3d::Zero();
    //! Plane: the unit normal (towards the side the scanners see). Cylinder:
    //! the unit axis from the start. Cone: the unit axis from the apex into the
    //! cone. Torus: the unit axis of symmetry.
    Vector3d axis = Vector3d::UnitZ();
    //! Plane: the unit direction of the rectangle's first side. Torus: the unit
    //! direction from the centre to where the arc starts. Both perpendicular to axis.
    Vector3d reference = Vector3d::UnitX();
    double radius = 0;       //!< cylinder, sphere; torus: major radius (m)
    double minorRadius = 0;  //!< torus: tube radius (m)
    double halfAngle = 0;    //!< cone: between axis and surface (rad)
    double length = 0;       //!< plane: side along reference; cylinder: along the axis (m)
    double width = 0;        //!< plane: side along axis x reference (m)
    double nearDistance = 0; //!< cone: start of the frustum along the axis from the apex (m)
    double farDistance = 0;  //!< cone: end of the frustum along the axis from the apex (m)
    double arcAngle = 0;     //!< torus: angle swept from reference towards axis x reference (rad)
};

inline ShapeSpec planePatch(std::string name, const Vector3d& centre, const Vector3d& normal, const Vector3d& side,
                            double length, double width)
{
    ShapeSpec s;
    s.name = std::move(name);
    s.kind = PrimitiveKind::Plane;
    s.centre = centre;
    s.axis = normal.normalized();
    s.reference = (side - side.dot(s.axis) * s.axis).normalized();
    s.length = length;
    s.width = width;
    return s;
}

inline ShapeSpec cylinderPiece(std::string name, const Vector3d& start, const Vector3d& axis, double radius, double length)
{
    ShapeSpec s;
    s.name = std::move(name);
    s.kind = PrimitiveKind::Cylinder;
    s.centre = start;
    s.axis = axis.normalized();
    s.reference = perpendicularTo(s.axis);
    s.radius = radius;
    s.length = length;
    return s;
}

inline ShapeSpec sphereShape(std::string name, const Vector3d& centre, double radius)
{
    ShapeSpec s;
    s.name = std::move(name);
    s.kind = PrimitiveKind::Sphere;
    s.centre = centre;
    s.radius = radius;
    return s;
}

inline ShapeSpec coneFrustum(std::string name, const Vector3d& apex, const Vector3d& axis, double halfAngle,
                             double nearDistance, double farDistance)
{
    ShapeSpec s;
    s.name = std::move(name);
    s.kind = PrimitiveKind::Cone;
    s.centre = apex;
    s.axis = axis.normalized();
    s.reference = perpendicularTo(s.axis);
    s.halfAngle = halfAngle;
    s.nearDistance = nearDistance;
    s.farDistance = farDistance;
    return s;
}

inline ShapeSpec torusSector(std::string name, const Vector3d& centre, const Vector3d& axis, const Vector3d& start,
                             double majorRadius, double minorRadius, double arcAngle)
{
    ShapeSpec s;
    s.name = std::move(name);
    s.kind = PrimitiveKind::Torus;
    s.centre = centre;
    s.axis = axis.normalized();
    s.reference = (start - start.dot(s.axis) * s.axis).normalized();
    s.radius = majorRadius;
    s.minorRadius = minorRadius;
    s.arcAngle = arcAngle;
    return s;
}

//! A small irregular object (valve, bag, junction box, cable bundle): a star
//! shape whose radius wobbles by three random lumps, so that no primitive fits
//! more than a small patch of it. Its points are clutter.
struct ClutterObject
{
    Vector3d centre = Vector3d::Zero();
    double radius = 0.1; //!< mean radius (m)
    std::array<Vector3d, 3> lumpAxis{};
    std::array<double, 3> lumpAmplitude{}; //!< relative to radius
    std::array<double, 3> lumpFrequency{}; //!< radians per unit of cosine
    std::array<double, 3> lumpPhase{};
};

inline ClutterObject randomClutterObject(SplitMix64& rng, const Vector3d& centre, double radius)
{
    ClutterObject c;
    c.centre = centre;
    c.radius = radius;
    for (std::size_t j = 0; j < 3; ++j) {
        c.lumpAxis[j] = randomUnitVector(rng);
        c.lumpAmplitude[j] = uniformIn(rng, 0.08, 0.18);
        c.lumpFrequency[j] = uniformIn(rng, 2.5, 6.0);
        c.lumpPhase[j] = uniformIn(rng, 0.0, 2.0 * kPi);
    }
    return c;
}

inline double clutterRadiusTowards(const ClutterObject& c, const Vector3d& unit)
{
    double factor = 1.0;
    for (std::size_t j = 0; j < 3; ++j)
        factor += c.lumpAmplitude[j] * std::sin(c.lumpFrequency[j] * unit.dot(c.lumpAxis[j]) + c.lumpPhase[j]);
    return c.radius * factor;
}

//! Negative inside the object, positive outside (not a true distance).
inline double clutterImplicit(const ClutterObject& c, const Vector3d& p)
{
    const Vector3d q = p - c.centre;
    const double n = q.norm();
    if (n < 1e-12)
        return -c.radius;
    return n - clutterRadiusTowards(c, q / n);
}

struct BoundingSphere
{
    Vector3d centre = Vector3d::Zero();
    double radius = 0;
};

inline BoundingSphere boundingSphere(const ShapeSpec& s)
{
    switch (s.kind) {
    case PrimitiveKind::Plane: return {s.centre, 0.5 * std::hypot(s.length, s.width)};
    case PrimitiveKind::Cylinder: return {s.centre + 0.5 * s.length * s.axis, std::hypot(0.5 * s.length, s.radius)};
    case PrimitiveKind::Sphere: return {s.centre, s.radius};
    case PrimitiveKind::Cone: {
        const double half = 0.5 * (s.farDistance - s.nearDistance);
        const double farRadius = s.farDistance * std::tan(s.halfAngle);
        return {s.centre + 0.5 * (s.nearDistance + s.farDistance) * s.axis, std::hypot(half, farRadius)};
    }
    case PrimitiveKind::Torus: return {s.centre, s.radius + s.minorRadius};
    }
    return {s.centre, 0};
}

inline BoundingSphere boundingSphere(const ClutterObject& c)
{
    double reach = 1.0;
    for (double a : c.lumpAmplitude)
        reach += a;
    return {c.centre, c.radius * reach};
}

//! Ray parameters where the ray o + t d (d unit) is inside the sphere; false if it misses.
inline bool raySphereSpan(const BoundingSphere& b, const Vector3d& o, const Vector3d& d, double& t0, double& t1)
{
    const Vector3d oc = o - b.centre;
    const double half = oc.dot(d);
    const double disc = half * half - (oc.squaredNorm() - b.radius * b.radius);
    if (disc < 0)
        return false;
    const double root = std::sqrt(disc);
    t0 = -half - root;
    t1 = -half + root;
    return t1 > 0;
}

//! Roots of a t^2 + b t + c = 0 in increasing order; returns how many (0..2).
inline int solveQuadratic(double a, double b, double c, double& r0, double& r1)
{
    if (std::abs(a) < 1e-14) {
        if (std::abs(b) < 1e-14)
            return 0;
        r0 = r1 = -c / b;
        return 1;
    }
    const double disc = b * b - 4 * a * c;
    if (disc < 0)
        return 0;
    // The numerically stable form (no cancellation between -b and the root).
    const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
    r0 = q / a;
    r1 = std::abs(q) > 1e-300 ? c / q : r0;
    if (r0 > r1)
        std::swap(r0, r1);
    return 2;
}

inline double intersectPlanePatch(const ShapeSpec& s, const Vector3d& o, const Vector3d& d, double tMin)
{
    const double denom = d.dot(s.axis);
    if (std::abs(denom) < 1e-12)
        return kNoHit;
    const double t = (s.centre - o).dot(s.axis) / denom;
    if (t <= tMin)
        return kNoHit;
    const Vector3d q = o + t * d - s.centre;
    const Vector3d other = s.axis.cross(s.reference);
    if (std::abs(q.dot(s.reference)) > 0.5 * s.length || std::abs(q.dot(other)) > 0.5 * s.width)
        return kNoHit;
    return t;
}

//! The lateral surface only (no end caps): pipes open into walls, elbows or
//! the air; a ray through an open end meets the inside, which is the same surface.
inline double intersectCylinder(const ShapeSpec& s, const Vector3d& o, const Vector3d& d, double tMin)
{
    const Vector3d oc = o - s.centre;
    const Vector3d dPerp = d - d.dot(s.axis) * s.axis;
    const Vector3d ocPerp = oc - oc.dot(s.axis) * s.axis;
    double r[2];
    const int n = solveQuadratic(dPerp.squaredNorm(), 2 * dPerp.dot(ocPerp), ocPerp.squaredNorm() - s.radius * s.radius,
                                 r[0], r[1]);
    for (int i = 0; i < n; ++i) {
        if (r[i] <= tMin)
            continue;
        const double h = (oc + r[i] * d).dot(s.axis);
        if (h >= 0 && h <= s.length)
            return r[i];
    }
    return kNoHit;
}

inline double intersectSphere(const ShapeSpec& s, const Vector3d& o, const Vector3d& d, double tMin)
{
    double t0 = 0, t1 = 0;
    if (!raySphereSpan({s.centre, s.radius}, o, d, t0, t1))
        return kNoHit;
    if (t0 > tMin)
        return t0;
    return t1 > tMin ? t1 : kNoHit;
}

inline double intersectCone(const ShapeSpec& s, const Vector3d& o, const Vector3d& d, double tMin)
{
    const Vector3d co = o - s.centre;
    const double cos2 = std::pow(std::cos(s.halfAngle), 2);
    const double dv = d.dot(s.axis), cv = co.dot(s.axis);
    double r[2];
    const int n = solveQuadratic(dv * dv - cos2, 2 * (dv * cv - cos2 * d.dot(co)), cv * cv - cos2 * co.squaredNorm(), r[0],
                                 r[1]);
    for (int i = 0; i < n; ++i) {
        if (r[i] <= tMin)
            continue;
        const double h = cv + r[i] * dv; // also rejects the mirrored nappe (h < 0)
        if (h >= s.nearDistance && h <= s.farDistance)
            return r[i];
    }
    return kNoHit;
}

//! Exact distance to the full torus's surface (negative inside the tube).
inline double torusSignedDistance(const ShapeSpec& s, const Vector3d& p)
{
    const Vector3d q = p - s.centre;
    const double along = q.dot(s.axis);
    const double ring = (q - along * s.axis).norm();
    return std::hypot(ring - s.radius, along) - s.minorRadius;
}

inline bool torusArcContains(const ShapeSpec& s, const Vector3d& p)
{
    const Vector3d q = p - s.centre;
    double angle = std::atan2(q.dot(s.axis.cross(s.reference)), q.dot(s.reference));
    if (angle < 0)
        angle += 2 * kPi;
    return angle <= s.arcAngle;
}

//! Marches the ray by the exact distance to the full torus (never past its
//! surface), bisects every crossing and keeps the first one on the sector: the
//! open ends of the sector let a ray meet the inside of the tube, as on a real elbow.
inline double intersectTorus(const ShapeSpec& s, const Vector3d& o, const Vector3d& d, double tMin)
{
    double t0 = 0, t1 = 0;
    if (!raySphereSpan(boundingSphere(s), o, d, t0, t1))
        return kNoHit;
    double t = std::max(t0, tMin);
    const double minStep = s.minorRadius / 40.0;
    double g = torusSignedDistance(s, o + t * d);
    while (t < t1) {
        const double tn = std::min(t + std::max(std::abs(g), minStep), t1);
        const double gn = torusSignedDistance(s, o + tn * d);
        if ((g > 0) != (gn > 0)) {
            double a = t, b = tn;
            for (int i = 0; i < 40; ++i) {
                const double m = 0.5 * (a + b);
                if ((torusSignedDistance(s, o + m * d) > 0) == (g > 0))
                    a = m;
                else
                    b = m;
            }
            const double root = 0.5 * (a + b);
            if (root > tMin && torusArcContains(s, o + root * d))
                return root;
        }
        if (tn >= t1)
            break;
        t = tn;
        g = gn;
    }
    return kNoHit;
}

inline double intersect(const ShapeSpec& s, const Vector3d& o, const Vector3d& d, double tMin)
{
    switch (s.kind) {
    case PrimitiveKind::Plane: return intersectPlanePatch(s, o, d, tMin);
    case PrimitiveKind::Cylinder: return intersectCylinder(s, o, d, tMin);
    case PrimitiveKind::Sphere: return intersectSphere(s, o, d, tMin);
    case PrimitiveKind::Cone: return intersectCone(s, o, d, tMin);
    case PrimitiveKind::Torus: return intersectTorus(s, o, d, tMin);
    }
    return kNoHit;
}

//! Fixed steps of a fifteenth of the radius (the lumps are smooth at that
//! scale), then bisection of the first entry.
inline double intersectClutter(const ClutterObject& c, const Vector3d& o, const Vector3d& d, double tMin)
{
    double t0 = 0, t1 = 0;
    if (!raySphereSpan(boundingSphere(c), o, d, t0, t1))
        return kNoHit;
    const double step = c.radius / 15.0;
    double t = std::max(t0, tMin);
    double f = clutterImplicit(c, o + t * d);
    while (t < t1) {
        const double tn = std::min(t + step, t1);
        const double fn = clutterImplicit(c, o + tn * d);
        if (f > 0 && fn <= 0) {
            double a = t, b = tn;
            for (int i = 0; i < 30; ++i) {
                const double m = 0.5 * (a + b);
                (clutterImplicit(c, o + m * d) > 0 ? a : b) = m;
            }
            return 0.5 * (a + b);
        }
        if (tn >= t1)
            break;
        t = tn;
        f = fn;
    }
    return kNoHit;
}

//! The surface normal at p (on the surface): a plane's own normal, away from
//! the axis or the centre for the others.
inline Vector3d outwardNormal(const ShapeSpec& s, const Vector3d& p)
{
    const Vector3d q = p - s.centre;
    switch (s.kind) {
    case PrimitiveKind::Plane: return s.axis;
    case PrimitiveKind::Sphere: return q.normalized();
    case PrimitiveKind::Cylinder: return (q - q.dot(s.axis) * s.axis).normalized();
    case PrimitiveKind::Cone: {
        const Vector3d radial = (q - q.dot(s.axis) * s.axis).normalized();
        return (std::cos(s.halfAngle) * radial - std::sin(s.halfAngle) * s.axis).normalized();
    }
    case PrimitiveKind::Torus: {
        const double along = q.dot(s.axis);
        const Vector3d ringDir = (q - along * s.axis).normalized();
        return (q - s.radius * ringDir).normalized();
    }
    }
    return s.axis;
}

inline Vector3d outwardNormal(const ClutterObject& c, const Vector3d& p)
{
    const double h = c.radius * 1e-3;
    Vector3d g;
    for (int k = 0; k < 3; ++k) {
        Vector3d e = Vector3d::Zero();
        e[k] = h;
        g[k] = clutterImplicit(c, p + e) - clutterImplicit(c, p - e);
    }
    return g.norm() > 0 ? g.normalized() : Vector3d::UnitZ();
}

//! A point on the bounded surface (uniform by area except on the torus, where
//! it is uniform in the two angles): where clutter gets placed.
inline Vector3d samplePointOn(const ShapeSpec& s, SplitMix64& rng)
{
    const Vector3d other = s.axis.cross(s.reference);
    const double angle = uniformIn(rng, 0.0, 2 * kPi);
    const Vector3d ring = std::cos(angle) * s.reference + std::sin(angle) * other;
    switch (s.kind) {
    case PrimitiveKind::Plane:
        return s.centre + uniformIn(rng, -0.5, 0.5) * s.length * s.reference + uniformIn(rng, -0.5, 0.5) * s.width * other;
    case PrimitiveKind::Cylinder: return s.centre + uniformIn(rng, 0.0, s.length) * s.axis + s.radius * ring;
    case PrimitiveKind::Sphere: return s.centre + s.radius * randomUnitVector(rng);
    case PrimitiveKind::Cone: {
        const double h = std::sqrt(uniformIn(rng, s.nearDistance * s.nearDistance, s.farDistance * s.farDistance));
        return s.centre + h * s.axis + h * std::tan(s.halfAngle) * ring;
    }
    case PrimitiveKind::Torus: {
        const double theta = uniformIn(rng, 0.0, s.arcAngle);
        const Vector3d ringDir = std::cos(theta) * s.reference + std::sin(theta) * other;
        return s.centre + s.radius * ringDir + s.minorRadius * (std::cos(angle) * ringDir + std::sin(angle) * s.axis);
    }
    }
    return s.centre;
}

//! The unbounded primitive the piece belongs to, in the scene frame (the
//! cylinder's axis point is its middle; make() moves it to the foot of the
//! centroid of the points, the convention of scandiff::Primitive).
inline Primitive toPrimitive(const ShapeSpec& s)
{
    Primitive p;
    p.kind = s.kind;
    p.point = s.centre;
    p.direction = s.axis;
    switch (s.kind) {
    case PrimitiveKind::Plane: break;
    case PrimitiveKind::Cylinder:
        p.point = s.centre + 0.5 * s.length * s.axis;
        p.radius = s.radius;
        break;
    case PrimitiveKind::Sphere: p.radius = s.radius; break;
    case PrimitiveKind::Cone: p.halfAngle = s.halfAngle; break;
    case PrimitiveKind::Torus:
        p.radius = s.radius;
        p.minorRadius = s.minorRadius;
        break;
    }
    return p;
}

inline const char* kindName(PrimitiveKind kind)
{
    switch (kind) {
    case PrimitiveKind::Plane: return "plane";
    case PrimitiveKind::Sphere: return "sphere";
    case PrimitiveKind::Cylinder: return "cylinder";
    case PrimitiveKind::Cone: return "cone";
    case PrimitiveKind::Torus: return "torus";
    }
    return "?";
}

} // namespace scandiff::test::family::primitives
