// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Family "façade openings at survey spacing": a building façade scanned from
//! one levelled terrestrial station, for tools that outline planar segments
//! with their openings and vectorise the outlines (lines, arcs).
//!
//! The scene, as a surveyor meets it (Boulaassal 2010, seed 001):
//! - a plane wall face [0,W] x [0,H] in its wall frame (u along, v up, n out),
//!   at Lambert-93 or UTM coordinates, any heading, vertical or leaning <= 2°;
//! - openings cut through it: windows (holes) and doors (reaching the bottom
//!   edge: notches of the outline), rectangular or with a semicircular top;
//! - each opening is a prism through the wall: its reveals run back to the
//!   joinery plane `glassDepth` behind the face, where an opaque frame
//!   `frameWidth` wide lines the opening and glass fills the rest; glass
//!   returns a few echoes (`glassReturn`), some rays go through and return
//!   from the room (`interiorReturn`, `roomDepth` further back), the rest are
//!   lost. Doors carry an opaque leaf. So no point of the face's plane lies in
//!   an opening, but recessed points (reveals, frames, glass, room) do;
//! - small relief proud of the face (string courses between floors, sills
//!   under windows, <= 2.5 cm proud), which belongs to the wall;
//! - the ground in front (kept `groundStrip` metres out: 0.5-3 m, at most
//!   0.3 x the station distance), nothing beyond the wall's edges (sky,
//!   cropped neighbours);
//! - a TLS at `stationDistance` in front, 1.4-1.9 m above the base, sweeping
//!   vertical profiles with one angular step chosen so that the MEDIAN spacing
//!   on the face is `spacing` (coarser at the far corners, finer in front);
//!   Gaussian range noise along each ray; occlusion by whatever is nearer.
//!
//! Issue case (issueCase()): 20 x 10 m wall, 3 floors x 6 windows of
//! 1.5 x 1.5 m, spacing 2.6 cm, noise 5 mm, string courses and sills 2 cm proud,
//! glass 15 cm back. Family (drawFamily()): wall 8-30 m x 4-15 m, spacing
//! 5 mm-3 cm (log-uniform), noise 1-10 mm (log-uniform), 4-30 openings
//! laid out by floors (2.8-4 m) and bays (1-5 m), windows 0.6-2.5 m wide and
//! 0.8-2.5 m high, doors on the ground floor in half of the draws (0.9-2.5 m
//! wide, 2-2.5 m high), arched tops in about a quarter of the rows, relief in
//! most draws, glass 10-25 cm back, heading 0-360°, lean 0 or up to ±2°.
//! `scale` < 1 removes bays and floors (smaller wall, fewer openings, possibly
//! below the family's minima) until the ray count fits 6e6 * scale (at least
//! 1.5e5); only then, if still too many, is the spacing made coarser (<= 3 cm).
//!
//! Truth and scoring: every opening's 2D polygon in the wall frame (arcs
//! densified to < 0.1 mm), the wall outline (rectangle with door notches).
//! Rings returned by the tool (3D, global) are projected to the wall frame;
//! rings more than `planeTolerance` (RMS) off the face plane are set aside
//! (they outline recessed segments). The outer ring (largest, unless given)
//! is scored against the outline. A window is right when exactly one ring
//! has IoU >= 0.5 with it and that ring's symmetric boundary Hausdorff
//! distance is <= 3 cm. A door, being a notch, is scored on the outer ring:
//! its IoU is that of the door rectangle with the part of a zone around the
//! door (30 cm wider and higher) outside the outer ring, and its Hausdorff
//! distance is the symmetric one between the truth outline and the outer ring
//! restricted to that zone; a door returned as a closed hole is a wrong door
//! (the face does not continue under it) but not a false polygon. The caller
//! passes the rings of the face's segment (relief belongs to the face; rings
//! of recessed or perpendicular segments are set aside). A false polygon is
//! a non-outer ring on the face matching no window with IoU >= 0.5. Issue
//! target: every opening right and at most two false polygons.

#include "WallSurveyCommon.h"

#include <cstdint>
#include <string>
#include <vector>

