// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Family A: two airborne (ALS) epochs of a park whose vegetation grew, for a
//! registration that must ignore the changes (`register --exclude-changes`).
//!
//! Conditions (issue case, issueCase()): a 250 m square park surveyed twice
//! from the air, 0.6 pulse/m^2 (about 0.7 point/m^2 with multiple returns),
//! scan angle +-20 deg from 700 m, strips with 30 % side overlap, the two
//! surveys flown across each other. Nearly flat ground (1.5 deg undulation), a
//! curving path, two flat-roofed buildings; trees and bushes making about half
//! of the points. Between the epochs each tree grew about 1 m (crowns higher
//! and wider), bushes grew, new bushes appeared, and the crowns got denser, so
//! the later epoch sees fewer ground points under trees. Both surveys are
//! already georeferenced: per-epoch vertical bias +1.5 cm / -1.0 cm plus
//! 2.5 cm range noise, so the stable ground agrees to about 4 cm. Truth: the
//! identity (later -> earlier). Target: the registered later epoch moves
//! vertically by at most 10 cm (median and p90 of |dz| against the truth).
//!
//! Family (drawFamily): pulse density 0.4-10 /m^2 (log-uniform); vegetation
//! share 20-70 %; tree growth 0.2-3 m; vertical survey disagreement 0-5 cm;
//! range noise 1.5-4 cm; terrain flat (max slope 0.3-3 deg) or hilly (3-20
//! deg), half of the draws each; 0-3 buildings; park side 200-500 m (shrunk by
//! sqrt(scale), at least 60 m, and so that a draw stays below ~1.2 M pulses);
//! foliage extinction 0.12-0.3 /m, 1.1-1.8 x denser later; echo continuation
//! after a foliage echo 0.25-0.6; new bushes 0-40 /ha;
//! flight height 300-1500 m, headings and strip overlap random; UTM
//! coordinates in 70 % of draws; a classification field in half. A known
//! motion of the later epoch, 0-2 m and 0-2 deg about a pivot at the scene
//! centre: on flat terrain horizontal translation and turns about the vertical
//! are undetermined by the data, so there the motion is only a vertical shift
//! and a tilt (the right answer is then 'do not move horizontally').
//!
//! The vegetation share is the mean of the two epochs (the later one is
//! higher: grown crowns, new bushes); the canopy cover giving it is found on a
//! model crown and corrected on sparse pilot surveys of the same scene.
//!
//! The real-data pair (ISPRS filter-test samples) is in AirborneRealPair.h,
//! included at the end of this file.
//!
//! Matrices everywhere act on global coordinates (see epochscene::globalFromLocal
//! to convert a tool's matrix expressed around a cloud origin).

