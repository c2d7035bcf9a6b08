// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The hall of family A (StationsFamily.h): its parameters, the solids it is
//! made of (structure laid out from the parameters, clutter laid out from a
//! seed clear of the stations and doors, objects moved between scans), the
//! station poses, and what each station can see of it (coverage, overlap of
//! two stations), computed from surface samples by ray casting.
//!
//! Independent of the code under test: only the data-model headers are used.

#include "TlsRayCast.h"

#include <scandiff/core/SplitMix.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace scandiff::test::family::stations {

using namespace tls;

//! An opening in an outer wall. Walls: 0 = south (y = 0), 1 = east (x = L),
//! 2 = north (y = W), 3 = west (x = 0); `along` is measured along x for
//! walls 0 and 2, along y for walls 1 and 3 (metres).
struct HallOpening
{
    int wall = 0;
    double along = 0.0;  //!< centre of the opening along its wall (m)
    double width = 1.0;  //!< m
    double bottom = 0.0; //!< sill height (m, 0 for a door)
    double top = 2.1;    //!< head height (m)
};

//! One scanner set-up, in the hall frame (x along the length, y across, z up, floor z = 0).
struct StationSetup
{
    Eigen::Vector2d position = Eigen::Vector2d::Zero(); //!< tripod position on the floor (m)
    double height = 1.6;                                //!< scanner centre above the floor (m)
    double headingDeg = 0.0;       //!< rotation of the scanner frame about the vertical (deg)
    double tiltDeg = 0.0;          //!< residual levelling error (deg), 0 = perfectly levelled
    double tiltAzimuthDeg = 0.0;   //!< horizontal axis the tilt turns about (deg)
};

struct StationsParams
{
    // Hall (hall frame, metres).
    double hallLength = 40.0, hallWidth = 20.0, hallHeight = 8.0; //!< inner dimensions
    double wallThickness = 0.3;
    std::vector<HallOpening> openings;
    double columnSpacing = 6.5; //!< along x; columns at k * spacing, k >= 1, up to L - spacing / 2
    int columnRows = 2;         //!< rows of columns across the hall (evenly spaced)
    double columnSize = 0.5;    //!< side (square) or diameter (round), m
    bool roundColumns = false;
    double beamDepth = 0.7;     //!< roof beams across the hall above each column line (m)
    // Interior partition across the hall at x = partitionX (none if height <= 0).
    double partitionX = 22.5, partitionHeight = 5.0, partitionThickness = 0.2;
    double partitionDoorCentreY = 14.0, partitionDoorWidth = 5.0, partitionDoorHeight = 4.5;
    // Clutter, laid out from clutterSeed, clear of stations, doors and each other.
    int racks = 3, machines = 4, tanks = 1, palletStacks = 8;
    int movingObjects = 0; //!< objects placed elsewhere for every station (moved between scans)
    std::uint64_t clutterSeed = 1;
    // Stations and scanner.
    std::vector<StationSetup> stations;
    double angularStepDeg = 0.42; //!< same step in yaw and pitch (deg)
    double pitchMinDeg = -60.0, pitchMaxDeg = 90.0;
    double minRange = 0.6, maxRange = 60.0; //!< m
    double rangeNoise = 0.002;             //!< standard deviation along the ray (m)
    // World frame: world = Rz(hallAzimuth) * hall + worldOffset.
    Eigen::Vector3d worldOffset = Eigen::Vector3d::Zero();
    double hallAzimuthDeg = 0.0;
    std::uint64_t seed = 1; //!< range noise
};

enum StationsTag : int { TagFloor = 1, TagRoof, TagWall, TagColumn, TagBeam, TagPartition, TagClutter, TagMover };

