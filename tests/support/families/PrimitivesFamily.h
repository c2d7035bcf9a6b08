// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Test family: primitive shapes (plane, sphere, cylinder, cone, torus) in a
//! plant-like scene scanned from a few terrestrial stations, for a shape
//! detection (efficient RANSAC, default settings) that returns shapes and, per
//! point, the index of the shape it was assigned to (-1: none).
//!
//! Issue case (issueCase()): about 1 M points, 15 shapes, 5 mm range noise, 5 %
//! clutter, four tripod stations in an 18 x 14 m hall corner (walls 6 m). A
//! 16 m pipe of radius 0.10 m crosses the hall at 3 m, 0.15 m behind a 4.5 m
//! tank and 0.1 m above a platform whose plate hides it from below: its points
//! come in pieces (gaps at x 5.0-5.4 and 7.5-9.3 m, sparse around them). A
//! column of radius 0.25 m stands on the floor touching the left wall. An
//! elbow (quarter torus R 0.8 m, r 0.15 m) joins a vertical leg rising from a
//! 20-degree reducer cone to a horizontal leg running into the back wall, each
//! straight leg its own cylinder. Planes: floor, two walls, platform
//! underside, three faces of a box in the corner; a sphere of 0.6 m rests on
//! the box; a 1 m tank. Every shape has 680 points or more.
//!
//! How the points are made: every station casts rays at one angular step over
//! a full turn (or a horizontal window) and -55..90 degrees of pitch; a ray
//! keeps the first surface met (occlusion), its range gets Gaussian noise
//! along the ray, grazing rays (incidence beyond ~87 degrees) return nothing.
//! A point's truth is the shape its ray met. Clutter, `clutterFraction` of all
//! points: small lumpy objects (valves, bags, cable boxes: no primitive fits
//! them) scanned with the scene and hiding what is behind them; mixed pixels
//! between the two ranges of a depth jump at silhouette edges (clear of the
//! surfaces they lie near by 4 noise sigmas, 3 cm at least); returns a
//! little in front of surfaces (2-15 cm and at least 4 noise sigmas off:
//! dust, straps, insulation); spurious returns in the air along real rays.
//! The points are shuffled; the cloud's sensors() holds the stations.
//!
//! Family (drawFamily()): rooms 14-28 m long times sqrt(scale), at least 4.5
//! m, width 0.55-0.85 of the length, walls 4-8 m (0-2 walls); 8-20 shapes:
//! cylinders 0.05-2 m (pipes 0.05-0.3 m in any direction, columns 0.15-0.5 m
//! often touching a wall, tanks 0.5-2 m), spheres 0.1-1 m (on the floor or on
//! a box), tori R 0.3-2 m with r 0.05-0.4 m (r < 0.45 R) between two legs,
//! cones of half-angle 10-40 degrees (standing or lying in any direction),
//! boxes at any yaw (each visible face a plane); 2-5 stations planned to see
//! the equipment; noise 1-10 mm; clutter 0-10 %; heading 0-360 degrees;
//! UTM-like coordinates in half the draws; 0.5-1.5 M points times scale. The
//! angular step is calibrated to the point count; below scale ~0.35 stations
//! scan a horizontal window aimed at the equipment, narrowed (then the point
//! count raised within its range) while the spacing at the median range
//! exceeds 3 cm.
//!
//! Truth: the shapes with at least `requiredPoints` visible points are
//! required (500 in the issue case; 500 per million points, at least 100, in
//! draws); the others are reported as not required.

#include "primitives/Layout.h"
#include "primitives/Scoring.h"

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/SplitMix.h>

#include <Eigen/Geometry>

#include <cstdio>
#include <numeric>
#include <unordered_map>
#include <string>
#include <vector>

