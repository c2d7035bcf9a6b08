// SPDX-License-Identifier: GPL-3.0-or-later
#include "ShapeParts.h"

#include <scandiff/core/Error.h>

#include <Eigen/Geometry>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <unordered_map>
#include <unordered_set>

namespace scandiff::plugins::detail {

namespace {

//! The key of the cube of side `cell` holding p, moved by (dx, dy, dz) cells.
std::uint64_t cellKey(const Eigen::Vector3d& p, double cell, int dx = 0, int dy = 0, int dz = 0)
{
    const auto c = [cell](double v, int d) {
        return static_cast<std::uint64_t>((static_cast<std::int64_t>(std::floor(v / cell)) + d) & 0x1fffff);
    };
    return c(p.x(), dx) | c(p.y(), dy) << 21 | c(p.z(), dz) << 42;
}

//! The keys of the 27 cells of side `cell` around p (its own among them).
std::array<std::uint64_t, 27> neighbourKeys(const Eigen::Vector3d& p, double cell)
{
    std::array<std::uint64_t, 27> keys{};
    std::size_t k = 0;
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz)
                keys[k++] = cellKey(p, cell, dx, dy, dz);
    return keys;
}

//! Whether a point (local) has a cell of `cells` among the 27 around it.
bool nearCells(const std::unordered_set<std::uint64_t>& cells, const Eigen::Vector3d& p, double cell)
{
    for (std::uint64_t key : neighbourKeys(p, cell))
        if (cells.count(key))
            return true;
    return false;
}

std::unordered_set<std::uint64_t> cellsOf(const std::vector<std::uint32_t>& members, const SurfaceEvidence& evidence)
{
    std::unordered_set<std::uint64_t> cells;
    for (std::uint32_t i : members)
        cells.insert(cellKey(evidence.points[i], evidence.linkDistance));
    return cells;
}

//! The surface's unit normal at (near) a global point: the gradient of the
//! signed distance, by central differences (every kind of shape alike).
Eigen::Vector3d surfaceNormal(const Primitive& shape, const Eigen::Vector3d& global)
{
    constexpr double h = 1e-4;
    Eigen::Vector3d g;
    for (int k = 0; k < 3; ++k) {
        Eigen::Vector3d step = Eigen::Vector3d::Zero();
        step[k] = h;
        g[k] = signedDistance(shape, global + step) - signedDistance(shape, global - step);
    }
    const double norm = g.norm();
    return norm > 0 ? Eigen::Vector3d(g / norm) : Eigen::Vector3d::Zero();
}

//! |distance| of point i to the shape when it lies within epsilon of it,
//! else infinity.
double distanceWithin(const Primitive& shape, std::uint32_t i, const SurfaceEvidence& evidence)
{
    const double d = std::abs(signedDistance(shape, evidence.centre + evidence.points[i]));
    return d <= evidence.epsilon ? d : std::numeric_limits<double>::infinity();
}

//! Whether point i's normal agrees with the shape's there (true where the
//! point has none).
bool normalAgrees(const Primitive& shape, std::uint32_t i, const SurfaceEvidence& evidence)
{
    if (evidence.normals.empty())
        return true;
    const Eigen::Vector3d n = evidence.normals[i].cast<double>();
    const double length = n.norm();
    return !(length > 0) || std::abs(n.dot(surfaceNormal(shape, evidence.centre + evidence.points[i]))) >= evidence.normalCosine * length;
}

//! |distance| of point i to the shape when it lies on it (within epsilon,
//! its normal agreeing where it has one), else infinity.
double distanceOnSurface(const Primitive& shape, std::uint32_t i, const SurfaceEvidence& evidence)
{
    const double d = distanceWithin(shape, i, evidence);
    return std::isfinite(d) && normalAgrees(shape, i, evidence) ? d : std::numeric_limits<double>::infinity();
}

//! At most `most` of the members, evenly spread over their order.
std::vector<std::uint32_t> sampleOf(const std::vector<std::uint32_t>& members, std::size_t most)
{
    if (members.size() <= most)
        return members;
    std::vector<std::uint32_t> sample;
    sample.reserve(most);
    for (std::size_t k = 0; k < most; ++k)
        sample.push_back(members[k * members.size() / most]);
    return sample;
}

std::vector<Eigen::Vector3d> positionsOf(const std::vector<std::uint32_t>& members, const SurfaceEvidence& evidence)
{
    std::vector<Eigen::Vector3d> out;
    out.reserve(members.size());
    for (std::uint32_t i : members)
        out.push_back(evidence.points[i]);
    return out;
}

//! The nearest of `among` to p (local).
Eigen::Vector3d nearestOf(const std::vector<std::uint32_t>& among, const Eigen::Vector3d& p, const SurfaceEvidence& evidence)
{
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector3d nearest = p;
    for (std::uint32_t i : among) {
        const double d = (evidence.points[i] - p).squaredNorm();
        if (d < best) {
            best = d;
            nearest = evidence.points[i];
        }
    }
    return nearest;
}

//! The closest points (local) of two parts: the closest pair of samples of
//! each, then the nearest point of each part to the other's (a sample of a
//! floor's 600,000 points is centimetres off its edge).
std::pair<Eigen::Vector3d, Eigen::Vector3d> closestPoints(const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& b,
                                                          const SurfaceEvidence& evidence)
{
    const std::vector<std::uint32_t> sa = sampleOf(a, 1500), sb = sampleOf(b, 1500);
    double best = std::numeric_limits<double>::infinity();
    std::pair<Eigen::Vector3d, Eigen::Vector3d> closest{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    for (std::uint32_t i : sa)
        for (std::uint32_t j : sb) {
            const double d = (evidence.points[i] - evidence.points[j]).squaredNorm();
            if (d < best) {
                best = d;
                closest = {evidence.points[i], evidence.points[j]};
            }
        }
    closest.first = nearestOf(a, closest.second, evidence);
    closest.second = nearestOf(b, closest.first, evidence);
    return closest;
}

//! Whether a scanner looked through where the surface would be at `x`
//! (global, on the surface) while facing it: a gap it saw into. A scanner
//! meeting the surface there at more than 80 degrees of incidence (or from
//! behind) says nothing: its rays would have grazed or missed it anyway.
bool seenThrough(const ScannerView& view, const Primitive& surface, const Eigen::Vector3d& x, double tolerance)
{
    const Eigen::Vector3d ray = (x - view.position()).normalized();
    const double incidence = std::abs(ray.dot(surfaceNormal(surface, x)));
    if (incidence < std::cos(80.0 * 3.14159265358979323846 / 180.0))
        return false;
    return view.lookedPast(x, tolerance / incidence);
}

//! Whether the way from one part to the other over the host's surface lies
//! where no scanner looked through: behind something from every scanner, or
//! outside their fields, in steps of half the link distance from the
//! parts' closest points. Along a cylinder or a cone the way is walked on
//! its axis and looked at, from each scanner, on the side of the surface
//! facing it (the straight way between two parts seen from two sides runs
//! along the silhouette, where an axis a little off puts it beside the
//! pipe); on other shapes the straight way is laid on the surface.
bool gapUnseen(const Primitive& host, const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& b,
               const SurfaceEvidence& evidence)
{
    if (evidence.views.empty())
        return false;
    const auto [from, to] = closestPoints(a, b, evidence);
    // A return this near the surface is the surface (or what hides it).
    const double tolerance = std::max(2.0 * evidence.epsilon, 0.5 * evidence.linkDistance);
    const int steps = static_cast<int>(std::min(400.0, std::ceil((to - from).norm() / (0.5 * evidence.linkDistance))));
    const bool axial = host.kind == PrimitiveKind::Cylinder || host.kind == PrimitiveKind::Cone;
    for (int k = 1; k < steps; ++k) {
        Eigen::Vector3d x = evidence.centre + from + (to - from) * (static_cast<double>(k) / steps);
        if (!axial) {
            for (int iteration = 0; iteration < 2; ++iteration) // onto the surface
                x -= signedDistance(host, x) * surfaceNormal(host, x);
            for (const ScannerView& view : evidence.views)
                if (seenThrough(view, host, x, tolerance))
                    return false;
            continue;
        }
        const Eigen::Vector3d axis = host.direction.normalized();
        const double t = (x - host.point).dot(axis);
        const Eigen::Vector3d onAxis = host.point + t * axis;
        const double radius = host.kind == PrimitiveKind::Cylinder ? host.radius : t * std::tan(host.halfAngle);
        if (!(radius > 0))
            continue;
        for (const ScannerView& view : evidence.views) {
            Eigen::Vector3d across = view.position() - onAxis;
            across -= across.dot(axis) * axis;
            if (across.norm() <= radius)
                continue; // the scanner stands inside the shape
            if (seenThrough(view, host, onAxis + radius * across.normalized(), tolerance))
                return false;
        }
    }
    return true;
}

//! The share of a sample of `part`'s points lying on `host`'s surface.
double shareOnSurface(const Primitive& host, const std::vector<std::uint32_t>& part, const SurfaceEvidence& evidence)
{
    const std::vector<std::uint32_t> sample = sampleOf(part, 200);
    std::size_t on = 0;
    for (std::uint32_t i : sample)
        on += std::isfinite(distanceOnSurface(host, i, evidence));
    return sample.empty() ? 0.0 : static_cast<double>(on) / static_cast<double>(sample.size());
}

//! A part may join a host of its own kind and no more points, or of more
//! parameters (a plane strip of a pipe joins the pipe's cylinder, never the
//! other way).
bool mayHost(const DetectedPrimitive& host, const DetectedPrimitive& part)
{
    if (host.primitive.kind == part.primitive.kind)
        return host.inliers.size() >= part.inliers.size();
    return static_cast<int>(host.primitive.kind) > static_cast<int>(part.primitive.kind);
}

} // namespace

ScannerView::ScannerView(const PointCloud& cloud, const SensorPose& pose, double step)
    : position_(pose.position), worldToSensor_(pose.orientation.toRotationMatrix().transpose())
{
    constexpr double kPi = 3.14159265358979323846;
    constexpr double kMostCells = 8.0 * (1 << 20); // 64 MB: a coarser grid for very fine steps
    constexpr float kNone = std::numeric_limits<float>::infinity();
    step_ = std::max(step, std::sqrt(2 * kPi * kPi / kMostCells));
    width_ = static_cast<int>(std::ceil(2 * kPi / step_));
    height_ = static_cast<int>(std::ceil(kPi / step_));
    nearest_.assign(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), {kNone, kNone});
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        int u = 0, v = 0;
        double range = 0;
        if (!cellOf(cloud.globalPosition(i), u, v, range))
            continue;
        std::array<float, 2>& cell = nearest_[static_cast<std::size_t>(v) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(u)];
        const auto r = static_cast<float>(range);
        if (r < cell[0]) {
            cell[1] = cell[0];
            cell[0] = r;
        } else if (r < cell[1]) {
            cell[1] = r;
        }
    }
}