namespace scandiff::test::family::facade {

// Using-declarations, not a using-directive: other families declare helpers
// of the same names (gaussian, kPi...) in scandiff::test::family, and names
// declared here are found first, so including several families stays unambiguous.
using wallsurvey::Box2;
using wallsurvey::boundaryHausdorff;
using wallsurvey::boxOf;
using wallsurvey::directedHausdorff;
using wallsurvey::drawProjectedCorner;
using wallsurvey::format;
using wallsurvey::gaussian;
using wallsurvey::kInf;
using wallsurvey::kPi;
using wallsurvey::logUniform;
using wallsurvey::makeCloud;
using wallsurvey::makeScanGrid;
using wallsurvey::makeWallFrame;
using wallsurvey::openRing;
using wallsurvey::Overlap;
using wallsurvey::Polygon2;
using wallsurvey::polygonArea;
using wallsurvey::polygonOverlap;
using wallsurvey::projectRing;
using wallsurvey::Ring3;
using wallsurvey::ScanGrid;
using wallsurvey::sensorPose;
using wallsurvey::uniform;
using wallsurvey::WallFrame;

//! An opening in wall 2D coordinates (m).
struct Opening
{
    double x0 = 0.0, y0 = 0.0;        //!< bottom-left corner; y0 = 0 for a door
    double width = 1.0, height = 1.0; //!< overall, the arch included
    bool arched = false;              //!< semicircular top of radius width / 2
    bool door = false;                //!< reaches the wall's bottom edge: a notch, not a hole

    double x1() const { return x0 + width; }
    double top() const { return y0 + height; }
    //! Where the arch springs (the top for a rectangle).
    double springY() const { return arched ? top() - 0.5 * width : top(); }
};

//! A band of relief proud of the face: the box [x0,x1] x [y0,y1] x [0, proud].
struct ReliefBand
{
    double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    double proud = 0.02; //!< m in front of the face
};

//! What a point lies on (truth, kept outside the cloud).
enum class Surface : std::uint8_t { WallFace, Relief, Reveal, Joinery, Glass, Interior, Ground };

struct FacadeParams
{
    double wallWidth = 20.0;  //!< m along u
    double wallHeight = 10.0; //!< m along v
    std::vector<Opening> openings;
    std::vector<ReliefBand> relief;
    double glassDepth = 0.15;     //!< m from the face back to the joinery/glass plane (depth of the reveals)
    double frameWidth = 0.06;     //!< m, opaque frame lining each window at the glass plane
    double glassReturn = 0.05;    //!< fraction of rays on glass returning from the glass
    double interiorReturn = 0.15; //!< fraction of rays on glass returning from the room behind
    double roomDepth = 4.0;       //!< m from the glass to the room's back wall
    double groundStrip = 2.0;     //!< m of ground in front of the face kept in the cloud

    double spacing = 0.026;        //!< median point spacing on the face (m)
    double rangeNoise = 0.005;     //!< standard deviation of the range along each ray (m)
    double stationDistance = 18.0; //!< horizontal distance of the scanner from the face (m)
    double stationAlong = 10.0;    //!< scanner position along u (m)
    double stationHeight = 1.6;    //!< scanner centre above the wall's base (m)

