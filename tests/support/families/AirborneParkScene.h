// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The world and the airborne scanner behind AirborneEpochsFamily.h.
//!
//! World: an analytic terrain (regional tilt plus a few long sinusoidal
//! undulations), flat-roofed buildings (oriented boxes), and plants whose
//! crowns are ellipsoids of foliage with a Beer-Lambert extinction
//! coefficient (1/m): a pulse entering a crown returns at a random depth
//! (exponential free path); what is left of the pulse after an echo goes on
//! only with some probability (the energy a crown intercepts is lost) and may
//! give further echoes deeper in the crown or on the ground (multiple returns,
//! separated by the receiver's dead distance); a pulse may also pass through. So canopy points fill the crown volume and
//! some ground is seen under trees: fewer when the crowns are denser.
//!
//! Scanner: an aircraft flies parallel strips (with side overlap) at a height
//! above the terrain, its mirror sweeping across track within +-maxScanAngle;
//! scan lines are jittered (attitude), each pulse is a ray cast into the
//! world, and the range carries Gaussian noise along the ray.

#include "EpochSceneCommon.h"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace scandiff::test::family::airborne::detail {

namespace es = epochscene;

//! What a return hit (the truth, independent of any classification field).
enum SurfaceKind : std::uint8_t { Ground = 0, Building = 1, Vegetation = 2 };

struct Wave
{
    Eigen::Vector2d k; //!< wave vector (rad/m)
    double amplitude = 0, phase = 0;
};

struct Terrain
{
    double base = 0;                                //!< elevation at the scene corner (m)
    Eigen::Vector2d tilt = Eigen::Vector2d::Zero(); //!< regional gradient (m/m)
    std::vector<Wave> waves;

    double height(double x, double y) const
    {
        double z = base + tilt.x() * x + tilt.y() * y;
        for (const auto& w : waves)
            z += w.amplitude * std::sin(w.k.x() * x + w.k.y() * y + w.phase);
        return z;
    }
    Eigen::Vector2d gradient(double x, double y) const
    {
        Eigen::Vector2d g = tilt;
        for (const auto& w : waves)
            g += w.amplitude * std::cos(w.k.x() * x + w.k.y() * y + w.phase) * w.k;
        return g;
    }
};

struct BuildingBox
{
    Eigen::Vector2d centre;
    double halfLength = 5, halfWidth = 4, headingRad = 0;
    double zBase = 0, zRoof = 5; //!< absolute elevations
};

struct Crown
{
    Eigen::Vector3d centre; //!< absolute
    Eigen::Vector3d radii;  //!< semi-axes x, y, z (m)
    double extinction = 0.3; //!< 1/m
};

//! A uniform grid of object indices over the xy plane: a near-vertical ray
//! only meets the objects of the few cells its xy shadow crosses.
struct ObjectGrid
{
    double cell = 8.0;
    Eigen::Vector2d lo = Eigen::Vector2d::Zero();
    int nx = 1, ny = 1;
    std::vector<std::vector<int>> cells;

    void init(const Eigen::Vector2d& low, const Eigen::Vector2d& high, double cellSize)
    {
        cell = cellSize;
        lo = low;
        nx = std::max(1, static_cast<int>(std::ceil((high.x() - low.x()) / cell)));
        ny = std::max(1, static_cast<int>(std::ceil((high.y() - low.y()) / cell)));
        cells.assign(static_cast<std::size_t>(nx) * ny, {});
    }
    void cellRange(double x0, double y0, double x1, double y1, int r[4]) const
    {
        r[0] = std::clamp(static_cast<int>(std::floor((x0 - lo.x()) / cell)), 0, nx - 1);
        r[1] = std::clamp(static_cast<int>(std::floor((y0 - lo.y()) / cell)), 0, ny - 1);
        r[2] = std::clamp(static_cast<int>(std::floor((x1 - lo.x()) / cell)), 0, nx - 1);
        r[3] = std::clamp(static_cast<int>(std::floor((y1 - lo.y()) / cell)), 0, ny - 1);
    }
    void insert(int id, double x0, double y0, double x1, double y1)
    {
        int r[4];
        cellRange(x0, y0, x1, y1, r);
        for (int j = r[1]; j <= r[3]; ++j)
            for (int i = r[0]; i <= r[2]; ++i)
                cells[static_cast<std::size_t>(j) * nx + i].push_back(id);
    }
};

