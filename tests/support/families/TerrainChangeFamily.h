// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Family B: change detection on a terrain from two independent samplings:
//! C2C distances (compared -> reference) then a local chi2 segmentation into
//! change regions. The distance field of unchanged ground is not zero: it is
//! the sampling distance between two independent point sets (about half the
//! reference spacing), plus noise and micro-relief, spatially correlated; a
//! change must stand out of that.
//!
//! Issue case (issueCase()): a 60 x 40 m undulating natural terrain (slopes to
//! 8 deg, 5 mm micro-relief at 0.4 m), sampled twice independently at random
//! positions, ~1 M compared points and as many reference points (spacing
//! 4.9 cm), 3 mm noise. In the compared epoch a 4 x 6 m block is raised 0.3 m
//! with 80 deg sides, and a 1 m diameter, 1.5 m high tank appeared (sampled on
//! its wall and top, hiding the terrain under it). Target with the tool's
//! defaults: at most 1 % of unchanged points flagged, each change its own
//! region holding at least 95 % of its changed points.
//!
//! Family (drawFamily): terrain extent 20-200 m; compared spacing 5 mm-10 cm
//! (log-uniform) with the sampled window limited to ~2 M points (fine spacing
//! means a window of a larger terrain); reference density 0.5-2 x the
//! compared's; noise 1-10 mm; micro-relief 1-20 mm at 0.1-1 m (never finer
//! than two spacings); slopes 2-20 deg; random or jittered-grid sampling; 1-4
//! changes among raised/lowered blocks (0.1-1 m, never below twice the
//! detectable change), appeared/removed cylinders and boxes, at most one
//! slump; UTM-like coordinates in half of the draws. `scale` shrinks the
//! window (then coarsens the spacing) down to ~60 k compared points.
//!
//! Truth per compared point: 0 unchanged, kAmbiguous, or a change id (1..).
//! A point is changed when its true distance to the reference surface
//! exceeds `detectableChange` = reference spacing + 3 sqrt(2) noise (below it
//! nobody could tell from C2C); points of a change below that, and points
//! within `ambiguityMargin` (the larger spacing) outside a change's border,
//! are ambiguous and left out of the scores. A slump gives two truth changes
//! (its lowered scarp and its raised toe, one `group`), with a near-zero band
//! between them.