namespace detail {

//! A solid's footprint on the floor, for laying out clutter without overlaps.
struct Footprint
{
    Eigen::Vector2d centre;
    Eigen::Vector2d half;
    double yaw = 0.0;
};

inline Footprint footprintOf(const Solid& s)
{
    return {s.centre.head<2>(), s.halfSize.head<2>(), s.kind == Solid::Kind::Box ? s.yaw : 0.0};
}

//! Separating-axis test between two turned rectangles grown by `clearance`.
inline bool footprintsOverlap(const Footprint& a, const Footprint& b, double clearance)
{
    const Eigen::Vector2d axes[4] = {{std::cos(a.yaw), std::sin(a.yaw)}, {-std::sin(a.yaw), std::cos(a.yaw)},
                                     {std::cos(b.yaw), std::sin(b.yaw)}, {-std::sin(b.yaw), std::cos(b.yaw)}};
    const Eigen::Vector2d d = b.centre - a.centre;
    for (const Eigen::Vector2d& n : axes) {
        const double ra = a.half.x() * std::abs(n.dot(axes[0])) + a.half.y() * std::abs(n.dot(axes[1]));
        const double rb = b.half.x() * std::abs(n.dot(axes[2])) + b.half.y() * std::abs(n.dot(axes[3]));
        if (std::abs(d.dot(n)) > ra + rb + clearance)
            return false;
    }
    return true;
}

//! The boxes of one outer wall: piers between openings, sills under windows, lintels over openings.
inline void addWall(const StationsParams& p, int wall, std::vector<Solid>& out)
{
    const double t = p.wallThickness, H = p.hallHeight;
    const bool alongX = (wall % 2 == 0);
    const double uStart = alongX ? -t : 0.0, uEnd = alongX ? p.hallLength + t : p.hallWidth;
    std::vector<HallOpening> ops;
    for (const HallOpening& o : p.openings)
        if (o.wall == wall)
            ops.push_back(o);
    std::sort(ops.begin(), ops.end(), [](const HallOpening& a, const HallOpening& b) { return a.along < b.along; });
    auto piece = [&](double u0, double u1, double z0, double z1) {
        if (u1 - u0 < 1e-6 || z1 - z0 < 1e-6)
            return;
        double w0, w1; // across the wall
        switch (wall) {
        case 0: w0 = -t, w1 = 0.0; break;
        case 1: w0 = p.hallLength, w1 = p.hallLength + t; break;
        case 2: w0 = p.hallWidth, w1 = p.hallWidth + t; break;
        default: w0 = -t, w1 = 0.0; break;
        }
        if (alongX)
            out.push_back(Solid::box({u0, w0, z0}, {u1, w1, z1}, TagWall));
        else
            out.push_back(Solid::box({w0, u0, z0}, {w1, u1, z1}, TagWall));
    };
    double cursor = uStart;
    for (const HallOpening& o : ops) {
        const double a = o.along - 0.5 * o.width, b = o.along + 0.5 * o.width;
        piece(cursor, a, 0.0, H);
        piece(a, b, 0.0, o.bottom);
        piece(a, b, o.top, H);
        cursor = b;
    }
    piece(cursor, uEnd, 0.0, H);
}

//! Floor (extended outside as ground), roof, walls, columns, beams, partition.
inline std::vector<Solid> structure(const StationsParams& p)
{
    const double L = p.hallLength, W = p.hallWidth, H = p.hallHeight, t = p.wallThickness;
    std::vector<Solid> s;
    s.push_back(Solid::box({-100.0, -100.0, -0.3}, {L + 100.0, W + 100.0, 0.0}, TagFloor));
    s.push_back(Solid::box({-t, -t, H}, {L + t, W + t, H + 0.3}, TagRoof));
    for (int wall = 0; wall < 4; ++wall)
        addWall(p, wall, s);
    const double columnTop = H - p.beamDepth;
    for (double x = p.columnSpacing; x <= L - 0.5 * p.columnSpacing + 1e-9; x += p.columnSpacing) {
        s.push_back(Solid::box({x - 0.15, 0.0, columnTop}, {x + 0.15, W, H}, TagBeam));
        for (int r = 1; r <= p.columnRows; ++r) {
            const double y = W * r / (p.columnRows + 1), h = 0.5 * p.columnSize;
            if (p.roundColumns)
                s.push_back(Solid::cylinder(x, y, h, 0.0, columnTop, TagColumn));
            else
                s.push_back(Solid::box({x - h, y - h, 0.0}, {x + h, y + h, columnTop}, TagColumn));
        }
    }
    if (p.partitionHeight > 0) {
        const double x0 = p.partitionX - 0.5 * p.partitionThickness, x1 = x0 + p.partitionThickness;
        const double d0 = p.partitionDoorCentreY - 0.5 * p.partitionDoorWidth, d1 = d0 + p.partitionDoorWidth;
        s.push_back(Solid::box({x0, 0.0, 0.0}, {x1, d0, p.partitionHeight}, TagPartition));
        s.push_back(Solid::box({x0, d1, 0.0}, {x1, W, p.partitionHeight}, TagPartition));
        if (p.partitionDoorHeight < p.partitionHeight)
            s.push_back(Solid::box({x0, d0, p.partitionDoorHeight}, {x1, d1, p.partitionHeight}, TagPartition));
    }
    return s;
}

//! Areas clutter must leave free: around each station, in front of every door.
inline std::vector<Footprint> keepOuts(const StationsParams& p)
{
    std::vector<Footprint> k;
    for (const StationSetup& st : p.stations)
        k.push_back({st.position, {0.9, 0.9}, 0.0});
    for (const HallOpening& o : p.openings) {
        if (o.bottom > 0.5)
            continue; // windows need no aisle
        const double depth = 3.0, half = 0.5 * o.width + 0.5;
        switch (o.wall) {
        case 0: k.push_back({{o.along, 0.5 * depth}, {half, 0.5 * depth}, 0.0}); break;
        case 1: k.push_back({{p.hallLength - 0.5 * depth, o.along}, {0.5 * depth, half}, 0.0}); break;
        case 2: k.push_back({{o.along, p.hallWidth - 0.5 * depth}, {half, 0.5 * depth}, 0.0}); break;
        default: k.push_back({{0.5 * depth, o.along}, {0.5 * depth, half}, 0.0}); break;
        }
    }
    if (p.partitionHeight > 0)
        k.push_back({{p.partitionX, p.partitionDoorCentreY}, {3.0, 0.5 * p.partitionDoorWidth + 0.3}, 0.0});
    return k;
}

//! Tries to put a footprint of half extents `half` somewhere free; returns false after many failures.
inline bool findFreeSpot(const StationsParams& p, SplitMix64& rng, const Eigen::Vector2d& half, bool axisAligned,
                         double wallGap, const std::vector<Footprint>& taken, Footprint& out)
{
    for (int attempt = 0; attempt < 300; ++attempt) {
        Footprint f;
        f.half = half;
        f.yaw = axisAligned ? (rng.uniform() < 0.5 ? 0.0 : 0.5 * kPi) : uniformIn(rng, 0.0, kPi);
        const double ex = std::abs(half.x() * std::cos(f.yaw)) + std::abs(half.y() * std::sin(f.yaw));
        const double ey = std::abs(half.x() * std::sin(f.yaw)) + std::abs(half.y() * std::cos(f.yaw));
        if (2 * (ex + wallGap) >= p.hallLength || 2 * (ey + wallGap) >= p.hallWidth)
            return false;
        f.centre = {uniformIn(rng, ex + wallGap, p.hallLength - ex - wallGap), uniformIn(rng, ey + wallGap, p.hallWidth - ey - wallGap)};
        bool ok = true;
        for (const Footprint& t : taken)
            if (footprintsOverlap(f, t, 0.8)) { // 0.8 m aisles
                ok = false;
                break;
            }
        if (ok) {
            out = f;
            return true;
        }
    }
    return false;
}

//! Racks, machines, tanks and pallet stacks, laid out from clutterSeed.
inline void addClutter(const StationsParams& p, std::vector<Solid>& s)
{
    std::vector<Footprint> taken = keepOuts(p);
    for (const Solid& solid : s)
        if (solid.tag == TagColumn || solid.tag == TagPartition)
            taken.push_back(footprintOf(solid));
    SplitMix64 rng(p.clutterSeed, 0xC1u);
    const double maxTop = p.hallHeight - p.beamDepth - 0.5;
    Footprint f;
    for (int i = 0; i < p.racks; ++i) // pallet racking full of goods: long, deep 1.1 m, tall
        if (findFreeSpot(p, rng, {uniformIn(rng, 2.5, 6.0), 0.55}, true, 0.1, taken, f)) {
            const double h = std::min(uniformIn(rng, 2.5, 5.5), maxTop);
            s.push_back(Solid::turnedBox({f.centre.x(), f.centre.y(), 0.5 * h}, {f.half.x(), f.half.y(), 0.5 * h}, f.yaw, TagClutter));
            taken.push_back(f);
        }
    for (int i = 0; i < p.machines; ++i) // a machine body and its control cabinet
        if (findFreeSpot(p, rng, {uniformIn(rng, 0.8, 2.2), uniformIn(rng, 0.5, 1.5)}, false, 0.6, taken, f)) {
            const double h = std::min(uniformIn(rng, 1.0, 2.5), maxTop);
            s.push_back(Solid::turnedBox({f.centre.x(), f.centre.y(), 0.5 * h}, {f.half.x(), f.half.y(), 0.5 * h}, f.yaw, TagClutter));
            const Eigen::Vector2d ax(std::cos(f.yaw), std::sin(f.yaw));
            const Eigen::Vector2d c = f.centre + ax * (0.5 * f.half.x());
            const double hc = std::min(0.8, maxTop - h);
            if (hc > 0.1)
                s.push_back(Solid::turnedBox({c.x(), c.y(), h + 0.5 * hc}, {0.3, 0.4, 0.5 * hc}, f.yaw, TagClutter));
            taken.push_back(f);
        }
    for (int i = 0; i < p.tanks; ++i) {
        const double r = uniformIn(rng, 0.6, 1.5);
        if (findFreeSpot(p, rng, {r, r}, true, 0.5, taken, f)) {
            s.push_back(Solid::cylinder(f.centre.x(), f.centre.y(), r, 0.0, std::min(uniformIn(rng, 2.0, 5.0), maxTop), TagClutter));
            taken.push_back(f);
        }
    }
    for (int i = 0; i < p.palletStacks; ++i)
        if (findFreeSpot(p, rng, {0.6, 0.4}, false, 0.3, taken, f)) {
            const double h = std::min(uniformIn(rng, 0.8, 2.0), maxTop);
            s.push_back(Solid::turnedBox({f.centre.x(), f.centre.y(), 0.5 * h}, {f.half.x(), f.half.y(), 0.5 * h}, f.yaw, TagClutter));
            taken.push_back(f);
        }
}

//! The objects that moved between scans, where they stood during station `station`.
inline void addMovers(const StationsParams& p, std::size_t station, std::vector<Solid>& s)
{
    std::vector<Footprint> taken = keepOuts(p);
    for (const Solid& solid : s)
        if (solid.tag == TagColumn || solid.tag == TagPartition || solid.tag == TagClutter)
            taken.push_back(footprintOf(solid));
    for (int m = 0; m < p.movingObjects; ++m) {
        SplitMix64 rng(p.clutterSeed ^ 0x5EEDu, 1000u * static_cast<std::uint64_t>(m) + station);
        Footprint f;
        const Eigen::Vector2d half = m % 2 == 0 ? Eigen::Vector2d(1.3, 0.6) : Eigen::Vector2d(0.6, 0.4); // forklift, pallet
        if (findFreeSpot(p, rng, half, false, 0.5, taken, f)) {
            const double h = m % 2 == 0 ? 2.2 : 1.4;
            s.push_back(Solid::turnedBox({f.centre.x(), f.centre.y(), 0.5 * h}, {f.half.x(), f.half.y(), 0.5 * h}, f.yaw, TagMover));
        }
    }
}

} // namespace detail

