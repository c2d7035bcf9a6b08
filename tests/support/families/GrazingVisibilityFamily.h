// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Family B: visibility of a compared cloud from a reference terrestrial scan,
//! at grazing incidence. For tools that label each compared point 0 visible,
//! 1 hidden, 2 out of range, 3 out of field, from the reference scan and its
//! SensorPose (depth-map visibility, thesis 000 §2.3.3).
//!
//! Conditions (a TLS on a tripod over open ground with a free-standing wall):
//! - ground: a plane through the tripod's foot with a slope, plus a gentle
//!   undulation of a few mm (wavelengths 3-8 m, shared by both epochs: it is
//!   the surface, not noise; its slopes stay below the grazing angle at the
//!   maximum range, so the ground never shadows itself);
//! - a wall of finite length and thickness standing on the ground (its
//!   foundation buried), turned by a random skew from facing the scanner;
//! - reference: a simulated scan from the scanner centre on a regular yaw x
//!   pitch grid, nearest hit of ground or wall, nothing beyond the maximum
//!   range or below the minimum range, Gaussian range noise along the ray;
//!   an echo at any incidence. Ground at tens of metres is met at 1-4 deg
//!   and still returns, as it does for TLS at these ranges: one pitch step
//!   spans tens of centimetres to metres of ground. Its SensorPose gives the position,
//!   orientation (heading), steps, field of view and maximum range;
//! - compared epoch: the same ground and wall sampled independently,
//!   uniformly over the surfaces (ground out to 1.1 x the maximum range, over
//!   the scanned sector and 10 deg beyond it; every face of the wall above
//!   ground) at the scan's densities (its mean over the ground in range; its
//!   density facing the wall at the wall's distance, capped in scaled draws),
//!   with isotropic Gaussian noise, plus a cube standing in the
//!   wall's shadow (entirely hidden from the scanner);
//! - truth per compared point, from its noise-free position P (what a
//!   surveyor knows the surface is): 3 out of field if P's direction from the
//!   scanner is outside the scanned angles, else 2 out of range if P is
//!   farther than the maximum range, else 1 hidden if the segment scanner -> P
//!   enters the reference wall (shrunk by a 5 mm tolerance so a point on the
//!   wall's own surface is not hidden by it; the ground, a plane seen from
//!   above with an undulation too gentle to cast shadows, hides nothing),
//!   else 0 visible. The cube is not in the
//!   reference scene: it occludes nothing.
//!
//! Issue case: tripod 1.8 m, 0.1 deg steps, 40 m range, full turn, flat
//! ground (3 mm undulation), a wall 2.5 m high, 15 m long, 0.25 m thick, 12 m
//! away, 3 mm noise on both epochs, a 1 m cube 1.5 m behind the wall:
//! about 2.1 M reference points, 2.7 M compared points (2.5 M of ground).
//!
//! Family ranges (drawFamily): tripod 1.4-2.0 m; angular step 0.03-0.2 deg;
//! maximum range 20-60 m; wall 1.5-4 m high, 3-30 m long, 0.2-0.3 m thick,
//! 5-25 m away (within 0.8 x range), skew +-50 deg, any bearing; ground slope
//! 0-5 deg towards any azimuth; undulation 1-5 mm; noise 1-10 mm (each
//! epoch); cube 0.5-1.2 m placed where it is entirely hidden (draws whose
//! shadow cannot hold one are redrawn); half of the draws at UTM-like world
//! coordinates (~500000, 5400000, 100-500 m).
//!
//! Scale: below 1 the horizontal field of view becomes a sector around the
//! wall (its angular extent + 15 deg each side); the step is coarsened when
//! needed so the reference holds about max(150 k, 3 M * scale^2) points
//! (scale 0.2 or less: ~70-200 k reference and ~130-320 k compared points,
//! about 0.2 s to build; scale 1: up to ~3 M reference points, full turn). The floor is higher than family A's because a
//! coarser step would space far ground returns by metres to tens of metres,
//! harsher than any real survey (and visibility runs fast).
//!
//! Namespace scandiff::test::family::grazing.
//!
//! Scoring: agreement (fraction of compared points whose label equals the
//! truth), fraction of truly visible points labelled hidden, fraction of the
//! cube's points labelled visible. Issue targets: >= 97 %, <= 3 %, <= 1 %.
//! Also reported: agreement per part (ground, wall, cube), the visible ground
//! labelled hidden (where grazing bites) and the confusion matrix.