namespace scandiff::test::family::primitives {

struct PrimitivesParams
{
    std::vector<ShapeSpec> shapes;       //!< the true shapes, scene frame
    std::vector<StationSpec> stations;   //!< scanner stations, scene frame
    double angularStep = 0.004;          //!< station yaw and pitch step (rad)
    double rangeNoise = 0.005;           //!< range noise, 1 sigma along the ray (m)
    double clutterFraction = 0.05;       //!< clutter points / all points
    std::size_t clutterObjects = 0;      //!< lumpy objects scanned with the scene
    double clutterObjectPoints = 200;    //!< points aimed at per object (its size follows from the spacing)
    double headingDeg = 0;               //!< rotation of the whole scene about the vertical (degrees)
    Eigen::Vector3d globalOffset = Eigen::Vector3d::Zero(); //!< added after the rotation (m)
    std::size_t requiredPoints = 500;    //!< fewer visible points: the shape is not required
    double maxRange = 120;               //!< scanner range (m)
    std::uint64_t seed = 1;              //!< noise, clutter, shuffling
};

enum class PointKind : std::uint8_t { Shape = 0, ClutterObject, MixedPixel, NearSurface, AirReturn };

struct PrimitivesScene
{
    PointCloud cloud;                    //!< global = origin + local; sensors() holds the stations
    std::vector<TrueShape> shapes;       //!< truth, global coordinates, in PrimitivesParams::shapes order
    std::vector<int> labels;             //!< per point: index in shapes, -1 clutter
    std::vector<PointKind> kinds;        //!< per point: what produced it
    double medianSpacing = 0;            //!< angular step x median range of the shape points (m)
    PrimitivesParams params;

