// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/plugins/primitives/PrimitiveDetection.h>

#include "EfficientRansac.h"
#include "RegionGrowing.h"
#include "SequentialRansac.h"
#include "ShapeParts.h"

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/processing/Normals.h>

#include <Eigen/Eigenvalues>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_set>

namespace scandiff::plugins {

namespace {

constexpr double kPi = 3.14159265358979323846;

//! The scan's point spacing and noise, from a sample of its neighbourhoods:
//! the median distance to the nearest other point, and the median standard
//! deviation across the least-squares plane of 16 neighbours.
struct ScanScale
{
    double spacing = 0;
    double sparseSpacing = 0; //!< the spacing that 90 % of the sampled points are within
    double noise = 0;
};

ScanScale estimateScale(const PointCloud& cloud, const octree::Octree& tree)
{
    constexpr std::size_t kSample = 2000, kNeighbours = 16;
    const std::size_t stride = std::max<std::size_t>(1, cloud.size() / kSample);
    std::vector<Eigen::Vector3f> queries;
    for (std::size_t i = 0; i < cloud.size(); i += stride)
        queries.push_back(cloud.positions()[i]);
    const int level = tree.levelNearestMeanPopulation(3.0 * kNeighbours);
    std::vector<octree::Neighbour> found;
    tree.nearestBatch(queries.data(), queries.size(), kNeighbours, level, found);
    std::vector<double> spacing, noise;
    for (std::size_t q = 0; q < queries.size(); ++q) {
        const octree::Neighbour* list = found.data() + q * kNeighbours;
        std::size_t count = 0;
        while (count < kNeighbours && list[count].index != std::numeric_limits<std::uint32_t>::max())
            ++count;
        if (count < 4)
            continue;
        spacing.push_back(std::sqrt(static_cast<double>(list[1].squaredDistance)));
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (std::size_t k = 0; k < count; ++k)
            mean += cloud.positions()[list[k].index].cast<double>();
        mean /= static_cast<double>(count);
        Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
        for (std::size_t k = 0; k < count; ++k) {
            const Eigen::Vector3d d = cloud.positions()[list[k].index].cast<double>() - mean;
            covariance.noalias() += d * d.transpose();
        }
        covariance /= static_cast<double>(count);
        noise.push_back(std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvalues()[0])));
    }
    ScanScale scale;
    auto median = [](std::vector<double>& v) {
        if (v.empty())
            return 0.0;
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
        return v[v.size() / 2];
    };
    if (!spacing.empty()) {
        std::nth_element(spacing.begin(), spacing.begin() + static_cast<std::ptrdiff_t>(spacing.size() * 9 / 10), spacing.end());
        scale.sparseSpacing = spacing[spacing.size() * 9 / 10];
    }
    scale.spacing = median(spacing);
    scale.noise = median(noise);
    return scale;
}

double extentOf(const std::vector<Eigen::Vector3d>& points)
{
    Eigen::Vector3d lo = points.front(), hi = points.front();
    for (const auto& p : points) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    return (hi - lo).norm();
}

//! The largest radius a curved shape may have for the extent of its points:
//! beyond it, the arc is so flat that the points do not say it is curved.
bool radiusPlausible(const Primitive& p, double extent)
{
    switch (p.kind) {
    case PrimitiveKind::Sphere:
    case PrimitiveKind::Cylinder: return p.radius > 0 && p.radius < 2.0 * extent;
    case PrimitiveKind::Torus: return p.minorRadius > 0 && p.radius > p.minorRadius && p.radius < 2.0 * extent;
    case PrimitiveKind::Cone: return p.halfAngle > 1e-3 && p.halfAngle < kPi / 2 - 1e-3;
    case PrimitiveKind::Plane: return true;
    }
    return false;
}

//! Point i's normal as RANSAC takes it: unit, +Z where the cloud has none
//! or the point's is zero.
Eigen::Vector3d unitNormalOf(const std::vector<Eigen::Vector3f>& normals, std::size_t i)
{
    const Eigen::Vector3d n = normals.empty() ? Eigen::Vector3d(Eigen::Vector3d::UnitZ()) : Eigen::Vector3d(normals[i].cast<double>());
    return n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d(Eigen::Vector3d::UnitZ());
}

//! The least-squares plane of points (their frame), as a primitive (global).
Primitive pcaPlane(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& centre)
{
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : points)
        mean += p;
    mean /= static_cast<double>(points.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const auto& p : points)
        covariance.noalias() += (p - mean) * (p - mean).transpose();
    Primitive plane;
    plane.kind = PrimitiveKind::Plane;
    plane.point = centre + mean;
    plane.direction = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvectors().col(0);
    return plane;
}