bool ScannerView::cellOf(const Eigen::Vector3d& point, int& u, int& v, double& range) const
{
    constexpr double kPi = 3.14159265358979323846;
    const Eigen::Vector3d local = worldToSensor_ * (point - position_);
    range = local.norm();
    if (!(range > 0) || !std::isfinite(range))
        return false;
    const double yaw = std::atan2(local.y(), local.x()), pitch = std::atan2(local.z(), std::hypot(local.x(), local.y()));
    u = std::clamp(static_cast<int>(std::floor((yaw + kPi) / step_)), 0, width_ - 1);
    v = std::clamp(static_cast<int>(std::floor((pitch + kPi / 2) / step_)), 0, height_ - 1);
    return true;
}

bool ScannerView::lookedPast(const Eigen::Vector3d& point, double tolerance, bool isAReturn) const
{
    int u = 0, v = 0;
    double range = 0;
    if (!cellOf(point, u, v, range))
        return false;
    // A stored range this close to the point's is the point's own (float rounding).
    const double self = 1e-5 * range + 1e-6;
    int withReturns = 0;
    for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du) {
            const int vv = v + dv, uu = (u + du + width_) % width_; // the yaw wraps
            if (vv < 0 || vv >= height_)
                continue;
            const std::array<float, 2>& cell = nearest_[static_cast<std::size_t>(vv) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(uu)];
            const bool ownReturnFirst = isAReturn && du == 0 && dv == 0 && std::abs(cell[0] - range) <= self;
            const float nearest = ownReturnFirst ? cell[1] : cell[0];
            if (!std::isfinite(nearest))
                continue;
            if (nearest <= range + tolerance)
                return false;
            ++withReturns;
        }
    return withReturns >= 3;
}

