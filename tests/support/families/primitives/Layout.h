// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Layouts of plant-like scenes for the primitives family: the issue's room
//! (fixed) and random rooms drawn over the ranges real plant surveys span.
//!
//! A room is a rectangular floor (x in [0, length], y in [0, width], z = 0),
//! optionally a back wall (y = width) and a left wall (x = 0), open elsewhere
//! (the scanners see nothing beyond: no ceiling, as under a high roof or on an
//! open-air skid). Equipment stands on the floor: tanks and columns (columns
//! may touch a wall), boxes (each visible face its own plane; a face against a
//! wall is hidden and is no shape), spheres (on the floor or on a box), cones
//! (standing frustums or lying reducers), pipes in any direction and elbows
//! (straight leg, quarter-ish torus, straight leg: three shapes, tangent at
//! the joints). Pieces of different assemblies keep a clearance; pieces of one
//! assembly touch by design.

#include "Scanner.h"

#include <optional>
#include <string>
#include <vector>

namespace scandiff::test::family::primitives {

struct Room
{
    double length = 18;     //!< along x (m)
    double width = 14;      //!< along y (m)
    double height = 6;      //!< of the walls, and the top of the volume shapes may use (m)
    bool backWall = true;   //!< the plane y = width
    bool leftWall = true;   //!< the plane x = 0
};

struct Layout
{
    Room room;
    std::vector<ShapeSpec> shapes;
    std::vector<StationSpec> stations;
};

//! The issue's scene: an 18 x 14 m hall corner with walls 6 m high, 15 shapes,
//! 4 tripod stations in front of the equipment. The 16 m pipe of radius 0.10
//! runs 2 m in front of the back wall at 3 m height, out of the left wall,
//! 0.15 m behind a 4.5 m tank and 0.1 m above a 3 x 4 m platform (seen from
//! below, its plate hides the pipe from every station), under an elbow's leg:
//! its points come in pieces.
inline Layout issueLayout()
{
    Layout lay;
    const Vector3d X = Vector3d::UnitX(), Y = Vector3d::UnitY(), Z = Vector3d::UnitZ();
    auto& s = lay.shapes;
    s.push_back(planePatch("floor", {9, 7, 0}, Z, X, 18, 14));
    s.push_back(planePatch("back wall", {9, 14, 3}, -Y, X, 18, 6));
    s.push_back(planePatch("left wall", {0, 7, 3}, X, Y, 14, 6));
    s.push_back(cylinderPiece("long pipe r0.10", {0, 12.0, 3.0}, X, 0.10, 16.0));
    s.push_back(cylinderPiece("column r0.25 on wall", {0.25, 6.0, 0}, Z, 0.25, 6.0));
    s.push_back(cylinderPiece("tank r1.0", {5.5, 10.75, 0}, Z, 1.0, 4.5));
    s.push_back(planePatch("platform underside", {9.0, 12.0, 2.8}, -Z, X, 3.0, 4.0));
    // A 2.4 x 2.2 x 1.0 m box in the corner: its back and left faces are against the walls.
    s.push_back(planePatch("box top", {1.2, 12.9, 1.0}, Z, X, 2.4, 2.2));
    s.push_back(planePatch("box front", {1.2, 11.8, 0.5}, -Y, X, 2.4, 1.0));
    s.push_back(planePatch("box side", {2.4, 12.9, 0.5}, X, Y, 2.2, 1.0));
    s.push_back(sphereShape("sphere r0.6 on box", {1.2, 12.9, 1.6}, 0.6));
    // Elbow line: a 20-degree reducer on the floor (radius 0.45 -> 0.15), a
    // vertical leg, a quarter torus (R 0.8, r 0.15) turning towards the back
    // wall, a horizontal leg into the wall passing 0.35 m above the long pipe.
    const double tan20 = std::tan(20.0 * kPi / 180);
    const double apexHeight = 0.45 / tan20, topHeight = apexHeight - 0.15 / tan20;
    s.push_back(coneFrustum("reducer cone 20deg", {13, 10.0, apexHeight}, -Z, 20.0 * kPi / 180, 0.15 / tan20, apexHeight));
    s.push_back(cylinderPiece("elbow leg up r0.15", {13, 10.0, topHeight}, Z, 0.15, 2.8 - topHeight));
    s.push_back(torusSector("elbow torus R0.8 r0.15", {13, 10.8, 2.8}, -X, -Y, 0.8, 0.15, 0.5 * kPi));
    s.push_back(cylinderPiece("elbow leg to wall r0.15", {13, 10.8, 3.6}, Y, 0.15, 3.2));
    for (const Vector3d& p : {Vector3d(3.5, 8.5, 1.7), Vector3d(8.0, 5.0, 1.6), Vector3d(12.5, 7.5, 1.75),
                              Vector3d(16.5, 4.0, 1.6)}) {
        StationSpec st;
        st.position = p;
        lay.stations.push_back(st);
    }
    return lay;
}

// ---------------------------------------------------------------- random rooms

//! What a piece occupies, to keep assemblies apart: a capsule (segment and
//! radius) or an upright box.
struct Blocker
{
    bool isBox = false;
    Vector3d a = Vector3d::Zero(), b = Vector3d::Zero();
    double radius = 0;
    Vector3d centre = Vector3d::Zero();  //!< box centre
    Vector3d xAxis = Vector3d::UnitX();  //!< box's horizontal axes
    Vector3d yAxis = Vector3d::UnitY();
    Vector3d half = Vector3d::Zero();    //!< box half extents along xAxis, yAxis, z
    int assembly = -1;                   //!< pieces of one assembly may touch
};

inline Blocker capsule(const Vector3d& a, const Vector3d& b, double radius)
{
    Blocker k;
    k.a = a;
    k.b = b;
    k.radius = radius;
    return k;
}

inline double segmentDistance(const Vector3d& p1, const Vector3d& q1, const Vector3d& p2, const Vector3d& q2)
{
    const Vector3d d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
    const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
    double s = 0, t = 0;
    if (a < 1e-12 && e < 1e-12)
        return r.norm();
    if (a < 1e-12) {
        t = std::clamp(f / e, 0.0, 1.0);
    } else {
        const double c = d1.dot(r);
        if (e < 1e-12) {
            s = std::clamp(-c / a, 0.0, 1.0);
        } else {
            const double bb = d1.dot(d2), denom = a * e - bb * bb;
            s = denom > 1e-12 ? std::clamp((bb * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (bb * s + f) / e;
            if (t < 0) {
                t = 0;
                s = std::clamp(-c / a, 0.0, 1.0);
            } else if (t > 1) {
                t = 1;
                s = std::clamp((bb - c) / a, 0.0, 1.0);
            }
        }
    }
    return ((p1 + s * d1) - (p2 + t * d2)).norm();
}

inline double boxSignedDistance(const Blocker& box, const Vector3d& p)
{
    const Vector3d q = p - box.centre;
    const Vector3d local(std::abs(q.dot(box.xAxis)), std::abs(q.dot(box.yAxis)), std::abs(q.z()));
    const Vector3d over = local - box.half;
    return over.cwiseMax(0.0).norm() + std::min(over.maxCoeff(), 0.0);
}

//! The box as an upright capsule around it (for box against box only: boxes stand on the floor).
inline Blocker boundingCapsule(const Blocker& box)
{
    const double r = std::hypot(box.half.x(), box.half.y());
    return capsule(box.centre - box.half.z() * Vector3d::UnitZ(), box.centre + box.half.z() * Vector3d::UnitZ(), r);
}

//! Clearance between two pieces (negative when they overlap).
inline double blockerGap(const Blocker& x, const Blocker& y)
{
    if (x.isBox && y.isBox)
        return blockerGap(boundingCapsule(x), boundingCapsule(y));
    if (x.isBox != y.isBox) {
        const Blocker& box = x.isBox ? x : y;
        const Blocker& cap = x.isBox ? y : x;
        const int samples = std::max(2, static_cast<int>(std::ceil((cap.b - cap.a).norm() / 0.05)) + 1);
        double best = kNoHit;
        for (int i = 0; i < samples; ++i)
            best = std::min(best, boxSignedDistance(box, cap.a + (cap.b - cap.a) * (double(i) / (samples - 1))));
        return best - cap.radius;
    }
    return segmentDistance(x.a, x.b, y.a, y.b) - x.radius - y.radius;
}

inline double pointGap(const Vector3d& p, const Blocker& k)
{
    if (k.isBox)
        return boxSignedDistance(k, p);
    return segmentDistance(p, p, k.a, k.b) - k.radius;
}

struct Assembly
{
    std::vector<ShapeSpec> shapes;
    std::vector<Blocker> blockers;
};

inline bool insideRoom(const Room& room, const Vector3d& p, double margin, double floorLevel)
{
    return p.x() >= margin && p.x() <= room.length - margin && p.y() >= margin && p.y() <= room.width - margin &&
           p.z() >= floorLevel && p.z() <= room.height;
}

inline Vector3d randomFloorPoint(SplitMix64& rng, const Room& room, double margin)
{
    return {uniformIn(rng, margin, room.length - margin), uniformIn(rng, margin, room.width - margin), 0.0};
}

//! A vertical cylinder on the floor: a column (0.15-0.5 m, full height, often
//! touching a wall) or a tank (0.5-2 m, limited to a fifth of the room's width).
inline std::optional<Assembly> drawTankOrColumn(SplitMix64& rng, const Room& room, int index)
{
    const bool column = rng.uniform() < 0.5;
    const double r = column ? uniformIn(rng, 0.15, 0.5) : uniformIn(rng, 0.5, std::max(0.5, std::min(2.0, 0.2 * room.width)));
    const double h = column ? room.height : uniformIn(rng, std::min(1.5, room.height), room.height);
    Vector3d foot = randomFloorPoint(rng, room, r + 0.3);
    const bool wallAvailable = room.backWall || room.leftWall;
    if (column && wallAvailable && rng.uniform() < 0.7) {
        const bool back = room.backWall && (!room.leftWall || rng.uniform() < 0.5);
        (back ? foot.y() : foot.x()) = back ? room.width - r : r; // touching the wall
    }
    if (foot.x() < r - 1e-9 || foot.y() < r - 1e-9 || foot.x() > room.length - r || foot.y() > room.width - r)
        return std::nullopt;
    Assembly a;
    const std::string name = (column ? "column " : "tank ") + std::to_string(index);
    a.shapes.push_back(cylinderPiece(name, foot, Vector3d::UnitZ(), r, h));
    a.blockers.push_back(capsule(foot, foot + h * Vector3d::UnitZ(), r));
    return a;
}

//! A box on the floor (an equipment skid, a cabinet): free-standing at any
//! yaw (top and four sides) or aligned against a wall (top and three sides).
//! With `sphere`, a sphere rests on its top (a spherical vessel on a skid).
inline std::optional<Assembly> drawBox(SplitMix64& rng, const Room& room, bool sphere, int index)
{
    const double w = uniformIn(rng, 0.6, std::max(0.8, std::min(3.0, 0.3 * room.length)));
    const double d = uniformIn(rng, 0.6, std::max(0.8, std::min(2.5, 0.3 * room.width)));
    const double h = uniformIn(rng, 0.4, 2.0);
    const bool againstBack = room.backWall && rng.uniform() < 0.35;
    const double yaw = againstBack ? 0.0 : uniformIn(rng, 0.0, 2 * kPi);
    const Vector3d ex(std::cos(yaw), std::sin(yaw), 0), ey(-std::sin(yaw), std::cos(yaw), 0), ez = Vector3d::UnitZ();
    Vector3d foot = randomFloorPoint(rng, room, 0.5 * std::hypot(w, d) + 0.1);
    if (againstBack)
        foot.y() = room.width - 0.5 * d;
    if (!insideRoom(room, foot, 0.5 * std::min(w, d), 0.0))
        return std::nullopt;
    Assembly a;
    const std::string name = "box " + std::to_string(index);
    a.shapes.push_back(planePatch(name + " top", foot + h * ez, ez, ex, w, d));
    for (int side = 0; side < 4; ++side) {
        const Vector3d normal = side == 0 ? ex : side == 1 ? -ex : side == 2 ? ey : -ey;
        if (againstBack && side == 2)
            continue; // against the wall: never seen, no shape
        const double across = side < 2 ? d : w, offset = side < 2 ? 0.5 * w : 0.5 * d;
        a.shapes.push_back(planePatch(name + " side " + std::to_string(side), foot + offset * normal + 0.5 * h * ez, normal,
                                      ez.cross(normal), across, h));
    }
    Blocker body;
    body.isBox = true;
    body.centre = foot + 0.5 * h * ez;
    body.xAxis = ex;
    body.yAxis = ey;
    body.half = Vector3d(0.5 * w, 0.5 * d, 0.5 * h);
    a.blockers.push_back(body);
    if (sphere) {
        const double r = uniformIn(rng, 0.1, std::max(0.1, std::min(1.0, 0.45 * std::min(w, d))));
        const Vector3d c = foot + uniformIn(rng, -0.5, 0.5) * (0.5 * w - r) * ex +
                           uniformIn(rng, -0.5, 0.5) * std::max(0.0, 0.5 * d - r) * ey + (h + r) * ez;
        a.shapes.push_back(sphereShape("sphere on " + name, c, r));
        a.blockers.push_back(capsule(c, c, r));
    }
    return a;
}

inline std::optional<Assembly> drawFloorSphere(SplitMix64& rng, const Room& room, int index)
{
    const double r = uniformIn(rng, 0.1, 1.0);
    const Vector3d c = randomFloorPoint(rng, room, r + 0.2) + r * Vector3d::UnitZ();
    Assembly a;
    a.shapes.push_back(sphereShape("sphere " + std::to_string(index), c, r));
    a.blockers.push_back(capsule(c, c, r));
    return a;
}

//! A frustum of half-angle 10-40 degrees: standing on the floor apex up (a
//! hood, a hopper outlet) or lying in the air in any direction (a reducer).
inline std::optional<Assembly> drawCone(SplitMix64& rng, const Room& room, int index)
{
    const double alpha = uniformIn(rng, 10.0, 40.0) * kPi / 180;
    const double rBase = uniformIn(rng, 0.2, 1.0), rTop = rBase * uniformIn(rng, 0.15, 0.6);
    const double nearD = rTop / std::tan(alpha), farD = rBase / std::tan(alpha);
    if (farD - nearD > 0.8 * room.height)
        return std::nullopt;
    Vector3d apex, axis;
    if (rng.uniform() < 0.7) {
        axis = -Vector3d::UnitZ();
        apex = randomFloorPoint(rng, room, rBase + 0.2) + farD * Vector3d::UnitZ();
    } else {
        axis = randomUnitVector(rng);
        const Vector3d mid = randomFloorPoint(rng, room, rBase + 0.2) +
                             uniformIn(rng, rBase + 0.3, room.height - rBase) * Vector3d::UnitZ();
        apex = mid - 0.5 * (nearD + farD) * axis;
    }
    const Vector3d e0 = apex + nearD * axis, e1 = apex + farD * axis;
    const double floorLevel = axis.z() < -0.99 ? -1e-9 : rBase + 0.05;
    if (!insideRoom(room, e0, rBase, floorLevel) || !insideRoom(room, e1, rBase, floorLevel))
        return std::nullopt;
    Assembly a;
    a.shapes.push_back(coneFrustum("cone " + std::to_string(index), apex, axis, alpha, nearD, farD));
    a.blockers.push_back(capsule(e0, e1, rBase));
    return a;
}

//! Straight leg, torus sector, straight leg, tangent at both joints. R 0.3-2
//! m, r 0.05-0.4 m below 0.45 R; the sector is a quarter (the usual elbow) or
//! 30-90 degrees; the first leg rises from the floor or points anywhere.
inline std::optional<Assembly> drawElbow(SplitMix64& rng, const Room& room, int index)
{
    const double R = uniformIn(rng, 0.3, std::max(0.3, std::min(2.0, 0.25 * std::min(room.width, room.height))));
    const double r = uniformIn(rng, 0.05, std::min(0.4, 0.45 * R));
    const double arc = rng.uniform() < 0.6 ? 0.5 * kPi : uniformIn(rng, 30.0, 90.0) * kPi / 180;
    const double leg1 = uniformIn(rng, 0.8, 4.0), leg2 = uniformIn(rng, 0.8, 4.0);
    const bool fromFloor = rng.uniform() < 0.4;
    Vector3d d1, start;
    if (fromFloor) {
        d1 = Vector3d::UnitZ();
        start = randomFloorPoint(rng, room, R + r + 0.2);
    } else {
        d1 = randomUnitVector(rng);
        start = randomFloorPoint(rng, room, r + 0.2) + uniformIn(rng, r + 0.3, room.height - r) * Vector3d::UnitZ();
    }
    const double turn = uniformIn(rng, 0.0, 2 * kPi);
    const Vector3d p = perpendicularTo(d1);
    const Vector3d e = std::cos(turn) * p + std::sin(turn) * d1.cross(p); // towards the bend's centre
    const Vector3d bendStart = start + leg1 * d1, centre = bendStart + R * e;
    const Vector3d axis = d1.cross(e); // so that the arc runs from -e towards d1
    const Vector3d endDir = std::cos(arc) * (-e) + std::sin(arc) * d1;          // centre -> arc end
    const Vector3d legDir = axis.cross(endDir).normalized();                    // tangent at the arc end
    const Vector3d bendEnd = centre + R * endDir, end = bendEnd + leg2 * legDir;
    const double floorLevel = r + 0.05;
    if (!insideRoom(room, start, r, fromFloor ? -1e-9 : floorLevel) || !insideRoom(room, end, r, floorLevel))
        return std::nullopt;
    Assembly a;
    const std::string name = "elbow " + std::to_string(index);
    a.shapes.push_back(cylinderPiece(name + " leg 1", start, d1, r, leg1));
    a.shapes.push_back(torusSector(name + " torus", centre, axis, -e, R, r, arc));
    a.shapes.push_back(cylinderPiece(name + " leg 2", bendEnd, legDir, r, leg2));
    a.blockers.push_back(capsule(start, bendStart, r));
    a.blockers.push_back(capsule(bendEnd, end, r));
    Vector3d previous = bendStart;
    for (int i = 1; i <= 6; ++i) {
        const double th = arc * i / 6.0;
        const Vector3d q = centre + R * (std::cos(th) * (-e) + std::sin(th) * d1);
        if (!insideRoom(room, q, r, floorLevel))
            return std::nullopt;
        a.blockers.push_back(capsule(previous, q, r * 1.05));
        previous = q;
    }
    return a;
}

//! A straight pipe, 0.05-0.3 m: horizontal at any heading, vertical from the
//! floor, or inclined in any direction; it may end in a wall or in the air.
inline std::optional<Assembly> drawPipe(SplitMix64& rng, const Room& room, int index)
{
    const double r = uniformIn(rng, 0.05, 0.3);
    const double which = rng.uniform();
    Vector3d dir;
    if (which < 0.45) {
        const double heading = uniformIn(rng, 0.0, 2 * kPi);
        dir = Vector3d(std::cos(heading), std::sin(heading), 0);
    } else if (which < 0.65) {
        dir = Vector3d::UnitZ();
    } else {
        do
            dir = randomUnitVector(rng);
        while (std::abs(dir.z()) > 0.95);
    }
    const Vector3d anchor = randomFloorPoint(rng, room, r + 0.1) + uniformIn(rng, r + 0.3, room.height - r) * Vector3d::UnitZ();
    // The span of the line inside the room's volume (slabs).
    const Vector3d lo(0, 0, dir.z() > 0.99 ? 0.0 : r + 0.05), hi(room.length, room.width, room.height);
    double t0 = -1e9, t1 = 1e9;
    for (int k = 0; k < 3; ++k) {
        if (std::abs(dir[k]) < 1e-9)
            continue;
        double a = (lo[k] - anchor[k]) / dir[k], b = (hi[k] - anchor[k]) / dir[k];
        if (a > b)
            std::swap(a, b);
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
    }
    if (t1 - t0 < 2.5)
        return std::nullopt;
    const double len = uniformIn(rng, 2.5, std::min(20.0, t1 - t0));
    const double from = dir.z() > 0.99 ? t0 : uniformIn(rng, t0, t1 - len);
    Assembly a;
    a.shapes.push_back(cylinderPiece("pipe " + std::to_string(index), anchor + from * dir, dir, r, len));
    a.blockers.push_back(capsule(anchor + from * dir, anchor + (from + len) * dir, r));
    return a;
}

//! Adds the assembly if it fits the shape budget and keeps `clearance` from
//! every piece already placed.
struct LayoutDraft
{
    Layout layout;
    std::vector<Blocker> blockers;
    std::vector<int> shapeAssembly; //!< per shape; -1 for the floor and walls
    int assemblies = 0;
    std::size_t targetShapes = 12;
    double clearance = 0.15;

    bool tryPlace(const std::optional<Assembly>& a)
    {
        if (!a || layout.shapes.size() + a->shapes.size() > targetShapes)
            return false;
        for (const Blocker& mine : a->blockers)
            for (const Blocker& other : blockers)
                if (blockerGap(mine, other) < clearance)
                    return false;
        layout.shapes.insert(layout.shapes.end(), a->shapes.begin(), a->shapes.end());
        shapeAssembly.insert(shapeAssembly.end(), a->shapes.size(), assemblies);
        for (Blocker k : a->blockers) {
            k.assembly = assemblies;
            blockers.push_back(k);
        }
        ++assemblies;
        return true;
    }

    //! Whether the segment a-b misses every piece except those of `ignored`.
    bool clearLine(const Vector3d& a, const Vector3d& b, int ignored) const
    {
        for (const Blocker& k : blockers) {
            if (k.assembly == ignored)
                continue;
            if (!k.isBox) {
                if (segmentDistance(a, b, k.a, k.b) < k.radius)
                    return false;
                continue;
            }
            const int samples = std::max(2, static_cast<int>((b - a).norm() / 0.05) + 1);
            for (int i = 0; i < samples; ++i)
                if (boxSignedDistance(k, a + (b - a) * (double(i) / (samples - 1))) < 0)
                    return false;
        }
        return true;
    }
};

inline void addRoomPlanes(LayoutDraft& draft)
{
    Layout& lay = draft.layout;
    const Room& r = lay.room;
    const Vector3d X = Vector3d::UnitX(), Y = Vector3d::UnitY(), Z = Vector3d::UnitZ();
    lay.shapes.push_back(planePatch("floor", {0.5 * r.length, 0.5 * r.width, 0}, Z, X, r.length, r.width));
    if (r.backWall)
        lay.shapes.push_back(planePatch("back wall", {0.5 * r.length, r.width, 0.5 * r.height}, -Y, X, r.length, r.height));
    if (r.leftWall)
        lay.shapes.push_back(planePatch("left wall", {0, 0.5 * r.width, 0.5 * r.height}, X, Y, r.width, r.height));
    draft.shapeAssembly.assign(lay.shapes.size(), -1);
}

//! Tripod stations (1.4-1.9 m), at least 0.5 m from any piece and 2 m apart,
//! chosen as a surveyor plans them: each next station is the candidate that
//! sees (within 15 m, facing it, nothing in between) the most equipment no
//! station sees yet, then the most equipment overall. With `windowHalfWidth`
//! below pi each station scans a horizontal window aimed at the equipment.
inline void placeStations(SplitMix64& rng, LayoutDraft& draft, int count, double windowHalfWidth)
{
    const Layout& lay = draft.layout;
    std::vector<Vector3d> candidates;
    std::vector<double> aims;
    Vector3d equipment = Vector3d::Zero();
    int pieces = 0;
    for (std::size_t s = 0; s < lay.shapes.size(); ++s)
        if (draft.shapeAssembly[s] >= 0) {
            equipment += boundingSphere(lay.shapes[s]).centre;
            ++pieces;
        }
    equipment = pieces > 0 ? Vector3d(equipment / pieces) : Vector3d(0.5 * lay.room.length, 0.5 * lay.room.width, 0);
    for (int attempt = 0; attempt < 600 && candidates.size() < 80; ++attempt) {
        Vector3d p = randomFloorPoint(rng, lay.room, 0.8);
        p.z() = uniformIn(rng, 1.4, 1.9);
        bool ok = true;
        for (const Blocker& k : draft.blockers)
            ok = ok && pointGap(p, k) >= 0.5;
        if (!ok)
            continue;
        candidates.push_back(p);
        aims.push_back(std::atan2(equipment.y() - p.y(), equipment.x() - p.x()));
    }
    // seen[c][s]: sample points of equipment shape s that candidate c sees (of 6).
    std::vector<std::vector<int>> seen(candidates.size(), std::vector<int>(lay.shapes.size(), 0));
    for (std::size_t s = 0; s < lay.shapes.size(); ++s) {
        if (draft.shapeAssembly[s] < 0)
            continue;
        for (int k = 0; k < 6; ++k) {
            const Vector3d q = samplePointOn(lay.shapes[s], rng), n = outwardNormal(lay.shapes[s], q);
            for (std::size_t c = 0; c < candidates.size(); ++c) {
                const Vector3d v = candidates[c] - q;
                const bool inWindow = windowHalfWidth >= kPi ||
                                      std::abs(std::remainder(std::atan2(-v.y(), -v.x()) - aims[c], 2 * kPi)) <= windowHalfWidth;
                if (inWindow && v.norm() < 15.0 && v.dot(n) > 0.1 * v.norm() &&
                    draft.clearLine(q + 0.02 * n, candidates[c], draft.shapeAssembly[s]))
                    ++seen[c][s];
            }
        }
    }
    std::vector<bool> covered(lay.shapes.size(), false), used(candidates.size(), false);
    for (int station = 0; station < count; ++station) {
        double bestGain = -1;
        std::size_t best = candidates.size();
        for (std::size_t c = 0; c < candidates.size(); ++c) {
            bool apart = !used[c];
            for (const StationSpec& st : draft.layout.stations)
                apart = apart && (st.position - candidates[c]).norm() >= 2.0;
            if (!apart)
                continue;
            double gain = 0;
            for (std::size_t s = 0; s < lay.shapes.size(); ++s)
                gain += (seen[c][s] >= 2 && !covered[s] ? 1.0 : 0.0) + 0.02 * seen[c][s];
            if (gain > bestGain) {
                bestGain = gain;
                best = c;
            }
        }
        if (best == candidates.size())
            break;
        used[best] = true;
        for (std::size_t s = 0; s < lay.shapes.size(); ++s)
            covered[s] = covered[s] || seen[best][s] >= 2;
        StationSpec st;
        st.position = candidates[best];
        st.yawCentre = aims[best];
        st.yawHalfWidth = windowHalfWidth;
        draft.layout.stations.push_back(st);
    }
}

//! A random room: length 14-28 m times `sizeFactor`, at least 4.5 m (width
//! 0.55-0.85 of it, at least 3 m; walls 4-8 m, at most 0.6 of the length
//! but 3.5 m), 8-20 shapes (fewer when a small room is full), 2-5 stations. The torus, the sphere and the
//! cone are placed first so every draw holds each kind.
inline Layout randomLayout(SplitMix64& rng, double sizeFactor, double windowHalfWidth = kPi)
{
    LayoutDraft draft;
    Room& room = draft.layout.room;
    room.length = std::max(4.5, uniformIn(rng, 14.0, 28.0) * sizeFactor);
    room.width = std::max(3.0, room.length * uniformIn(rng, 0.55, 0.85));
    room.height = std::min(uniformIn(rng, 4.0, 8.0), std::max(3.5, 0.6 * room.length));
    room.backWall = rng.uniform() < 0.8;
    room.leftWall = rng.uniform() < 0.6;
    draft.targetShapes = 8 + static_cast<std::size_t>(rng.below(13));
    draft.clearance = uniformIn(rng, 0.1, 0.4);
    addRoomPlanes(draft);
    int index = 1;
    for (int attempt = 0; attempt < 80 && !draft.tryPlace(drawElbow(rng, room, index)); ++attempt) {}
    ++index;
    const bool sphereOnBox = draft.targetShapes - draft.layout.shapes.size() >= 7 && rng.uniform() < 0.5;
    for (int attempt = 0; attempt < 80; ++attempt)
        if (draft.tryPlace(sphereOnBox ? drawBox(rng, room, true, index) : drawFloorSphere(rng, room, index)))
            break;
    ++index;
    for (int attempt = 0; attempt < 80 && !draft.tryPlace(drawCone(rng, room, index)); ++attempt) {}
    for (int attempt = 0; attempt < 600 && draft.layout.shapes.size() < draft.targetShapes; ++attempt) {
        const double pick = rng.uniform();
        std::optional<Assembly> a;
        if (pick < 0.22)
            a = drawBox(rng, room, rng.uniform() < 0.2, index + 1);
        else if (pick < 0.45)
            a = drawTankOrColumn(rng, room, index + 1);
        else if (pick < 0.82)
            a = drawPipe(rng, room, index + 1);
        else if (pick < 0.94)
            a = drawElbow(rng, room, index + 1);
        else if (pick < 0.97)
            a = drawFloorSphere(rng, room, index + 1);
        else
            a = drawCone(rng, room, index + 1);
        if (draft.tryPlace(a))
            ++index;
    }
    const int stations = std::clamp(1 + static_cast<int>(room.length / 7.0) + static_cast<int>(rng.below(2)), 2, 5);
    placeStations(rng, draft, stations, windowHalfWidth);
    return draft.layout;
}

} // namespace scandiff::test::family::primitives
