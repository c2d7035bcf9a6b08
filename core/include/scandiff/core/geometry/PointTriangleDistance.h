// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Exact distance from a point to a triangle, in double (thesis 000 §2.2.2:
//! the point-to-facet distance of the Metro-like cloud-to-mesh comparison).
//!
//! Method (Voronoi regions, as in Ericson, "Real-Time Collision Detection"
//! §5.1.5, written for robustness rather than for the fewest operations):
//! - the triangle is *degenerate* when its vertices are collinear or repeated
//!   (|n|^2 <= 1e-24 * (longest edge)^4, n = (b - a) x (c - a)); it is then the
//!   segment or point it collapses to, and the answer is the exact distance to
//!   that set (the minimum over its three edges), never NaN;
//! - otherwise, if p projects inside the closed triangle (the three signed
//!   volumes ((v[i+1] - v[i]) x (p - v[i])) . n are >= 0), the closest point is
//!   that projection and d^2 = ((p - a) . n)^2 / |n|^2 (region Face);
//! - otherwise the closest point is on the boundary: the minimum over the three
//!   edges (first edge wins a tie), each a clamped projection on the segment.
//!
//! Every edge is computed with its endpoints in a canonical (lexicographic)
//! order and a clamped parameter returns the vertex itself, so two triangles
//! sharing an edge or a vertex give bit-identical distances for a point whose
//! closest point lies on it: callers can break such ties by other criteria.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>

namespace scandiff::geometry {

//! Which feature of the triangle (a, b, c) holds the closest point. Edge01 is
//! [a, b], Edge12 is [b, c], Edge20 is [c, a]; Vertex0/1/2 are a, b, c.
enum class TriangleRegion { Face, Edge01, Edge12, Edge20, Vertex0, Vertex1, Vertex2 };

struct PointTriangleResult
{
    double squaredDistance = 0.0;
    Eigen::Vector3d closestPoint = Eigen::Vector3d::Zero();
    TriangleRegion region = TriangleRegion::Face;
    bool degenerate = false; //!< the triangle was treated as a segment or a point
};

namespace detail {

//! Lexicographic order of two points (x, then y, then z).
inline bool lexicographicLess(const Eigen::Vector3d& u, const Eigen::Vector3d& v)
{
    if (u.x() != v.x())
        return u.x() < v.x();
    if (u.y() != v.y())
        return u.y() < v.y();
    return u.z() < v.z();
}

//! Where on a segment the closest point lies.
enum class SegmentPart { First, Interior, Second };

struct SegmentResult
{
    double squaredDistance;
    Eigen::Vector3d closestPoint;
    SegmentPart part; //!< relative to the arguments' order (u, v)
};

//! Closest point of [u, v] to p; symmetric in (u, v) to the last bit.
inline SegmentResult pointSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& u, const Eigen::Vector3d& v)
{
    const bool swapped = lexicographicLess(v, u);
    const Eigen::Vector3d& s = swapped ? v : u;
    const Eigen::Vector3d& e = swapped ? u : v;
    const Eigen::Vector3d d = e - s;
    const double length2 = d.squaredNorm();
    const double t = length2 > 0.0 ? (p - s).dot(d) / length2 : 0.0;
    SegmentResult r;
    if (!(t > 0.0)) {
        r.closestPoint = s;
        r.part = swapped ? SegmentPart::Second : SegmentPart::First;
    } else if (t >= 1.0) {
        r.closestPoint = e;
        r.part = swapped ? SegmentPart::First : SegmentPart::Second;
    } else {
        r.closestPoint = s + t * d;
        r.part = SegmentPart::Interior;
    }
    r.squaredDistance = (p - r.closestPoint).squaredNorm();
    return r;
}

} // namespace detail

//! True when the triangle has no usable normal (collinear or repeated vertices):
//! |(b - a) x (c - a)|^2 <= 1e-24 * (longest edge)^4. pointTriangleDistance
//! then measures the distance to the segment or point it collapses to.
inline bool isDegenerateTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c)
{
    const double longest2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    const double normal2 = (b - a).cross(c - a).squaredNorm();
    return !(normal2 > 1e-24 * longest2 * longest2);
}

//! Exact squared distance from p to the triangle (a, b, c), with the closest
//! point and its region. Finite inputs give finite outputs, degenerate
//! triangles included.
inline PointTriangleResult pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                                 const Eigen::Vector3d& b, const Eigen::Vector3d& c)
{
    PointTriangleResult result;
    const Eigen::Vector3d ab = b - a, ac = c - a;
    const Eigen::Vector3d n = ab.cross(ac);
    const double normal2 = n.squaredNorm();
    const double longest2 = std::max({ab.squaredNorm(), (c - b).squaredNorm(), ac.squaredNorm()});
    result.degenerate = !(normal2 > 1e-24 * longest2 * longest2);
    if (!result.degenerate) {
        const Eigen::Vector3d ap = p - a;
        const bool inside = ab.cross(ap).dot(n) >= 0.0 && (c - b).cross(p - b).dot(n) >= 0.0 &&
                            (a - c).cross(p - c).dot(n) >= 0.0;
        if (inside) {
            const double h = ap.dot(n);
            result.squaredDistance = h * h / normal2;
            result.closestPoint = p - (h / normal2) * n;
            result.region = TriangleRegion::Face;
            return result;
        }
    }
    // Boundary: the closest of the three edges (also the whole answer for a
    // degenerate triangle, whose points all lie on its edges).
    using detail::SegmentPart;
    const Eigen::Vector3d* vertices[3] = {&a, &b, &c};
    constexpr TriangleRegion kEdges[3] = {TriangleRegion::Edge01, TriangleRegion::Edge12, TriangleRegion::Edge20};
    constexpr TriangleRegion kVertices[3] = {TriangleRegion::Vertex0, TriangleRegion::Vertex1, TriangleRegion::Vertex2};
    bool first = true;
    for (int e = 0; e < 3; ++e) {
        const int f = (e + 1) % 3;
        const detail::SegmentResult s = detail::pointSegment(p, *vertices[e], *vertices[f]);
        if (first || s.squaredDistance < result.squaredDistance) {
            first = false;
            result.squaredDistance = s.squaredDistance;
            result.closestPoint = s.closestPoint;
            result.region = s.part == SegmentPart::Interior ? kEdges[e]
                            : s.part == SegmentPart::First  ? kVertices[e]
                                                            : kVertices[f];
        }
    }
    return result;
}

} // namespace scandiff::geometry