std::vector<ScannerView> scannerViews(const PointCloud& cloud, double spacing)
{
    std::vector<ScannerView> views;
    for (const SensorPose& pose : cloud.sensors()) {
        double step = std::max(pose.yawStep, pose.pitchStep);
        if (!(step > 0)) {
            std::vector<double> ranges;
            for (std::size_t i = 0; i < cloud.size(); i += std::max<std::size_t>(1, cloud.size() / 2000))
                ranges.push_back((cloud.globalPosition(i) - pose.position).norm());
            std::nth_element(ranges.begin(), ranges.begin() + static_cast<std::ptrdiff_t>(ranges.size() / 2), ranges.end());
            step = ranges.empty() || !(ranges[ranges.size() / 2] > 0) ? 1e-3 : spacing / ranges[ranges.size() / 2];
        }
        views.emplace_back(cloud, pose, step);
    }
    return views;
}

void measureShape(DetectedPrimitive& shape, const SurfaceEvidence& evidence)
{
    const double cell = std::max(2.0 * evidence.spacing, 1e-6);
    std::unordered_set<std::uint64_t> cells;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    const bool hasAxis = shape.primitive.kind == PrimitiveKind::Cylinder || shape.primitive.kind == PrimitiveKind::Cone;
    for (std::uint32_t i : shape.inliers) {
        const Eigen::Vector3d& p = evidence.points[i];
        cells.insert(cellKey(p, cell));
        sum += p;
        if (hasAxis) {
            const double t = (evidence.centre + p - shape.primitive.point).dot(shape.primitive.direction);
            lo = std::min(lo, t);
            hi = std::max(hi, t);
        }
    }
    shape.area = static_cast<double>(cells.size()) * cell * cell;
    // The RMS of the inliers as they are now (points given or taken since the fit).
    double squares = 0;
    for (std::uint32_t i : shape.inliers) {
        const double d = signedDistance(shape.primitive, evidence.centre + evidence.points[i]);
        squares += d * d;
    }
    shape.rms = std::sqrt(squares / static_cast<double>(std::max<std::size_t>(1, shape.inliers.size())));
    shape.centroid = evidence.centre + sum / static_cast<double>(std::max<std::size_t>(1, shape.inliers.size()));
    shape.length = hasAxis ? hi - lo : 0.0;
}