    ScoreOptions scoreOptions() const
    {
        ScoreOptions o;
        o.requiredPoints = params.requiredPoints;
        return o;
    }
};

namespace detail {

inline ScanSettings scanSettings(const PrimitivesParams& p, double step)
{
    ScanSettings s;
    s.angularStep = step;
    s.rangeNoise = p.rangeNoise;
    s.maxRange = p.maxRange;
    return s;
}

//! Noise-free, clutter-free scan of the shapes at `step`: their hit count
//! and (optionally) the ranges.
inline std::size_t pilotShapeHits(const PrimitivesParams& p, double step, std::vector<double>* ranges = nullptr)
{
    std::size_t hits = 0;
    for (std::size_t k = 0; k < p.stations.size(); ++k) {
        const StationScan scan = scanStation(p.shapes, {}, p.stations[k], int(k), scanSettings(p, step), p.seed, false);
        for (const ScanHit& h : scan.hits) {
            if (h.target < 0)
                continue;
            ++hits;
            if (ranges)
                ranges->push_back(h.range);
        }
    }
    return hits;
}

inline double median(std::vector<double> v)
{
    if (v.empty())
        return 0;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
}

//! Small lumpy objects on the surfaces (half on floor-like planes, by area;
//! half on any shape), sized from the spacing of the nearest station so that
//! each gets about clutterObjectPoints points.
inline std::vector<ClutterObject> placeClutterObjects(const PrimitivesParams& p)
{
    std::vector<ClutterObject> objects;
    if (p.clutterFraction <= 0 || p.clutterObjects == 0 || p.shapes.empty() || p.stations.empty())
        return objects;
    SplitMix64 rng(p.seed, 0xC1u);
    std::vector<std::size_t> floorLike;
    double floorArea = 0;
    for (std::size_t i = 0; i < p.shapes.size(); ++i)
        if (p.shapes[i].kind == PrimitiveKind::Plane && p.shapes[i].axis.z() > 0.9) {
            floorLike.push_back(i);
            floorArea += p.shapes[i].length * p.shapes[i].width;
        }
    for (std::size_t attempt = 0; attempt < 4 * p.clutterObjects && objects.size() < p.clutterObjects; ++attempt) {
        std::size_t which = rng.below(p.shapes.size());
        if (!floorLike.empty() && rng.uniform() < 0.5) {
            double pick = rng.uniform() * floorArea;
            for (std::size_t i : floorLike) {
                which = i;
                pick -= p.shapes[i].length * p.shapes[i].width;
                if (pick <= 0)
                    break;
            }
        }
        const ShapeSpec& s = p.shapes[which];
        const Vector3d q = samplePointOn(s, rng);
        double nearest = kNoHit;
        for (const StationSpec& st : p.stations)
            nearest = std::min(nearest, (st.position - q).norm());
        const double spacing = nearest * p.angularStep;
        const double radius = std::clamp(spacing * std::sqrt(p.clutterObjectPoints / (1.5 * kPi)), 0.02, 0.3);
        if (nearest < 2 * radius + 0.5)
            continue; // would swallow the scanner
        objects.push_back(randomClutterObject(rng, q + 0.7 * radius * outwardNormal(s, q), radius));
    }
    return objects;
}

//! Picks `count` of `n` indices at random (partial Fisher-Yates).
inline std::vector<std::size_t> pickIndices(SplitMix64& rng, std::size_t n, std::size_t count)
{
    std::vector<std::size_t> all(n);
    std::iota(all.begin(), all.end(), std::size_t(0));
    count = std::min(count, n);
    for (std::size_t i = 0; i < count; ++i)
        std::swap(all[i], all[i + rng.below(n - i)]);
    all.resize(count);
    return all;
}

struct RawPoint
{
    Vector3d position;
    int label;
    PointKind kind;
};

//! Clutter from the scan: objects (thinned to 60 % of the budget at most),
//! mixed pixels (20 % at most), then returns in front of surfaces (70 % of the
//! rest) and in the air (30 %), all along real rays of real stations.
inline void addClutter(const PrimitivesParams& p, const std::vector<ScanHit>& shapeHits, const std::vector<ScanHit>& objectHits,
                       const std::vector<EdgeCandidate>& edges, std::vector<RawPoint>& out)
{
    if (p.clutterFraction <= 0 || shapeHits.empty())
        return;
    SplitMix64 rng(p.seed, 0xC2u);
    const auto budget = static_cast<std::size_t>(std::llround(p.clutterFraction / (1 - p.clutterFraction) * shapeHits.size()));
    for (std::size_t i : pickIndices(rng, objectHits.size(), budget * 6 / 10))
        out.push_back({objectHits[i].position, -1, PointKind::ClutterObject});
    const std::size_t objects = std::min(objectHits.size(), budget * 6 / 10);
    // A mixed pixel lies between the two surfaces, clear of both by 4 noise sigmas (3 cm at least).
    const double edgeMargin = std::max(0.03, 4 * p.rangeNoise);
    std::vector<std::size_t> wideEdges;
    for (std::size_t i = 0; i < edges.size(); ++i)
        if (edges[i].farRange - edges[i].nearRange > 2 * edgeMargin + 0.02)
            wideEdges.push_back(i);
    // Clear of them across the surfaces too where they are: a ray running
    // along a face (a box side seen edge-on) would put its "mixed pixel" on
    // the face, where it is a return of the face. Such draws are dropped:
    // within the margin of a shape's surface and within 10 cm of one of that
    // shape's returns. (On the surface's extension past the face they stay:
    // a detector must tell them from the face.)
    std::vector<Primitive> surfaces;
    for (const ShapeSpec& shape : p.shapes)
        surfaces.push_back(toPrimitive(shape));
    constexpr double kFaceReach = 0.10;
    const auto cellOf = [&](const Vector3d& x, int dx, int dy, int dz) {
        const auto c = [](double v, int d) { return static_cast<std::uint64_t>((static_cast<std::int64_t>(std::floor(v / kFaceReach)) + d) & 0x1fffff); };
        return c(x.x(), dx) | c(x.y(), dy) << 21 | c(x.z(), dz) << 42;
    };
    std::unordered_map<std::uint64_t, std::vector<std::size_t>> hitsByCell;
    for (std::size_t h = 0; h < shapeHits.size(); ++h)
        hitsByCell[cellOf(shapeHits[h].position, 0, 0, 0)].push_back(h);
    const auto clearOfSurfaces = [&](const Vector3d& x) {
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const auto found = hitsByCell.find(cellOf(x, dx, dy, dz));
                    if (found == hitsByCell.end())
                        continue;
                    for (std::size_t h : found->second)
                        if ((shapeHits[h].position - x).norm() < kFaceReach &&
                            std::abs(signedDistance(surfaces[std::size_t(shapeHits[h].target)], x)) < edgeMargin)
                            return false;
                }
        return true;
    };
    const std::size_t mixed = std::min(wideEdges.size(), budget / 5);
    std::size_t mixedMade = 0;
    for (std::size_t i : pickIndices(rng, wideEdges.size(), mixed)) {
        const EdgeCandidate& e = edges[wideEdges[i]];
        const double range = uniformIn(rng, e.nearRange + edgeMargin, e.farRange - edgeMargin);
        const Vector3d x = p.stations[std::size_t(e.station)].position + range * e.direction;
        if (!clearOfSurfaces(x))
            continue;
        out.push_back({x, -1, PointKind::MixedPixel});
        ++mixedMade;
    }
    const std::size_t rest = budget - objects - mixedMade, near = rest * 7 / 10;
    const double minOffset = std::max(0.02, 4 * p.rangeNoise);
    for (std::size_t made = 0, attempt = 0; made < rest && attempt < 20 * rest + 100; ++attempt) {
        const ScanHit& h = shapeHits[rng.below(shapeHits.size())];
        const Vector3d station = p.stations[std::size_t(h.station)].position;
        const Vector3d dir = (h.position - station) / h.range;
        double range;
        PointKind kind;
        if (made < near) {
            kind = PointKind::NearSurface;
            range = h.range - uniformIn(rng, minOffset, 0.15) / std::max(double(h.cosIncidence), 0.25);
        } else {
            kind = PointKind::AirReturn;
            range = h.range > 1.5 ? uniformIn(rng, 0.5, h.range - 0.5) : 0.0;
        }
        if (range < 0.3)
            continue;
        out.push_back({station + range * dir, -1, kind});
        ++made;
    }
}

} // namespace detail