    double headingDeg = 37.0; //!< azimuth of u, counter-clockwise from east (deg)
    double tiltDeg = 0.0;     //!< lean of the face from vertical, + towards the scanner (deg)
    Eigen::Vector3d corner{681234.567, 6862345.678, 143.21}; //!< global bottom-left corner (Lambert-93, m)
    std::uint64_t seed = 1;   //!< noise and glass returns
};

struct FacadeScene
{
    FacadeParams params;
    WallFrame frame;                    //!< origin = bottom-left corner of the face
    PointCloud cloud;                   //!< the scan (global = origin + local), one sensor pose
    std::vector<Surface> surface;       //!< per point, what it lies on
    std::vector<Polygon2> openingTruth; //!< per params.openings entry, counter-clockwise, wall 2D
    Polygon2 outlineTruth;              //!< the face's outline (rectangle with door notches), counter-clockwise
    ScanGrid scanner;                   //!< in wall coordinates
};

// ------------------------------------------------------------- truth shapes

//! The opening's outline, counter-clockwise; an arch becomes `arcSegments` chords.
inline Polygon2 openingPolygon(const Opening& o, int arcSegments = 256)
{
    Polygon2 p{{o.x0, o.y0}, {o.x1(), o.y0}, {o.x1(), o.springY()}};
    if (o.arched) {
        const double r = 0.5 * o.width, cx = o.x0 + r;
        for (int k = 1; k < arcSegments; ++k) {
            const double a = kPi * k / arcSegments;
            p.emplace_back(cx + r * std::cos(a), o.springY() + r * std::sin(a));
        }
    } else {
        p.emplace_back(o.x1(), o.top());
        p.emplace_back(o.x0, o.top());
    }
    p.emplace_back(o.x0, o.springY());
    return p;
}

//! The face outline: the rectangle, each door cut in from the bottom edge.
inline Polygon2 outlinePolygon(const FacadeParams& p)
{
    std::vector<Opening> doors;
    for (const auto& o : p.openings)
        if (o.door)
            doors.push_back(o);
    std::sort(doors.begin(), doors.end(), [](const Opening& a, const Opening& b) { return a.x0 < b.x0; });
    Polygon2 out{{0.0, 0.0}};
    for (const auto& d : doors) { // the door's own outline, walked backwards, without its sill edge
        const Polygon2 hole = openingPolygon(d);
        out.push_back(hole.front());
        for (std::size_t k = hole.size() - 1; k >= 1; --k)
            out.push_back(hole[k]);
    }
    for (const Eigen::Vector2d& c : {Eigen::Vector2d(p.wallWidth, 0.0), Eigen::Vector2d(p.wallWidth, p.wallHeight),
                                     Eigen::Vector2d(0.0, p.wallHeight)})
        out.push_back(c);
    return openRing(std::move(out));
}

inline bool opensAt(const Opening& o, const Eigen::Vector2d& q)
{
    if (q.x() < o.x0 || q.x() > o.x1() || q.y() < o.y0)
        return false;
    if (q.y() <= o.springY())
        return true;
    return o.arched && (q - Eigen::Vector2d(o.x0 + 0.5 * o.width, o.springY())).norm() <= 0.5 * o.width;
}

//! Distance from q (inside the opening) to the opening's outline.
inline double depthInside(const Opening& o, const Eigen::Vector2d& q)
{
    if (o.arched && q.y() > o.springY())
        return 0.5 * o.width - (q - Eigen::Vector2d(o.x0 + 0.5 * o.width, o.springY())).norm();
    double d = std::min({q.x() - o.x0, o.x1() - q.x(), q.y() - o.y0});
    if (!o.arched)
        d = std::min(d, o.top() - q.y());
    return d;
}

//! How far (in units of e) the 2D ray p + s e, p inside the (convex) opening,
//! runs before leaving it: where the ray meets a reveal.
inline double exitParameter(const Opening& o, const Eigen::Vector2d& p, const Eigen::Vector2d& e)
{
    double s = kInf;
    if (e.x() > 0) s = std::min(s, (o.x1() - p.x()) / e.x());
    if (e.x() < 0) s = std::min(s, (o.x0 - p.x()) / e.x());
    if (e.y() < 0) s = std::min(s, (o.y0 - p.y()) / e.y());
    if (!o.arched) {
        if (e.y() > 0) s = std::min(s, (o.top() - p.y()) / e.y());
        return std::max(s, 0.0);
    }
    const double ys = o.springY(), r = 0.5 * o.width, a = e.squaredNorm();
    if (a < 1e-24)
        return std::max(s, 0.0);
    double s0 = 0.0;
    Eigen::Vector2d start = p;
    if (p.y() <= ys) { // the ray must first rise to the springing line
        if (e.y() <= 0 || (s0 = (ys - p.y()) / e.y()) >= s)
            return std::max(s, 0.0);
        start = p + s0 * e;
    }
    const Eigen::Vector2d f = start - Eigen::Vector2d(o.x0 + r, ys);
    const double b = 2.0 * f.dot(e), c = f.squaredNorm() - r * r;
    const double k = std::max(0.0, (-b + std::sqrt(std::max(0.0, b * b - 4 * a * c))) / (2 * a));
    if ((start + k * e).y() >= ys - 1e-12) // else it dropped back into the rectangle: linear bounds hold
        s = std::min(s, s0 + k);
    return std::max(s, 0.0);
}

//! Entry distance of the ray S + t d into a relief box (kInf if missed).
inline double boxEntry(const ReliefBand& b, const Eigen::Vector3d& s, const Eigen::Vector3d& d)
{
    const double lo[3] = {b.x0, b.y0, 0.0}, hi[3] = {b.x1, b.y1, b.proud};
    double tMin = 0.0, tMax = kInf;
    for (int k = 0; k < 3; ++k) {
        if (std::abs(d[k]) < 1e-15) {
            if (s[k] < lo[k] || s[k] > hi[k])
                return kInf;
            continue;
        }
        double t1 = (lo[k] - s[k]) / d[k], t2 = (hi[k] - s[k]) / d[k];
        if (t1 > t2)
            std::swap(t1, t2);
        tMin = std::max(tMin, t1), tMax = std::min(tMax, t2);
        if (tMin > tMax)
            return kInf;
    }
    return tMin > 0.0 ? tMin : kInf;
}

struct Hit
{
    double t = kInf;
    Surface surface = Surface::WallFace;
};

//! The first surface along one ray from the station (wall coordinates), or none.
inline bool castRay(const FacadeParams& p, const WallFrame& frame, const Eigen::Vector3d& s, const Eigen::Vector3d& d,
                    SplitMix64& rng, Hit& hit)
{
    hit = Hit{};
    auto offer = [&](double t, Surface what) {
        if (t < hit.t)
            hit.t = t, hit.surface = what;
    };
    for (const auto& band : p.relief)
        offer(boxEntry(band, s, d), Surface::Relief);
    if (d.z() < 0.0) {
        const double t0 = -s.z() / d.z();
        const Eigen::Vector2d q(s.x() + t0 * d.x(), s.y() + t0 * d.y());
        if (q.x() >= 0 && q.x() <= p.wallWidth && q.y() >= 0 && q.y() <= p.wallHeight && t0 < hit.t) {
            const Opening* in = nullptr;
            for (const auto& o : p.openings)
                if (opensAt(o, q))
                    in = &o;
            if (!in) {
                offer(t0, Surface::WallFace);
            } else {
                const Eigen::Vector2d e(d.x(), d.y());
                const double tGlass = p.glassDepth / -d.z(), tReveal = exitParameter(*in, q, e);
                if (tReveal < tGlass) {
                    offer(t0 + tReveal, Surface::Reveal);
                } else if (in->door || depthInside(*in, q + tGlass * e) < p.frameWidth) {
                    offer(t0 + tGlass, Surface::Joinery);
                } else {
                    const double draw = rng.uniform();
                    if (draw < p.glassReturn)
                        offer(t0 + tGlass, Surface::Glass);
                    else if (draw < p.glassReturn + p.interiorReturn)
                        offer(t0 + (p.glassDepth + p.roomDepth) / -d.z(), Surface::Interior);
                }
            }
        }
    }
    const Eigen::Vector3d up = frame.upInWall(), out = frame.outwardInWall();
    if (d.dot(up) < 0.0) { // level ground through the wall's base line, kept on a strip in front
        const double t = -s.dot(up) / d.dot(up);
        const Eigen::Vector3d g = s + t * d;
        if (g.dot(out) >= 0.0 && g.dot(out) <= p.groundStrip && g.x() >= -0.5 && g.x() <= p.wallWidth + 0.5)
            offer(t, Surface::Ground);
    }
    return hit.t < kInf;
}

inline Eigen::Vector3d stationInWall(const FacadeParams& p, const WallFrame& frame)
{
    return Eigen::Vector3d(p.stationAlong, 0, 0) + p.stationHeight * frame.upInWall() + p.stationDistance * frame.outwardInWall();
}

inline ScanGrid scanGridFor(const FacadeParams& p, const WallFrame& frame)
{
    const Eigen::Vector3d out = frame.outwardInWall();
    std::vector<Eigen::Vector3d> ground;
    for (double x : {0.0, 0.5 * p.wallWidth, p.wallWidth})
        ground.push_back(Eigen::Vector3d(x, 0, 0) + std::min(p.groundStrip, 0.9 * p.stationDistance) * out);
    return makeScanGrid(frame, stationInWall(p, frame), 0.0, p.wallWidth, 0.0, p.wallHeight, p.spacing, ground);
}

inline FacadeScene make(const FacadeParams& p)
{
    FacadeScene scene;
    scene.params = p;
    scene.frame = makeWallFrame(p.corner, p.headingDeg, p.tiltDeg);
    for (const auto& o : p.openings)
        scene.openingTruth.push_back(openingPolygon(o));
    scene.outlineTruth = outlinePolygon(p);
    scene.scanner = scanGridFor(p, scene.frame);
    const Eigen::Vector3d s = scene.scanner.position;
    std::vector<Eigen::Vector3d> global;
    scene.scanner.sweep([&](const Eigen::Vector3d& d, std::size_t ray) {
        SplitMix64 rng(p.seed, ray); // per ray: reproducible whatever the sweep order
        Hit hit;
        if (!castRay(p, scene.frame, s, d, rng, hit))
            return;
        const double range = hit.t + p.rangeNoise * gaussian(rng);
        global.push_back(scene.frame.toGlobal(s + range * d));
        scene.surface.push_back(hit.surface);
    });
    scene.cloud = makeCloud(global, "facade");
    scene.cloud.sensors().push_back(sensorPose(scene.frame, scene.scanner));
    return scene;
}

// ------------------------------------------------------------------- params

inline std::string describe(const FacadeParams& p)
{
    int doors = 0, arches = 0;
    for (const auto& o : p.openings)
        doors += o.door, arches += o.arched;
    return format("facade %.1fx%.1f m, ", p.wallWidth, p.wallHeight) + std::to_string(p.openings.size()) +
           " openings (" + std::to_string(doors) + " doors, " + std::to_string(arches) + " arched), " +
           std::to_string(p.relief.size()) + " relief bands, " +
           format("spacing %.1f mm, noise %.1f mm, glass %.0f cm back, station %.1f m, heading %.0f deg, tilt %.2f deg, seed ",
                  p.spacing * 1e3, p.rangeNoise * 1e3, p.glassDepth * 100, p.stationDistance, p.headingDeg, p.tiltDeg) +
           std::to_string(p.seed);
}

//! 20 x 10 m, 3 rows of 6 windows 1.5 x 1.5 m, 2.6 cm spacing, 5 mm noise.
inline FacadeParams issueCase()
{
    FacadeParams p;
    const double floorHeight = 10.0 / 3.0, bay = 20.0 / 6.0;
    for (int f = 0; f < 3; ++f) {
        for (int b = 0; b < 6; ++b) {
            Opening o;
            o.width = o.height = 1.5;
            o.x0 = b * bay + 0.5 * (bay - o.width);
            o.y0 = f * floorHeight + 0.9;
            p.openings.push_back(o);
            p.relief.push_back({o.x0 - 0.05, o.y0 - 0.07, o.x1() + 0.05, o.y0, 0.02}); // sill
        }
        if (f > 0)
            p.relief.push_back({0.0, f * floorHeight - 0.1, p.wallWidth, f * floorHeight + 0.1, 0.02}); // string course
    }
    return p;
}

struct Layout
{
    int floors = 1, bays = 1;
    double floorHeight = 3.0, bay = 3.0, attic = 0.0;
};

//! Openings and relief for a layout, from its own stream of draws.
inline void drawOpenings(FacadeParams& p, const Layout& l, SplitMix64& rng)
{
    p.openings.clear(), p.relief.clear();
    const bool hasDoors = rng.uniform() < 0.5, stringCourses = rng.uniform() < 0.6, sills = rng.uniform() < 0.5;
    const double proud = uniform(rng, 0.01, 0.025);
    const int doorCount = hasDoors ? std::max(1, std::min(l.bays / 2, 1 + static_cast<int>(rng.below(2)))) : 0;
    std::vector<int> doorBays;
    while (static_cast<int>(doorBays.size()) < doorCount) {
        const int b = static_cast<int>(rng.below(static_cast<std::uint64_t>(l.bays)));
        if (std::find(doorBays.begin(), doorBays.end(), b) == doorBays.end())
            doorBays.push_back(b);
    }
    for (int f = 0; f < l.floors; ++f) {
        const double base = f * l.floorHeight;
        const double w = uniform(rng, 0.6, std::min(2.5, l.bay - 0.4));
        const double h = uniform(rng, 0.8, std::min(2.5, l.floorHeight - 0.6));
        const double sill = uniform(rng, 0.3, l.floorHeight - h - 0.3);
        const bool arched = rng.uniform() < 0.25 && h - 0.5 * w >= 0.3;
        for (int b = 0; b < l.bays; ++b) {
            Opening o;
            const bool door = f == 0 && std::find(doorBays.begin(), doorBays.end(), b) != doorBays.end();
            const double doorMax = std::min(2.5, l.bay - 0.4);
            o.width = door ? uniform(rng, std::min(0.9, doorMax), doorMax) : w;
            o.height = door ? uniform(rng, 2.0, std::min(2.5, l.floorHeight - 0.3)) : h;
            o.door = door;
            o.arched = door ? (rng.uniform() < 0.3 && o.height - 0.5 * o.width >= 1.6) : arched;
            const double slack = std::max(0.0, std::min(0.1, 0.5 * (l.bay - o.width) - 0.2));
            o.x0 = b * l.bay + 0.5 * (l.bay - o.width) + uniform(rng, -slack, slack); // not a perfect grid
            o.y0 = door ? 0.0 : base + sill;
            p.openings.push_back(o);
            if (sills && !door)
                p.relief.push_back({o.x0 - 0.05, o.y0 - 0.07, o.x1() + 0.05, o.y0, proud});
        }
        if (stringCourses && f > 0) {
            const double half = uniform(rng, 0.06, 0.14);
            p.relief.push_back({0.0, base - half, p.wallWidth, base + half, proud});
        }
    }
}

inline double rayCount(const FacadeParams& p)
{
    const ScanGrid g = scanGridFor(p, makeWallFrame(p.corner, p.headingDeg, p.tiltDeg));
    return static_cast<double>(g.columns()) * static_cast<double>(g.rows());
}

//! A façade drawn over the ranges real surveys span; see the file comment.
inline FacadeParams drawFamily(std::uint64_t seed, double scale)
{
    SplitMix64 rng(seed, 0xFACADE);
    FacadeParams p;
    p.seed = seed;
    p.spacing = logUniform(rng, 0.005, 0.03);
    p.rangeNoise = logUniform(rng, 0.001, 0.01);
    p.headingDeg = uniform(rng, 0.0, 360.0);
    p.tiltDeg = rng.uniform() < 0.5 ? 0.0 : uniform(rng, -2.0, 2.0);
    p.corner = drawProjectedCorner(rng);
    p.glassDepth = uniform(rng, 0.10, 0.25);
    p.frameWidth = uniform(rng, 0.04, 0.09);
    p.glassReturn = uniform(rng, 0.0, 0.10);
    p.interiorReturn = uniform(rng, 0.0, 0.30);
    p.roomDepth = uniform(rng, 2.5, 7.0);
    p.groundStrip = uniform(rng, 0.5, 3.0);
    p.stationHeight = uniform(rng, 1.4, 1.9);
    const double fullWidth = uniform(rng, 8.0, 30.0), fullHeight = uniform(rng, 4.0, 15.0);
    Layout l;
    // whole floors of 2.8-4 m; what a whole number of floors leaves is an attic band
    l.floors = std::max(1, static_cast<int>(std::lround(fullHeight / uniform(rng, 2.8, 4.0))));
    l.floorHeight = std::clamp(fullHeight / l.floors, 2.8, 4.0);
    // bays of 1-5 m (a window every 1-5 m, as on real façades), 4-30 openings in all
    const int minBays = std::max((4 + l.floors - 1) / l.floors, static_cast<int>(std::ceil(fullWidth / 5.0)));
    const int maxBays = std::max(minBays, std::min(30 / l.floors, static_cast<int>(std::floor(fullWidth / 1.0))));
    l.bays = minBays + static_cast<int>(rng.below(static_cast<std::uint64_t>(maxBays - minBays + 1)));
    l.bay = fullWidth / l.bays;
    l.attic = std::max(0.0, fullHeight - l.floors * l.floorHeight);
    const double distanceFactor = uniform(rng, 0.7, 1.3), alongFactor = uniform(rng, -0.25, 0.25);
    const std::uint64_t layoutSeed = rng.next();
    const double budget = std::max(1.5e5, 6e6 * scale);
    for (;;) { // fewer bays, then fewer floors, until the scan fits the budget
        p.wallWidth = l.bays * l.bay;
        p.wallHeight = l.floors * l.floorHeight + l.attic;
        p.stationDistance = std::max(4.0, distanceFactor * std::max(p.wallWidth, 1.2 * p.wallHeight));
        p.stationAlong = p.wallWidth * (0.5 + alongFactor);
        if (rayCount(p) <= budget || (l.bays <= 2 && l.floors <= 1))
            break;
        if (l.bays > 2 && (l.bays >= 2 * l.floors || l.floors == 1))
            --l.bays;
        else if (l.floors > 1)
            --l.floors, l.attic = std::min(l.attic, 0.5);
        else
            --l.bays;
    }
    p.groundStrip = std::min(p.groundStrip, 0.3 * p.stationDistance); // a close station: ground would swamp the face
    const double rays = rayCount(p);
    if (rays > budget)
        p.spacing = std::min(0.03, p.spacing * std::sqrt(rays / budget));
    SplitMix64 layoutRng(layoutSeed, 1);
    drawOpenings(p, l, layoutRng);
    return p;
}

// ------------------------------------------------------------------ scoring

struct OpeningScore
{
    int ring = -1;                //!< best ring (for a door: the outer ring)
    double iou = 0.0;             //!< best IoU with the truth
    double hausdorff = kInf;      //!< symmetric boundary Hausdorff distance (m); doors: within the door's zone
    std::size_t vertices = 0;     //!< vertex count of that ring
    int ringsMatching = 0;        //!< rings with IoU >= matchIoU (1 = one closed polygon)
    bool right = false;
};

struct FacadeScore
{
    std::vector<OpeningScore> openings; //!< per params.openings entry
    OpeningScore outline;               //!< the outer ring against the outline truth
    int falsePolygons = 0;              //!< on-face rings, outer excluded, matching no window
    int offPlaneRings = 0;              //!< rings set aside as not on the face
    int doorsAsHoles = 0;               //!< rings matching a door (IoU >= matchIoU): not false, but the door
                                        //!< still counts as wrong unless the outer ring has its notch
    int openingsRight = 0;
    double worstHausdorff = 0.0;        //!< over the openings
    double meanIoU = 0.0;               //!< over the openings
    bool meetsIssueTarget = false;      //!< every opening right and <= maxFalsePolygons
    std::string summary() const
    {
        return std::to_string(openingsRight) + "/" + std::to_string(openings.size()) + " openings right, " +
               std::to_string(falsePolygons) + " false polygons, " + std::to_string(offPlaneRings) + " off-plane rings, " +
               std::to_string(doorsAsHoles) + " doors as holes, " +
               format("worst Hausdorff %.1f mm, mean IoU %.4f, outline IoU %.4f Hausdorff %.1f mm", worstHausdorff * 1e3,
                      meanIoU, outline.iou, outline.hausdorff * 1e3);
    }
};

struct ScoreOptions
{
    double hausdorffTolerance = 0.03; //!< m
    double matchIoU = 0.5;            //!< a ring matches a window from this IoU on
    double planeTolerance = 0.05;     //!< m, RMS offset from the face beyond which a ring is set aside
    double doorZoneMargin = 0.3;      //!< m, the zone around a door scored on the outer ring
    int outerRing = -1;               //!< index of the outer ring; -1: the largest on-face ring
    int maxFalsePolygons = 2;
};

//! Scores a door against the outer ring (see the file comment).
inline OpeningScore scoreDoor(const FacadeScene& scene, const Opening& door, const Polygon2& outer, int outerIndex,
                              double margin)
{
    OpeningScore s;
    s.ring = outerIndex;
    s.vertices = outer.size();
    const Polygon2 doorPoly = openingPolygon(door);
    const double zx0 = door.x0 - margin, zx1 = door.x1() + margin, ztop = door.top() + margin;
    const Polygon2 zone{{zx0, 0.0}, {zx1, 0.0}, {zx1, ztop}, {zx0, ztop}};
    const Overlap door_ = polygonOverlap(doorPoly, outer), zone_ = polygonOverlap(zone, outer);
    const double inter = door_.areaA - door_.intersection, notch = zone_.areaA - zone_.intersection;
    s.iou = std::clamp(inter / std::max(1e-12, door_.areaA + notch - inter), 0.0, 1.0);
    Box2 box;
    box.add({zx0, -margin}), box.add({zx1, ztop});
    s.hausdorff = std::max(directedHausdorff(scene.outlineTruth, outer, &box),
                           directedHausdorff(outer, scene.outlineTruth, &box));
    s.ringsMatching = 1;
    return s;
}

//! Scores rings (3D, global coordinates, closed implicitly) from the tool.
inline FacadeScore score(const FacadeScene& scene, const std::vector<Ring3>& rings, const ScoreOptions& opt = {})
{
    FacadeScore out;
    std::vector<Polygon2> flat(rings.size());
    std::vector<bool> onFace(rings.size(), false);
    int outer = opt.outerRing;
    double outerArea = -1.0;
    for (std::size_t i = 0; i < rings.size(); ++i) {
        double rms = 0.0;
        flat[i] = projectRing(scene.frame, rings[i], &rms);
        onFace[i] = rms <= opt.planeTolerance && flat[i].size() >= 3;
        out.offPlaneRings += !onFace[i];
        if (opt.outerRing < 0 && onFace[i] && polygonArea(flat[i]) > outerArea)
            outerArea = polygonArea(flat[i]), outer = static_cast<int>(i);
    }
    if (outer >= 0) {
        out.outline.ring = outer;
        out.outline.iou = polygonOverlap(flat[outer], scene.outlineTruth).iou();
        out.outline.hausdorff = boundaryHausdorff(flat[outer], scene.outlineTruth);
        out.outline.vertices = flat[outer].size();
    }
    std::vector<bool> matched(rings.size(), false);
    double iouSum = 0.0;
    for (std::size_t k = 0; k < scene.params.openings.size(); ++k) {
        const Opening& o = scene.params.openings[k];
        OpeningScore s;
        if (o.door) {
            if (outer >= 0)
                s = scoreDoor(scene, o, flat[outer], outer, opt.doorZoneMargin);
        } else {
            const Polygon2& truth = scene.openingTruth[k];
            const Box2 tb = boxOf(truth);
            for (std::size_t i = 0; i < rings.size(); ++i) {
                if (!onFace[i] || static_cast<int>(i) == outer || !boxOf(flat[i]).overlaps(tb))
                    continue;
                const double iou = polygonOverlap(flat[i], truth).iou();
                if (iou >= opt.matchIoU)
                    ++s.ringsMatching, matched[i] = true;
                if (iou > s.iou)
                    s.iou = iou, s.ring = static_cast<int>(i);
            }
            if (s.ring >= 0) {
                s.hausdorff = boundaryHausdorff(flat[s.ring], truth);
                s.vertices = flat[s.ring].size();
            }
            s.right = s.ringsMatching == 1 && s.iou >= opt.matchIoU;
        }
        if (o.door)
            s.right = s.iou >= opt.matchIoU;
        s.right = s.right && s.hausdorff <= opt.hausdorffTolerance;
        out.openingsRight += s.right;
        out.worstHausdorff = std::max(out.worstHausdorff, s.hausdorff);
        iouSum += s.iou;
        out.openings.push_back(s);
    }
    for (std::size_t k = 0; k < scene.params.openings.size(); ++k) { // a door closed into a hole
        if (!scene.params.openings[k].door)
            continue;
        for (std::size_t i = 0; i < rings.size(); ++i)
            if (onFace[i] && static_cast<int>(i) != outer && !matched[i] &&
                polygonOverlap(flat[i], scene.openingTruth[k]).iou() >= opt.matchIoU)
                matched[i] = true, ++out.doorsAsHoles;
    }
    for (std::size_t i = 0; i < rings.size(); ++i)
        out.falsePolygons += onFace[i] && static_cast<int>(i) != outer && !matched[i];
    out.meanIoU = out.openings.empty() ? 1.0 : iouSum / out.openings.size();
    out.meetsIssueTarget =
        out.openingsRight == static_cast<int>(out.openings.size()) && out.falsePolygons <= opt.maxFalsePolygons;
    return out;
}

//! The truth as rings a perfect tool would return (3D, global): the outline
//! first, then each window; a check that scoring gives full marks.
inline std::vector<Ring3> truthRings(const FacadeScene& scene)
{
    auto lift = [&](const Polygon2& p) {
        Ring3 r;
        for (const auto& q : p)
            r.push_back(scene.frame.toGlobal({q.x(), q.y(), 0.0}));
        return r;
    };
    std::vector<Ring3> rings{lift(scene.outlineTruth)};
    for (std::size_t k = 0; k < scene.params.openings.size(); ++k)
        if (!scene.params.openings[k].door)
            rings.push_back(lift(scene.openingTruth[k]));
    return rings;
}

} // namespace scandiff::test::family::facade