std::size_t mergeSurfaceParts(std::vector<DetectedPrimitive>& shapes, const SurfaceEvidence& evidence, bool mergeApart,
                              std::vector<std::string>& notes)
{
    // Pairs (by the shapes' first inlier, stable while they are not merged)
    // found apart: not looked at again until one of them changes.
    std::set<std::pair<std::uint32_t, std::uint32_t>> apart;
    std::size_t merges = 0;
    for (bool merged = true; merged;) {
        merged = false;
        for (std::size_t h = 0; h < shapes.size() && !merged; ++h) {
            std::optional<std::unordered_set<std::uint64_t>> hostCells; // built when a part first needs it
            for (std::size_t p = 0; p < shapes.size() && !merged; ++p) {
                evidence.checkCancel();
                DetectedPrimitive& host = shapes[h];
                const DetectedPrimitive& part = shapes[p];
                if (h == p || !mayHost(host, part) || apart.count({host.inliers.front(), part.inliers.front()}))
                    continue;
                const double needed = host.primitive.kind == part.primitive.kind ? 0.5 : 0.9;
                if (shareOnSurface(host.primitive, part.inliers, evidence) < needed)
                    continue;
                if (!hostCells)
                    hostCells = cellsOf(host.inliers, evidence);
                bool touch = false;
                for (std::uint32_t i : part.inliers)
                    if ((touch = nearCells(*hostCells, evidence.points[i], evidence.linkDistance)))
                        break;
                const bool hiddenGap = !touch && mergeApart && gapUnseen(host.primitive, host.inliers, part.inliers, evidence);
                PrimitiveRefinement joint;
                std::vector<std::uint32_t> both = host.inliers;
                both.insert(both.end(), part.inliers.begin(), part.inliers.end());
                bool fits = touch || hiddenGap;
                if (fits) {
                    try {
                        joint = refinePrimitive(positionsOf(both, evidence), evidence.centre, host.primitive);
                        fits = joint.rms <= (1 + evidence.typeTolerance) * std::max(host.rms, part.rms) && joint.rms <= evidence.epsilon;
                    } catch (const Error&) {
                        fits = false;
                    }
                }
                if (!fits) {
                    apart.insert({host.inliers.front(), part.inliers.front()});
                    continue;
                }
                const std::uint32_t hostKey = host.inliers.front();
                const std::string partKind = primitiveKindName(part.primitive.kind);
                const std::size_t partPoints = part.inliers.size();
                std::sort(both.begin(), both.end());
                host.inliers = std::move(both);
                host.primitive = joint.primitive;
                host.uncertainty = joint.uncertainty;
                measureShape(host, evidence); // its RMS too
                notes.push_back(std::string("a ") + partKind + " of " + std::to_string(partPoints) + " points joined a " +
                                primitiveKindName(host.primitive.kind) + (touch ? " it touches" : " across a gap no scanner saw into"));
                // The grown shape may now touch, or fit, one it was apart from:
                // its pairs, and the part's, are looked at again.
                const std::uint32_t partKey = shapes[p].inliers.front();
                for (auto pair = apart.begin(); pair != apart.end();) {
                    const bool involved = pair->first == hostKey || pair->second == hostKey || pair->first == partKey ||
                                          pair->second == partKey || pair->first == host.inliers.front() || pair->second == host.inliers.front();
                    pair = involved ? apart.erase(pair) : std::next(pair);
                }
                shapes.erase(shapes.begin() + static_cast<std::ptrdiff_t>(p));
                ++merges;
                merged = true;
            }
        }
    }
    return merges;
}