#include "TlsRayCast.h"

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/SensorPose.h>
#include <scandiff/core/SplitMix.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace scandiff::test::family::grazing {

using namespace tls;

enum VisibilityLabel : int { LabelVisible = 0, LabelHidden = 1, LabelOutOfRange = 2, LabelOutOfField = 3 };
enum ComparedPart : int { PartGround = 0, PartWall = 1, PartCube = 2 };

//! Site frame: origin at the ground under the scanner, z up; world = site + worldOffset.
struct GrazingParams
{
    // Scanner.
    double tripodHeight = 1.8;                  //!< scanner centre above the ground at its foot (m)
    double yawStepDeg = 0.1, pitchStepDeg = 0.1; //!< angular steps (deg)
    double yawMinDeg = -180.0, yawMaxDeg = 180.0; //!< horizontal field, scanner frame (deg)
    double pitchMinDeg = -60.0, pitchMaxDeg = 90.0;
    double minRange = 0.6, maxRange = 40.0;     //!< m
    double scannerHeadingDeg = 0.0;             //!< world azimuth of the scanner frame's x axis (deg)
    double referenceNoise = 0.003;              //!< range noise of the reference scan (m, 1 sigma)
    // Ground.
    double groundSlopeDeg = 0.0, groundSlopeAzimuthDeg = 0.0; //!< rising towards the azimuth (deg)
    double groundUndulation = 0.003;                          //!< largest height of the undulation (m)
    // Wall.
    double wallBearingDeg = 0.0; //!< direction of the wall's centre from the scanner, scanner frame (deg)
    double wallDistance = 12.0;  //!< horizontal distance to the middle of the wall's near face (m)
    double wallLength = 15.0, wallHeight = 2.5, wallThickness = 0.25; //!< m; the height above the ground at its middle
    double wallSkewDeg = 0.0;    //!< the wall turned away from facing the scanner (deg)
    // Cube (compared epoch only).
    double cubeSize = 1.0;    //!< edge (m)
    double cubeBehind = 1.5;  //!< gap from the middle of the wall's back face to the cube (m, along the sight line)
    double cubeLateral = 0.0; //!< offset of the cube along the wall (m)
    double cubeYawDeg = 10.0;
    // Compared epoch.
    double comparedNoise = 0.003;          //!< isotropic (m, 1 sigma per axis)
    double comparedGroundDensity = 410.0;   //!< points per m^2 (the scan's mean over the ground in range)
    double comparedSurfaceDensity = 2300.0; //!< points per m^2 on the wall and cube (the scan's, facing, at the wall)
    // Truth and world.
    double truthTolerance = 0.005; //!< a surface hides a point only if the segment goes this far into it (m)
    Eigen::Vector3d worldOffset = Eigen::Vector3d::Zero();
    std::uint64_t seed = 1;
};

struct GrazingScene
{
    GrazingParams params;
    PointCloud reference;   //!< with its SensorPose in sensors()[0]
    PointCloud compared;
    std::vector<int> truth; //!< per compared point: VisibilityLabel
    std::vector<int> part;  //!< per compared point: ComparedPart
    SensorPose sensor;      //!< the reference scanner (same as reference.sensors()[0])
};

namespace detail {

//! The ground: plane + undulation, heights in the site frame.
struct Ground
{
    double slopeX = 0, slopeY = 0; //!< dz/dx, dz/dy of the plane
    std::array<Eigen::Vector2d, 3> waveVector; //!< 2 pi / wavelength along a direction
    std::array<double, 3> phase{}, amplitude{};