//! One epoch's world, ready for ray casting.
struct World
{
    Terrain terrain;
    std::vector<BuildingBox> buildings;
    std::vector<Crown> crowns;
    double zTop = 0, zBottom = 0; //!< elevation range of everything
    ObjectGrid crownGrid, buildingGrid;

    void index(double side)
    {
        const Eigen::Vector2d lo(-40, -40), hi(side + 40, side + 40);
        crownGrid.init(lo, hi, 8.0);
        buildingGrid.init(lo, hi, 8.0);
        zTop = -1e9;
        zBottom = 1e9;
        for (int c = 0; c < static_cast<int>(crowns.size()); ++c) {
            const Crown& k = crowns[c];
            crownGrid.insert(c, k.centre.x() - k.radii.x(), k.centre.y() - k.radii.y(), k.centre.x() + k.radii.x(),
                             k.centre.y() + k.radii.y());
            zTop = std::max(zTop, k.centre.z() + k.radii.z());
        }
        for (int b = 0; b < static_cast<int>(buildings.size()); ++b) {
            const BuildingBox& h = buildings[b];
            const double r = std::hypot(h.halfLength, h.halfWidth);
            buildingGrid.insert(b, h.centre.x() - r, h.centre.y() - r, h.centre.x() + r, h.centre.y() + r);
            zTop = std::max(zTop, h.zRoof);
            zBottom = std::min(zBottom, h.zBase);
        }
        // Terrain range from a coarse scan (the waves are long: 2 m is plenty).
        for (double y = -40; y <= side + 40; y += 2.0)
            for (double x = -40; x <= side + 40; x += 2.0) {
                const double z = terrain.height(x, y);
                zTop = std::max(zTop, z);
                zBottom = std::min(zBottom, z);
            }
        zTop += 1.0;
        zBottom -= 1.0;
    }
};

//! Ray-terrain intersection by Newton's method on z_ray(t) - h(xy(t)): the
//! ray is within 20-25 deg of vertical and slopes stay below ~25 deg, so the
//! derivative keeps its sign and a few steps reach micrometres.
inline double terrainHit(const Terrain& t, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double zGuess)
{
    double s = (o.z() - zGuess) / -d.z();
    for (int it = 0; it < 12; ++it) {
        const double x = o.x() + s * d.x(), y = o.y() + s * d.y();
        const double f = o.z() + s * d.z() - t.height(x, y);
        const double df = d.z() - t.gradient(x, y).dot(d.head<2>());
        const double step = f / df;
        s -= step;
        if (std::abs(step) < 1e-7)
            break;
    }
    return s;
}

//! Entry distance of a ray into an oriented box (infinity when missed).
inline double buildingHit(const BuildingBox& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d)
{
    const double c = std::cos(b.headingRad), s = std::sin(b.headingRad);
    const Eigen::Vector2d rel = o.head<2>() - b.centre;
    const double lo3[3] = {-b.halfLength, -b.halfWidth, b.zBase};
    const double hi3[3] = {b.halfLength, b.halfWidth, b.zRoof};
    const double oo[3] = {c * rel.x() + s * rel.y(), -s * rel.x() + c * rel.y(), o.z()};
    const double dd[3] = {c * d.x() + s * d.y(), -s * d.x() + c * d.y(), d.z()};
    double t0 = 0, t1 = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
        if (std::abs(dd[a]) < 1e-12) {
            if (oo[a] < lo3[a] || oo[a] > hi3[a])
                return std::numeric_limits<double>::infinity();
            continue;
        }
        double ta = (lo3[a] - oo[a]) / dd[a], tb = (hi3[a] - oo[a]) / dd[a];
        if (ta > tb)
            std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1)
            return std::numeric_limits<double>::infinity();
    }
    return t0;
}

//! Entry and exit distances of a ray through an ellipsoid crown.
inline bool crownSpan(const Crown& c, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& t0, double& t1)
{
    const Eigen::Vector3d oo = (o - c.centre).cwiseQuotient(c.radii), dd = d.cwiseQuotient(c.radii);
    const double a = dd.squaredNorm(), b = 2.0 * oo.dot(dd), cc = oo.squaredNorm() - 1.0;
    const double disc = b * b - 4.0 * a * cc;
    if (disc <= 0)
        return false;
    const double q = std::sqrt(disc);
    t0 = (-b - q) / (2.0 * a);
    t1 = (-b + q) / (2.0 * a);
    return t1 > 0;
}