namespace {

//! Where two shapes meet smoothly (an elbow's torus and its straight leg, a
//! reducer and its pipe) a band of points lies within epsilon of both, and
//! the nearer surface is a matter of noise. Each point of such a band goes
//! to the shape of the nearest point that lies on one surface only: the band
//! is split where the shapes meet. Returns the points that changed hands.
std::size_t splitWhereShapesMeet(const std::vector<DetectedPrimitive>& shapes, const SurfaceEvidence& evidence,
                                 const std::vector<std::uint32_t>& contested, std::vector<int>& owner)
{
    // The shapes each contested point lies on (its own and others), and
    // which of them are in a band (on two or more).
    std::vector<std::vector<int>> on(contested.size());
    std::unordered_set<std::uint32_t> inBand;
    for (std::size_t k = 0; k < contested.size(); ++k) {
        const std::uint32_t i = contested[k];
        for (std::size_t s = 0; s < shapes.size(); ++s)
            if (std::isfinite(distanceOnSurface(shapes[s].primitive, i, evidence)))
                on[k].push_back(static_cast<int>(s));
        if (on[k].size() >= 2)
            inBand.insert(i);
    }
    if (inBand.empty())
        return 0;
    // Points on one surface only, near a band, by cell.
    const double cell = evidence.linkDistance;
    std::unordered_set<std::uint64_t> bandCells;
    for (std::uint32_t i : inBand)
        for (std::uint64_t key : neighbourKeys(evidence.points[i], cell))
            bandCells.insert(key);
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> anchors;
    for (std::size_t i = 0; i < owner.size(); ++i)
        if (owner[i] >= 0 && !inBand.count(static_cast<std::uint32_t>(i))) {
            const std::uint64_t key = cellKey(evidence.points[i], cell);
            if (bandCells.count(key))
                anchors[key].push_back(static_cast<std::uint32_t>(i));
        }
    std::vector<std::pair<std::uint32_t, int>> moves;
    for (std::size_t k = 0; k < contested.size(); ++k) {
        if (on[k].size() < 2)
            continue;
        const std::uint32_t i = contested[k];
        const Eigen::Vector3d& p = evidence.points[i];
        double best = std::numeric_limits<double>::infinity();
        int nearestShape = owner[i];
        for (std::uint64_t key : neighbourKeys(p, cell)) {
            const auto found = anchors.find(key);
            if (found == anchors.end())
                continue;
            for (std::uint32_t j : found->second) {
                const double d = (evidence.points[j] - p).squaredNorm();
                if (d < best && std::find(on[k].begin(), on[k].end(), owner[j]) != on[k].end()) {
                    best = d;
                    nearestShape = owner[j];
                }
            }
        }
        if (nearestShape != owner[i])
            moves.emplace_back(i, nearestShape);
    }
    for (const auto& [i, s] : moves)
        owner[i] = s;
    return moves.size();
}

//! Where the shapes are while they grow: each point's shape (-1: none), the
//! cells (of the link distance) each shape holds points in, and the box its
//! next point may lie in.
struct ShapeGrowth
{
    std::vector<int>& owner;
    std::vector<std::unordered_set<std::uint64_t>>& cells;
    std::vector<Eigen::AlignedBox3d>& reach;