    explicit Ground(const GrazingParams& p)
    {
        const double s = std::tan(degToRad(p.groundSlopeDeg)), a = degToRad(p.groundSlopeAzimuthDeg);
        slopeX = s * std::cos(a);
        slopeY = s * std::sin(a);
        SplitMix64 rng(p.seed, 0x6E0u);
        for (int i = 0; i < 3; ++i) {
            const double dir = uniformIn(rng, 0.0, 2 * kPi), wavelength = uniformIn(rng, 3.0, 8.0);
            waveVector[i] = (2 * kPi / wavelength) * Eigen::Vector2d(std::cos(dir), std::sin(dir));
            phase[i] = uniformIn(rng, 0.0, 2 * kPi);
            amplitude[i] = p.groundUndulation / 3.0;
        }
    }
    double height(double x, double y) const
    {
        double z = slopeX * x + slopeY * y;
        for (int i = 0; i < 3; ++i)
            z += amplitude[i] * std::sin(waveVector[i].dot(Eigen::Vector2d(x, y)) + phase[i]);
        return z;
    }
    Eigen::Vector2d gradient(double x, double y) const
    {
        Eigen::Vector2d g(slopeX, slopeY);
        for (int i = 0; i < 3; ++i)
            g += amplitude[i] * std::cos(waveVector[i].dot(Eigen::Vector2d(x, y)) + phase[i]) * waveVector[i];
        return g;
    }
    //! First crossing of the ray o + t d (o above the ground) with the ground, by Newton from the plane's.
    bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tMax, double& t) const
    {
        const double h0 = o.z() - (slopeX * o.x() + slopeY * o.y());
        const double k = d.z() - (slopeX * d.x() + slopeY * d.y()); // rate of height above the plane
        if (k >= 0)
            return false;
        t = -h0 / k;
        if (t > 1.2 * tMax)
            return false;
        for (int it = 0; it < 6; ++it) {
            const Eigen::Vector3d q = o + t * d;
            const double f = q.z() - height(q.x(), q.y());
            const double df = d.z() - gradient(q.x(), q.y()).dot(d.head<2>());
            t -= f / df;
        }
        return t > 0 && t < tMax;
    }
};

inline Eigen::Vector3d scannerCentre(const GrazingParams& p, const Ground& g)
{
    return {0.0, 0.0, g.height(0.0, 0.0) + p.tripodHeight};
}

inline Eigen::Matrix3d scannerRotation(const GrazingParams& p) { return rotationZ(degToRad(p.scannerHeadingDeg)); }

//! Unit horizontal vector from the scanner to the wall's middle (site frame).
inline Eigen::Vector3d sightLine(const GrazingParams& p)
{
    const double a = degToRad(p.scannerHeadingDeg + p.wallBearingDeg);
    return {std::cos(a), std::sin(a), 0.0};
}

//! The wall: box along the wall (local x), thickness away from the scanner (local y).
inline Solid wallSolid(const GrazingParams& p, const Ground& g)
{
    const Eigen::Vector3d sight = sightLine(p);
    const double yaw = std::atan2(sight.y(), sight.x()) + 0.5 * kPi + degToRad(p.wallSkewDeg);
    const Eigen::Vector3d along(std::cos(yaw), std::sin(yaw), 0.0);
    Eigen::Vector3d away(-along.y(), along.x(), 0.0);
    if (away.dot(sight) < 0)
        away = -away;
    const Eigen::Vector3d mid = sight * p.wallDistance + away * (0.5 * p.wallThickness);
    double lowest = 1e300; // foundation below the lowest ground under the footprint
    for (const double u : {-1.0, 1.0})
        for (const double v : {-1.0, 1.0}) {
            const Eigen::Vector3d c = mid + along * (0.5 * u * p.wallLength) + away * (0.5 * v * p.wallThickness);
            lowest = std::min(lowest, g.height(c.x(), c.y()));
        }
    const double bottom = lowest - 0.3 - p.groundUndulation, top = g.height(mid.x(), mid.y()) + p.wallHeight;
    return Solid::turnedBox({mid.x(), mid.y(), 0.5 * (bottom + top)},
                            {0.5 * p.wallLength, 0.5 * p.wallThickness, 0.5 * (top - bottom)}, yaw);
}

