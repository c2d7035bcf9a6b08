// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The surfaces behind TerrainChangeFamily.h and how a survey samples them.
//!
//! Terrain: long smooth undulations (a few sinusoids) plus a micro-relief of
//! value noise (stones, clods, grass tussocks) that both epochs share: it is
//! the surface, not measurement noise. Changes: blocks lifted or lowered with
//! steep sides (a side band whose slope is the side angle), a slump (a scarp
//! lowered above a toe bulging below it, along the fall line), objects
//! (vertical cylinders and boxes standing on the terrain, top flat at terrain
//! height at the centre + height) that appear or are removed. An object hides
//! the terrain under it in the epoch where it stands.
//!
//! Sampling: points uniform per unit of *surface* area (a random survey of
//! density lambda: the terrain by rejection on sqrt(1 + |grad z|^2), the steep
//! block sides, object walls and tops on their own), or, as an option, the
//! terrain on a jittered xy grid (one point per cell, as gridded products and
//! many ALS/photogrammetric clouds are). Noise: Gaussian along the surface normal.

#include "EpochSceneCommon.h"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace scandiff::test::family::terrainchange {

namespace es = epochscene;

enum class ChangeKind { RaisedBlock, LoweredBlock, AppearedCylinder, RemovedCylinder, AppearedBox, RemovedBox, Slump };

//! One change between the epochs (scene frame: x, y in [0, size], metres).
struct ChangeSpec
{
    ChangeKind kind = ChangeKind::RaisedBlock;
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    double headingDeg = 0;  //!< orientation of blocks and boxes (slumps follow the fall line)
    double length = 4;      //!< m: block/box side along the heading; cylinder diameter; slump length along the fall line
    double width = 3;       //!< m: block/box side across; slump width (ignored for cylinders)
    double magnitude = 0.3; //!< m: block lift or drop; object height; slump scarp depth (= toe bulge)
    double sideAngleDeg = 80; //!< steepness of a block's sides
};

namespace detail {

struct Wave
{
    Eigen::Vector2d k;
    double amplitude = 0, phase = 0;
};

//! The shared terrain surface: smooth relief + micro-relief.
struct Relief
{
    double base = 0;
    std::vector<Wave> waves;
    es::ValueNoise2 noise{0};
    double roughness = 0, roughnessWavelength = 0.3;

    double smooth(double x, double y) const
    {
        double z = base;
        for (const auto& w : waves)
            z += w.amplitude * std::sin(w.k.x() * x + w.k.y() * y + w.phase);
        return z;
    }
    double rough(double x, double y) const
    {
        if (roughness <= 0)
            return 0;
        const double u = x / roughnessWavelength, v = y / roughnessWavelength;
        return roughness * (0.7 * noise(u, v) + 0.3 * noise(2.03 * u + 17.1, 2.03 * v - 3.7));
    }
    double height(double x, double y) const { return smooth(x, y) + rough(x, y); }
    Eigen::Vector2d gradient(double x, double y) const
    {
        Eigen::Vector2d g = Eigen::Vector2d::Zero();
        for (const auto& w : waves)
            g += w.amplitude * std::cos(w.k.x() * x + w.k.y() * y + w.phase) * w.k;
        if (roughness > 0) {
            const double h = 0.01 * roughnessWavelength;
            g += Eigen::Vector2d(rough(x + h, y) - rough(x - h, y), rough(x, y + h) - rough(x, y - h)) / (2 * h);
        }
        return g;
    }
};

//! A change made geometric: frames, signed lift, footprints.
struct ChangeGeom
{
    ChangeSpec spec;
    Eigen::Vector2d c, axisU, axisV; //!< centre and local axes (u along heading / fall line)
    double halfU = 0, halfV = 0;     //!< half sizes (blocks, boxes); lobe half-length / half-width (slump)
    double band = 0;                 //!< block side band width (m)
    double top = 0;                  //!< object top elevation

    bool isBlock() const { return spec.kind == ChangeKind::RaisedBlock || spec.kind == ChangeKind::LoweredBlock; }
    bool isObject() const { return !isBlock() && spec.kind != ChangeKind::Slump; }
    bool isCylinder() const { return spec.kind == ChangeKind::AppearedCylinder || spec.kind == ChangeKind::RemovedCylinder; }
    bool inCompared() const
    {
        return spec.kind != ChangeKind::RemovedCylinder && spec.kind != ChangeKind::RemovedBox;
    }
    Eigen::Vector2d local(const Eigen::Vector2d& p) const { return {(p - c).dot(axisU), (p - c).dot(axisV)}; }