#include "EpochSceneCommon.h"
#include "TerrainChangeGeometry.h"

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/SplitMix.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace scandiff::test::family::terrainchange {

constexpr int kUnchanged = 0;
constexpr int kAmbiguous = -1;

struct TerrainChangeParams
{
    std::uint64_t seed = 1;
    double sizeX = 60, sizeY = 40;        //!< sampled window (m)
    double terrainExtent = 60;            //!< size of the terrain the window belongs to (m): relief scale
    double comparedSpacing = 0.049;       //!< m: mean spacing, density = 1 / spacing^2 per m^2 of surface
    double referenceDensityRatio = 1.0;   //!< reference density / compared density
    double noise = 0.003;                 //!< m (1 sigma) along the normal, both epochs
    double roughness = 0.005;             //!< m, micro-relief amplitude (shared surface)
    double roughnessWavelength = 0.4;     //!< m
    double maxSlopeDeg = 8;               //!< steepest slope of the smooth relief
    double reliefWavelength = 25;         //!< m, typical undulation wavelength
    double baseElevation = 45;            //!< m
    bool jitteredGrid = false;            //!< terrain on a jittered xy grid instead of random positions
    bool largeCoordinates = false;
    Eigen::Vector2d utmCorner{651230.0, 6862410.0};
    std::vector<ChangeSpec> changes;
};

//! One truth change (a slump gives two: scarp and toe, same group).
struct ChangeTruth
{
    int id = 0;      //!< value in `truth`
    int group = 0;   //!< index of the ChangeSpec it comes from
    std::string label;
    double magnitude = 0;
    std::size_t changedPoints = 0, ambiguousPoints = 0;
};

struct TerrainChangeScene
{
    PointCloud reference, compared;
    std::vector<int> truth;         //!< per compared point: kUnchanged, kAmbiguous or a change id
    std::vector<float> trueChange;  //!< per compared point: true distance to the reference surface (m), 0 if unchanged
    std::vector<ChangeTruth> changes;
    double comparedSpacing = 0, referenceSpacing = 0;
    double detectableChange = 0, ambiguityMargin = 0;
    std::string description;
};

inline TerrainChangeParams issueCase()
{
    TerrainChangeParams p;
    ChangeSpec block;
    block.kind = ChangeKind::RaisedBlock;
    block.centre = {20, 22};
    block.headingDeg = 20;
    block.length = 6;
    block.width = 4;
    block.magnitude = 0.3;
    block.sideAngleDeg = 80;
    ChangeSpec tank;
    tank.kind = ChangeKind::AppearedCylinder;
    tank.centre = {42, 14};
    tank.length = 1.0;
    tank.width = 1.0;
    tank.magnitude = 1.5;
    p.changes = {block, tank};
    return p;
}

inline const char* kindName(ChangeKind k)
{
    switch (k) {
    case ChangeKind::RaisedBlock: return "raised block";
    case ChangeKind::LoweredBlock: return "lowered block";
    case ChangeKind::AppearedCylinder: return "appeared cylinder";
    case ChangeKind::RemovedCylinder: return "removed cylinder";
    case ChangeKind::AppearedBox: return "appeared box";
    case ChangeKind::RemovedBox: return "removed box";
    case ChangeKind::Slump: return "slump";
    }
    return "?";
}

inline double referenceSpacingOf(const TerrainChangeParams& p) { return p.comparedSpacing / std::sqrt(p.referenceDensityRatio); }

//! True change a careful surveyor could see in C2C: the reference sampling
//! distance (one spacing, twice the mean nearest-neighbour distance) plus
//! three sigma of the difference of two noisy surfaces.
inline double detectableChangeOf(const TerrainChangeParams& p)
{
    return referenceSpacingOf(p) + 3 * std::sqrt(2.0) * p.noise;
}

inline std::string describe(const TerrainChangeParams& p)
{
    std::string s = es::format("terrain seed=%llu %.1fx%.1fm spacing=%.4fm ref x%.2f noise=%.4fm rough=%.4fm@%.2fm slope<=%.0fdeg%s%s:",
                               static_cast<unsigned long long>(p.seed), p.sizeX, p.sizeY, p.comparedSpacing,
                               p.referenceDensityRatio, p.noise, p.roughness, p.roughnessWavelength, p.maxSlopeDeg,
                               p.jitteredGrid ? " grid" : "", p.largeCoordinates ? " UTM" : "");
    for (const auto& c : p.changes)
        s += es::format(" [%s %.2fx%.2fm %.2fm at %.1f,%.1f]", kindName(c.kind), c.length, c.width, c.magnitude,
                        c.centre.x(), c.centre.y());
    return s;
}

namespace detail {

//! Draws one change that fits the window, clear of the others.
inline bool drawChange(TerrainChangeParams& p, ChangeKind kind, SplitMix64& rng)
{
    const double w = std::min(p.sizeX, p.sizeY), s = std::max(p.comparedSpacing, referenceSpacingOf(p));
    const double delta = detectableChangeOf(p);
    ChangeSpec c;
    c.kind = kind;
    c.headingDeg = es::uniform(rng, 0, 180);
    c.sideAngleDeg = es::uniform(rng, 60, 88);
    if (kind == ChangeKind::RaisedBlock || kind == ChangeKind::LoweredBlock) {
        c.length = std::max(12 * s, es::uniform(rng, 0.08, 0.3) * w);
        c.width = std::max(12 * s, es::uniform(rng, 0.08, 0.3) * w);
        c.magnitude = std::max(es::uniform(rng, 0.1, 1.0), 2 * delta);
    } else if (kind == ChangeKind::Slump) {
        c.length = std::max(24 * s, es::uniform(rng, 0.15, 0.35) * w);
        c.width = std::max(12 * s, es::uniform(rng, 0.5, 0.8) * c.length);
        c.magnitude = std::clamp(es::uniform(rng, 0.1, 0.15) * c.length, 2 * delta, std::max(2 * delta, 1.0));
    } else {
        const double diameter = std::max({14 * s, 6 * delta, std::clamp(es::uniform(rng, 0.04, 0.12) * w, 0.2, 1.5)});
        c.length = diameter;
        c.width = (kind == ChangeKind::AppearedBox || kind == ChangeKind::RemovedBox) ? diameter * es::uniform(rng, 0.5, 1.5) : diameter;
        c.magnitude = std::max(es::uniform(rng, 0.5, 2.0), 3 * delta);
    }
    const double radius = 0.5 * std::hypot(c.length, c.width) + (c.kind == ChangeKind::Slump ? 0 : c.magnitude);
    for (int attempt = 0; attempt < 100; ++attempt) {
        c.centre = {es::uniform(rng, radius + 2 * s, p.sizeX - radius - 2 * s), es::uniform(rng, radius + 2 * s, p.sizeY - radius - 2 * s)};
        if (radius * 2 + 4 * s > w)
            return false;
        bool clear = true;
        for (const auto& o : p.changes)
            clear = clear && (o.centre - c.centre).norm() > radius + 0.5 * std::hypot(o.length, o.width) + o.magnitude + 10 * s;
        if (clear) {
            p.changes.push_back(c);
            return true;
        }
    }
    return false;
}

} // namespace detail

inline TerrainChangeParams drawFamily(std::uint64_t seed, double scale)
{
    SplitMix64 rng(seed, 0xB1);
    TerrainChangeParams p;
    p.seed = seed;
    scale = std::clamp(scale, 1e-4, 1.0);
    p.terrainExtent = es::logUniform(rng, 20, 200);
    const double aspect = es::uniform(rng, 0.6, 1.0);
    p.comparedSpacing = es::logUniform(rng, 0.005, 0.10);
    // The window: the whole terrain unless that exceeds ~2 M points at full scale.
    double side = std::min(p.terrainExtent, p.comparedSpacing * std::sqrt(2e6 / aspect));
    const double fullCount = side * side * aspect / (p.comparedSpacing * p.comparedSpacing);
    const double wanted = std::min(fullCount, std::max(6e4, fullCount * scale));
    side *= std::sqrt(wanted / fullCount);
    const double minSide = std::min(p.terrainExtent, 8.0);
    if (side < minSide) { // keep a useful window; coarsen the sampling instead
        side = minSide;
        p.comparedSpacing = std::min(0.10, side * std::sqrt(aspect / wanted));
    }
    p.sizeX = side;
    p.sizeY = side * aspect;
    p.referenceDensityRatio = es::logUniform(rng, 0.5, 2.0);
    p.noise = es::logUniform(rng, 0.001, 0.010);
    p.roughness = es::logUniform(rng, 0.001, 0.02);
    p.roughnessWavelength = std::max(2 * p.comparedSpacing, es::logUniform(rng, 0.1, 1.0));
    p.maxSlopeDeg = es::uniform(rng, 2, 20);
    p.reliefWavelength = p.terrainExtent * es::uniform(rng, 0.2, 0.6);
    p.baseElevation = es::uniform(rng, 0, 2000);
    p.jitteredGrid = rng.uniform() < 0.3;
    p.largeCoordinates = rng.uniform() < 0.5;
    p.utmCorner = {es::uniform(rng, 3e5, 7e5), es::uniform(rng, 4.5e6, 6.9e6)};
    const int count = 1 + static_cast<int>(rng.below(4));
    bool slump = false;
    for (int i = 0; i < count; ++i) {
        auto kind = static_cast<ChangeKind>(rng.below(7));
        if (kind == ChangeKind::Slump && slump)
            kind = ChangeKind::RaisedBlock;
        slump = slump || kind == ChangeKind::Slump;
        detail::drawChange(p, kind, rng);
    }
    if (p.changes.empty()) // the window was too small for the drawn kind: a block always fits
        detail::drawChange(p, ChangeKind::RaisedBlock, rng);
    return p;
}

namespace detail {

inline Relief makeRelief(const TerrainChangeParams& p)
{
    SplitMix64 rng(p.seed, 0xB2);
    Relief r;
    r.base = p.baseElevation;
    r.noise = es::ValueNoise2(splitMix(p.seed ^ 0xB3));
    r.roughness = p.roughness;
    r.roughnessWavelength = p.roughnessWavelength;
    const double budget = std::tan(es::degToRad(p.maxSlopeDeg));
    double weights[4], sum = 0;
    for (double& w : weights)
        sum += (w = es::uniform(rng, 0.5, 1.0));
    for (double w : weights) {
        const double wavelength = p.reliefWavelength * es::uniform(rng, 0.5, 1.5), k = 2 * es::kPi / wavelength;
        const double dir = es::uniform(rng, 0, 2 * es::kPi);
        r.waves.push_back({k * Eigen::Vector2d(std::cos(dir), std::sin(dir)), budget * (w / sum) / k, es::uniform(rng, 0, 2 * es::kPi)});
    }
    return r;
}

inline std::vector<Sample> sampleEpoch(const TerrainChangeParams& p, const Relief& relief, const std::vector<ChangeGeom>& geoms,
                                       bool compared, SplitMix64& rng)
{
    EpochSurface s;
    s.relief = &relief;
    for (const auto& g : geoms) {
        if (g.isObject() && g.inCompared() == compared)
            s.objects.push_back(&g);
        if (!g.isObject() && compared)
            s.deformations.push_back(&g);
    }
    const double density = (compared ? 1.0 : p.referenceDensityRatio) / (p.comparedSpacing * p.comparedSpacing);
    std::vector<Sample> out;
    out.reserve(static_cast<std::size_t>(density * p.sizeX * p.sizeY * 1.05));
    sampleTerrain(s, p.sizeX, p.sizeY, density, p.jitteredGrid, rng, out);
    for (std::size_t i = 0; i < geoms.size(); ++i) {
        if (compared && geoms[i].isBlock())
            sampleBlockSides(s, geoms[i], static_cast<int>(i), density, rng, out);
        if (geoms[i].isObject() && geoms[i].inCompared() == compared)
            sampleObject(relief, geoms[i], static_cast<int>(i), density, rng, out);
    }
    return out;
}

//! True change magnitude of a compared sample against change g (0 if none) and
//! whether the sample is in g's zone (its footprint or within `margin` of it).
inline double changeAt(const Sample& q, const ChangeGeom& g, int index, int lobe, const Relief& relief, double margin, bool& inZone)
{
    const Eigen::Vector2d p = q.truePosition.head<2>();
    inZone = false;
    if (q.change == index) { // the change's own surface: block side, wall, top
        inZone = true;
        return q.source == Source::BlockSide ? std::abs(g.blockLift(p)) : q.truePosition.z() - relief.height(p.x(), p.y());
    }
    if (q.source != Source::Terrain)
        return 0;
    if (g.isBlock()) {
        const double d = g.rectDistance(p);
        inZone = d < g.band + margin;
        return d == 0 ? g.spec.magnitude : 0;
    }
    if (g.spec.kind == ChangeKind::Slump) {
        inZone = g.inLobe(p, lobe, margin);
        return std::abs(g.lobe(p, lobe));
    }
    const double f = g.footprintDistance(p); // objects: terrain near or under them
    inZone = f < margin;
    return g.inCompared() ? 0 : std::max(0.0, -f); // removed: distance to the walls that stood there
}

} // namespace detail

inline TerrainChangeScene make(const TerrainChangeParams& p)
{
    using namespace detail;
    const Relief relief = makeRelief(p);
    std::vector<ChangeGeom> geoms;
    for (const auto& c : p.changes)
        geoms.push_back(makeGeom(c, relief));
    SplitMix64 refRng(p.seed, 0xB4), cmpRng(p.seed, 0xB5), noiseRng(p.seed, 0xB6);
    const auto ref = sampleEpoch(p, relief, geoms, false, refRng);
    const auto cmp = sampleEpoch(p, relief, geoms, true, cmpRng);

    TerrainChangeScene s;
    s.comparedSpacing = p.comparedSpacing;
    s.referenceSpacing = referenceSpacingOf(p);
    s.detectableChange = detectableChangeOf(p);
    s.ambiguityMargin = std::max(s.comparedSpacing, s.referenceSpacing);
    // Truth entries: one per change, two for a slump (scarp -1, toe +1).
    struct Entry { int geom, lobe; };
    std::vector<Entry> entries;
    for (int i = 0; i < static_cast<int>(geoms.size()); ++i) {
        const bool slump = geoms[i].spec.kind == ChangeKind::Slump;
        for (int lobe : slump ? std::vector<int>{-1, 1} : std::vector<int>{0}) {
            entries.push_back({i, lobe});
            ChangeTruth t;
            t.id = static_cast<int>(entries.size());
            t.group = i;
            t.label = std::string(kindName(geoms[i].spec.kind)) + (lobe < 0 ? " scarp" : lobe > 0 ? " toe" : "");
            t.magnitude = geoms[i].spec.magnitude;
            s.changes.push_back(t);
        }
    }
    s.truth.assign(cmp.size(), kUnchanged);
    s.trueChange.assign(cmp.size(), 0.f);
    for (std::size_t k = 0; k < cmp.size(); ++k)
        for (std::size_t e = 0; e < entries.size(); ++e) {
            bool inZone = false;
            const double m = changeAt(cmp[k], geoms[entries[e].geom], entries[e].geom, entries[e].lobe, relief, s.ambiguityMargin, inZone);
            if (m > s.detectableChange && s.truth[k] <= 0) {
                s.truth[k] = static_cast<int>(e) + 1;
                s.trueChange[k] = static_cast<float>(m);
            } else if (inZone && s.truth[k] == kUnchanged) {
                s.truth[k] = kAmbiguous;
                s.trueChange[k] = static_cast<float>(m);
            }
        }
    for (int t : s.truth)
        if (t > 0)
            ++s.changes[t - 1].changedPoints;
    const Eigen::Vector3d shift = p.largeCoordinates ? Eigen::Vector3d(p.utmCorner.x(), p.utmCorner.y(), 0) : Eigen::Vector3d::Zero();
    auto toGlobal = [&](const std::vector<Sample>& v) {
        std::vector<Eigen::Vector3d> g(v.size());
        for (std::size_t i = 0; i < v.size(); ++i)
            g[i] = shift + v[i].truePosition + p.noise * es::gaussian(noiseRng) * v[i].normal;
        return g;
    };
    s.reference = es::makeCloud(toGlobal(ref), "terrain-reference");
    s.compared = es::makeCloud(toGlobal(cmp), "terrain-compared");
    s.description = describe(p);
    return s;
}

// ---------------------------------------------------------------- scoring

struct ChangeScore
{
    int id = 0;
    std::string label;
    std::size_t changedPoints = 0, flaggedPoints = 0; //!< flagged: in any region
    double largestShare = 0;        //!< largest share of its changed points held by one region
    std::int64_t bestRegion = 0;    //!< that region (0 if none)
    bool merged = false;            //!< that region also holds changed points of another change (other group)
};

struct SegmentationScore
{
    std::size_t unchangedPoints = 0, unchangedFlagged = 0;
    double unchangedFlaggedFraction = 0;
    std::vector<ChangeScore> changes;
    std::size_t regions = 0;
    std::size_t falseRegions = 0;               //!< regions holding no changed point
    std::size_t falseRegionsAwayFromChanges = 0; //!< ... nor any ambiguous point (wholly in unchanged ground)
    std::size_t largestFalseRegion = 0;         //!< points
};

//! Scores per-point region ids of the compared cloud: an id <= 0 means not
//! flagged (unchanged), any positive id is a change region.
template <typename Id>
SegmentationScore scoreSegmentation(const TerrainChangeScene& scene, const std::vector<Id>& regionIds)
{
    SegmentationScore r;
    struct Tally { std::size_t points = 0, ambiguous = 0; std::map<int, std::size_t> changed; };
    std::map<std::int64_t, Tally> regions;
    std::vector<std::size_t> flagged(scene.changes.size(), 0);
    for (std::size_t i = 0; i < scene.truth.size(); ++i) {
        const auto id = i < regionIds.size() ? static_cast<std::int64_t>(regionIds[i]) : 0;
        const int t = scene.truth[i];
        r.unchangedPoints += t == kUnchanged;
        if (id <= 0)
            continue;
        Tally& tally = regions[id];
        ++tally.points;
        if (t == kUnchanged)
            ++r.unchangedFlagged;
        else if (t == kAmbiguous)
            ++tally.ambiguous;
        else {
            ++tally.changed[t];
            ++flagged[t - 1];
        }
    }
    r.unchangedFlaggedFraction = r.unchangedPoints ? double(r.unchangedFlagged) / double(r.unchangedPoints) : 0;
    r.regions = regions.size();
    for (const auto& [id, tally] : regions)
        if (tally.changed.empty()) {
            ++r.falseRegions;
            r.falseRegionsAwayFromChanges += tally.ambiguous == 0;
            r.largestFalseRegion = std::max(r.largestFalseRegion, tally.points);
        }
    for (const auto& c : scene.changes) {
        ChangeScore cs;
        cs.id = c.id;
        cs.label = c.label;
        cs.changedPoints = c.changedPoints;
        cs.flaggedPoints = flagged[c.id - 1];
        std::size_t best = 0;
        for (const auto& [id, tally] : regions) {
            const auto it = tally.changed.find(c.id);
            if (it != tally.changed.end() && it->second > best) {
                best = it->second;
                cs.bestRegion = id;
            }
        }
        cs.largestShare = c.changedPoints ? double(best) / double(c.changedPoints) : 0;
        if (best > 0)
            for (const auto& [other, n] : regions[cs.bestRegion].changed)
                cs.merged = cs.merged || (n > 0 && scene.changes[other - 1].group != c.group);
        r.changes.push_back(cs);
    }
    return r;
}

//! Issue targets: at most `maxUnchangedFlagged` of unchanged points flagged;
//! every change held at >= `minShare` by its own region, not merged with another.
inline bool meetsIssueTargets(const SegmentationScore& s, double maxUnchangedFlagged = 0.01, double minShare = 0.95)
{
    if (s.unchangedFlaggedFraction > maxUnchangedFlagged)
        return false;
    for (const auto& c : s.changes)
        if (c.largestShare < minShare || c.merged)
            return false;
    return true;
}

inline std::string describe(const SegmentationScore& s)
{
    std::string out = es::format("unchanged flagged %.3f%% (%zu/%zu), %zu regions, %zu false (%zu away, largest %zu pts);",
                                 100 * s.unchangedFlaggedFraction, s.unchangedFlagged, s.unchangedPoints, s.regions,
                                 s.falseRegions, s.falseRegionsAwayFromChanges, s.largestFalseRegion);
    for (const auto& c : s.changes)
        out += es::format(" [%d %s: %zu changed, %.1f%% flagged, best region %lld holds %.1f%%%s]", c.id, c.label.c_str(),
                          c.changedPoints, c.changedPoints ? 100.0 * c.flaggedPoints / c.changedPoints : 0.0,
                          static_cast<long long>(c.bestRegion), 100 * c.largestShare, c.merged ? " MERGED" : "");
    return out;
}

} // namespace scandiff::test::family::terrainchange