//! The cube behind the wall, its base a little into the ground.
inline Solid cubeSolid(const GrazingParams& p, const Ground& g)
{
    const Solid wall = wallSolid(p, g);
    const Eigen::Vector3d sight = sightLine(p);
    const Eigen::Vector3d along(wall.cosYaw, wall.sinYaw, 0.0);
    const double h = 0.5 * p.cubeSize;
    const Eigen::Vector3d centre = sight * (p.wallDistance + p.wallThickness + p.cubeBehind + h) + along * p.cubeLateral;
    double lowest = 1e300;
    for (const double u : {-1.0, 1.0})
        for (const double v : {-1.0, 1.0})
            lowest = std::min(lowest, g.height(centre.x() + u * h * 1.42, centre.y() + v * h * 1.42));
    return Solid::turnedBox({centre.x(), centre.y(), lowest - 0.02 + h}, {h, h, h}, degToRad(p.cubeYawDeg));
}

} // namespace detail

//! The reference scanner's SensorPose, in world coordinates.
inline SensorPose referenceSensor(const GrazingParams& p)
{
    const detail::Ground g(p);
    SensorPose s;
    s.position = detail::scannerCentre(p, g) + p.worldOffset;
    s.orientation = Eigen::Quaterniond(detail::scannerRotation(p));
    s.yawStep = degToRad(p.yawStepDeg);
    s.pitchStep = degToRad(p.pitchStepDeg);
    s.yawMin = degToRad(p.yawMinDeg);
    s.yawMax = degToRad(p.yawMaxDeg);
    s.pitchMin = degToRad(p.pitchMinDeg);
    s.pitchMax = degToRad(p.pitchMaxDeg);
    s.maxRange = p.maxRange;
    return s;
}

namespace detail {

//! What the truth needs of the reference scene, computed once.
struct TruthContext
{
    const GrazingParams& p;
    Ground ground;
    std::vector<Solid> occluders; //!< the reference wall
    Eigen::Vector3d centre;
    Eigen::Matrix3d rotation;

    explicit TruthContext(const GrazingParams& params)
        : p(params), ground(params), occluders{wallSolid(params, ground)}, centre(scannerCentre(params, ground)),
          rotation(scannerRotation(params))
    {
    }
    int label(const Eigen::Vector3d& site) const
    {
        const Eigen::Vector3d local = rotation.transpose() * (site - centre);
        const double yaw = radToDeg(std::atan2(local.y(), local.x()));
        const double pitch = radToDeg(std::atan2(local.z(), local.head<2>().norm()));
        if (yaw < p.yawMinDeg || yaw > p.yawMaxDeg || pitch < p.pitchMinDeg || pitch > p.pitchMaxDeg)
            return LabelOutOfField;
        if (local.norm() > p.maxRange)
            return LabelOutOfRange;
        return segmentBlocked(occluders, centre, site, p.truthTolerance) ? LabelHidden : LabelVisible;
    }
};

} // namespace detail

//! The label the geometry gives to a point at `site` (site frame, noise-free).
inline int truthLabel(const GrazingParams& p, const Eigen::Vector3d& site)
{
    return detail::TruthContext(p).label(site);
}