    //! Blocks: distance from the top rectangle (0 on it) and its outward direction.
    double rectDistance(const Eigen::Vector2d& p, Eigen::Vector2d* outward = nullptr) const
    {
        const Eigen::Vector2d q = local(p);
        const Eigen::Vector2d e(std::max(std::abs(q.x()) - halfU, 0.0), std::max(std::abs(q.y()) - halfV, 0.0));
        const double d = e.norm();
        if (outward && d > 0) {
            const Eigen::Vector2d el(std::copysign(e.x(), q.x()), std::copysign(e.y(), q.y()));
            *outward = (el.x() * axisU + el.y() * axisV) / d;
        }
        return d;
    }
    double blockLift(const Eigen::Vector2d& p) const
    {
        const double h = spec.kind == ChangeKind::RaisedBlock ? spec.magnitude : -spec.magnitude;
        return h * std::clamp(1.0 - rectDistance(p) / band, 0.0, 1.0);
    }
    //! Slump lobes: lobe -1 (scarp, lowered) and +1 (toe, raised); value and gradient.
    double lobe(const Eigen::Vector2d& p, int which, Eigen::Vector2d* grad = nullptr) const
    {
        const Eigen::Vector2d q = local(p);
        const double du = (q.x() - which * halfU) / halfU, dv = q.y() / halfV;
        const double r2 = du * du + dv * dv;
        if (grad)
            grad->setZero();
        if (r2 >= 1)
            return 0;
        const double a = which * spec.magnitude, f = 1 - r2;
        if (grad) {
            const double dfdr2 = -2 * a * f;
            *grad = dfdr2 * (2 * du / halfU * axisU + 2 * dv / halfV * axisV);
        }
        return a * f * f;
    }
    //! Slump lobe support grown by `margin` (m).
    bool inLobe(const Eigen::Vector2d& p, int which, double margin) const
    {
        const Eigen::Vector2d q = local(p);
        const double du = (q.x() - which * halfU) / (halfU + margin), dv = q.y() / (halfV + margin);
        return du * du + dv * dv < 1;
    }
    //! Objects: signed horizontal distance to the footprint border (negative inside).
    double footprintDistance(const Eigen::Vector2d& p) const
    {
        if (isCylinder())
            return (p - c).norm() - halfU;
        const Eigen::Vector2d q = local(p);
        const Eigen::Vector2d e(std::abs(q.x()) - halfU, std::abs(q.y()) - halfV);
        if (e.maxCoeff() <= 0)
            return e.maxCoeff();
        return e.cwiseMax(0.0).norm();
    }
};

inline ChangeGeom makeGeom(const ChangeSpec& s, const Relief& relief)
{
    ChangeGeom g;
    g.spec = s;
    g.c = s.centre;
    double heading = es::degToRad(s.headingDeg);
    if (s.kind == ChangeKind::Slump) { // along the fall line of the smooth relief
        const Eigen::Vector2d grad = relief.gradient(s.centre.x(), s.centre.y());
        if (grad.norm() > 1e-3)
            heading = std::atan2(-grad.y(), -grad.x());
    }
    g.axisU = {std::cos(heading), std::sin(heading)};
    g.axisV = {-g.axisU.y(), g.axisU.x()};
    g.halfU = s.kind == ChangeKind::Slump ? s.length / 4 : s.length / 2;
    g.halfV = (g.isCylinder() ? s.length : s.width) / 2;
    g.band = s.magnitude / std::tan(es::degToRad(std::clamp(s.sideAngleDeg, 5.0, 89.5)));
    g.top = relief.smooth(g.c.x(), g.c.y()) + s.magnitude;
    return g;
}

//! Where a sampled point came from (for the truth).
enum class Source : std::uint8_t { Terrain, BlockSide, ObjectWall, ObjectTop };

struct Sample
{
    Eigen::Vector3d truePosition; //!< on the surface, before noise
    Eigen::Vector3d normal;
    Source source = Source::Terrain;
    int change = -1; //!< index of the change whose surface it is (sides, walls, tops)
};

//! One epoch's surface: the relief with the changes present in it.
struct EpochSurface
{
    const Relief* relief = nullptr;
    std::vector<const ChangeGeom*> deformations; //!< blocks and slumps (compared epoch)
    std::vector<const ChangeGeom*> objects;      //!< objects standing in this epoch