//! Every solid of the hall as it stood while station `station` scanned.
inline std::vector<Solid> hallSolids(const StationsParams& p, std::size_t station)
{
    std::vector<Solid> s = detail::structure(p);
    detail::addClutter(p, s);
    detail::addMovers(p, station, s);
    return s;
}

//! Station -> hall frame.
inline Eigen::Matrix4d stationPoseInHall(const StationsParams& p, std::size_t i)
{
    const StationSetup& st = p.stations[i];
    const double az = degToRad(st.tiltAzimuthDeg);
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(degToRad(st.tiltDeg), Eigen::Vector3d(std::cos(az), std::sin(az), 0.0)).toRotationMatrix();
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = tilt * rotationZ(degToRad(st.headingDeg));
    m.topRightCorner<3, 1>() = Eigen::Vector3d(st.position.x(), st.position.y(), st.height);
    return m;
}

//! Hall frame -> world frame.
inline Eigen::Matrix4d hallToWorld(const StationsParams& p)
{
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = rotationZ(degToRad(p.hallAzimuthDeg));
    m.topRightCorner<3, 1>() = p.worldOffset;
    return m;
}

//! Surface samples of the hall's inside (floor, roof underside, walls,
//! columns, partition, clutter), each with its outward normal and area.
struct SurfaceSample
{
    Eigen::Vector3d position, normal;
    double area;
    bool building = true; //!< floor, roof, walls, columns, beams, partition (false: clutter)
};

