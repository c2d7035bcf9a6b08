// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/plugins/contours/PlaneJoining.h>

#include <scandiff/core/geometry/PlanarRings.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

namespace scandiff::plugins {

namespace {

struct Line
{
    Eigen::Vector3d point, direction;
};

//! The line where two planes meet (they are not parallel: the caller checked the angle).
Line intersection(const PlaneFrame& a, const PlaneFrame& b)
{
    Line line;
    line.direction = a.normal.cross(b.normal).normalized();
    // The point of the line nearest a's origin: on both planes and on the plane through a.origin across the line.
    Eigen::Matrix3d m;
    m.row(0) = a.normal.transpose();
    m.row(1) = b.normal.transpose();
    m.row(2) = line.direction.transpose();
    const Eigen::Vector3d rhs(a.normal.dot(a.origin), b.normal.dot(b.origin), line.direction.dot(a.origin));
    line.point = m.colPivHouseholderQr().solve(rhs);
    return line;
}

double distanceToLine(const Eigen::Vector3d& p, const Line& line)
{
    const Eigen::Vector3d d = p - line.point;
    return (d - d.dot(line.direction) * line.direction).norm();
}

double distanceToSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
    const Eigen::Vector3d ab = b - a;
    const double length2 = ab.squaredNorm();
    const double t = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
    return (a + t * ab - p).norm();
}

double distanceToRing(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& ring)
{
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < ring.size(); ++k)
        best = std::min(best, distanceToSegment(p, ring[k], ring[(k + 1) % ring.size()]));
    return best;
}

std::vector<Eigen::Vector2d> inPlane(const PlaneFrame& frame, const std::vector<Eigen::Vector3d>& ring)
{
    std::vector<Eigen::Vector2d> out;
    out.reserve(ring.size());
    for (const Eigen::Vector3d& p : ring)
        out.push_back(frame.toPlane(p));
    return out;
}

//! A plane's rings in its own (u, v) frame, made once for every vertex's inside test.
struct RingsInPlane
{
    std::vector<std::vector<Eigen::Vector2d>> outer, holes;
};

RingsInPlane ringsInPlane(const OutlinedPlane& plane, const Drawing& drawing)
{
    RingsInPlane rings;
    for (std::size_t k : plane.outer)
        rings.outer.push_back(inPlane(plane.frame, drawing.polylines[k].points));
    for (std::size_t k : plane.holes)
        rings.holes.push_back(inPlane(plane.frame, drawing.polylines[k].points));
    return rings;
}

//! Whether `p` lies on the surface `plane` outlines (inside an outer ring, not in a hole) or within `tolerance` of its outline.
bool onOrNear(const OutlinedPlane& plane, const RingsInPlane& rings, const Drawing& drawing, const Eigen::Vector3d& p, double tolerance)
{
    for (std::size_t k : plane.outer)
        if (distanceToRing(p, drawing.polylines[k].points) <= tolerance)
            return true;
    for (std::size_t k : plane.holes)
        if (distanceToRing(p, drawing.polylines[k].points) <= tolerance)
            return true;
    const Eigen::Vector2d q = plane.frame.toPlane(p);
    bool inside = false;
    for (const auto& ring : rings.outer)
        inside = inside || containsPoint(ring, q);
    for (const auto& ring : rings.holes)
        inside = inside && !containsPoint(ring, q);
    return inside;
}

struct Vertex
{
    std::size_t polyline = 0, index = 0;
    std::vector<std::size_t> planes; //!< its own plane first, then those it joins (increasing)
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

//! The point nearest `v` on every plane listed (least squares when they do not share one).
Eigen::Vector3d onAll(const Eigen::Vector3d& v, const std::vector<std::size_t>& planeList, const std::vector<OutlinedPlane>& planes)
{
    Eigen::MatrixXd n(static_cast<Eigen::Index>(planeList.size()), 3);
    Eigen::VectorXd c(static_cast<Eigen::Index>(planeList.size()));
    for (std::size_t k = 0; k < planeList.size(); ++k) {
        const PlaneFrame& f = planes[planeList[k]].frame;
        n.row(static_cast<Eigen::Index>(k)) = f.normal.transpose();
        c[static_cast<Eigen::Index>(k)] = f.normal.dot(f.origin);
    }
    return v + n.completeOrthogonalDecomposition().solve(c - n * v);
}

} // namespace