    //! Terrain height with the deformations, and its gradient.
    double height(const Eigen::Vector2d& p, Eigen::Vector2d* grad) const
    {
        double z = relief->height(p.x(), p.y());
        if (grad)
            *grad = relief->gradient(p.x(), p.y());
        for (const ChangeGeom* g : deformations) {
            if (g->isBlock()) {
                Eigen::Vector2d out;
                const double d = g->rectDistance(p, &out);
                z += g->blockLift(p);
                if (grad && d > 0 && d < g->band)
                    *grad -= (g->blockLift(g->c) / g->band) * out;
            } else {
                Eigen::Vector2d gs, gt;
                z += g->lobe(p, -1, grad ? &gs : nullptr) + g->lobe(p, +1, grad ? &gt : nullptr);
                if (grad)
                    *grad += gs + gt;
            }
        }
        return z;
    }
    //! Terrain samples there belong to a block side (sampled apart) or lie under an object.
    bool excluded(const Eigen::Vector2d& p) const
    {
        for (const ChangeGeom* g : deformations)
            if (g->isBlock()) {
                const double d = g->rectDistance(p);
                if (d > 0 && d < g->band)
                    return true;
            }
        for (const ChangeGeom* g : objects)
            if (g->footprintDistance(p) < 0)
                return true;
        return false;
    }
};

inline Eigen::Vector3d normalOf(const Eigen::Vector2d& grad)
{
    return Eigen::Vector3d(-grad.x(), -grad.y(), 1.0).normalized();
}

//! Terrain: random (area-weighted rejection) or jittered grid.
inline void sampleTerrain(const EpochSurface& s, double sx, double sy, double density, bool jittered, SplitMix64& rng,
                          std::vector<Sample>& out)
{
    auto emit = [&](const Eigen::Vector2d& p, bool areaWeighted, double wmax) {
        if (s.excluded(p))
            return;
        Eigen::Vector2d g;
        const double z = s.height(p, &g);
        const double w = std::sqrt(1 + g.squaredNorm());
        if (areaWeighted && rng.uniform() * wmax > w)
            return;
        out.push_back({Eigen::Vector3d(p.x(), p.y(), z), normalOf(g), Source::Terrain, -1});
    };
    if (jittered) {
        const double step = 1 / std::sqrt(density);
        for (double y = 0; y < sy; y += step)
            for (double x = 0; x < sx; x += step)
                emit({std::min(sx, x + step * rng.uniform()), std::min(sy, y + step * rng.uniform())}, false, 1);
        return;
    }
    constexpr double wmax = 1.5; // slopes to 48 deg; steeper parts are the sampled-apart sides
    const auto candidates = static_cast<std::size_t>(std::llround(density * sx * sy * wmax));
    for (std::size_t i = 0; i < candidates; ++i)
        emit({sx * rng.uniform(), sy * rng.uniform()}, true, wmax);
}

//! The steep side band of a block (compared epoch), uniform per area.
inline void sampleBlockSides(const EpochSurface& s, const ChangeGeom& g, int index, double density, SplitMix64& rng,
                             std::vector<Sample>& out)
{
    const double strips[4] = {2 * g.halfV * g.band, 2 * g.halfV * g.band, 2 * g.halfU * g.band, 2 * g.halfU * g.band};
    const double corner = 0.25 * es::kPi * g.band * g.band, planar = strips[0] + strips[1] + strips[2] + strips[3] + 4 * corner;
    const double slopeFactor = std::hypot(1.0, g.spec.magnitude / g.band);
    const auto n = static_cast<std::size_t>(std::llround(density * planar * slopeFactor));
    for (std::size_t i = 0; i < n; ++i) {
        double pick = rng.uniform() * planar, u = 0, v = 0;
        const double t = g.band * rng.uniform();
        int k = 0;
        while (k < 4 && pick >= strips[k])
            pick -= strips[k++];
        if (k < 4) { // a straight side: +u, -u, +v, -v
            const double along = es::uniform(rng, -1, 1);
            u = k == 0 ? g.halfU + t : k == 1 ? -g.halfU - t : along * g.halfU;
            v = k == 2 ? g.halfV + t : k == 3 ? -g.halfV - t : along * g.halfV;
        } else { // a rounded corner
            const int q = static_cast<int>(pick / corner) % 4;
            const double r = g.band * std::sqrt(rng.uniform()), a = 0.5 * es::kPi * rng.uniform();
            u = (q & 1 ? -1 : 1) * (g.halfU + r * std::cos(a));
            v = (q & 2 ? -1 : 1) * (g.halfV + r * std::sin(a));
        }
        const Eigen::Vector2d p = g.c + u * g.axisU + v * g.axisV;
        Eigen::Vector2d grad;
        const double z = s.height(p, &grad);
        out.push_back({Eigen::Vector3d(p.x(), p.y(), z), normalOf(grad), Source::BlockSide, index});
    }
}

//! Walls (from the terrain up to the top) and the flat top of an object.
inline void sampleObject(const Relief& relief, const ChangeGeom& g, int index, double density, SplitMix64& rng,
                         std::vector<Sample>& out)
{
    // Border point and outward normal at border parameter t in [0, 1).
    const double perimeter = g.isCylinder() ? 2 * es::kPi * g.halfU : 4 * (g.halfU + g.halfV);
    auto border = [&](double t, Eigen::Vector2d& n) -> Eigen::Vector2d {
        if (g.isCylinder()) {
            const double a = 2 * es::kPi * t;
            n = std::cos(a) * g.axisU + std::sin(a) * g.axisV;
            return g.c + g.halfU * n;
        }
        double s = t * perimeter;
        const double sides[4] = {2 * g.halfV, 2 * g.halfU, 2 * g.halfV, 2 * g.halfU};
        int k = 0;
        while (k < 3 && s >= sides[k])
            s -= sides[k++];
        const double f = s / sides[k] * 2 - 1;
        const Eigen::Vector2d q = k == 0 ? Eigen::Vector2d(g.halfU, f * g.halfV)
                                 : k == 1 ? Eigen::Vector2d(-f * g.halfU, g.halfV)
                                 : k == 2 ? Eigen::Vector2d(-g.halfU, -f * g.halfV)
                                          : Eigen::Vector2d(f * g.halfU, -g.halfV);
        n = k == 0 ? g.axisU : k == 1 ? g.axisV : k == 2 ? Eigen::Vector2d(-g.axisU) : Eigen::Vector2d(-g.axisV);
        return g.c + q.x() * g.axisU + q.y() * g.axisV;
    };
    double meanHeight = 0, maxHeight = 0;
    for (int i = 0; i < 256; ++i) {
        Eigen::Vector2d n;
        const Eigen::Vector2d b = border((i + 0.5) / 256, n);
        const double h = std::max(0.0, g.top - relief.height(b.x(), b.y()));
        meanHeight += h / 256;
        maxHeight = std::max(maxHeight, h);
    }
    const auto walls = static_cast<std::size_t>(std::llround(density * perimeter * meanHeight));
    for (std::size_t made = 0; made < walls;) {
        Eigen::Vector2d n;
        const Eigen::Vector2d b = border(rng.uniform(), n);
        const double ground = relief.height(b.x(), b.y()), h = g.top - ground;
        if (h <= 0 || rng.uniform() * maxHeight > h)
            continue;
        out.push_back({Eigen::Vector3d(b.x(), b.y(), ground + h * rng.uniform()), Eigen::Vector3d(n.x(), n.y(), 0),
                       Source::ObjectWall, index});
        ++made;
    }
    const double topArea = g.isCylinder() ? es::kPi * g.halfU * g.halfU : 4 * g.halfU * g.halfV;
    const auto tops = static_cast<std::size_t>(std::llround(density * topArea));
    for (std::size_t i = 0; i < tops; ++i) {
        Eigen::Vector2d p;
        if (g.isCylinder()) {
            const double r = g.halfU * std::sqrt(rng.uniform()), a = 2 * es::kPi * rng.uniform();
            p = g.c + r * (std::cos(a) * g.axisU + std::sin(a) * g.axisV);
        } else {
            p = g.c + es::uniform(rng, -g.halfU, g.halfU) * g.axisU + es::uniform(rng, -g.halfV, g.halfV) * g.axisV;
        }
        out.push_back({Eigen::Vector3d(p.x(), p.y(), g.top), Eigen::Vector3d::UnitZ(), Source::ObjectTop, index});
    }
}

} // namespace detail
} // namespace scandiff::test::family::terrainchange