//! The cylinder a "plane" of RANSAC's is a strip of, when it is one: on a
//! thin pipe a strip as wide as the noise allows fits a plane within
//! epsilon, and RANSAC, trying planes first, takes the pipe as planes. The
//! normals turn across such a strip; the cylinder orthogonal to them, refitted
//! on an even sample of the points (at most 5,000), must fit clearly better
//! than the plane on the same sample and be no wider than twice the points'
//! extent. Empty otherwise (a flat wall: the cylinder is huge or no better).
std::optional<Primitive> cylinderOfStrip(const std::vector<Eigen::Vector3d>& members, const std::vector<Eigen::Vector3d>& memberNormals,
                                         const Eigen::Vector3d& centre, const Primitive& plane, double typeTolerance)
{
    const std::size_t stride = std::max<std::size_t>(1, (members.size() + 4999) / 5000);
    std::vector<Eigen::Vector3d> sample, sampleNormals;
    for (std::size_t k = 0; k < members.size(); k += stride)
        if (memberNormals[k].squaredNorm() > 0) {
            sample.push_back(members[k]);
            sampleNormals.push_back(memberNormals[k]);
        }
    const std::optional<Primitive> start = cylinderFromNormals(sample, sampleNormals, centre);
    const double extent = extentOf(members);
    if (!start || !radiusPlausible(*start, extent))
        return std::nullopt;
    try {
        const PrimitiveRefinement cylinder = refinePrimitive(sample, centre, *start);
        const PrimitiveRefinement flat = refinePrimitive(sample, centre, plane);
        if (radiusPlausible(cylinder.primitive, extent) && (1 + typeTolerance) * cylinder.rms < flat.rms)
            return cylinder.primitive;
    } catch (const Error&) {
        // Neither fit says more than RANSAC's plane.
    }
    return std::nullopt;
}

//! The shape's type, chosen among the types asked for: each candidate (the
//! type RANSAC found, a plane, a sphere, a cylinder for a cone) refitted by
//! least squares, and the
//! simplest one kept whose RMS is within params.typeTolerance (20 %) of the best plausible fit's
//! (fewer parameters: plane 3, sphere 4, cylinder 5, cone 6, torus 7). So a
//! box side is a plane even when a huge cylinder fits it as well, and a
//! sphere stays a sphere when a spindle torus fits it too. Empty when no
//! candidate holds the points within epsilon. `foundIsAGuess`: the shape is
//! a grown region's first guess, not a type a detector claimed, and a change
//! of type is not worth a note. `memberNormals` (one per member, or empty):
//! a plane a detector found is also tried as the cylinder it may be a strip of.
std::optional<PrimitiveRefinement> chooseType(const std::vector<Eigen::Vector3d>& members, const std::vector<Eigen::Vector3d>& memberNormals,
                                              const Eigen::Vector3d& centre, const Primitive& found, const PrimitiveDetectionParams& params,
                                              double epsilon, std::vector<std::string>& notes, bool foundIsAGuess = false)
{
    std::vector<Primitive> candidates{found};
    if (params.kinds.count(PrimitiveKind::Cylinder) && found.kind == PrimitiveKind::Plane && !foundIsAGuess && !memberNormals.empty())
        if (const auto cylinder = cylinderOfStrip(members, memberNormals, centre, found, params.typeTolerance))
            candidates.push_back(*cylinder);
    if (params.kinds.count(PrimitiveKind::Plane) && found.kind != PrimitiveKind::Plane)
        candidates.push_back(pcaPlane(members, centre));
    if (params.kinds.count(PrimitiveKind::Sphere) && found.kind != PrimitiveKind::Sphere && found.kind != PrimitiveKind::Plane)
        if (const auto sphere = algebraicSphere(members, centre))
            candidates.push_back(*sphere);
    if (params.kinds.count(PrimitiveKind::Cylinder) && found.kind == PrimitiveKind::Cone) {
        // A cone of a small angle may be a cylinder: the same axis, the mean radius.
        Primitive cylinder = found;
        cylinder.kind = PrimitiveKind::Cylinder;
        double radius = 0;
        for (const auto& p : members) {
            const Eigen::Vector3d v = centre + p - found.point;
            radius += (v - v.dot(found.direction) * found.direction).norm();
        }
        cylinder.radius = radius / static_cast<double>(members.size());
        candidates.push_back(cylinder);
    }
    const double extent = extentOf(members);
    std::vector<PrimitiveRefinement> fits;
    for (const Primitive& candidate : candidates) {
        try {
            PrimitiveRefinement fit = refinePrimitive(members, centre, candidate);
            if (radiusPlausible(fit.primitive, extent) && fit.rms < epsilon)
                fits.push_back(std::move(fit));
        } catch (const Error&) {
            // This type does not fit these points: the others are tried.
        }
    }
    if (fits.empty()) {
        notes.push_back(std::string("a ") + (foundIsAGuess ? "region" : primitiveKindName(found.kind)) + " of " + std::to_string(members.size()) +
                        " points was left out: no shape type holds them within epsilon");
        return std::nullopt;
    }
    double best = std::numeric_limits<double>::infinity();
    for (const auto& fit : fits)
        best = std::min(best, fit.rms);
    const PrimitiveRefinement* chosen = nullptr;
    for (const auto& fit : fits)
        if (fit.rms <= (1 + params.typeTolerance) * best && (!chosen || fit.primitive.kind < chosen->primitive.kind))
            chosen = &fit;
    if (chosen->primitive.kind != found.kind && !foundIsAGuess)
        notes.push_back(std::string("a ") + primitiveKindName(found.kind) + " of " + std::to_string(members.size()) + " points is a " +
                        primitiveKindName(chosen->primitive.kind) + " (it fits them as well, with fewer parameters)");
    return *chosen;
}