struct PulseReturn
{
    Eigen::Vector3d position; //!< scene frame, noise-free along the ray
    double range = 0;
    SurfaceKind kind = Ground;
};

struct CrownSpan
{
    double t0, t1, k;
};

//! Candidate object ids of a grid along the xy shadow of the ray between the
//! world's top and bottom elevations (each id once: `stamp` marks them).
inline void gatherCandidates(const ObjectGrid& g, const World& w, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                             std::vector<std::uint32_t>& stamp, std::uint32_t pulse, std::vector<int>& out)
{
    out.clear();
    const double ta = (o.z() - w.zTop) / -d.z(), tb = (o.z() - w.zBottom) / -d.z();
    const Eigen::Vector3d a = o + ta * d, b = o + tb * d;
    int r[4];
    g.cellRange(std::min(a.x(), b.x()), std::min(a.y(), b.y()), std::max(a.x(), b.x()), std::max(a.y(), b.y()), r);
    for (int j = r[1]; j <= r[3]; ++j)
        for (int i = r[0]; i <= r[2]; ++i)
            for (int id : g.cells[static_cast<std::size_t>(j) * g.nx + i])
                if (stamp[id] != pulse) {
                    stamp[id] = pulse;
                    out.push_back(id);
                }
}

//! Scratch space of castPulse (reused between pulses).
struct CastScratch
{
    std::vector<std::uint32_t> crownStamp, buildingStamp;
    std::vector<int> candidates;
    std::vector<CrownSpan> spans;
    std::uint32_t pulse = 0;
};

//! Optical depth per metre at distance t along the ray (overlapping crowns add).
inline double extinctionAt(const std::vector<CrownSpan>& spans, double t)
{
    double k = 0;
    for (const auto& s : spans)
        if (t >= s.t0 && t < s.t1)
            k += s.k;
    return k;
}

//! Start of the next foliage span after t (infinity if none).
inline double nextSpanStart(const std::vector<CrownSpan>& spans, double t)
{
    double n = std::numeric_limits<double>::infinity();
    for (const auto& s : spans)
        if (s.t0 > t)
            n = std::min(n, s.t0);
    return n;
}

//! Casts one pulse; appends its returns (foliage first, then the hard surface
//! if the pulse got through and returns are left).
inline void castPulse(const World& w, const Eigen::Vector3d& o, const Eigen::Vector3d& d, int maxReturns,
                      double deadDistance, double continuation, SplitMix64& rng, CastScratch& sc,
                      std::vector<PulseReturn>& out)
{
    ++sc.pulse;
    double tSurface = terrainHit(w.terrain, o, d, 0.5 * (w.zTop + w.zBottom));
    SurfaceKind surface = Ground;
    gatherCandidates(w.buildingGrid, w, o, d, sc.buildingStamp, sc.pulse, sc.candidates);
    for (int b : sc.candidates) {
        const double t = buildingHit(w.buildings[b], o, d);
        if (t < tSurface) {
            tSurface = t;
            surface = Building;
        }
    }
    gatherCandidates(w.crownGrid, w, o, d, sc.crownStamp, sc.pulse, sc.candidates);
    sc.spans.clear();
    for (int c : sc.candidates) {
        double t0, t1;
        if (crownSpan(w.crowns[c], o, d, t0, t1) && t0 < tSurface)
            sc.spans.push_back({std::max(t0, 0.0), std::min(t1, tSurface), w.crowns[c].extinction});
    }
    int returns = 0;
    double t = nextSpanStart(sc.spans, -1.0);
    double freePath = -std::log(1.0 - rng.uniform()); // optical depth to the next interaction
    constexpr double step = 0.1;                     // metres of marching through foliage
    while (t < tSurface && returns < maxReturns) {
        const double k = extinctionAt(sc.spans, t);
        if (k <= 0) {
            t = nextSpanStart(sc.spans, t);
            continue;
        }
        const double len = std::min(step, tSurface - t);
        if (k * len >= freePath) {
            const double tr = t + freePath / k;
            out.push_back({o + tr * d, tr, Vegetation});
            ++returns;
            if (rng.uniform() >= continuation)
                return; // the crown took what the receiver could still detect
            t = tr + deadDistance; // the receiver cannot separate closer echoes
            freePath = -std::log(1.0 - rng.uniform());
        } else {
            freePath -= k * len;
            t += len;
        }
    }
    const double lastT = out.empty() || returns == 0 ? -1e9 : out.back().range;
    if (returns < maxReturns && std::isfinite(tSurface) && tSurface - lastT >= deadDistance)
        out.push_back({o + tSurface * d, tSurface, surface});
}