namespace detail {

inline bool insideHall(const StationsParams& p, const Eigen::Vector3d& q)
{
    return q.x() > 0 && q.x() < p.hallLength && q.y() > 0 && q.y() < p.hallWidth && q.z() > 0 && q.z() < p.hallHeight;
}

//! Grid samples of a rectangle centre + u * a + v * b, |u|, |v| <= 1.
inline void sampleRectangle(const Eigen::Vector3d& centre, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& normal, double cell, std::vector<SurfaceSample>& out)
{
    const int na = std::max(1, static_cast<int>(std::ceil(2 * a.norm() / cell)));
    const int nb = std::max(1, static_cast<int>(std::ceil(2 * b.norm() / cell)));
    const double area = 4 * a.norm() * b.norm() / (na * nb);
    for (int i = 0; i < na; ++i)
        for (int j = 0; j < nb; ++j)
            out.push_back({centre + a * (2.0 * (i + 0.5) / na - 1.0) + b * (2.0 * (j + 0.5) / nb - 1.0), normal, area});
}

inline void sampleSolid(const Solid& s, double cell, std::vector<SurfaceSample>& out)
{
    if (s.kind == Solid::Kind::Box) {
        const Eigen::Matrix3d R = rotationZ(s.yaw);
        for (int axis = 0; axis < 3; ++axis)
            for (const double sign : {-1.0, 1.0}) {
                const Eigen::Vector3d n = sign * R.col(axis);
                const Eigen::Vector3d a = R.col((axis + 1) % 3) * s.halfSize[(axis + 1) % 3];
                const Eigen::Vector3d b = R.col((axis + 2) % 3) * s.halfSize[(axis + 2) % 3];
                sampleRectangle(s.centre + n * s.halfSize[axis], a, b, n, cell, out);
            }
        return;
    }
    const double r = s.halfSize.x(), h = s.halfSize.z();
    const int nu = std::max(6, static_cast<int>(std::ceil(2 * kPi * r / cell)));
    const int nz = std::max(1, static_cast<int>(std::ceil(2 * h / cell)));
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nz; ++j) {
            const double a = 2 * kPi * (i + 0.5) / nu;
            const Eigen::Vector3d n(std::cos(a), std::sin(a), 0.0);
            out.push_back({s.centre + r * n + Eigen::Vector3d(0, 0, -h + 2 * h * (j + 0.5) / nz), n, 2 * kPi * r * 2 * h / (nu * nz)});
        }
    std::vector<SurfaceSample> cap;
    sampleRectangle(s.centre + Eigen::Vector3d(0, 0, h), {r, 0, 0}, {0, r, 0}, Eigen::Vector3d::UnitZ(), cell, cap);
    for (const SurfaceSample& c : cap)
        if ((c.position.head<2>() - s.centre.head<2>()).norm() <= r)
            out.push_back(c);
}

} // namespace detail