//! The shapes efficient RANSAC finds (in the frame of `points`).
//! `unitNormals` taken by value: CGAL copies them, and the copy given up
//! early lowers the run's peak (24 MB a million points).
std::vector<detail::RansacShape> findByRansac(const std::vector<Eigen::Vector3d>& points, std::vector<Eigen::Vector3d> unitNormals,
                                              const PrimitiveDetectionParams& params, const PrimitiveDetectionResult& result,
                                              ProgressObserver* progress, bool& cancelled)
{
    detail::RansacSettings settings;
    settings.kinds = params.kinds;
    settings.epsilon = result.epsilon;
    settings.clusterEpsilon = result.clusterEpsilon;
    settings.normalCosine = std::cos(params.normalDeviationDegrees * kPi / 180.0);
    settings.minPoints = params.minPoints;
    settings.probability = params.probability;
    settings.seed = params.seed;
    return detail::efficientRansac(points, std::move(unitNormals), settings, [&](double) {
        if (progress && progress->cancelRequested()) {
            cancelled = true;
            return false;
        }
        return true;
    });
}

//! The shape most of a rejected candidate's points lie on, when RANSAC's
//! type holds none of them within epsilon (a reducer and part of its pipe
//! taken for one torus): each other type asked for fitted from the points'
//! normals (fitPrimitive), its points within epsilon kept, the type keeping
//! the most, if at least half of them and the minimum support, refitted on
//! them. `kept`: their positions in `members`.
std::optional<PrimitiveRefinement> mainShapeOf(const std::vector<Eigen::Vector3d>& members, const std::vector<Eigen::Vector3d>& memberNormals,
                                               const Eigen::Vector3d& centre, const PrimitiveDetectionParams& params,
                                               const detail::SurfaceEvidence& evidence, std::vector<std::size_t>& kept,
                                               std::vector<std::string>& notes)
{
    PointCloud part;
    part.setOrigin(centre);
    part.resize(members.size());
    std::vector<Eigen::Vector3f>& normals = part.enableNormals();
    for (std::size_t k = 0; k < members.size(); ++k) {
        part.positions()[k] = members[k].cast<float>();
        normals[k] = memberNormals[k].cast<float>();
    }
    std::optional<PrimitiveRefinement> best;
    for (PrimitiveKind kind : {PrimitiveKind::Plane, PrimitiveKind::Sphere, PrimitiveKind::Cylinder, PrimitiveKind::Cone}) {
        if (!params.kinds.count(kind))
            continue;
        try {
            const Primitive start = fitPrimitive(part, kind).primitive;
            std::vector<std::size_t> within;
            for (std::size_t k = 0; k < members.size(); ++k)
                if (std::abs(signedDistance(start, centre + members[k])) <= evidence.epsilon)
                    within.push_back(k);
            if (within.size() < std::max(evidence.minPoints, members.size() / 2) || (best && within.size() <= kept.size()))
                continue;
            std::vector<Eigen::Vector3d> points;
            for (std::size_t k : within)
                points.push_back(members[k]);
            PrimitiveRefinement refined = refinePrimitive(points, centre, start);
            if (!(refined.rms < evidence.epsilon) || !radiusPlausible(refined.primitive, extentOf(points)))
                continue;
            best = std::move(refined);
            kept = std::move(within);
        } catch (const Error&) {
            // This type does not fit them: the others are tried.
        }
    }
    if (best)
        notes.push_back(std::string("of those, ") + std::to_string(kept.size()) + " points are a " + primitiveKindName(best->primitive.kind));
    return best;
}