    void give(std::uint32_t i, int shape, const SurfaceEvidence& evidence)
    {
        const Eigen::Vector3d& p = evidence.points[i];
        const double link = evidence.linkDistance;
        owner[i] = shape;
        cells[std::size_t(shape)].insert(cellKey(p, link));
        reach[std::size_t(shape)].extend(Eigen::Vector3d(p.array() - link));
        reach[std::size_t(shape)].extend(Eigen::Vector3d(p.array() + link));
    }
};

//! Passes over the contested points while shapes grow: each goes to the
//! shape it lies nearest to among those holding points next to it.
std::size_t growByAdjacency(const std::vector<DetectedPrimitive>& shapes, const SurfaceEvidence& evidence,
                            const std::vector<std::uint32_t>& contested, ShapeGrowth& growth)
{
    constexpr int kMaxPasses = 30;
    std::size_t changed = 0;
    std::vector<std::pair<int, double>> near; // the shapes next to a point that it lies within epsilon of (its own first)
    for (int pass = 0; pass < kMaxPasses; ++pass) {
        evidence.checkCancel();
        std::size_t changedThisPass = 0;
        for (std::uint32_t i : contested) {
            const Eigen::Vector3d& p = evidence.points[i];
            const int current = growth.owner[i];
            near.clear();
            if (current >= 0)
                near.emplace_back(current, distanceWithin(shapes[std::size_t(current)].primitive, i, evidence));
            for (std::size_t s = 0; s < shapes.size(); ++s) {
                if (static_cast<int>(s) == current || !growth.reach[s].contains(p))
                    continue;
                const double d = distanceWithin(shapes[s].primitive, i, evidence);
                if (std::isfinite(d) && nearCells(growth.cells[s], p, evidence.linkDistance))
                    near.emplace_back(static_cast<int>(s), d);
            }
            // Between shapes its normal decides, then the distance; on one
            // surface only, the distance alone (a normal fitted on one scan
            // line at grazing incidence turns anywhere about it).
            int best = current;
            double bestDistance = std::numeric_limits<double>::infinity();
            const bool between = std::count_if(near.begin(), near.end(), [](const auto& n) { return std::isfinite(n.second); }) >= 2;
            for (const auto& [s, d] : near)
                if (d < bestDistance && (!between || normalAgrees(shapes[std::size_t(s)].primitive, i, evidence))) {
                    best = s;
                    bestDistance = d;
                }
            if (best == current)
                continue;
            growth.give(i, best, evidence);
            ++changedThisPass;
        }
        changed += changedThisPass;
        if (changedThisPass == 0)
            break;
    }
    return changed;
}

//! The points left on no shape that lie on one in groups apart from it (a
//! box top cut by the shadow of the sphere standing on it, in parts too
//! small for RANSAC): a group of at least 10 points joins the shape when no
//! scanner looked through the gap between them.
std::size_t joinHiddenParts(const std::vector<DetectedPrimitive>& shapes, const SurfaceEvidence& evidence,
                            const std::vector<std::uint32_t>& contested, ShapeGrowth& growth, std::vector<std::string>& notes)
{
    constexpr std::size_t kSmallestGroup = 10;
    if (evidence.views.empty())
        return 0;
    std::size_t joined = 0;
    for (std::size_t s = 0; s < shapes.size(); ++s) {
        evidence.checkCancel();
        // The free points on this shape's surface, by cell.
        std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> free;
        for (std::uint32_t i : contested)
            if (growth.owner[i] < 0 && std::isfinite(distanceOnSurface(shapes[s].primitive, i, evidence)))
                free[cellKey(evidence.points[i], evidence.linkDistance)].push_back(i);
        // Their groups: cells linked through their 26 neighbours.
        std::unordered_set<std::uint64_t> visited;
        for (const auto& [start, unused] : free) {
            if (!visited.insert(start).second)
                continue;
            std::vector<std::uint32_t> group;
            std::vector<std::uint64_t> stack{start};
            while (!stack.empty()) {
                const std::uint64_t key = stack.back();
                stack.pop_back();
                const std::vector<std::uint32_t>& here = free.at(key);
                group.insert(group.end(), here.begin(), here.end());
                const Eigen::Vector3d& p = evidence.points[here.front()];
                for (std::uint64_t next : neighbourKeys(p, evidence.linkDistance))
                    if (free.count(next) && visited.insert(next).second)
                        stack.push_back(next);
            }
            std::sort(group.begin(), group.end()); // the cells' hash order out of the samples taken
            if (group.size() < kSmallestGroup || !gapUnseen(shapes[s].primitive, shapes[s].inliers, group, evidence))
                continue;
            for (std::uint32_t i : group)
                growth.give(i, static_cast<int>(s), evidence);
            joined += group.size();
        }
    }
    if (joined)
        notes.push_back(std::to_string(joined) + " points on no shape joined the shape they lie on across gaps no scanner saw into");
    return joined;
}

} // namespace