//! Sets the angular step so the scene gives about `totalPoints` points (two
//! noise-free pilot scans), and the number of clutter objects from the budget.
//! Returns the expected spacing at the median range of the shape points (m).
inline double calibrateSampling(PrimitivesParams& p, double totalPoints)
{
    p.clutterObjects = static_cast<std::size_t>(
        std::min(400.0, std::round(0.4 * p.clutterFraction * totalPoints / p.clutterObjectPoints)));
    // The clutter objects will hide about as many shape points as they get.
    const double hidden = std::min(0.6 * p.clutterFraction * totalPoints, double(p.clutterObjects) * p.clutterObjectPoints);
    const double shapeTarget = totalPoints * (1 - p.clutterFraction) + hidden;
    const double coarse = 0.02;
    const double first = coarse * std::sqrt(double(std::max<std::size_t>(1, detail::pilotShapeHits(p, coarse))) / shapeTarget);
    const double pilot = 2 * first;
    std::vector<double> ranges;
    const std::size_t hits = detail::pilotShapeHits(p, pilot, &ranges);
    p.angularStep = pilot * std::sqrt(double(std::max<std::size_t>(1, hits)) / shapeTarget);
    return p.angularStep * detail::median(std::move(ranges));
}

//! The issue's condition, full size (about 1 M points).
inline PrimitivesParams issueCase()
{
    PrimitivesParams p;
    const Layout lay = issueLayout();
    p.shapes = lay.shapes;
    p.stations = lay.stations;
    p.rangeNoise = 0.005;
    p.clutterFraction = 0.05;
    p.requiredPoints = 500;
    p.seed = 20240615;
    // What calibrateSampling(p, 1.0e6) gives (5.209 mrad, 100 objects), as a
    // fixed scanner setting: about 0.997 M points, 19 mm at the median range.
    p.angularStep = 5.21e-3;
    p.clutterObjects = 100;
    return p;
}