//! RANSAC's (or the regions') shapes refitted by least squares, each with
//! its type checked (chooseType), measured; the ones no type holds are left
//! out. In parallel, one task a shape; the outcome and the notes in the
//! shapes' order, whatever the threads.
std::vector<DetectedPrimitive> typedShapes(const std::vector<detail::RansacShape>& found, const std::vector<Eigen::Vector3d>& points,
                                           const std::vector<Eigen::Vector3f>& normals, const Eigen::Vector3d& centre,
                                           const PrimitiveDetectionParams& typeParams, bool typedRegions,
                                           const detail::SurfaceEvidence& evidence, ProgressObserver* progress, std::vector<std::string>& notes)
{
    std::vector<std::optional<DetectedPrimitive>> refitted(found.size());
    std::vector<std::vector<std::string>> shapeNotes(found.size());
    std::atomic<bool> stopped{false};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, found.size(), 1), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t s = range.begin(); s != range.end(); ++s) {
            // Asked before each shape, kept or not: a refit can take a few tenths of a second.
            if (stopped || (progress && progress->cancelRequested())) {
                stopped = true;
                return;
            }
            const detail::RansacShape& shape = found[s];
            std::vector<Eigen::Vector3d> members, memberNormals;
            members.reserve(shape.members.size());
            for (std::uint32_t i : shape.members)
                members.push_back(points[i]);
            if (!normals.empty())
                for (std::uint32_t i : shape.members)
                    memberNormals.push_back(normals[i].cast<double>().normalized());
            if (members.size() < evidence.minPoints)
                continue;
            Primitive initial = shape.primitive;
            if (!typeParams.kinds.count(initial.kind)) { // a region whose normals turn, cylinders not asked for
                if (typeParams.kinds.count(PrimitiveKind::Sphere)) {
                    const std::optional<Primitive> sphere = algebraicSphere(members, Eigen::Vector3d::Zero());
                    if (!sphere)
                        continue;
                    initial = *sphere;
                } else if (typeParams.kinds.count(PrimitiveKind::Plane)) {
                    initial = pcaPlane(members, Eigen::Vector3d::Zero());
                } else {
                    continue; // a flat region, planes not asked for
                }
            }
            initial.point += centre; // CGAL's frame -> global
            std::optional<PrimitiveRefinement> chosen = chooseType(members, memberNormals, centre, initial, typeParams, evidence.epsilon, shapeNotes[s], typedRegions);
            std::vector<std::uint32_t> inliers(shape.members.begin(), shape.members.end());
            if (!chosen && !typedRegions && !memberNormals.empty()) {
                std::vector<std::size_t> kept;
                chosen = mainShapeOf(members, memberNormals, centre, typeParams, evidence, kept, shapeNotes[s]);
                inliers.clear();
                for (std::size_t k : kept)
                    inliers.push_back(shape.members[k]);
            }
            if (!chosen)
                continue;
            const PrimitiveRefinement& refined = *chosen;
            DetectedPrimitive detected;
            detected.primitive = refined.primitive;
            detected.inliers = std::move(inliers);
            std::sort(detected.inliers.begin(), detected.inliers.end());
            detected.uncertainty = refined.uncertainty;
            detail::measureShape(detected, evidence); // its RMS too
            refitted[s] = std::move(detected);
        }
    }, tbb::simple_partitioner());
    std::vector<DetectedPrimitive> shapes;
    for (std::size_t s = 0; s < found.size(); ++s) {
        notes.insert(notes.end(), shapeNotes[s].begin(), shapeNotes[s].end());
        if (refitted[s])
            shapes.push_back(std::move(*refitted[s]));
    }
    return shapes;
}