//! Flight geometry of one epoch's survey.
struct Flight
{
    double headingRad = 0;       //!< flight direction from +x
    double altitude = 800;       //!< above the mean terrain (m)
    double maxScanAngleRad = 0.35;
    double stripOverlap = 0.3;   //!< side overlap of neighbouring strips (0..1)
    double pulseDensity = 0.7;   //!< mean pulses per m^2 over the area (strips summed)
    double rangeNoise = 0.025;   //!< m, along the ray
    double verticalBias = 0;     //!< m, added to every z of the epoch (GNSS/INS)
    int maxReturns = 4;
    double deadDistance = 1.2;   //!< m between separable echoes
    double echoContinuation = 0.4; //!< probability a pulse goes on after a foliage echo
};

struct ScannedPoint
{
    Eigen::Vector3d position; //!< scene frame (x, y in [0, side], absolute z)
    SurfaceKind kind;
    double heightAboveGround;
};

//! Flies the strips needed to cover [0, side]^2 and keeps the returns inside it.
inline std::vector<ScannedPoint> flySurvey(const World& w, double side, const Flight& f, SplitMix64& rng)
{
    const Eigen::Vector2d along(std::cos(f.headingRad), std::sin(f.headingRad)), across(-along.y(), along.x());
    double aMin = 1e300, aMax = -1e300, cMin = 1e300, cMax = -1e300;
    for (int corner = 0; corner < 4; ++corner) {
        const Eigen::Vector2d p((corner & 1) * side, (corner >> 1) * side);
        aMin = std::min(aMin, p.dot(along));
        aMax = std::max(aMax, p.dot(along));
        cMin = std::min(cMin, p.dot(across));
        cMax = std::max(cMax, p.dot(across));
    }
    const double meanZ = w.terrain.height(side / 2, side / 2), flyZ = meanZ + f.altitude;
    const double halfSwath = f.altitude * std::tan(f.maxScanAngleRad);
    const double lineSpacing = 2.0 * halfSwath * (1.0 - f.stripOverlap);
    const double singleStripDensity = f.pulseDensity * lineSpacing / (2.0 * halfSwath);
    const double spacing = 1.0 / std::sqrt(singleStripDensity); // along and across at nadir
    const double angleStep = spacing / f.altitude;
    CastScratch sc;
    sc.crownStamp.assign(w.crowns.size(), 0);
    sc.buildingStamp.assign(w.buildings.size(), 0);
    std::vector<PulseReturn> returns;
    std::vector<ScannedPoint> points;
    const double firstLine = cMin - halfSwath + es::uniform(rng, 0.0, lineSpacing);
    for (double c = firstLine; c < cMax + halfSwath; c += lineSpacing) {
        // Only the part of the sweep that can land in the area (+30 m for the heights).
        const double thLo = std::max(-f.maxScanAngleRad, std::atan((cMin - 30 - c) / f.altitude));
        const double thHi = std::min(f.maxScanAngleRad, std::atan((cMax + 30 - c) / f.altitude));
        if (thLo >= thHi)
            continue;
        for (double a = aMin - 30 + es::uniform(rng, 0.0, spacing); a < aMax + 30; a += spacing) {
            const double aJitter = a + 0.15 * spacing * es::gaussian(rng); // pitch wobble
            const double phase = es::uniform(rng, 0.0, angleStep);
            for (double th = thLo + phase; th < thHi; th += angleStep) {
                const Eigen::Vector2d xy = along * aJitter + across * c;
                const Eigen::Vector3d o(xy.x(), xy.y(), flyZ);
                const Eigen::Vector3d d(across.x() * std::sin(th), across.y() * std::sin(th), -std::cos(th));
                returns.clear();
                castPulse(w, o, d, f.maxReturns, f.deadDistance, f.echoContinuation, rng, sc, returns);
                for (const auto& r : returns) {
                    if (r.position.x() < 0 || r.position.y() < 0 || r.position.x() > side || r.position.y() > side)
                        continue;
                    Eigen::Vector3d p = o + (r.range + f.rangeNoise * es::gaussian(rng)) * d;
                    p.z() += f.verticalBias;
                    const double hag = r.position.z() - w.terrain.height(r.position.x(), r.position.y());
                    points.push_back({p, r.kind, hag});
                }
            }
        }
    }
    return points;
}

} // namespace scandiff::test::family::airborne::detail