PlaneJoinResult joinNeighbouringPlanes(Drawing& drawing, const std::vector<OutlinedPlane>& planes, const PlaneJoinParams& params)
{
    PlaneJoinResult result;
    const double minSine = std::sin(params.minAngleDegrees * M_PI / 180.0);
    // The lines where pairs of planes meet, for the pairs that are not near parallel.
    std::map<std::pair<std::size_t, std::size_t>, Line> lines;
    for (std::size_t a = 0; a < planes.size(); ++a)
        for (std::size_t b = a + 1; b < planes.size(); ++b)
            if (planes[a].frame.normal.cross(planes[b].frame.normal).norm() >= minSine)
                lines[{a, b}] = intersection(planes[a].frame, planes[b].frame);

    std::vector<RingsInPlane> flat;
    for (const OutlinedPlane& plane : planes)
        flat.push_back(ringsInPlane(plane, drawing));

    // Which planes each vertex meets.
    std::vector<Vertex> joined;
    std::set<std::pair<std::size_t, std::size_t>> meetingPairs;
    for (std::size_t a = 0; a < planes.size(); ++a) {
        std::vector<std::size_t> rings = planes[a].outer;
        rings.insert(rings.end(), planes[a].holes.begin(), planes[a].holes.end());
        for (std::size_t k : rings)
            for (std::size_t i = 0; i < drawing.polylines[k].points.size(); ++i) {
                const Eigen::Vector3d& v = drawing.polylines[k].points[i];
                Vertex vertex{k, i, {a}, v};
                // The planes it meets, nearest line first; at most two, each
                // well apart from those taken (its own included), so the
                // point on all of them exists, is unique and is on its own plane.
                std::vector<std::pair<double, std::size_t>> candidates;
                for (std::size_t b = 0; b < planes.size(); ++b) {
                    const auto line = lines.find({std::min(a, b), std::max(a, b)});
                    if (b == a || line == lines.end())
                        continue;
                    const double distance = distanceToLine(v, line->second);
                    if (distance <= params.tolerance && onOrNear(planes[b], flat[b], drawing, v, params.tolerance))
                        candidates.emplace_back(distance, b);
                }
                std::sort(candidates.begin(), candidates.end());
                for (const auto& [distance, b] : candidates) {
                    if (vertex.planes.size() == 3)
                        break;
                    bool apart = true;
                    for (std::size_t taken : vertex.planes)
                        apart = apart && planes[taken].frame.normal.cross(planes[b].frame.normal).norm() >= minSine;
                    if (vertex.planes.size() == 2) // three planes meet at one point only if their normals span space
                        apart = apart && std::abs(planes[vertex.planes[0]].frame.normal.cross(planes[vertex.planes[1]].frame.normal)
                                                      .dot(planes[b].frame.normal)) >= minSine * minSine;
                    if (!apart)
                        continue;
                    vertex.planes.push_back(b);
                    meetingPairs.insert({std::min(a, b), std::max(a, b)});
                }
                if (vertex.planes.size() < 2)
                    continue;
                const Eigen::Vector3d moved = onAll(v, vertex.planes, planes);
                // Three planes meeting at a shallow angle put their common point
                // far away: such a vertex stays where it is.
                if (!moved.allFinite() || (moved - v).norm() > 3.0 * params.tolerance)
                    continue;
                vertex.position = moved;
                joined.push_back(std::move(vertex));
            }
    }
    result.joints = meetingPairs.size();

    // Vertices on the same planes and close together become one point (the
    // mean of points on those planes is on them too).
    std::vector<bool> done(joined.size(), false);
    for (std::size_t i = 0; i < joined.size(); ++i) {
        if (done[i])
            continue;
        std::vector<std::size_t> setI(joined[i].planes.begin(), joined[i].planes.end());
        std::sort(setI.begin(), setI.end());
        std::vector<std::size_t> cluster{i};
        for (std::size_t j = i + 1; j < joined.size(); ++j) {
            // Only vertices of different outlines' planes become one: two
            // vertices of one outline along a shared edge stay two.
            if (done[j] || joined[j].planes.front() == joined[i].planes.front() ||
                (joined[j].position - joined[i].position).norm() > params.tolerance)
                continue;
            std::vector<std::size_t> setJ(joined[j].planes.begin(), joined[j].planes.end());
            std::sort(setJ.begin(), setJ.end());
            if (setJ == setI)
                cluster.push_back(j);
        }
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (std::size_t k : cluster)
            mean += joined[k].position;
        mean /= static_cast<double>(cluster.size());
        for (std::size_t k : cluster) {
            joined[k].position = mean;
            done[k] = true;
        }
    }
    for (const Vertex& vertex : joined) {
        Eigen::Vector3d& p = drawing.polylines[vertex.polyline].points[vertex.index];
        result.moves[{p.x(), p.y(), p.z()}] = vertex.position;
        p = vertex.position;
        ++result.movedVertices;
    }
    return result;
}

} // namespace scandiff::plugins