//! A second search among the points left on no shape: RANSAC draws at
//! random, and a shape whose first candidate no type held (a reducer taken
//! for a torus with part of its pipe) leaves its points to nobody. Their
//! shapes, typed, join the result. Returns how many.
std::size_t searchLeftOver(PrimitiveDetectionResult& result, const std::vector<Eigen::Vector3d>& points,
                           const std::vector<Eigen::Vector3f>& normals, const Eigen::Vector3d& centre,
                           const PrimitiveDetectionParams& params, const detail::SurfaceEvidence& evidence, ProgressObserver* progress,
                           bool& cancelled)
{
    std::vector<char> taken(points.size(), 0);
    for (const DetectedPrimitive& shape : result.primitives)
        for (std::uint32_t i : shape.inliers)
            taken[i] = 1;
    std::vector<std::uint32_t> left;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (!taken[i])
            left.push_back(static_cast<std::uint32_t>(i));
    if (left.size() < 2 * params.minPoints)
        return 0;
    std::vector<Eigen::Vector3d> leftPoints, leftNormals;
    for (std::uint32_t i : left) {
        leftPoints.push_back(points[i]);
        leftNormals.push_back(unitNormalOf(normals, i));
    }
    std::vector<detail::RansacShape> found = findByRansac(leftPoints, std::move(leftNormals), params, result, progress, cancelled);
    if (cancelled)
        return 0;
    for (detail::RansacShape& shape : found)
        for (std::uint32_t& member : shape.members)
            member = left[member];
    std::vector<DetectedPrimitive> more = typedShapes(found, points, normals, centre, params, false, evidence, progress, result.notes);
    for (DetectedPrimitive& shape : more)
        result.primitives.push_back(std::move(shape));
    if (!more.empty())
        result.notes.push_back(std::to_string(more.size()) + " shapes found in a second search among the " + std::to_string(left.size()) +
                               " points left on no shape");
    return more.size();
}

//! The candidates of the method asked for (in the frame of `points`):
//! regions grown, a façade's planes by sequential RANSAC, or efficient
//! RANSAC's shapes. `keepGoing` asks for Cancel; `cancelled` says it came.
std::vector<detail::RansacShape> findCandidates(const PointCloud& cloud, const std::vector<Eigen::Vector3d>& points,
                                                std::vector<Eigen::Vector3d> unitNormals, const octree::Octree& tree, double spacing,
                                                const PrimitiveDetectionParams& params, PrimitiveDetectionResult& result,
                                                ProgressObserver* progress, const std::function<bool()>& keepGoing, bool& cancelled)
{
    if (params.method == PrimitiveMethod::RegionGrowing) {
        detail::RegionGrowingSettings growing;
        growing.epsilon = result.epsilon;
        growing.normalDegrees = params.normalDeviationDegrees;
        growing.neighbourRadius = result.clusterEpsilon;
        growing.minPoints = params.minPoints;
        growing.smoothnessDegrees = params.smoothnessDegrees;
        growing.curvature = params.curvature;
        growing.tolerance = params.valueTolerance;
        if (params.growOn == GrowOn::Plane) {
            return detail::growPlanarRegions(points, unitNormals, tree, growing, keepGoing);
        } else {
            detail::GrowingOutcome outcome;
            if (params.growOn == GrowOn::Smoothness) {
                outcome = detail::growSmoothRegions(points, unitNormals, tree, growing, keepGoing);
                result.notes.push_back("smooth regions: neighbours' normals within " + std::to_string(params.smoothnessDegrees) +
                                       " deg, spread by points of surface variation up to " + std::to_string(outcome.curvature));
            } else {
                const ScalarField* field = cloud.field(params.valueField);
                if (!field)
                    throw Error(ErrorCode::InvalidArgument, "primitives: the cloud '" + cloud.name + "' has no field '" + params.valueField +
                                                                "' to grow regions on");
                const double radius = params.valueRadius ? *params.valueRadius : 2.0 * spacing;
                outcome = detail::growValueRegions(points, field->values(), tree, radius, growing, keepGoing);
                result.notes.push_back("regions of " + params.valueField + ": variance up to " + std::to_string(outcome.tolerance) +
                                       ", grown by " + std::to_string(radius) + " m");
            }
            for (detail::RansacShape& region : outcome.regions)
                region.primitive = detail::initialShape(points, unitNormals, region.members);
            return std::move(outcome.regions);
        }
    } else if (params.method == PrimitiveMethod::Sequential) {
        detail::SequentialSettings sequential;
        sequential.distance = result.epsilon;
        sequential.pixel = result.clusterEpsilon;
        sequential.toleranceDegrees = params.orientationToleranceDegrees;
        sequential.minPoints = params.minPoints;
        sequential.probability = 1.0 - params.probability;
        sequential.seed = params.seed;
        detail::SequentialOutcome outcome = detail::sequentialPlanes(points, tree, sequential, keepGoing);
        result.facadeNormal = outcome.facadeNormal;
        result.notes.insert(result.notes.end(), outcome.notes.begin(), outcome.notes.end());
        return std::move(outcome.planes);
    } else {
        return findByRansac(points, std::move(unitNormals), params, result, progress, cancelled);
    }
}