//! A draw over the family's ranges; `scale` in (0, 1] multiplies the point
//! count (0.5-1.5 M at 1) and shrinks the room by sqrt(scale) so the spacing
//! stays within survey values.
inline PrimitivesParams drawFamily(std::uint64_t seed, double scale)
{
    scale = std::clamp(scale, 0.01, 1.0);
    SplitMix64 rng(seed, 0x9121u);
    PrimitivesParams p;
    // Below scale ~0.35 the stations scan a horizontal window aimed at the
    // equipment (+-72 degrees at the smallest scales), as a surveyor does for a small area.
    const double windowHalfWidth = kPi * std::clamp(1.7 * std::sqrt(scale), 0.4, 1.0);
    const Layout lay = randomLayout(rng, std::sqrt(scale), windowHalfWidth);
    p.shapes = lay.shapes;
    p.stations = lay.stations;
    const double totalPoints = uniformIn(rng, 0.5e6, 1.5e6) * scale;
    p.rangeNoise = uniformIn(rng, 0.001, 0.010);
    p.clutterFraction = uniformIn(rng, 0.0, 0.10);
    p.headingDeg = uniformIn(rng, 0.0, 360.0);
    if (rng.uniform() < 0.5)
        p.globalOffset = Eigen::Vector3d(uniformIn(rng, 3.0e5, 8.0e5), uniformIn(rng, 4.5e6, 5.5e6), uniformIn(rng, 0.0, 600.0));
    p.seed = splitMix(seed ^ 0x5052494dULL);
    // Survey spacing stays within 3 cm: where a small scene would need coarser
    // steps for its point budget, narrower windows (yaw down to +-54 degrees),
    // then more points (up to the top of the range, 1.5 M times scale).
    double points = totalPoints;
    for (int narrowing = 0; calibrateSampling(p, points) > 0.03 && narrowing < 8; ++narrowing) {
        if (p.stations.empty() || p.stations.front().yawHalfWidth > 0.301 * kPi) {
            for (StationSpec& st : p.stations)
                st.yawHalfWidth = std::max(0.3 * kPi, 0.75 * std::min(st.yawHalfWidth, 0.999 * kPi));
        } else {
            points = std::min(1.5e6 * scale, 1.25 * points);
        }
    }
    p.requiredPoints = static_cast<std::size_t>(std::max(100.0, std::round(500.0 * points / 1.0e6)));
    return p;
}

inline std::string describe(const PrimitivesParams& p)
{
    int count[5] = {0, 0, 0, 0, 0};
    for (const ShapeSpec& s : p.shapes)
        ++count[static_cast<int>(s.kind)];
    double window = kPi;
    for (const StationSpec& st : p.stations)
        window = std::min(window, st.yawHalfWidth);
    char buffer[400];
    std::snprintf(buffer, sizeof buffer,
                  "primitives: %zu shapes (plane %d, sphere %d, cylinder %d, cone %d, torus %d), %zu stations (window "
                  "+-%.0f deg), step %.3f mrad, noise %.1f mm, clutter %.1f %% (%zu objects), heading %.1f deg, offset "
                  "(%.0f, %.0f, %.0f), required >= %zu points, seed %llu",
                  p.shapes.size(), count[0], count[1], count[2], count[3], count[4], p.stations.size(),
                  window * 180 / kPi, p.angularStep * 1e3, p.rangeNoise * 1e3, p.clutterFraction * 100, p.clutterObjects, p.headingDeg,
                  p.globalOffset.x(), p.globalOffset.y(), p.globalOffset.z(), p.requiredPoints,
                  static_cast<unsigned long long>(p.seed));
    return buffer;
}

namespace detail {

//! Truth in global coordinates; a cylinder's axis point is the foot of its points' centroid.
inline std::vector<TrueShape> trueShapes(const PrimitivesParams& p, const std::vector<RawPoint>& points,
                                         const Eigen::Matrix3d& rotation)
{
    std::vector<TrueShape> truth(p.shapes.size());
    std::vector<Vector3d> sums(p.shapes.size(), Vector3d::Zero());
    for (const RawPoint& r : points)
        if (r.label >= 0) {
            ++truth[std::size_t(r.label)].points;
            sums[std::size_t(r.label)] += r.position;
        }
    for (std::size_t i = 0; i < p.shapes.size(); ++i) {
        const ShapeSpec& s = p.shapes[i];
        Primitive prim = toPrimitive(s);
        if (s.kind == PrimitiveKind::Cylinder && truth[i].points > 0) {
            const Vector3d c = sums[i] / double(truth[i].points);
            prim.point = s.centre + (c - s.centre).dot(s.axis) * s.axis;
        }
        prim.point = p.globalOffset + rotation * prim.point;
        prim.direction = rotation * prim.direction;
        truth[i].name = s.name;
        truth[i].primitive = prim;
        truth[i].required = truth[i].points >= p.requiredPoints;
    }
    return truth;
}

} // namespace detail