//! Simulated reference scan: global (world) coordinates.
inline std::vector<Eigen::Vector3d> scanReference(const GrazingParams& p)
{
    using namespace detail;
    const Ground g(p);
    const Solid wall = wallSolid(p, g);
    const Eigen::Vector3d c = scannerCentre(p, g);
    const Eigen::Matrix3d R = scannerRotation(p);
    const double yawStep = degToRad(p.yawStepDeg), pitchStep = degToRad(p.pitchStepDeg);
    const int columns = static_cast<int>(std::floor(degToRad(p.yawMaxDeg - p.yawMinDeg) / yawStep + 1e-9));
    const int rows = static_cast<int>(std::floor(degToRad(p.pitchMaxDeg - p.pitchMinDeg) / pitchStep + 1e-9)) + 1;
    const std::uint64_t seed = splitMix(p.seed ^ 0x5CA4u);
    std::vector<Eigen::Vector3d> points;
    for (int col = 0; col < columns; ++col) {
        const double yaw = degToRad(p.yawMinDeg) + (col + 0.5) * yawStep;
        for (int row = 0; row < rows; ++row) {
            const double pitch = std::min(degToRad(p.pitchMinDeg) + row * pitchStep, 0.5 * kPi - 0.5 * pitchStep);
            const Eigen::Vector3d d = R * directionOf(yaw, pitch);
            double t = p.maxRange, tGround;
            RayHit hit;
            if (intersectSolid(wall, c, d, 0.0, t, 0.0, hit))
                t = hit.t;
            if (g.intersect(c, d, t, tGround))
                t = tGround;
            if (t >= p.maxRange || t < p.minRange)
                continue;
            SplitMix64 rng(seed, static_cast<std::uint64_t>(col) * rows + row);
            points.push_back(c + d * (t + p.referenceNoise * gaussian(rng)) + p.worldOffset);
        }
    }
    return points;
}

namespace detail {

//! Noise-free compared samples with their part.
struct TrueSample
{
    Eigen::Vector3d site;
    int part;
};

//! Uniform samples over the faces of a box except its bottom, above the ground.
inline void sampleBoxFaces(const Solid& box, const Ground& g, double density, int part, SplitMix64& rng,
                           std::vector<TrueSample>& out)
{
    const Eigen::Vector3d h = box.halfSize;
    for (int axis = 0; axis < 3; ++axis)
        for (const double sign : {-1.0, 1.0}) {
            if (axis == 2 && sign < 0)
                continue; // the bottom rests in the ground
            const int a = (axis + 1) % 3, b = (axis + 2) % 3;
            const double area = 4 * h[a] * h[b];
            const auto count = static_cast<std::size_t>(std::llround(area * density));
            for (std::size_t i = 0; i < count; ++i) {
                Eigen::Vector3d local;
                local[axis] = sign * h[axis];
                local[a] = uniformIn(rng, -h[a], h[a]);
                local[b] = uniformIn(rng, -h[b], h[b]);
                const Eigen::Vector3d site = box.centre + box.toWorldVector(local);
                if (site.z() > g.height(site.x(), site.y()))
                    out.push_back({site, part});
            }
        }
}

//! Uniform ground samples over the sector (scanner-frame yaw) out to `radius`.
inline void sampleGround(const GrazingParams& p, const Ground& g, const std::vector<Solid>& standing, double yawMin,
                         double yawMax, double radius, SplitMix64& rng, std::vector<TrueSample>& out)
{
    const double area = 0.5 * (yawMax - yawMin) * radius * radius;
    const auto count = static_cast<std::size_t>(std::llround(area * p.comparedGroundDensity));
    const double heading = degToRad(p.scannerHeadingDeg);
    for (std::size_t i = 0; i < count; ++i) {
        const double a = heading + uniformIn(rng, yawMin, yawMax), r = radius * std::sqrt(rng.uniform());
        Eigen::Vector3d site(r * std::cos(a), r * std::sin(a), 0.0);
        site.z() = g.height(site.x(), site.y());
        bool underSolid = false; // no ground inside the wall's or the cube's footprint
        for (const Solid& s : standing)
            underSolid = underSolid || s.contains({site.x(), site.y(), s.centre.z()});
        if (!underSolid)
            out.push_back({site, PartGround});
    }
}

} // namespace detail