#include "AirborneParkScene.h"
#include "EpochSceneCommon.h"

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/SplitMix.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace scandiff::test::family::airborne {

using detail::SurfaceKind;
namespace es = epochscene;

struct AirborneEpochsParams
{
    std::uint64_t seed = 1;
    // Site
    double side = 250;                //!< park side (m), square
    bool largeCoordinates = true;     //!< UTM-like global coordinates
    Eigen::Vector2d utmCorner{691250.0, 5335480.0}; //!< easting, northing of the corner (m) when large
    double baseElevation = 312;       //!< ground elevation at the corner (m)
    // Terrain
    double maxSlopeDeg = 1.5;         //!< steepest slope of tilt + undulations (deg)
    double undulationWavelength = 100; //!< typical wavelength of the undulations (m)
    int buildings = 2;                //!< flat-roofed buildings (stable)
    bool path = true;                 //!< a curving path free of trees
    // Vegetation
    double vegetationShare = 0.5;     //!< target share of vegetation points (mean of the epochs)
    double bushShare = 0.3;           //!< share of plants that are bushes
    double coniferShare = 0.25;       //!< share of trees with narrow tall crowns
    double treeHeightMin = 8, treeHeightMax = 20; //!< earlier-epoch tree heights (m)
    double growth = 1.0;              //!< mean height growth of a tree between the epochs (m)
    double newBushesPerHectare = 15;  //!< bushes present only in the later epoch
    double extinctionEarlier = 0.22;  //!< foliage extinction (1/m), earlier epoch
    double extinctionLater = 0.35;    //!< denser crowns later: fewer ground points under them
    // Acquisition
    double pulseDensity = 0.6;        //!< pulses per m^2 over the area (strips summed)
    double flightAltitude = 700;      //!< above the ground (m)
    double maxScanAngleDeg = 20;
    double stripOverlap = 0.3;
    double headingEarlierDeg = 0, headingLaterDeg = 90;
    double rangeNoise = 0.025;        //!< m (1 sigma), along the ray
    double verticalBiasEarlier = 0.015, verticalBiasLater = -0.010; //!< m, per survey
    int maxReturns = 4;
    double deadDistance = 1.2;        //!< m between separable echoes of one pulse
    double echoContinuation = 0.4;    //!< probability a pulse goes on after a foliage echo
    bool withClassification = true;   //!< write ASPRS `classification` (2, 3-5, 6)
    // Known motion applied to the later epoch (p' = R (p - pivot) + pivot + t), pivot: scene centre on the ground
    Eigen::Vector3d motionTranslation = Eigen::Vector3d::Zero(); //!< m
    Eigen::Vector3d motionAxis = Eigen::Vector3d::UnitZ();
    double motionAngleDeg = 0;
};

//! Two epochs and their truth. Per-point kinds are the truth (what the return
//! hit), whatever the classification field says or whether it exists.
struct AirborneEpochsScene
{
    PointCloud earlier, later;
    std::vector<std::uint8_t> earlierKind, laterKind; //!< SurfaceKind per point
    Eigen::Matrix4d appliedToLater = Eigen::Matrix4d::Identity();
    Eigen::Matrix4d trueLaterToEarlier = Eigen::Matrix4d::Identity(); //!< what registration must return
    double earlierVegetationShare = 0, laterVegetationShare = 0;
    double earlierPointDensity = 0, laterPointDensity = 0; //!< points per m^2
    std::size_t earlierGroundUnderCrowns = 0, laterGroundUnderCrowns = 0; //!< ground returns below foliage
    std::string description;
};

inline AirborneEpochsParams issueCase() { return AirborneEpochsParams{}; }

inline std::string describe(const AirborneEpochsParams& p)
{
    return es::format("ALS park seed=%llu side=%.0fm pulses=%.2f/m2 slope<=%.1fdeg veg=%.0f%% growth=%.2fm "
                      "bias=%+.3f/%+.3fm noise=%.3fm motion=(%.2f,%.2f,%.2f)m %.2fdeg%s%s",
                      static_cast<unsigned long long>(p.seed), p.side, p.pulseDensity, p.maxSlopeDeg,
                      100 * p.vegetationShare, p.growth, p.verticalBiasEarlier, p.verticalBiasLater, p.rangeNoise,
                      p.motionTranslation.x(), p.motionTranslation.y(), p.motionTranslation.z(), p.motionAngleDeg,
                      p.largeCoordinates ? " UTM" : "", p.withClassification ? " class" : "");
}

inline AirborneEpochsParams drawFamily(std::uint64_t seed, double scale)
{
    SplitMix64 rng(seed, 0xA1);
    AirborneEpochsParams p;
    p.seed = seed;
    scale = std::clamp(scale, 1e-3, 1.0);
    p.side = std::max(60.0, es::uniform(rng, 200, 500) * std::sqrt(scale));
    p.pulseDensity = es::logUniform(rng, 0.4, 10.0);
    const double maxPulses = 1.2e6 * scale;
    if (p.side * p.side * p.pulseDensity > maxPulses)
        p.side = std::max(60.0, std::sqrt(maxPulses / p.pulseDensity));
    if (p.side * p.side * p.pulseDensity > maxPulses)
        p.pulseDensity = std::max(0.4, maxPulses / (p.side * p.side));
    p.largeCoordinates = rng.uniform() < 0.7;
    p.utmCorner = {es::uniform(rng, 300000, 700000), es::uniform(rng, 4.5e6, 6.5e6)};
    p.baseElevation = es::uniform(rng, 0, 1500);
    const bool hilly = rng.uniform() < 0.5;
    p.maxSlopeDeg = hilly ? es::uniform(rng, 3, 20) : es::uniform(rng, 0.3, 3);
    p.undulationWavelength = es::uniform(rng, 40, 200);
    p.buildings = static_cast<int>(rng.below(4));
    p.path = rng.uniform() < 0.7;
    p.vegetationShare = es::uniform(rng, 0.2, 0.7);
    p.bushShare = es::uniform(rng, 0.1, 0.5);
    p.coniferShare = es::uniform(rng, 0, 0.6);
    p.treeHeightMin = es::uniform(rng, 5, 10);
    p.treeHeightMax = p.treeHeightMin + es::uniform(rng, 5, 15);
    p.growth = es::uniform(rng, 0.2, 3.0);
    p.newBushesPerHectare = es::uniform(rng, 0, 40);
    p.extinctionEarlier = es::uniform(rng, 0.12, 0.3);
    p.extinctionLater = p.extinctionEarlier * es::uniform(rng, 1.1, 1.8);
    p.flightAltitude = es::uniform(rng, 300, 1500);
    p.stripOverlap = es::uniform(rng, 0.15, 0.5);
    p.headingEarlierDeg = es::uniform(rng, 0, 360);
    p.headingLaterDeg = es::uniform(rng, 0, 360);
    p.rangeNoise = es::uniform(rng, 0.015, 0.04);
    p.echoContinuation = es::uniform(rng, 0.25, 0.6);
    const double disagreement = es::uniform(rng, 0, 0.05);
    p.verticalBiasEarlier = es::uniform(rng, -0.02, 0.02);
    p.verticalBiasLater = p.verticalBiasEarlier + (rng.uniform() < 0.5 ? -disagreement : disagreement);
    p.withClassification = rng.uniform() < 0.5;
    const double shift = es::uniform(rng, 0, 2), angle = es::uniform(rng, 0, 2);
    if (hilly) {
        p.motionTranslation = shift * es::randomUnitVector(rng);
        p.motionAxis = es::randomUnitVector(rng);
    } else { // only what flat ground determines: height and tilt
        p.motionTranslation = {0, 0, rng.uniform() < 0.5 ? -shift : shift};
        const double a = es::uniform(rng, 0, 2 * es::kPi);
        p.motionAxis = {std::cos(a), std::sin(a), 0};
    }
    p.motionAngleDeg = angle;
    return p;
}

namespace detail {

//! A plant in both epochs (heights above its ground, radii in m).
struct Plant
{
    Eigen::Vector2d xy;
    bool bush = false, inEarlier = true;
    double baseHeight = 0, heightEarlier = 0, heightLater = 0;
    double radiusEarlier = 0, radiusLater = 0, aspect = 1;
};

inline Terrain makeTerrain(const AirborneEpochsParams& p, SplitMix64& rng)
{
    Terrain t;
    t.base = p.baseElevation;
    const double budget = std::tan(es::degToRad(p.maxSlopeDeg)); // sum of slope terms bounds the slope
    const double tiltDir = es::uniform(rng, 0, 2 * es::kPi);
    t.tilt = 0.3 * budget * Eigen::Vector2d(std::cos(tiltDir), std::sin(tiltDir));
    double weights[4], sum = 0;
    for (double& w : weights)
        sum += (w = es::uniform(rng, 0.5, 1.0));
    for (double w : weights) {
        const double wavelength = p.undulationWavelength * es::uniform(rng, 0.4, 1.2);
        const double dir = es::uniform(rng, 0, 2 * es::kPi), k = 2 * es::kPi / wavelength;
        t.waves.push_back({k * Eigen::Vector2d(std::cos(dir), std::sin(dir)), 0.7 * budget * (w / sum) / k,
                           es::uniform(rng, 0, 2 * es::kPi)});
    }
    return t;
}

inline std::vector<Eigen::Vector2d> makePath(const AirborneEpochsParams& p, SplitMix64& rng)
{
    std::vector<Eigen::Vector2d> pts;
    if (!p.path)
        return pts;
    const double turn = es::uniform(rng, 0, es::kPi), phase = es::uniform(rng, 0, 2 * es::kPi);
    const Eigen::Vector2d c(p.side / 2, p.side / 2), u(std::cos(turn), std::sin(turn)), v(-u.y(), u.x());
    for (double s = -0.75 * p.side; s <= 0.75 * p.side; s += 1.0)
        pts.push_back(c + s * u + 0.2 * p.side * std::sin(2 * es::kPi * s / p.side + phase) * v);
    return pts;
}

inline double distanceTo(const std::vector<Eigen::Vector2d>& pts, const Eigen::Vector2d& q)
{
    double d = 1e300;
    for (const auto& a : pts)
        d = std::min(d, (a - q).squaredNorm());
    return std::sqrt(d);
}

inline std::vector<BuildingBox> makeBuildings(const AirborneEpochsParams& p, const Terrain& t,
                                              const std::vector<Eigen::Vector2d>& path, SplitMix64& rng)
{
    std::vector<BuildingBox> out;
    for (int attempt = 0; attempt < 200 && static_cast<int>(out.size()) < p.buildings; ++attempt) {
        BuildingBox b;
        b.centre = {es::uniform(rng, 0.15, 0.85) * p.side, es::uniform(rng, 0.15, 0.85) * p.side};
        b.halfLength = es::uniform(rng, 4, 9);
        b.halfWidth = es::uniform(rng, 3, std::min(7.0, b.halfLength));
        b.headingRad = es::uniform(rng, 0, es::kPi);
        const double r = std::hypot(b.halfLength, b.halfWidth);
        bool ok = path.empty() || distanceTo(path, b.centre) > r + 4;
        for (const auto& o : out)
            ok = ok && (o.centre - b.centre).norm() > r + std::hypot(o.halfLength, o.halfWidth) + 6;
        if (!ok)
            continue;
        double lowest = t.height(b.centre.x(), b.centre.y());
        for (int k = 0; k < 4; ++k)
            lowest = std::min(lowest, t.height(b.centre.x() + ((k & 1) ? r : -r), b.centre.y() + ((k & 2) ? r : -r)));
        b.zBase = lowest - 0.5;
        b.zRoof = t.height(b.centre.x(), b.centre.y()) + es::uniform(rng, 3.5, 9);
        out.push_back(b);
    }
    return out;
}

inline Crown crownOf(const Plant& pl, const Terrain& t, bool later, double extinction)
{
    const double g = t.height(pl.xy.x(), pl.xy.y());
    const double top = later ? pl.heightLater : pl.heightEarlier, r = later ? pl.radiusLater : pl.radiusEarlier;
    Crown c;
    c.centre = {pl.xy.x(), pl.xy.y(), g + 0.5 * (pl.baseHeight + top)};
    c.radii = {r * pl.aspect, r / pl.aspect, 0.5 * (top - pl.baseHeight)};
    c.extinction = extinction;
    return c;
}

inline Plant drawPlant(const AirborneEpochsParams& p, bool bush, SplitMix64& rng)
{
    Plant pl;
    pl.bush = bush;
    pl.aspect = es::uniform(rng, 0.85, 1.15);
    if (bush) {
        pl.heightEarlier = es::uniform(rng, 0.8, 3.0);
        pl.baseHeight = 0.1;
        pl.radiusEarlier = es::uniform(rng, 0.6, 2.0);
        const double dh = std::min(p.growth, 1.5) * es::uniform(rng, 0.3, 0.8);
        pl.heightLater = pl.heightEarlier + dh;
        pl.radiusLater = pl.radiusEarlier + 0.4 * dh;
        return pl;
    }
    const bool conifer = rng.uniform() < p.coniferShare;
    pl.heightEarlier = es::uniform(rng, p.treeHeightMin, p.treeHeightMax);
    pl.baseHeight = pl.heightEarlier * (conifer ? es::uniform(rng, 0.1, 0.2) : es::uniform(rng, 0.3, 0.5));
    pl.radiusEarlier = conifer ? es::uniform(rng, 1.5, 3.0) : pl.heightEarlier * es::uniform(rng, 0.2, 0.35);
    const double dh = p.growth * es::uniform(rng, 0.5, 1.5);
    pl.heightLater = pl.heightEarlier + dh;
    pl.radiusLater = pl.radiusEarlier + (conifer ? 0.15 : 0.3) * dh;
    return pl;
}

//! Canopy cover that gives the target vegetation share: the returns of pulses
//! through a typical crown (same caster, mean epoch) give foliage and ground
//! returns per pulse v and g; share = c v / (c v + c g + 1 - c).
inline double coverForShare(const AirborneEpochsParams& p, SplitMix64& rng)
{
    double veg = 0, ground = 0, weightSum = 0;
    std::vector<PulseReturn> out;
    for (int type = 0; type < 2; ++type) {
        World w;
        Plant pl = drawPlant(p, type == 1, rng);
        pl.xy = {0, 0};
        if (type == 0) {
            pl.heightEarlier = 0.5 * (p.treeHeightMin + p.treeHeightMax);
            pl.baseHeight = 0.4 * pl.heightEarlier;
            pl.radiusEarlier = 0.27 * pl.heightEarlier;
            pl.heightLater = pl.heightEarlier + p.growth;
            pl.radiusLater = pl.radiusEarlier + 0.3 * p.growth;
        }
        Crown c = crownOf(pl, w.terrain, false, 0.5 * (p.extinctionEarlier + p.extinctionLater));
        c.radii += 0.5 * (crownOf(pl, w.terrain, true, 0).radii - c.radii);
        c.centre.z() = pl.baseHeight + c.radii.z();
        w.crowns.push_back(c);
        w.index(1.0);
        CastScratch sc;
        sc.crownStamp.assign(1, 0);
        double v = 0, g = 0;
        const int n = 600;
        for (int i = 0; i < n; ++i) {
            const double a = es::uniform(rng, 0, 2 * es::kPi), r = std::sqrt(rng.uniform());
            const Eigen::Vector3d target(r * c.radii.x() * std::cos(a), r * c.radii.y() * std::sin(a), 0);
            const double th = es::degToRad(es::uniform(rng, -p.maxScanAngleDeg, p.maxScanAngleDeg));
            const Eigen::Vector3d d(std::sin(th), 0, -std::cos(th));
            out.clear();
            castPulse(w, target + Eigen::Vector3d(c.centre.x(), 0, c.centre.z()) - 200 * d, d, p.maxReturns,
                      p.deadDistance, p.echoContinuation, rng, sc, out);
            for (const auto& ret : out)
                (ret.kind == Vegetation ? v : g) += 1.0;
        }
        const double area = c.radii.x() * c.radii.y(), weight = (type == 1 ? p.bushShare : 1 - p.bushShare) * area;
        veg += weight * v / n;
        ground += weight * g / n;
        weightSum += weight;
    }
    const double v = veg / weightSum, g = ground / weightSum, s = p.vegetationShare;
    return std::clamp(s / (v - s * (v + g - 1.0)), 0.02, 0.9);
}

//! Plants until the mean crown footprints cover the wanted fraction of the
//! park: grouped in groves (two thirds) or scattered, off the path and buildings.
inline std::vector<Plant> placePlants(const AirborneEpochsParams& p, double cover,
                                      const std::vector<BuildingBox>& buildings,
                                      const std::vector<Eigen::Vector2d>& path, SplitMix64& rng)
{
    const int n = std::max(1, static_cast<int>(std::ceil(p.side)));
    std::vector<std::uint8_t> covered(static_cast<std::size_t>(n) * n, 0);
    std::size_t coveredCells = 0;
    std::vector<Eigen::Vector2d> groves;
    for (int g = 0, count = 3 + static_cast<int>(rng.below(4)); g < count; ++g)
        groves.push_back({es::uniform(rng, 0, p.side), es::uniform(rng, 0, p.side)});
    std::vector<Plant> plants;
    for (int attempt = 0; attempt < 200000 && coveredCells < cover * n * n; ++attempt) {
        Plant pl = drawPlant(p, rng.uniform() < p.bushShare, rng);
        const Eigen::Vector2d& grove = groves[rng.below(groves.size())];
        pl.xy = rng.uniform() < 0.67 ? Eigen::Vector2d(grove.x() + 18 * es::gaussian(rng), grove.y() + 18 * es::gaussian(rng))
                                     : Eigen::Vector2d(es::uniform(rng, 0, p.side), es::uniform(rng, 0, p.side));
        if (pl.xy.minCoeff() < 0 || pl.xy.maxCoeff() > p.side)
            continue;
        const double r = 0.5 * (pl.radiusEarlier + pl.radiusLater);
        bool ok = path.empty() || distanceTo(path, pl.xy) > 0.5 * r + 2.0;
        for (const auto& b : buildings)
            ok = ok && (pl.xy - b.centre).norm() > std::hypot(b.halfLength, b.halfWidth) + r + 1.0;
        if (!ok)
            continue;
        plants.push_back(pl);
        for (int j = std::max(0, int(pl.xy.y() - r)); j < std::min(n, int(pl.xy.y() + r) + 1); ++j)
            for (int i = std::max(0, int(pl.xy.x() - r)); i < std::min(n, int(pl.xy.x() + r) + 1); ++i)
                if ((Eigen::Vector2d(i + 0.5, j + 0.5) - pl.xy).norm() < r && !covered[std::size_t(j) * n + i]) {
                    covered[std::size_t(j) * n + i] = 1;
                    ++coveredCells;
                }
    }
    return plants;
}

//! New bushes of the later epoch on open ground (not under crowns, off the path).
inline void addNewBushes(const AirborneEpochsParams& p, const std::vector<BuildingBox>& buildings,
                         const std::vector<Eigen::Vector2d>& path, std::vector<Plant>& plants, SplitMix64& rng)
{
    const int wanted = static_cast<int>(std::lround(p.newBushesPerHectare * p.side * p.side / 1e4));
    const std::size_t existing = plants.size();
    for (int attempt = 0, added = 0; attempt < 50 * wanted + 50 && added < wanted; ++attempt) {
        Plant pl = drawPlant(p, true, rng);
        pl.inEarlier = false;
        pl.xy = {es::uniform(rng, 0, p.side), es::uniform(rng, 0, p.side)};
        bool ok = path.empty() || distanceTo(path, pl.xy) > pl.radiusLater + 2.0;
        for (const auto& b : buildings)
            ok = ok && (pl.xy - b.centre).norm() > std::hypot(b.halfLength, b.halfWidth) + pl.radiusLater + 1.0;
        for (std::size_t k = 0; ok && k < existing; ++k)
            ok = (plants[k].xy - pl.xy).norm() > plants[k].radiusLater + pl.radiusLater;
        if (!ok)
            continue;
        plants.push_back(pl);
        ++added;
    }
}

inline Flight flightOf(const AirborneEpochsParams& p, bool later)
{
    Flight f;
    f.headingRad = es::degToRad(later ? p.headingLaterDeg : p.headingEarlierDeg);
    f.altitude = p.flightAltitude;
    f.maxScanAngleRad = es::degToRad(p.maxScanAngleDeg);
    f.stripOverlap = p.stripOverlap;
    f.pulseDensity = p.pulseDensity;
    f.rangeNoise = p.rangeNoise;
    f.verticalBias = later ? p.verticalBiasLater : p.verticalBiasEarlier;
    f.maxReturns = p.maxReturns;
    f.deadDistance = p.deadDistance;
    f.echoContinuation = p.echoContinuation;
    return f;
}

inline float asprsClass(const ScannedPoint& s)
{
    if (s.kind == Ground)
        return 2.f;
    if (s.kind == Building)
        return 6.f;
    return s.heightAboveGround < 0.5 ? 3.f : (s.heightAboveGround < 2.0 ? 4.f : 5.f);
}

//! Whether a point's xy lies under any crown's footprint.
inline bool underCrown(const World& w, const Eigen::Vector3d& p)
{
    int r[4];
    w.crownGrid.cellRange(p.x(), p.y(), p.x(), p.y(), r);
    for (int id : w.crownGrid.cells[static_cast<std::size_t>(r[1]) * w.crownGrid.nx + r[0]]) {
        const Crown& c = w.crowns[id];
        const double u = (p.x() - c.centre.x()) / c.radii.x(), v = (p.y() - c.centre.y()) / c.radii.y();
        if (u * u + v * v < 1)
            return true;
    }
    return false;
}

//! Survey points to a cloud in global coordinates (+ the motion), its kinds and fields.
inline PointCloud toCloud(const AirborneEpochsParams& p, const std::vector<ScannedPoint>& pts, const Eigen::Matrix4d& motion,
                          const std::string& name, std::vector<std::uint8_t>& kinds)
{
    const Eigen::Vector3d shift = p.largeCoordinates ? Eigen::Vector3d(p.utmCorner.x(), p.utmCorner.y(), 0)
                                                     : Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> global(pts.size());
    std::vector<float> cls(pts.size());
    kinds.resize(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
        global[i] = es::apply(motion, pts[i].position + shift);
        kinds[i] = pts[i].kind;
        cls[i] = asprsClass(pts[i]);
    }
    PointCloud cloud = es::makeCloud(global, name);
    if (p.withClassification)
        es::addFieldValues(cloud, "classification", cls);
    return cloud;
}

} // namespace detail

namespace detail {

struct Worlds
{
    World earlier, later;
};

//! Both epochs' worlds for a canopy cover: the plants are drawn from their
//! own stream, so a larger cover keeps the same first plants and adds more.
inline Worlds buildWorlds(const AirborneEpochsParams& p, const Terrain& terrain, const std::vector<BuildingBox>& buildings,
                          const std::vector<Eigen::Vector2d>& path, double cover)
{
    SplitMix64 plantRng(p.seed, 5), bushRng(p.seed, 6);
    std::vector<Plant> plants = placePlants(p, cover, buildings, path, plantRng);
    addNewBushes(p, buildings, path, plants, bushRng);
    Worlds w;
    w.earlier.terrain = w.later.terrain = terrain;
    w.earlier.buildings = w.later.buildings = buildings;
    for (const auto& pl : plants) {
        if (pl.inEarlier)
            w.earlier.crowns.push_back(crownOf(pl, terrain, false, p.extinctionEarlier));
        w.later.crowns.push_back(crownOf(pl, terrain, true, p.extinctionLater));
    }
    w.earlier.index(p.side);
    w.later.index(p.side);
    return w;
}

//! Mean vegetation share of the two epochs from sparse pilot surveys.
inline double pilotShare(const AirborneEpochsParams& p, const Worlds& w)
{
    double share = 0;
    for (int e = 0; e < 2; ++e) {
        Flight f = flightOf(p, e == 1);
        f.pulseDensity = std::min(p.pulseDensity, 30000.0 / (p.side * p.side));
        SplitMix64 rng(p.seed, 7 + e);
        const auto pts = flySurvey(e == 0 ? w.earlier : w.later, p.side, f, rng);
        const auto veg = std::count_if(pts.begin(), pts.end(), [](const ScannedPoint& q) { return q.kind == Vegetation; });
        share += 0.5 * double(veg) / double(std::max<std::size_t>(1, pts.size()));
    }
    return share;
}

//! The worlds whose vegetation share is the wanted one: a first cover from a
//! model crown, then corrected on pilot surveys (crowns overlap, tall crowns
//! are seen from the side at 20 deg, the later epoch is larger), with the
//! one-parameter law share = c a / (c a + 1 - c).
inline Worlds calibratedWorlds(const AirborneEpochsParams& p, const Terrain& terrain,
                               const std::vector<BuildingBox>& buildings, const std::vector<Eigen::Vector2d>& path,
                               SplitMix64& rng)
{
    const double s = p.vegetationShare;
    double cover = coverForShare(p, rng);
    Worlds w = buildWorlds(p, terrain, buildings, path, cover);
    for (int pass = 0; pass < 3; ++pass) {
        const double measured = std::clamp(pilotShare(p, w), 0.01, 0.99);
        if (std::abs(measured - s) < 0.02)
            break;
        const double a = measured * (1 - cover) / (cover * (1 - measured));
        cover = std::clamp(s / (a * (1 - s) + s), 0.01, 0.9);
        w = buildWorlds(p, terrain, buildings, path, cover);
    }
    return w;
}

} // namespace detail

inline AirborneEpochsScene make(const AirborneEpochsParams& p)
{
    using namespace detail;
    SplitMix64 terrainRng(p.seed, 1), layoutRng(p.seed, 2), earlierRng(p.seed, 3), laterRng(p.seed, 4);
    const Terrain terrain = makeTerrain(p, terrainRng);
    const auto path = makePath(p, layoutRng);
    const auto buildings = makeBuildings(p, terrain, path, layoutRng);
    const Worlds w = calibratedWorlds(p, terrain, buildings, path, layoutRng);
    const auto earlierPts = flySurvey(w.earlier, p.side, flightOf(p, false), earlierRng);
    const auto laterPts = flySurvey(w.later, p.side, flightOf(p, true), laterRng);

    AirborneEpochsScene s;
    const Eigen::Vector3d shift = p.largeCoordinates ? Eigen::Vector3d(p.utmCorner.x(), p.utmCorner.y(), 0)
                                                     : Eigen::Vector3d::Zero();
    const Eigen::Vector3d pivot = shift + Eigen::Vector3d(p.side / 2, p.side / 2, terrain.height(p.side / 2, p.side / 2));
    s.appliedToLater = es::rigidMotion(p.motionAxis, p.motionAngleDeg, pivot, p.motionTranslation);
    s.trueLaterToEarlier = es::rigidInverse(s.appliedToLater);
    s.earlier = toCloud(p, earlierPts, Eigen::Matrix4d::Identity(), "als-earlier", s.earlierKind);
    s.later = toCloud(p, laterPts, s.appliedToLater, "als-later", s.laterKind);
    auto share = [](const std::vector<std::uint8_t>& k) {
        return k.empty() ? 0.0 : double(std::count(k.begin(), k.end(), Vegetation)) / double(k.size());
    };
    s.earlierVegetationShare = share(s.earlierKind);
    s.laterVegetationShare = share(s.laterKind);
    s.earlierPointDensity = double(earlierPts.size()) / (p.side * p.side);
    s.laterPointDensity = double(laterPts.size()) / (p.side * p.side);
    for (const auto& q : earlierPts)
        s.earlierGroundUnderCrowns += q.kind == Ground && underCrown(w.earlier, q.position);
    for (const auto& q : laterPts)
        s.laterGroundUnderCrowns += q.kind == Ground && underCrown(w.later, q.position);
    s.description = describe(p);
    return s;
}

// ---------------------------------------------------------------- scoring

//! How far a registration result is from the truth, measured on the later
//! epoch's points: d_i = E p_i - T p_i (E estimated, T true later->earlier).
struct AlignmentError
{
    double medianAbsDz = 0, p90AbsDz = 0;             //!< |d_i.z| over all later points (m)
    double medianAbsDzGround = 0, p90AbsDzGround = 0; //!< the same over the ground points
    double maxGroundDisplacement = 0;                 //!< max |d_i| (3D) over the ground points (m)
    double maxHorizontalGround = 0;                   //!< max horizontal |d_i| over the ground points (m)
    double rotationErrorDeg = 0;                      //!< angle of E.R * T.R^T
};

inline AlignmentError scoreAlignment(const PointCloud& later, const std::vector<std::uint8_t>& laterKind,
                                     const Eigen::Matrix4d& estimatedLaterToEarlier,
                                     const Eigen::Matrix4d& trueLaterToEarlier)
{
    AlignmentError e;
    std::vector<double> dz, dzGround;
    dz.reserve(later.size());
    for (std::size_t i = 0; i < later.size(); ++i) {
        const Eigen::Vector3d p = later.globalPosition(i);
        const Eigen::Vector3d d = es::apply(estimatedLaterToEarlier, p) - es::apply(trueLaterToEarlier, p);
        dz.push_back(std::abs(d.z()));
        if (i < laterKind.size() && laterKind[i] == detail::Ground) {
            dzGround.push_back(std::abs(d.z()));
            e.maxGroundDisplacement = std::max(e.maxGroundDisplacement, d.norm());
            e.maxHorizontalGround = std::max(e.maxHorizontalGround, d.head<2>().norm());
        }
    }
    e.medianAbsDz = es::quantile(dz, 0.5);
    e.p90AbsDz = es::quantile(dz, 0.9);
    e.medianAbsDzGround = es::quantile(dzGround, 0.5);
    e.p90AbsDzGround = es::quantile(dzGround, 0.9);
    e.rotationErrorDeg = es::rotationDifferenceDeg(estimatedLaterToEarlier, trueLaterToEarlier);
    return e;
}

//! Issue target of the synthetic park: the later epoch moves vertically by at
//! most 10 cm against the truth (median and p90 of |dz|).
inline bool meetsParkTarget(const AlignmentError& e, double tolerance = 0.10)
{
    return e.medianAbsDz <= tolerance && e.p90AbsDz <= tolerance;
}

//! Issue target of the real pair: back to the truth within 5 cm on every ground point.
inline bool meetsRealPairTarget(const AlignmentError& e, double tolerance = 0.05)
{
    return e.maxGroundDisplacement <= tolerance;
}

inline std::string describe(const AlignmentError& e)
{
    return es::format("|dz| median %.3f p90 %.3f (ground %.3f/%.3f) max ground 3D %.3f (horiz %.3f) m, rot %.4f deg",
                      e.medianAbsDz, e.p90AbsDz, e.medianAbsDzGround, e.p90AbsDzGround, e.maxGroundDisplacement,
                      e.maxHorizontalGround, e.rotationErrorDeg);
}

} // namespace scandiff::test::family::airborne

#include "AirborneRealPair.h"