std::size_t dropUnseeable(std::vector<DetectedPrimitive>& shapes, const SurfaceEvidence& evidence, std::vector<std::string>& notes)
{
    if (evidence.views.empty())
        return 0;
    const double grazing = std::cos(88.0 * 3.14159265358979323846 / 180.0);
    const double tolerance = std::max(2.0 * evidence.epsilon, 0.5 * evidence.linkDistance);
    std::size_t dropped = 0, shapesDropped = 0;
    std::vector<DetectedPrimitive> kept;
    for (DetectedPrimitive& shape : shapes) {
        evidence.checkCancel();
        const Primitive& surface = shape.primitive;
        const bool twoSided = surface.kind == PrimitiveKind::Plane;
        // The inside of a sphere, a cylinder, a cone (convex) faces a scanner
        // standing in it (a tunnel, a hopper seen from above its rim), the
        // outside one standing out of it; a plane faces both sides.
        std::vector<double> side;
        for (const ScannerView& view : evidence.views)
            side.push_back(twoSided ? 0.0 : signedDistance(surface, view.position()) >= 0 ? 1.0 : -1.0);
        std::vector<char> keep(shape.inliers.size(), 0);
        tbb::parallel_for(std::size_t(0), shape.inliers.size(), [&](std::size_t k) {
            const Eigen::Vector3d x = evidence.centre + evidence.points[shape.inliers[k]];
            const Eigen::Vector3d outward = surfaceNormal(surface, x);
            // A plane is kept up to grazing incidence: a floor 45 m from a
            // tripod is met at 88 degrees and still returns; the facing test
            // is for the back of a curved shape, where mixed pixels land.
            bool facing = twoSided;
            for (std::size_t v = 0; v < evidence.views.size(); ++v) {
                const ScannerView& view = evidence.views[v];
                const Eigen::Vector3d toScanner = (view.position() - x).normalized();
                const double c = twoSided ? std::abs(toScanner.dot(outward)) : side[v] * toScanner.dot(outward);
                if (c <= (twoSided ? 0.0 : grazing))
                    continue;
                facing = true;
                if (c > std::cos(80.0 * 3.14159265358979323846 / 180.0) && view.lookedPast(x, tolerance / c, true))
                    return; // a scanner facing the surface there saw through it
            }
            keep[k] = facing;
        });
        std::vector<std::uint32_t> inliers;
        for (std::size_t k = 0; k < keep.size(); ++k)
            if (keep[k])
                inliers.push_back(shape.inliers[k]);
        dropped += shape.inliers.size() - inliers.size();
        if (inliers.size() < evidence.minPoints) {
            ++shapesDropped;
            continue;
        }
        if (inliers.size() != shape.inliers.size()) {
            shape.inliers = std::move(inliers);
            measureShape(shape, evidence);
        }
        kept.push_back(std::move(shape));
    }
    shapes = std::move(kept);
    if (dropped)
        notes.push_back(std::to_string(dropped) + " points left out where no scanner faced their shape, or one facing it saw through it" +
                        (shapesDropped ? " (" + std::to_string(shapesDropped) + " shapes dropped)" : std::string()));
    return dropped;
}

double residualStructure(const DetectedPrimitive& shape, const SurfaceEvidence& evidence)
{
    struct Cell
    {
        double sum = 0;
        std::size_t count = 0;
    };
    std::unordered_map<std::uint64_t, Cell> cells;
    double squares = 0;
    for (std::uint32_t i : shape.inliers) {
        const double r = signedDistance(shape.primitive, evidence.centre + evidence.points[i]);
        Cell& cell = cells[cellKey(evidence.points[i], evidence.linkDistance)];
        cell.sum += r;
        ++cell.count;
        squares += r * r;
    }
    const double variance = squares / static_cast<double>(std::max<std::size_t>(1, shape.inliers.size()));
    double weighted = 0;
    std::size_t used = 0;
    for (const auto& [key, cell] : cells)
        if (cell.count >= 4) {
            weighted += cell.sum * cell.sum / static_cast<double>(cell.count); // n * mean^2
            ++used;
        }
    return used == 0 || !(variance > 0) ? 1.0 : weighted / (static_cast<double>(used) * variance);
}