inline GrazingScene make(const GrazingParams& p)
{
    using namespace detail;
    GrazingScene scene;
    scene.params = p;
    scene.sensor = referenceSensor(p);
    scene.reference = cloudFromGlobal(scanReference(p), "reference scan");
    scene.reference.sensors().push_back(scene.sensor);

    const Ground g(p);
    const Solid wall = wallSolid(p, g), cube = cubeSolid(p, g);
    SplitMix64 rng(p.seed, 0xC0u);
    std::vector<TrueSample> samples;
    const bool fullTurn = p.yawMaxDeg - p.yawMinDeg >= 359.999;
    const double margin = fullTurn ? 0.0 : 10.0; // sample a little beyond the scanned sector
    sampleGround(p, g, {wall, cube}, degToRad(fullTurn ? -180.0 : p.yawMinDeg - margin),
                 degToRad(fullTurn ? 180.0 : p.yawMaxDeg + margin), 1.1 * p.maxRange, rng, samples);
    sampleBoxFaces(wall, g, p.comparedSurfaceDensity, PartWall, rng, samples);
    sampleBoxFaces(cube, g, p.comparedSurfaceDensity, PartCube, rng, samples);

    const TruthContext truth(p);
    std::vector<Eigen::Vector3d> global;
    global.reserve(samples.size());
    for (const TrueSample& s : samples) {
        const Eigen::Vector3d noise(gaussian(rng), gaussian(rng), gaussian(rng));
        global.push_back(s.site + p.comparedNoise * noise + p.worldOffset);
        scene.truth.push_back(truth.label(s.site));
        scene.part.push_back(s.part);
    }
    scene.compared = cloudFromGlobal(global, "compared epoch");
    return scene;
}

//! The scan's point density on flat ground at horizontal distance r (points per m^2).
inline double scanGroundDensity(double tripodHeight, double r, double yawStepRad, double pitchStepRad)
{
    return tripodHeight / (r * r * r * yawStepRad * pitchStepRad);
}

//! The scan's mean point density over the flat ground within its range: its
//! ground returns (rows from the lowest pitch up to the one meeting the ground
//! at the maximum range) over the ground area in range. Very dense under the
//! scanner, sparse at the far end: the compared epoch gets this mean everywhere.
inline double scanMeanGroundDensity(double tripodHeight, double maxRange, double pitchMinDeg, double stepRad)
{
    const double rows = (degToRad(-pitchMinDeg) - std::atan2(tripodHeight, maxRange)) / stepRad;
    return rows / stepRad / (0.5 * maxRange * maxRange); // (columns * rows) / (sector * R^2 / 2), per radian of sector
}

//! The issue's condition (see the header comment).
inline GrazingParams issueCase()
{
    GrazingParams p;
    p.scannerHeadingDeg = 30.0;
    p.wallBearingDeg = 40.0;
    p.cubeLateral = 1.0;
    const double step = degToRad(0.1);
    p.comparedGroundDensity = scanMeanGroundDensity(p.tripodHeight, p.maxRange, p.pitchMinDeg, step);
    p.comparedSurfaceDensity = 1.0 / (p.wallDistance * p.wallDistance * step * step);
    p.seed = 11;
    return p;
}

//! Whether the cube of `p`, grown by 10 cm, is hidden everywhere (its faces
//! and inside, on a 10 cm grid).
inline bool cubeFullyHidden(const GrazingParams& p)
{
    using namespace detail;
    const TruthContext truth(p);
    const Ground& g = truth.ground;
    Solid grown = cubeSolid(p, g);
    grown.halfSize += Eigen::Vector3d::Constant(0.1);
    const int n = std::max(2, static_cast<int>(std::ceil(2 * grown.halfSize.x() / 0.1)));
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j)
            for (int k = 0; k <= n; ++k) {
                const Eigen::Vector3d local = grown.halfSize.cwiseProduct(Eigen::Vector3d(2.0 * i / n - 1, 2.0 * j / n - 1, 2.0 * k / n - 1));
                const Eigen::Vector3d site = grown.centre + grown.toWorldVector(local);
                if (site.z() >= g.height(site.x(), site.y()) && truth.label(site) != LabelHidden)
                    return false;
            }
    return true;
}