//! The shapes once typed, completed (ShapeParts.h). RANSAC returns a
//! surface in parts (a wall cut by a column's shadow, a sphere's cap found
//! apart from the rest) and gives the points where two shapes meet to the
//! one found first: parts of one surface merged, each point given to the
//! shape it lies on (repeated while the refits move shapes: a torus fitted
//! without the points its leg took gives them back once refitted), a second
//! search among the points left on no shape, then the returns no scanner
//! could make and the shapes that are no surface left out. Other methods'
//! shapes: touching parts merged only.
void completeShapes(PrimitiveDetectionResult& result, const PointCloud& cloud, const std::vector<Eigen::Vector3d>& points,
                    const std::vector<Eigen::Vector3f>& normals, const Eigen::Vector3d& centre, const PrimitiveDetectionParams& params,
                    detail::SurfaceEvidence& evidence, ProgressObserver* progress, bool& cancelled)
{
    if (params.method != PrimitiveMethod::EfficientRansac) {
        detail::mergeSurfaceParts(result.primitives, evidence, false, result.notes);
        return;
    }
    evidence.views = detail::scannerViews(cloud, evidence.spacing);
    const auto claimAndMerge = [&] {
        for (int round = 0; round < 3 && detail::claimPoints(result.primitives, evidence, cloud.size(), result.notes) > cloud.size() / 2000; ++round)
            ;
        detail::mergeSurfaceParts(result.primitives, evidence, true, result.notes);
    };
    detail::mergeSurfaceParts(result.primitives, evidence, true, result.notes);
    claimAndMerge();
    if (searchLeftOver(result, points, normals, centre, params, evidence, progress, cancelled) > 0) {
        detail::mergeSurfaceParts(result.primitives, evidence, true, result.notes);
        claimAndMerge();
    }
    detail::dropUnseeable(result.primitives, evidence, result.notes);
    detail::dropFormedResiduals(result.primitives, evidence, result.notes);
}

void checkParameters(const PrimitiveDetectionParams& params)
{
    auto bad = [](const std::string& why) { throw Error(ErrorCode::InvalidArgument, "primitives: " + why); };
    if (params.kinds.empty())
        bad("no shape type asked for");
    const bool typedRegions = params.method == PrimitiveMethod::RegionGrowing && params.growOn != GrowOn::Plane;
    if (typedRegions && !params.kinds.count(PrimitiveKind::Plane) && !params.kinds.count(PrimitiveKind::Sphere) &&
        !params.kinds.count(PrimitiveKind::Cylinder))
        bad("grown regions are typed as planes, spheres or cylinders: ask for one of them, or use efficient RANSAC");
    if (params.method != PrimitiveMethod::EfficientRansac && !typedRegions && !params.kinds.count(PrimitiveKind::Plane))
        bad(std::string(params.method == PrimitiveMethod::Sequential ? "sequential RANSAC finds" : "region growing on planes grows") +
            " planes: ask for planes, or use efficient RANSAC for curved shapes");
    if (!(params.smoothnessDegrees > 0 && params.smoothnessDegrees < 90))
        bad("the smoothness angle must be between 0 and 90 degrees");
    if (params.curvature && !(*params.curvature >= 0 && *params.curvature <= 1 / 3.0))
        bad("the curvature (surface variation) threshold must be in [0, 1/3]");
    if (params.valueTolerance && !(*params.valueTolerance > 0 && std::isfinite(*params.valueTolerance)))
        bad("the value tolerance (a variance) must be > 0");
    if (params.valueRadius && !(*params.valueRadius > 0 && std::isfinite(*params.valueRadius)))
        bad("the growing radius must be > 0");
    if (!(params.orientationToleranceDegrees > 0 && params.orientationToleranceDegrees < 45))
        bad("the orientation tolerance must be between 0 and 45 degrees");
    if (params.epsilon && !(*params.epsilon > 0))
        bad("epsilon must be > 0");
    if (params.clusterEpsilon && !(*params.clusterEpsilon > 0))
        bad("the cluster epsilon must be > 0");
    if (!(params.normalDeviationDegrees > 0 && params.normalDeviationDegrees < 90))
        bad("the normal deviation must be between 0 and 90 degrees");
    if (params.minPoints < 10)
        bad("the minimum support is at least 10 points");
    if (!(params.probability > 0 && params.probability < 1))
        bad("the probability must be in (0, 1)");
    if (!(params.typeTolerance >= 0 && params.typeTolerance <= 1))
        bad("the type tolerance must be in [0, 1]");
}

} // namespace