//! Samples of every inside surface of the hall (movers excluded), `cell` m apart.
inline std::vector<SurfaceSample> hallSurfaceSamples(const StationsParams& p, double cell)
{
    using namespace detail;
    std::vector<Solid> solids = structure(p);
    addClutter(p, solids);
    std::vector<SurfaceSample> raw, kept;
    const double L = p.hallLength, W = p.hallWidth, H = p.hallHeight;
    sampleRectangle({0.5 * L, 0.5 * W, 0.0}, {0.5 * L, 0, 0}, {0, 0.5 * W, 0}, Eigen::Vector3d::UnitZ(), cell, raw);
    sampleRectangle({0.5 * L, 0.5 * W, H}, {0.5 * L, 0, 0}, {0, 0.5 * W, 0}, -Eigen::Vector3d::UnitZ(), cell, raw);
    for (const Solid& s : solids)
        if (s.tag != TagFloor && s.tag != TagRoof) {
            const std::size_t first = raw.size();
            sampleSolid(s, cell, raw);
            for (std::size_t k = first; k < raw.size(); ++k)
                raw[k].building = s.tag != TagClutter;
        }
    for (const SurfaceSample& sample : raw) {
        const Eigen::Vector3d q = sample.position + 0.01 * sample.normal;
        if (!insideHall(p, q))
            continue; // outside faces of the walls, beam faces inside the roof...
        bool buried = false; // faces against another solid (a box on the floor, a column under a beam)
        for (const Solid& s : solids)
            if (s.contains(q)) {
                buried = true;
                break;
            }
        if (!buried)
            kept.push_back(sample);
    }
    return kept;
}