//! A draw over the ranges of real surveys (header comment).
inline GrazingParams drawFamily(std::uint64_t seed, double scale)
{
    GrazingParams p;
    SplitMix64 rng(seed, 0xB0u);
    for (int attempt = 0; attempt < 200; ++attempt) {
        p.tripodHeight = uniformIn(rng, 1.4, 2.0);
        p.maxRange = uniformIn(rng, 20.0, 60.0);
        p.wallHeight = uniformIn(rng, 1.5, 4.0);
        p.wallDistance = uniformIn(rng, 5.0, std::min(25.0, 0.8 * p.maxRange));
        p.wallLength = uniformIn(rng, 3.0, 30.0);
        p.wallThickness = uniformIn(rng, 0.2, 0.3);
        p.wallSkewDeg = uniformIn(rng, -50.0, 50.0);
        p.groundSlopeDeg = uniformIn(rng, 0.0, 5.0);
        p.groundSlopeAzimuthDeg = uniformIn(rng, 0.0, 360.0);
        p.groundUndulation = uniformIn(rng, 0.001, 0.005);
        p.cubeSize = uniformIn(rng, 0.5, 1.2);
        p.cubeBehind = uniformIn(rng, 0.3, 3.0);
        p.cubeLateral = uniformIn(rng, -0.3, 0.3) * std::max(0.0, p.wallLength - p.cubeSize);
        p.cubeYawDeg = uniformIn(rng, 0.0, 90.0);
        p.scannerHeadingDeg = uniformIn(rng, 0.0, 360.0);
        // Half angular extent of the wall seen from the scanner, for the sector at scale < 1.
        const double halfExtentDeg = radToDeg(std::atan2(0.5 * p.wallLength, p.wallDistance)) + 15.0;
        const double sectorHalf = scale < 1.0 ? std::min(180.0, halfExtentDeg) : 180.0;
        p.wallBearingDeg = sectorHalf >= 180.0 ? uniformIn(rng, -180.0, 180.0) : uniformIn(rng, -180.0 + sectorHalf, 180.0 - sectorHalf);
        p.yawMinDeg = sectorHalf >= 180.0 ? -180.0 : p.wallBearingDeg - sectorHalf;
        p.yawMaxDeg = sectorHalf >= 180.0 ? 180.0 : p.wallBearingDeg + sectorHalf;
        p.pitchMinDeg = uniformIn(rng, -65.0, -50.0);
        // Step: the survey's, coarsened to the point budget (ground rays dominate).
        const double surveyStep = uniformIn(rng, 0.03, 0.2);
        const double budget = std::max(150000.0, 3.0e6 * scale * scale);
        const double groundPitchSpan = degToRad(-p.pitchMinDeg) - std::atan2(p.tripodHeight, p.maxRange);
        const double budgetStep = radToDeg(std::sqrt(degToRad(p.yawMaxDeg - p.yawMinDeg) * groundPitchSpan / budget));
        p.yawStepDeg = p.pitchStepDeg = std::max(surveyStep, budgetStep);
        p.referenceNoise = logUniformIn(rng, 0.001, 0.010);
        p.comparedNoise = logUniformIn(rng, 0.001, 0.010);
        const double step = degToRad(p.yawStepDeg);
        p.comparedGroundDensity = scanMeanGroundDensity(p.tripodHeight, p.maxRange, p.pitchMinDeg, step);
        const double wallArea = 2.0 * p.wallLength * (p.wallHeight + 0.5) + p.wallLength * p.wallThickness;
        p.comparedSurfaceDensity = std::min(1.0 / (p.wallDistance * p.wallDistance * step * step), 0.5 * budget / wallArea);
        p.worldOffset = rng.uniform() < 0.5 ? Eigen::Vector3d(uniformIn(rng, 400000.0, 600000.0), uniformIn(rng, 5300000.0, 5500000.0),
                                                              uniformIn(rng, 100.0, 500.0))
                                            : Eigen::Vector3d::Zero();
        p.seed = rng.next();
        if (cubeFullyHidden(p))
            return p;
    }
    return p; // not reached in practice
}