inline PrimitivesScene make(const PrimitivesParams& p)
{
    PrimitivesScene scene;
    scene.params = p;
    const std::vector<ClutterObject> objects = detail::placeClutterObjects(p);
    std::vector<ScanHit> shapeHits, objectHits;
    std::vector<EdgeCandidate> edges;
    for (std::size_t k = 0; k < p.stations.size(); ++k) {
        StationScan scan = scanStation(p.shapes, objects, p.stations[k], int(k), detail::scanSettings(p, p.angularStep), p.seed);
        for (const ScanHit& h : scan.hits)
            (h.target >= 0 ? shapeHits : objectHits).push_back(h);
        edges.insert(edges.end(), scan.edges.begin(), scan.edges.end());
    }
    std::vector<detail::RawPoint> raw;
    raw.reserve(shapeHits.size() * 11 / 10 + 16);
    std::vector<double> ranges;
    for (const ScanHit& h : shapeHits) {
        raw.push_back({h.position, h.target, PointKind::Shape});
        ranges.push_back(h.range);
    }
    scene.medianSpacing = p.angularStep * detail::median(std::move(ranges));
    detail::addClutter(p, shapeHits, objectHits, edges, raw);
    SplitMix64 rng(p.seed, 0xC3u);
    for (std::size_t i = raw.size(); i > 1; --i)
        std::swap(raw[i - 1], raw[rng.below(i)]);

    const Eigen::Matrix3d rotation = Eigen::AngleAxisd(p.headingDeg * kPi / 180, Vector3d::UnitZ()).toRotationMatrix();
    scene.shapes = detail::trueShapes(p, raw, rotation);
    BoundingBox box;
    std::vector<Vector3d> global(raw.size());
    for (std::size_t i = 0; i < raw.size(); ++i) {
        global[i] = p.globalOffset + rotation * raw[i].position;
        box.min = box.empty ? global[i] : box.min.cwiseMin(global[i]);
        box.max = box.empty ? global[i] : box.max.cwiseMax(global[i]);
        box.empty = false;
    }
    PointCloud& cloud = scene.cloud;
    cloud.name = "primitives family scene";
    cloud.setOrigin(suggestOrigin(box));
    cloud.resize(raw.size());
    scene.labels.resize(raw.size());
    scene.kinds.resize(raw.size());
    for (std::size_t i = 0; i < raw.size(); ++i) {
        cloud.positions()[i] = (global[i] - cloud.origin()).cast<float>();
        scene.labels[i] = raw[i].label;
        scene.kinds[i] = raw[i].kind;
    }
    for (const StationSpec& st : p.stations) {
        SensorPose pose;
        pose.position = p.globalOffset + rotation * st.position;
        pose.orientation = Eigen::Quaterniond(rotation);
        pose.yawStep = pose.pitchStep = p.angularStep;
        pose.pitchMin = st.pitchMin;
        pose.pitchMax = st.pitchMax;
        if (st.yawHalfWidth < kPi) {
            pose.yawMin = st.yawCentre - st.yawHalfWidth;
            pose.yawMax = st.yawCentre + st.yawHalfWidth;
        }
        pose.maxRange = p.maxRange;
        cloud.sensors().push_back(pose);
    }
    return scene;
}

//! Scores a detection on the scene: `detected` shapes (global coordinates) and,
//! per point of scene.cloud, the index of the detected shape it went to (-1: none).
inline DetectionScore score(const PrimitivesScene& scene, const std::vector<Primitive>& detected, const std::vector<int>& assignment)
{
    return scoreDetection(scene.shapes, scene.labels, detected, assignment, scene.scoreOptions());
}

inline DetectionScore score(const PrimitivesScene& scene, const std::vector<Primitive>& detected, const std::vector<int>& assignment,
                            const ScoreOptions& options)
{
    return scoreDetection(scene.shapes, scene.labels, detected, assignment, options);
}

} // namespace scandiff::test::family::primitives