//! What the stations see of the hall: coverage[i] = area fraction of the
//! hall's inside surfaces station i sees (within range and field, facing it
//! at less than 88 deg incidence, as the scanner needs for an echo, not occluded); overlap(i, j) = area seen by
//! both / area seen by the one that sees less (so 100 % when one view is
//! inside the other).
struct ViewStats
{
    std::vector<double> coverage;         //!< of every inside surface, clutter included
    std::vector<double> buildingCoverage; //!< of the building's surfaces only (clutter left out)
    double unionCoverage = 0.0;           //!< of every inside surface, by all stations together
    Eigen::MatrixXd overlap;
    //! Station i's share of the surveyed hall (what all stations together see).
    double shareOfSurvey(std::size_t i) const { return unionCoverage > 0 ? coverage[i] / unionCoverage : 0.0; }
};

inline ViewStats viewStats(const StationsParams& p, double cell = 0.5)
{
    const std::vector<SurfaceSample> samples = hallSurfaceSamples(p, cell);
    const std::size_t n = p.stations.size();
    std::vector<std::vector<char>> seen(n, std::vector<char>(samples.size(), 0));
    double total = 0, buildingTotal = 0;
    for (const SurfaceSample& s : samples) {
        total += s.area;
        buildingTotal += s.building ? s.area : 0.0;
    }
    ViewStats v;
    for (std::size_t i = 0; i < n; ++i) {
        const std::vector<Solid> solids = hallSolids(p, i);
        const Eigen::Matrix4d pose = stationPoseInHall(p, i);
        const Eigen::Vector3d c = pose.topRightCorner<3, 1>();
        const Eigen::Matrix3d R = pose.topLeftCorner<3, 3>();
        double area = 0, buildingArea = 0;
        for (std::size_t k = 0; k < samples.size(); ++k) {
            const Eigen::Vector3d q = samples[k].position + 0.01 * samples[k].normal;
            const Eigen::Vector3d v3 = q - c;
            const double dist = v3.norm();
            if (dist > p.maxRange || dist < p.minRange || samples[k].normal.dot(-v3) < 0.035 * dist)
                continue;
            const Eigen::Vector3d local = R.transpose() * v3;
            if (std::atan2(local.z(), local.head<2>().norm()) < degToRad(p.pitchMinDeg))
                continue;
            RayHit hit;
            if (firstHit(solids, c, v3 / dist, 0.0, dist, hit))
                continue;
            seen[i][k] = 1;
            area += samples[k].area;
            buildingArea += samples[k].building ? samples[k].area : 0.0;
        }
        v.coverage.push_back(area / total);
        v.buildingCoverage.push_back(buildingArea / buildingTotal);
    }
    double unionArea = 0;
    for (std::size_t k = 0; k < samples.size(); ++k)
        for (std::size_t i = 0; i < n; ++i)
            if (seen[i][k]) {
                unionArea += samples[k].area;
                break;
            }
    v.unionCoverage = unionArea / total;
    v.overlap = Eigen::MatrixXd::Identity(n, n);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j) {
            double both = 0;
            for (std::size_t k = 0; k < samples.size(); ++k)
                if (seen[i][k] && seen[j][k])
                    both += samples[k].area;
            v.overlap(i, j) = v.overlap(j, i) = both / (total * std::min(v.coverage[i], v.coverage[j]));
        }
    return v;
}

} // namespace scandiff::test::family::stations