//! Figures of merit of a tool's labels against the truth.
struct VisibilityScore
{
    double agreement = 0.0;             //!< fraction of compared points labelled as the truth says
    double visibleLabelledHidden = 0.0; //!< fraction of the truly visible points labelled hidden
    double visibleGroundLabelledHidden = 0.0; //!< the same over the ground only (where grazing bites)
    double cubeLabelledVisible = 0.0;   //!< fraction of the cube's points labelled visible
    std::array<double, 3> agreementByPart{}; //!< agreement over the ground, wall, cube points (ComparedPart)
    std::array<std::array<std::size_t, 4>, 4> confusion{}; //!< [truth][label]; labels outside 0-3 are not counted here
    std::size_t count = 0, visibleCount = 0, cubeCount = 0;

    bool meetsIssueTargets() const { return agreement >= 0.97 && visibleLabelledHidden <= 0.03 && cubeLabelledVisible <= 0.01; }
};

//! `labels[i]`: the tool's label of compared point i (any numeric type).
template <class Labels>
VisibilityScore scoreLabels(const GrazingScene& scene, const Labels& labels)
{
    VisibilityScore s;
    std::size_t agree = 0, visibleHidden = 0, cubeVisible = 0, visibleGround = 0, visibleGroundHidden = 0;
    std::array<std::size_t, 3> partCount{}, partAgree{};
    for (std::size_t i = 0; i < scene.truth.size(); ++i) {
        const int truth = scene.truth[i];
        const int label = i < labels.size() ? static_cast<int>(std::lround(static_cast<double>(labels[i]))) : -1;
        ++s.count;
        agree += label == truth;
        ++partCount[scene.part[i]];
        partAgree[scene.part[i]] += label == truth;
        if (label >= 0 && label <= 3)
            ++s.confusion[truth][label];
        if (truth == LabelVisible) {
            ++s.visibleCount;
            visibleHidden += label == LabelHidden;
            if (scene.part[i] == PartGround) {
                ++visibleGround;
                visibleGroundHidden += label == LabelHidden;
            }
        }
        if (scene.part[i] == PartCube) {
            ++s.cubeCount;
            cubeVisible += label == LabelVisible;
        }
    }
    auto frac = [](std::size_t a, std::size_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : 0.0; };
    s.agreement = frac(agree, s.count);
    s.visibleLabelledHidden = frac(visibleHidden, s.visibleCount);
    s.cubeLabelledVisible = frac(cubeVisible, s.cubeCount);
    s.visibleGroundLabelledHidden = frac(visibleGroundHidden, visibleGround);
    for (int part = 0; part < 3; ++part)
        s.agreementByPart[part] = frac(partAgree[part], partCount[part]);
    return s;
}

inline std::string describe(const GrazingParams& p)
{
    char buf[400];
    std::snprintf(buf, sizeof buf,
                  "grazing: tripod %.2f m, step %.3f deg, range %.0f m, yaw %.0f..%.0f deg, wall %.1f m high %.1f m long at %.1f m "
                  "(skew %.0f deg), slope %.1f deg, noise %.1f/%.1f mm, cube %.2f m %.1f m behind, world (%.0f, %.0f), seed %llu",
                  p.tripodHeight, p.yawStepDeg, p.maxRange, p.yawMinDeg, p.yawMaxDeg, p.wallHeight, p.wallLength, p.wallDistance,
                  p.wallSkewDeg, p.groundSlopeDeg, 1000 * p.referenceNoise, 1000 * p.comparedNoise, p.cubeSize, p.cubeBehind,
                  p.worldOffset.x(), p.worldOffset.y(), static_cast<unsigned long long>(p.seed));
    return buf;
}

} // namespace scandiff::test::family::grazing