std::size_t dropFormedResiduals(std::vector<DetectedPrimitive>& shapes, const SurfaceEvidence& evidence, std::vector<std::string>& notes)
{
    constexpr double kNoiseStructure = 4, kNoiseShare = 0.5;
    const std::size_t before = shapes.size();
    shapes.erase(std::remove_if(shapes.begin(), shapes.end(),
                                [&](const DetectedPrimitive& shape) {
                                    return shape.rms > kNoiseShare * evidence.epsilon && residualStructure(shape, evidence) > kNoiseStructure;
                                }),
                 shapes.end());
    const std::size_t dropped = before - shapes.size();
    if (dropped)
        notes.push_back(std::to_string(dropped) + " shapes left out: their points lie off them in a form of their own, wider than the noise "
                        "(lumpy objects, a corner fitted with a curve)");
    return dropped;
}

std::size_t claimPoints(std::vector<DetectedPrimitive>& shapes, const SurfaceEvidence& evidence, std::size_t cloudSize,
                        std::vector<std::string>& notes)
{
    const double link = evidence.linkDistance;
    std::vector<int> owner(cloudSize, -1);
    std::vector<std::unordered_set<std::uint64_t>> cells(shapes.size());
    std::vector<Eigen::AlignedBox3d> reach(shapes.size()); // where a shape's next point may lie
    for (std::size_t s = 0; s < shapes.size(); ++s) {
        for (std::uint32_t i : shapes[s].inliers) {
            owner[i] = static_cast<int>(s);
            reach[s].extend(evidence.points[i]);
        }
        cells[s] = cellsOf(shapes[s].inliers, evidence);
        reach[s].min().array() -= link;
        reach[s].max().array() += link;
    }
    // The points lying on a surface other than their own shape's: the only
    // ones that may change hands (found in parallel, in the points' order).
    std::vector<char> onAnother(cloudSize, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloudSize, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i)
            for (std::size_t s = 0; s < shapes.size() && !onAnother[i]; ++s)
                onAnother[i] = static_cast<int>(s) != owner[i] &&
                               std::isfinite(distanceWithin(shapes[s].primitive, static_cast<std::uint32_t>(i), evidence));
    });
    std::vector<std::uint32_t> contested;
    for (std::size_t i = 0; i < cloudSize; ++i)
        if (onAnother[i])
            contested.push_back(static_cast<std::uint32_t>(i));
    std::vector<char>().swap(onAnother);
    ShapeGrowth growth{owner, cells, reach};
    std::size_t changed = 0;
    for (int round = 0; round < 3; ++round) {
        const std::size_t grown = growByAdjacency(shapes, evidence, contested, growth);
        const std::size_t joined = joinHiddenParts(shapes, evidence, contested, growth, notes);
        changed += grown + joined;
        if (joined == 0)
            break;
    }
    changed += splitWhereShapesMeet(shapes, evidence, contested, owner);
    if (changed == 0)
        return 0;

    std::vector<std::vector<std::uint32_t>> members(shapes.size());
    for (std::size_t i = 0; i < cloudSize; ++i)
        if (owner[i] >= 0)
            members[std::size_t(owner[i])].push_back(static_cast<std::uint32_t>(i));
    std::vector<DetectedPrimitive> kept;
    std::size_t dropped = 0;
    for (std::size_t s = 0; s < shapes.size(); ++s) {
        DetectedPrimitive& shape = shapes[s];
        if (members[s] == shape.inliers) {
            kept.push_back(std::move(shape));
            continue;
        }
        if (members[s].size() < evidence.minPoints) {
            ++dropped;
            continue;
        }
        shape.inliers = std::move(members[s]);
        try {
            const PrimitiveRefinement refit = refinePrimitive(positionsOf(shape.inliers, evidence), evidence.centre, shape.primitive);
            if (refit.rms <= evidence.epsilon) {
                shape.primitive = refit.primitive;
                shape.uncertainty = refit.uncertainty;
            }
        } catch (const Error&) {
            // The shape keeps the parameters it was found with.
        }
        measureShape(shape, evidence);
        kept.push_back(std::move(shape));
    }
    shapes = std::move(kept);
    notes.push_back(std::to_string(changed) + " points given to the shape they lie on (left out, or taken by a shape found before it)" +
                    (dropped ? "; " + std::to_string(dropped) + " shapes left below the minimum support dropped" : std::string()));
    return changed;
}

} // namespace scandiff::plugins::detail