PrimitiveMethod parsePrimitiveMethod(const std::string& name)
{
    if (name == "efficient-ransac")
        return PrimitiveMethod::EfficientRansac;
    if (name == "region-growing")
        return PrimitiveMethod::RegionGrowing;
    if (name == "sequential")
        return PrimitiveMethod::Sequential;
    throw Error(ErrorCode::InvalidArgument, "primitives: method '" + name + "': expected efficient-ransac, region-growing or sequential");
}

GrowOn parseGrowOn(const std::string& name)
{
    if (name == "plane")
        return GrowOn::Plane;
    if (name == "smoothness")
        return GrowOn::Smoothness;
    if (name == "intensity" || name == "value")
        return GrowOn::Value;
    throw Error(ErrorCode::InvalidArgument, "primitives: region growing on '" + name + "': give plane, smoothness or intensity");
}

PrimitiveDetectionResult detectPrimitives(const PointCloud& cloud, const PrimitiveDetectionParams& params, ProgressObserver* progress)
{
    checkParameters(params);
    if (cloud.empty())
        throw Error(ErrorCode::InvalidData, "primitives: cloud '" + cloud.name + "' is empty");
    if (cloud.size() < params.minPoints)
        throw Error(ErrorCode::InvalidData, "primitives: cloud '" + cloud.name + "' has " + std::to_string(cloud.size()) +
                                                " points, fewer than the minimum support (" + std::to_string(params.minPoints) + ")");
    ProgressTicker ticker(progress, "Primitives", 100);
    PrimitiveDetectionResult result;
    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    const ScanScale scale = estimateScale(cloud, tree);
    result.epsilon = params.epsilon ? *params.epsilon : std::max(3.0 * scale.noise, 1e-6);
    // A scan's spacing grows with range: RANSAC's shapes linked at the
    // spacing near the scanner leave a far wall in pieces too small to be
    // shapes. Regions grow at the median spacing (thesis 003's stones, 001's
    // façade pixels), where a wider link would bridge a joint.
    const bool ransac = params.method == PrimitiveMethod::EfficientRansac;
    result.clusterEpsilon = params.clusterEpsilon ? *params.clusterEpsilon
                                                  : std::max(3.0 * (ransac ? scale.sparseSpacing : scale.spacing), result.epsilon);
    if (!params.epsilon)
        result.notes.push_back("epsilon " + std::to_string(result.epsilon) + " m: 3 x the noise estimated from the points");
    if (!params.clusterEpsilon)
        result.notes.push_back("cluster epsilon " + std::to_string(result.clusterEpsilon) + " m: 3 x the " +
                               (ransac ? "spacing 90 % of the points are within" : "median spacing"));

    std::vector<Eigen::Vector3f> normalsStore;
    const std::vector<Eigen::Vector3f>* normals = &cloud.normals();
    // Sequential RANSAC uses coordinates only, as the thesis does.
    if (!cloud.hasNormals() && params.method != PrimitiveMethod::Sequential) {
        // A neighbourhood wide enough for the noise to tilt a normal by no
        // more than about 5 degrees (radius >= 10 sigma), and holding a few
        // spacings: 12 neighbours of a dense, noisy scan give normals too
        // scattered for the shapes' normal test, which then breaks them up.
        NormalParams normalParams;
        normalParams.radius = std::max(2.5 * scale.spacing, 10.0 * scale.noise);
        // Far from the scanner the spacing is several times the median: there
        // the radius widens to the 12 nearest points (a far wall's normals
        // otherwise come from one or two neighbours, and its points fail the
        // shapes' normal test).
        normalParams.minNeighbours = 12;
        normalParams.orientation.kind = NormalOrientation::Kind::None;
        normalsStore = computeNormals(cloud, normalParams, progress).normals;
        normals = &normalsStore;
        result.normalsComputed = true;
        result.notes.push_back("the cloud has no normals: fitted within " + std::to_string(*normalParams.radius) + " m");
    }
    ticker.step(10);

    // Local coordinates in double, centred on the cloud: CGAL and the fits
    // never see a UTM magnitude.
    const BoundingBox box = cloud.bounds();
    const Eigen::Vector3d localCentre = (box.min + box.max) / 2 - cloud.origin();
    const Eigen::Vector3d centre = cloud.origin() + localCentre;
    std::vector<Eigen::Vector3d> points(cloud.size()), unitNormals(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        points[i] = cloud.positions()[i].cast<double>() - localCentre;
        unitNormals[i] = unitNormalOf(*normals, i);
    }

    std::vector<detail::RansacShape> found;
    bool cancelled = false;
    // A stage of its own: what the progress dialog shows (and the cancel-latency bench counts) after the normals.
    const ProgressTicker findingStage(progress,
                                      params.method == PrimitiveMethod::RegionGrowing ? "Primitives: region growing"
                                      : params.method == PrimitiveMethod::Sequential  ? "Primitives: sequential RANSAC"
                                                                                      : "Primitives: efficient RANSAC",
                                      1);
    auto keepGoing = [&] {
        cancelled = cancelled || (progress && progress->cancelRequested());
        return !cancelled;
    };
    found = findCandidates(cloud, points, std::move(unitNormals), tree, scale.spacing, params, result, progress, keepGoing, cancelled);
    if (cancelled)
        ticker.checkCancel();
    ticker.step(60);
    // Region growing grows planes: the type check does not turn them into curved shapes.
    // Regions grown on smoothness or a value are typed as planes, spheres or
    // cylinders (within the types asked for).
    PrimitiveDetectionParams typeParams = params;
    const bool typedRegions = params.method == PrimitiveMethod::RegionGrowing && params.growOn != GrowOn::Plane;
    if (params.method != PrimitiveMethod::EfficientRansac) {
        typeParams.kinds = {PrimitiveKind::Plane};
        if (typedRegions) {
            typeParams.kinds.clear();
            for (PrimitiveKind kind : {PrimitiveKind::Plane, PrimitiveKind::Sphere, PrimitiveKind::Cylinder})
                if (params.kinds.count(kind))
                    typeParams.kinds.insert(kind);
        }
        if (params.kinds.size() > typeParams.kinds.size())
            result.notes.push_back(typedRegions ? "regions are typed as planes, spheres or cylinders: cones and tori are left to efficient RANSAC"
                                                : "this method finds planes: the other shape types asked for are left to efficient RANSAC");
    }

    // Each shape refitted, its type checked; a curved shape that does not fit
    // clearly better than a plane becomes a plane when a plane holds its
    // points within epsilon, and is dropped otherwise.
    // The shapes are independent: refitted in parallel (one task each), their
    // results and notes then taken in the shapes' order, so the outcome never
    // depends on the threads.
    detail::SurfaceEvidence evidence(points, *normals);
    evidence.centre = centre;
    evidence.epsilon = result.epsilon;
    evidence.linkDistance = result.clusterEpsilon;
    evidence.normalCosine = std::cos(params.normalDeviationDegrees * kPi / 180.0);
    evidence.typeTolerance = params.typeTolerance;
    evidence.spacing = scale.spacing;
    evidence.minPoints = params.minPoints;
    evidence.checkCancel = [&ticker] { ticker.checkCancel(); };
    result.primitives = typedShapes(found, points, *normals, centre, typeParams, typedRegions, evidence, progress, result.notes);
    ticker.checkCancel();
    ticker.step(20);

    // Regions grown on a value are apart by their values (the stones of one
    // wall plane): left as they are.
    if (!(params.method == PrimitiveMethod::RegionGrowing && params.growOn == GrowOn::Value))
        completeShapes(result, cloud, points, *normals, centre, params, evidence, progress, cancelled);
    if (cancelled)
        ticker.checkCancel();

    // Largest first; ties by first inlier, so the order never depends on threads.
    std::sort(result.primitives.begin(), result.primitives.end(), [](const DetectedPrimitive& a, const DetectedPrimitive& b) {
        return a.inliers.size() != b.inliers.size() ? a.inliers.size() > b.inliers.size() : a.inliers.front() < b.inliers.front();
    });
    result.primitiveId.assign(cloud.size(), -1);
    result.distance.assign(cloud.size(), std::numeric_limits<float>::quiet_NaN());
    for (std::size_t k = 0; k < result.primitives.size(); ++k) {
        DetectedPrimitive& shape = result.primitives[k];
        shape.id = static_cast<int>(k);
        for (std::uint32_t i : shape.inliers) {
            result.primitiveId[i] = shape.id;
            result.distance[i] = static_cast<float>(signedDistance(shape.primitive, centre + points[i]));
        }
    }
    ticker.step(10);
    return result;
}

} // namespace scandiff::plugins
