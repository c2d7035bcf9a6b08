// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/plugins/registration/Icp.h>

#include "ReferenceSurface.h"

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/RobustStatistics.h>
#include <scandiff/core/processing/GroundFilter.h>
#include <scandiff/core/processing/Subsampling.h>

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

namespace scandiff::plugins {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
//! Moving points of the coarse iterations.
constexpr std::size_t kCoarsePoints = 4000;

double kernelWeight(RobustKernel kernel, double u)
{
    switch (kernel) {
    case RobustKernel::None: return 1.0;
    case RobustKernel::Huber: { // tuning constant 1.345: 95 % efficiency on Gaussian noise
        const double a = std::abs(u);
        return a <= 1.345 ? 1.0 : 1.345 / a;
    }
    case RobustKernel::Cauchy: { // 2.3849: 95 % efficiency
        const double v = u / 2.3849;
        return 1.0 / (1.0 + v * v);
    }
    case RobustKernel::GemanMcClure: {
        const double d = 1.0 + u * u;
        return 1.0 / (d * d);
    }
    }
    return 1.0;
}

void checkParams(const IcpParams& params)
{
    if (params.maxDistance && !(*params.maxDistance > 0 && std::isfinite(*params.maxDistance)))
        throw Error(ErrorCode::InvalidArgument, "registration: the maximum distance must be > 0");
    if (!(params.overlap > 0 && params.overlap <= 1))
        throw Error(ErrorCode::InvalidArgument, "registration: the overlap must be in (0, 1]");
    if (params.maxIterations < 1)
        throw Error(ErrorCode::InvalidArgument, "registration: at least one iteration");
    if (!params.initial.allFinite() || params.initial.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
        throw Error(ErrorCode::InvalidArgument, "registration: the initial matrix must be finite with a last row 0 0 0 1");
    if (!(params.constraint.axis.norm() > 0))
        throw Error(ErrorCode::InvalidArgument, "registration: the rotation axis must not be zero");
}

//! One pass of correspondences: for the points x (frame), their closest
//! points, residuals and the selection the rules keep.
struct Correspondences
{
    detail::ClosestPoints closest;
    std::vector<double> distance; //!< Euclidean, to the closest point
    std::vector<double> residual; //!< signed (point-to-plane) or the distance
    std::vector<char> used;
    //! In the change-robust mode, on a reference that knows its roughness:
    //! each residual's tolerance relative to the usual one, at least 1 (see correspond).
    std::vector<double> tolerance;
    double toleranceOf(std::size_t i) const { return tolerance.empty() ? 1.0 : tolerance[i]; }
    std::size_t usedCount = 0;
    double cutoff = kInfinity; //!< the largest |residual| kept (trimming, threshold), in units of tolerance
};

//! Each correspondence's tolerance in the change-robust mode: where the
//! reference is rougher than it is at most correspondences (sparse returns on
//! steep or broken ground: neighbours' RMS off their plane above the median),
//! a residual of the same size says less about change, and the threshold
//! widens and the weight shrinks in proportion (weighted least squares with
//! the residual's expected size). Without this the shrinking threshold of
//! thesis 000 §1.4 keeps the smooth parts only, and on hilly airborne ground
//! those leave the horizontal position to the flat areas: 10-70 cm off on the
//! real samp53 pairs where the plain fit is within 5 cm. Never below 1, so a
//! uniform surface keeps the thesis's rule. Only where the moving points are
//! known to be stable (classed ground or building): a planar moving point
//! (the selection without classes) that lands on a rough part of the
//! reference has met change (a grown crown), and the thesis's rule holds it
//! out (on the synthetic parks, tolerated, it pulled three draws 1-2 m sideways).
void tolerancesOf(const detail::ClosestPoints& closest, std::vector<double>& tolerance)
{
    tolerance.clear();
    if (closest.spread.empty())
        return;
    std::vector<double> spreads;
    for (std::size_t i = 0; i < closest.spread.size(); ++i)
        if (closest.found[i] && closest.spread[i] > 0)
            spreads.push_back(closest.spread[i]);
    if (spreads.empty())
        return;
    const auto middle = spreads.begin() + static_cast<std::ptrdiff_t>(spreads.size() / 2);
    std::nth_element(spreads.begin(), middle, spreads.end());
    const double usual = *middle;
    tolerance.assign(closest.spread.size(), 1.0);
    for (std::size_t i = 0; i < closest.spread.size(); ++i)
        if (closest.found[i])
            tolerance[i] = std::max(1.0, closest.spread[i] / usual);
}

//! `searchBound`: closest points farther than this are not sought (the
//! correspondence is left out).
void correspond(const detail::ReferenceSurface& surface, const std::vector<Eigen::Vector3d>& x, const IcpParams& params,
                double threshold, Correspondences& c, double searchBound = kInfinity, bool roughnessTolerated = false)
{
    surface.closest(x, c.closest, searchBound);
    const std::size_t n = x.size();
    c.distance.assign(n, kInfinity);
    c.residual.assign(n, std::numeric_limits<double>::quiet_NaN());
    c.used.assign(n, 0);
    const bool plane = params.method == IcpMethod::PointToPlane;
    if (params.changeRobust && roughnessTolerated)
        tolerancesOf(c.closest, c.tolerance);
    else
        c.tolerance.clear();
    std::vector<double> kept;
    for (std::size_t i = 0; i < n; ++i) {
        if (!c.closest.found[i])
            continue;
        const Eigen::Vector3d d = x[i] - c.closest.points[i];
        c.distance[i] = d.norm();
        if (plane && c.closest.normals[i] == Eigen::Vector3d::Zero())
            continue; // no normal there: no point-to-plane residual
        c.residual[i] = plane ? c.closest.normals[i].dot(d) : c.distance[i];
        const bool near = !params.maxDistance || c.distance[i] <= *params.maxDistance;
        const double relative = std::abs(c.residual[i]) / c.toleranceOf(i);
        if (near && relative <= threshold) {
            c.used[i] = 1;
            kept.push_back(relative);
        }
    }
    c.cutoff = threshold;
    if (params.overlap < 1 && !kept.empty()) {
        // Trimming: the closest fraction only.
        const auto keep = static_cast<std::size_t>(std::ceil(params.overlap * static_cast<double>(kept.size())));
        const auto at = kept.begin() + static_cast<std::ptrdiff_t>(std::max<std::size_t>(keep, 1) - 1);
        std::nth_element(kept.begin(), at, kept.end());
        c.cutoff = std::min(threshold, *at);
        for (std::size_t i = 0; i < n; ++i)
            if (c.used[i] && std::abs(c.residual[i]) / c.toleranceOf(i) > c.cutoff)
                c.used[i] = 0;
    }
    c.usedCount = static_cast<std::size_t>(std::count(c.used.begin(), c.used.end(), 1));
}

//! Each sampled point's local plane: the spread of its 12 nearest
//! neighbours off their best plane (infinite with fewer than 5) and how
//! upright that plane's normal is (|n_z|).
struct LocalPlanes
{
    std::vector<double> spread, uprightness;
};

LocalPlanes localPlanes(const PointCloud& moving, const std::vector<std::size_t>& sample)
{
    constexpr std::size_t kNeighbours = 12;
    const octree::Octree tree = buildOctree(moving);
    std::vector<Eigen::Vector3f> queries(sample.size());
    for (std::size_t k = 0; k < sample.size(); ++k)
        queries[k] = moving.positions()[sample[k]];
    std::vector<octree::Neighbour> found;
    tree.nearestBatch(queries.data(), queries.size(), kNeighbours, tree.levelNearestMeanPopulation(8.0), found);
    LocalPlanes planes{std::vector<double>(sample.size(), kInfinity), std::vector<double>(sample.size(), 0.0)};
    for (std::size_t k = 0; k < sample.size(); ++k) {
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        std::size_t count = 0;
        for (std::size_t j = 0; j < kNeighbours; ++j)
            if (found[k * kNeighbours + j].index != UINT32_MAX) {
                mean += moving.positions()[found[k * kNeighbours + j].index].cast<double>();
                ++count;
            }
        if (count < 5)
            continue;
        mean /= static_cast<double>(count);
        Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
        for (std::size_t j = 0; j < kNeighbours; ++j)
            if (found[k * kNeighbours + j].index != UINT32_MAX) {
                const Eigen::Vector3d d = moving.positions()[found[k * kNeighbours + j].index].cast<double>() - mean;
                covariance += d * d.transpose() / static_cast<double>(count);
            }
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
        planes.spread[k] = std::sqrt(std::max(0.0, eigen.eigenvalues()(0)));
        planes.uprightness[k] = std::abs(eigen.eigenvectors()(2, 0));
    }
    return planes;
}

//! The sampled moving points on what does not change (change-robust mode),
//! by `parts` (StableParts): the ASPRS classes ground (2) and building (6)
//! when the cloud has them; otherwise the planar points (12 nearest
//! neighbours within 3 times the 20th percentile of that spread over the
//! sample of their plane) and, with Ground, of those only the ground and the
//! steep ones (walls). A grown tree, a bush, a car, a person is a scatter of
//! points, not a surface: on airborne epochs of a park half the points are
//! vegetation that grew between the epochs, no minority the threshold can
//! leave out, and it pulled the later epoch down by half a metre onto the
//! earlier canopy. A raised roof is planar and still pulls (8.8 cm on the
//! real samp11 pair): the ground under it does not move.
struct StableSelection
{
    std::vector<char> first; //!< per sampled point; empty: too few left to register on (every point is used)
    //! With Ground on a cloud without classes: the second phase's points,
    //! the first's with their whole reference normal and every other planar
    //! one with its horizontal part only. What grows (a tree, a raised roof)
    //! grows upwards: it would pull the height (a roof raised by 0.3-1.5 m
    //! pulled the real samp11 pair by 8.8 cm) while its edges stay where they
    //! were, and they hold the horizontal position and the heading where the
    //! ground is flat.
    std::vector<char> second;
    bool byClass = false; //!< `first` holds the points classed ground or building
};

StableSelection stableSurfaces(const PointCloud& moving, const std::vector<std::size_t>& sample, StableParts parts, std::string& note)
{
    std::vector<char> keep(sample.size(), 0);
    const std::size_t enough = std::max<std::size_t>(100, sample.size() / 20);
    std::size_t kept = 0;
    if (const ScalarField* classes = moving.field("classification")) {
        for (std::size_t k = 0; k < sample.size(); ++k) {
            const double c = classes->value(sample[k]);
            keep[k] = c == 2 || c == 6;
            kept += keep[k];
        }
        if (kept >= enough) {
            note = "change-robust: the " + std::to_string(kept) + " sampled points classed ground (2) or building (6) registered";
            return {keep, {}, true};
        }
        std::fill(keep.begin(), keep.end(), 0);
        kept = 0;
    }
    const LocalPlanes planes = localPlanes(moving, sample);
    std::vector<double> finite;
    for (double v : planes.spread)
        if (std::isfinite(v))
            finite.push_back(v);
    if (finite.size() < 20)
        return {};
    const auto at = finite.begin() + static_cast<std::ptrdiff_t>(finite.size() / 5); // the 20th percentile
    std::nth_element(finite.begin(), at, finite.end());
    const double limit = 3.0 * std::max(*at, 1e-9);
    for (std::size_t k = 0; k < sample.size(); ++k) {
        keep[k] = planes.spread[k] <= limit;
        kept += keep[k];
    }
    std::ostringstream text;
    if (parts == StableParts::Ground) {
        // Ground (SMRF with its defaults) and walls (a plane within 30 deg of vertical).
        const GroundFilterResult ground = filterGround(moving);
        std::vector<char> groundOrWalls(sample.size(), 0), surfaces(sample.size(), 0);
        std::size_t onGround = 0, onWalls = 0;
        for (std::size_t k = 0; k < sample.size(); ++k) {
            const bool wall = keep[k] && planes.uprightness[k] < 0.5;
            groundOrWalls[k] = ground.ground[sample[k]] || wall;
            surfaces[k] = groundOrWalls[k] || keep[k];
            onGround += ground.ground[sample[k]];
            onWalls += wall && !ground.ground[sample[k]];
        }
        if (onGround + onWalls >= enough) {
            text << "change-robust: " << onGround << " of " << sample.size() << " sampled points on the ground (morphological filter) and "
                 << onWalls << " on walls registered";
            if (kept >= enough)
                text << ", then with them the " << kept << " on surfaces (12 neighbours within " << limit
                     << " m of a plane), those off the ground for the horizontal and the heading only";
            text << "; the rest (vegetation, clutter) left out";
            note = text.str();
            return {groundOrWalls, kept >= enough ? surfaces : std::vector<char>()};
        }
    }
    if (kept < enough)
        return {};
    text << "change-robust: " << kept << " of " << sample.size() << " sampled points on surfaces (12 neighbours within "
         << limit << " m of a plane) registered; scattered points (vegetation, clutter) left out";
    note = text.str();
    return {keep, {}};
}

} // namespace

IcpMethod parseIcpMethod(const std::string& text)
{
    if (text == "point-to-point")
        return IcpMethod::PointToPoint;
    if (text == "point-to-plane")
        return IcpMethod::PointToPlane;
    throw Error(ErrorCode::InvalidArgument, "registration: method '" + text + "' is not point-to-point or point-to-plane");
}

RobustKernel parseRobustKernel(const std::string& text)
{
    if (text == "none")
        return RobustKernel::None;
    if (text == "huber")
        return RobustKernel::Huber;
    if (text == "cauchy")
        return RobustKernel::Cauchy;
    if (text == "geman-mcclure")
        return RobustKernel::GemanMcClure;
    throw Error(ErrorCode::InvalidArgument, "registration: kernel '" + text + "' is not none, huber, cauchy or geman-mcclure");
}

IcpResult icpRegister(const PointCloud& moving, const PointCloud* referenceCloud, const Mesh* referenceMesh,
                      const IcpParams& params, ProgressObserver* progress)
{
    checkParams(params);
    if (moving.empty())
        throw Error(ErrorCode::InvalidData, "registration: the moving cloud '" + moving.name + "' is empty");
    if (referenceCloud && referenceCloud->empty())
        throw Error(ErrorCode::InvalidData, "registration: the reference cloud '" + referenceCloud->name + "' is empty");
    const std::unique_ptr<detail::ReferenceSurface> surface =
        referenceMesh ? detail::meshSurface(*referenceMesh)
                      : detail::cloudSurface(*referenceCloud, true, params.normalNeighbours, progress);
    return detail::icpOnSurface(moving, *surface, params, progress);
}

namespace {

//! The moving points the iterations use, in the reference's frame (double),
//! an even share of them first (the coarse iterations'), and the scale that
//! turns a rotation into metres.
struct IterationPoints
{
    std::vector<Eigen::Vector3d> x0;
    std::size_t coarse = 0; //!< the first `coarse` points are the coarse stage's
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    double length = 1.0; //!< the points' RMS distance to their centroid
    std::string note;    //!< what the change-robust selection kept
    //! The points of a second phase, from where the first ends (StableSelection::second).
    std::shared_ptr<const IterationPoints> secondPhase;
    //! Per point (empty: none), those whose residual counts along the
    //! horizontal part of the reference normal only (StableSelection::second).
    std::vector<char> sidewaysOnly;
    //! The points are known stable (by class): see tolerancesOf.
    bool roughnessTolerated = false;
};

//! The sampled points (indices) in the reference's frame, an even share of
//! them first (the coarse iterations'), their centroid and spread.
//! `sideways`, when given, flags per sampled point those that hold the
//! horizontal only (IterationPoints::sidewaysOnly).
IterationPoints pointsOf(const PointCloud& moving, const Eigen::Vector3d& origin, const std::vector<std::size_t>& sample,
                         const std::vector<char>& sideways = {});

//! The sampled points the selection keeps (all when it is empty).
std::vector<std::size_t> selected(const std::vector<std::size_t>& sample, const std::vector<char>& keep)
{
    if (keep.empty())
        return sample;
    std::vector<std::size_t> kept;
    for (std::size_t k = 0; k < sample.size(); ++k)
        if (keep[k])
            kept.push_back(sample[k]);
    return kept;
}

IterationPoints iterationPoints(const PointCloud& moving, const Eigen::Vector3d& origin, const IcpParams& params)
{
    const std::vector<std::size_t> sample = params.sampleCount > 0 ? randomSubsample(moving, params.sampleCount, params.seed)
                                                                   : randomSubsample(moving, moving.size(), 0);
    if (!params.changeRobust)
        return pointsOf(moving, origin, sample);
    std::string note;
    const StableSelection stable = stableSurfaces(moving, sample, params.stableParts, note);
    IterationPoints points = pointsOf(moving, origin, selected(sample, stable.first));
    points.note = note;
    points.roughnessTolerated = stable.byClass;
    if (!stable.second.empty()) {
        std::vector<char> sideways;
        for (std::size_t k = 0; k < sample.size(); ++k)
            if (stable.second[k])
                sideways.push_back(!stable.first[k]); // not ground nor wall: for the horizontal only
        points.secondPhase = std::make_shared<IterationPoints>(pointsOf(moving, origin, selected(sample, stable.second), sideways));
    }
    return points;
}

IterationPoints pointsOf(const PointCloud& moving, const Eigen::Vector3d& origin, const std::vector<std::size_t>& sample,
                         const std::vector<char>& sideways)
{
    IterationPoints points;
    std::vector<Eigen::Vector3d>& x0 = points.x0;
    std::vector<char> flags;
    x0.reserve(sample.size());
    for (std::size_t k = 0; k < sample.size(); ++k)
        if (moving.positions()[sample[k]].allFinite()) {
            x0.push_back(moving.globalPosition(sample[k]) - origin);
            if (!sideways.empty())
                flags.push_back(sideways[k]);
        }
    if (x0.size() < 6)
        throw Error(ErrorCode::InvalidData, "registration: the moving cloud has fewer than 6 points with finite coordinates");
    // Coarse to fine: the first iterations, while the clouds are still apart
    // and each closest-point search goes far, use an even share of the
    // sample (put first); once they have converged, the whole sample.
    points.coarse = x0.size();
    if (x0.size() > 2 * kCoarsePoints) {
        const std::size_t stride = x0.size() / kCoarsePoints;
        std::vector<std::size_t> order;
        order.reserve(x0.size());
        for (std::size_t i = 0; i < x0.size(); i += stride)
            order.push_back(i);
        points.coarse = order.size();
        for (std::size_t i = 0; i < x0.size(); ++i)
            if (i % stride != 0)
                order.push_back(i);
        std::vector<Eigen::Vector3d> ordered(x0.size());
        std::vector<char> orderedFlags(flags.size());
        for (std::size_t k = 0; k < order.size(); ++k) {
            ordered[k] = x0[order[k]];
            if (!flags.empty())
                orderedFlags[k] = flags[order[k]];
        }
        x0 = std::move(ordered);
        flags = std::move(orderedFlags);
    }
    points.sidewaysOnly = std::move(flags);
    for (const auto& p : x0)
        points.centroid += p;
    points.centroid /= static_cast<double>(x0.size());
    double spread = 0;
    for (const auto& p : x0)
        spread += (p - points.centroid).squaredNorm();
    points.length = std::max(std::sqrt(spread / static_cast<double>(x0.size())), 1e-9);
    return points;
}

//! Where a run of iterations ended.
struct IterationRun
{
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    Eigen::MatrixXd normalMatrix;
    double threshold = kInfinity; //!< the change threshold reached
    double cutoff = kInfinity;    //!< the last correspondences' cutoff (trimming, threshold)
    bool converged = false;
    std::vector<RegistrationIteration> trace;
};

//! The iterations from `motion`: match, select, weigh, solve, apply, until
//! converged or at the limit; `held` directions (orthonormal columns in the
//! solver's unknowns) are never moved along; the change-robust threshold
//! starts at `startThreshold` (a second phase goes on from the first's).
IterationRun runIterations(const detail::ReferenceSurface& surface, const IterationPoints& points, const IcpParams& params,
                           Eigen::Isometry3d motion, const Eigen::MatrixXd* held, ProgressTicker& ticker,
                           double startThreshold = kInfinity)
{
    const bool plane = params.method == IcpMethod::PointToPlane;
    const std::vector<Eigen::Vector3d>& x0 = points.x0;
    const double length = points.length;
    std::size_t active = points.coarse;
    IterationRun run;
    const Eigen::Vector3d centre = motion * points.centroid;
    double threshold = startThreshold, previousRms = kInfinity, rmsTwoBefore = kInfinity;
    bool kernelActive = false;
    double kernelScale = kInfinity, medianDistance = kInfinity;
    std::vector<Eigen::Vector3d> x(x0.size()), xs, ys, ns;
    std::vector<double> w, usedResiduals, usedTolerances, relativeResiduals;
    Correspondences c;
    for (std::size_t iteration = 1; iteration <= params.maxIterations; ++iteration) {
        x.resize(active);
        for (std::size_t i = 0; i < active; ++i)
            x[i] = motion * x0[i];
        // Beyond the maximum distance, or far beyond the change threshold
        // (ten times: a closest point that far lies past the edge of the
        // reference, not on the same surface), a closest point is not sought.
        // With the kernel on, beyond 30 scales, where its weight is below 1 %,
        // neither.
        // (Never below ten median correspondence distances: on a sparse
        // reference the closest point is far while the plane is near.)
        const double searchBound =
            std::min({params.maxDistance.value_or(kInfinity), std::isfinite(threshold) ? 10 * threshold : kInfinity,
                      kernelActive ? std::max(30 * kernelScale, 10 * medianDistance) : kInfinity});
        correspond(surface, x, params, threshold, c, searchBound, points.roughnessTolerated);
        if (c.usedCount < static_cast<std::size_t>(dofCount(params.constraint.dof)) + 3)
            throw Error(ErrorCode::InvalidData, "registration: only " + std::to_string(c.usedCount) +
                                                    " correspondences left (iteration " + std::to_string(iteration) +
                                                    "): the clouds do not overlap, or the maximum distance is too small");
        xs.clear();
        ys.clear();
        ns.clear();
        usedResiduals.clear();
        usedTolerances.clear();
        std::vector<double> usedDistances;
        for (std::size_t i = 0; i < x.size(); ++i)
            if (c.used[i]) {
                xs.push_back(x[i]);
                ys.push_back(c.closest.points[i]);
                ns.push_back(c.closest.normals[i]);
                usedResiduals.push_back(c.residual[i]);
                usedTolerances.push_back(c.toleranceOf(i));
                usedDistances.push_back(c.distance[i]);
                if (plane && !points.sidewaysOnly.empty() && points.sidewaysOnly[i]) {
                    // Horizontal only: a roof's upward normal then weighs nothing, an edge's sideways one holds.
                    ns.back().z() = 0;
                    usedResiduals.back() = ns.back().dot(x[i] - ys.back());
                }
            }
        // Robust weights on the residuals over their robust scale, once the
        // plain iterations have converged: a scale taken from residuals that
        // are still large with misalignment would down-weight the far points
        // that hold the rotation, and the result could slide into a wrong basin.
        // (Each residual over its tolerance: 1 except in the change-robust mode
        // on rough parts of the reference, see tolerancesOf.)
        relativeResiduals.resize(usedResiduals.size());
        for (std::size_t i = 0; i < usedResiduals.size(); ++i)
            relativeResiduals[i] = usedResiduals[i] / usedTolerances[i];
        const double scale = std::max(kMadToSigma * medianAbsolute(relativeResiduals), 1e-12 * length);
        kernelScale = scale;
        w.resize(xs.size());
        double sum2 = 0;
        for (std::size_t i = 0; i < xs.size(); ++i) {
            w[i] = (kernelActive ? kernelWeight(params.kernel, relativeResiduals[i] / scale) : 1.0) /
                   (usedTolerances[i] * usedTolerances[i]);
            sum2 += usedResiduals[i] * usedResiduals[i];
        }
        const double rms = std::sqrt(sum2 / static_cast<double>(xs.size()));
        Eigen::Isometry3d step;
        bool solved;
        // The normal matrix of the point-to-plane problem is what tells whether
        // the surfaces hold every direction, whichever method moves the points.
        // About the points' centroid (where the start put it): rotations and
        // translations are then as apart as they can be, and a direction the
        // surfaces do not hold is a pure one (flat ground: the horizontal
        // translations and the turn about the vertical through the data),
        // not a mix with a tilt about a far frame origin.
        std::vector<Eigen::Vector3d> xc(xs.size()), yc(ys.size());
        for (std::size_t i = 0; i < xs.size(); ++i) {
            xc[i] = xs[i] - centre;
            yc[i] = ys[i] - centre;
        }
        Eigen::Isometry3d centredStep;
        const bool planeSolved = stepPointToPlane(xc, yc, ns, w, params.constraint, length, centredStep, run.normalMatrix, held);
        const Eigen::Isometry3d planeStep = Eigen::Translation3d(centre) * centredStep * Eigen::Translation3d(-centre);
        if (plane) {
            solved = planeSolved;
            step = planeStep;
        } else {
            solved = fitPointToPoint(xs, ys, w, params.constraint, step);
            if (solved && held && held->cols() > 0)
                step = planeStep; // the closed form cannot hold a direction: the plane step does
        }
        if (!solved)
            throw Error(ErrorCode::InvalidData, "registration: the correspondences do not determine a motion (degenerate geometry)");
        motion = step * motion;
        const double rotationStep = rotationDegrees(step.linear());
        const double translationStep = step.translation().norm();
        run.trace.push_back({iteration, rms, xs.size(), threshold, rotationStep, translationStep});
        medianDistance = medianAbsolute(usedDistances);
        if (params.changeRobust) {
            // Thesis 000 §1.4: the threshold shrinks with the residuals (3 robust
            // sigmas), never below the median spacing of the correspondences,
            // never growing back.
            threshold = std::min(threshold, std::max(3.0 * kMadToSigma * medianAbsolute(relativeResiduals), medianDistance));
        }
        ticker.step();
        // Converged when the step moves the points by less than the tolerance
        // (the largest displacement it gives a point at twice the cloud's RMS
        // radius), or the RMS no longer changes. With a kernel asked for, the
        // first convergence switches it on and the iterations go on.
        // On a sparse reference, nearest neighbours can flip between two sets
        // and the iterations between two states (a two-cycle): an RMS back to
        // what it was two iterations ago counts as converged too.
        const double move = rotationStep * 3.14159265358979323846 / 180.0 * length * 2 + translationStep;
        const double rmsTolerance = params.rmsTolerance * std::max(rms, 1e-12);
        const bool still = move < params.moveTolerance || std::abs(previousRms - rms) <= rmsTolerance ||
                           std::abs(rmsTwoBefore - rms) <= rmsTolerance;
        rmsTwoBefore = previousRms;
        previousRms = rms;
        // The coarse stage only has to bring the clouds together: it ends
        // once a step moves the points by less than 1e-4 of their radius. The
        // whole sample then starts with the kernel on, if asked for: the
        // coarse convergence is what the kernel waits for.
        if ((still || move < 1e-4 * length) && active < x0.size()) {
            active = x0.size();
            kernelActive = params.kernel != RobustKernel::None;
            previousRms = rmsTwoBefore = kInfinity;
            continue;
        }
        if (still && !kernelActive && params.kernel != RobustKernel::None) {
            kernelActive = true;
            previousRms = rmsTwoBefore = kInfinity;
            continue;
        }
        if (still) {
            run.converged = true;
            break;
        }
    }
    run.motion = motion;
    run.threshold = threshold;
    run.cutoff = c.cutoff;
    return run;
}

//! The sample's point-to-plane residuals under a motion, each at most
//! `cutoff` (a truncated quadratic: what changed does not pull), squared and
//! summed; each relative to its tolerance (tolerancesOf), as the iterations
//! weigh it.
double truncatedCost(const detail::ReferenceSurface& surface, const IterationPoints& points, const IcpParams& params,
                     const Eigen::Isometry3d& motion, double cutoff)
{
    std::vector<Eigen::Vector3d> x(points.x0.size());
    for (std::size_t i = 0; i < x.size(); ++i)
        x[i] = motion * points.x0[i];
    Correspondences c;
    correspond(surface, x, params, kInfinity, c, 10 * cutoff, points.roughnessTolerated);
    double cost = 0;
    for (std::size_t i = 0; i < c.residual.size(); ++i) {
        const double r = c.residual[i] / c.toleranceOf(i);
        cost += std::isfinite(r) ? std::min(r * r, cutoff * cutoff) : cutoff * cutoff;
    }
    return cost;
}

//! A motion's small-motion coordinates in the solver's unknowns: the
//! rotation about `centre` as a rotation vector times `length` (metres at
//! that distance), then the translation of the centre (Six); the turn about
//! the axis then the translation (Four); the translation alone.
Eigen::VectorXd twistAbout(const Eigen::Isometry3d& motion, const Eigen::Vector3d& centre, double length, const DofConstraint& constraint)
{
    const Eigen::AngleAxisd turn(motion.linear());
    const Eigen::Vector3d rotation = turn.angle() * turn.axis() * length;
    const Eigen::Vector3d shift = motion * centre - centre;
    Eigen::VectorXd v(dofCount(constraint.dof));
    switch (constraint.dof) {
    case Dof::Six: v << rotation, shift; break;
    case Dof::Four: v << rotation.dot(constraint.axis.normalized()), shift; break;
    case Dof::Translation: v << shift; break;
    }
    return v;
}

//! The report's residual statistics: over the |residuals| of the points
//! used, of `considered` points.
void summarise(const std::vector<double>& magnitudes, std::size_t considered, const IcpParams& params, RegistrationReport& report)
{
    double sum2 = 0;
    for (double m : magnitudes)
        sum2 += m * m;
    report.rms = magnitudes.empty() ? std::numeric_limits<double>::quiet_NaN() : std::sqrt(sum2 / static_cast<double>(magnitudes.size()));
    report.median = percentileOf(magnitudes, 0.5);
    report.p90 = percentileOf(magnitudes, 0.9);
    report.p95 = percentileOf(magnitudes, 0.95);
    report.p99 = percentileOf(magnitudes, 0.99);
    report.overlap = static_cast<double>(magnitudes.size()) / static_cast<double>(std::max<std::size_t>(considered, 1));
    if (!report.converged)
        report.notes.push_back("not converged after " + std::to_string(params.maxIterations) + " iterations");
}

} // namespace

namespace detail {

//! Directions the surfaces hold weakly: solved when the data show the
//! motion along them, else held fixed and the run redone so (see below).
//! Returns whether the run now holds them; its note goes to the report.
bool holdOrSolveWeakDirections(const ReferenceSurface& surface, const IterationPoints& points, const IcpParams& params,
                               const Eigen::Isometry3d& start, IterationRun& run, ProgressTicker& ticker, RegistrationReport& report)
{
    // Directions the surfaces do not hold are held, unless the data show
    // them. The steps a free run takes along them follow noise and a few
    // edges (airborne epochs of a flat park slid by up to 1.5 m), or the
    // first steps of a large correction (a 2 degree tilt also turned the
    // epoch 0.65 degree about the vertical) that no later step undoes; yet
    // gentle hills do hold the horizontal, weakly, and a real shift there
    // must be found. Whether the free run's motion along those directions is
    // in the data: two free runs on the two halves of the sample (a
    // checkerboard of cells half the sample's radius wide, so each half
    // spans the site) must agree on it within half its size, and it must
    // lower the sample's squared residuals (truncated at 3 robust sigmas) by
    // 1 % at least. Neither alone tells: a chi-square test on the residuals
    // takes a slide along noise for a finding (neighbouring residuals are not
    // independent), and roof edges seen from the air pull both halves the
    // same way; a real shift over hills lowers the residuals by 2-17 %.
    const Eigen::MatrixXd held = weakDirections(run.normalMatrix);
    if (held.cols() == 0 || held.cols() >= run.normalMatrix.rows())
        return false;
    bool holding = false;
    {
        const Eigen::Vector3d centre = start * points.centroid;
        const auto along = [&](const Eigen::Isometry3d& motion) {
            return Eigen::VectorXd(held.transpose() * twistAbout(motion * start.inverse(), centre, points.length, params.constraint));
        };
        const Eigen::VectorXd full = along(run.motion);
        std::array<IterationPoints, 2> halves;
        const double cell = 0.5 * points.length;
        for (std::size_t i = 0; i < points.x0.size(); ++i) {
            const Eigen::Vector3d q = points.x0[i] - points.centroid;
            const auto parity = static_cast<std::size_t>(std::abs(static_cast<long long>(std::floor(q.x() / cell)) +
                                                                  static_cast<long long>(std::floor(q.y() / cell)) +
                                                                  static_cast<long long>(std::floor(q.z() / cell))) % 2);
            halves[parity].x0.push_back(points.x0[i]);
        }
        bool reproduced = false;
        double apart = 0;
        if (halves[0].x0.size() >= 50 && halves[1].x0.size() >= 50) {
            for (IterationPoints& half : halves) {
                half.coarse = half.x0.size();
                half.centroid = points.centroid;
                half.length = points.length;
                half.roughnessTolerated = points.roughnessTolerated;
            }
            const Eigen::VectorXd first = along(runIterations(surface, halves[0], params, start, nullptr, ticker).motion);
            const Eigen::VectorXd second = along(runIterations(surface, halves[1], params, start, nullptr, ticker).motion);
            apart = (first - second).norm();
            reproduced = apart <= 0.5 * full.norm();
        }
        double gain = 0;
        IterationRun fixed;
        if (reproduced) {
            fixed = runIterations(surface, points, params, start, &held, ticker);
            const double cutoff = std::isfinite(run.threshold) ? run.threshold : params.maxDistance.value_or(points.length);
            const double freeCost = truncatedCost(surface, points, params, run.motion, cutoff);
            gain = freeCost > 0 ? truncatedCost(surface, points, params, fixed.motion, cutoff) / freeCost - 1.0 : 0.0;
            reproduced = gain >= 0.01;
        }
        std::ostringstream note;
        note.precision(3);
        if (reproduced) {
            note << "the directions the surfaces hold weakly were solved: " << full.norm()
                 << " m along them, which both halves of the sample find (within " << apart << " m) and which lowers the "
                 << "residuals by " << 100 * gain << " %";
        } else {
            run = fixed.trace.empty() ? runIterations(surface, points, params, start, &held, ticker) : std::move(fixed);
            holding = true;
            note << held.cols() << " direction(s) the surfaces do not hold held fixed (see the degeneracy warning): a free run "
                 << "moved " << full.norm() << " m along them, which the halves of the sample do not agree on (" << apart
                 << " m apart) or which lowers the residuals by " << 100 * gain << " % only";
        }
        report.notes.push_back(note.str());
    }
    return holding;
}

//! Every moving point, moved: its residual, and whether the last
//! iteration's rules keep it; the magnitudes of those kept.
std::vector<double> residualsOfEveryPoint(const PointCloud& moving, const ReferenceSurface& surface, const IcpParams& final,
                                          const Eigen::Isometry3d& motion, const Eigen::Vector3d& origin, double finalThreshold,
                                          IcpResult& result, ProgressObserver* progress)
{
    // The field and the report judge every moving point, grown crowns
    // included, by the thesis's threshold: the tolerance of tolerancesOf is
    // for the classed points the iterations use, and a crown over a rough
    // crown must not pass as unchanged.
    std::vector<double> magnitudes;
    // In chunks, each a step of its own stage: on a
    // large cloud this pass (closest points and the reference normals they
    // need) takes longer than all the iterations, and Cancel must be heard.
    const std::size_t n = moving.size();
    result.residual = ScalarField(fields::kRegistrationResidual, n);
    result.excluded = ScalarField(fields::kRegistrationExcluded, n);
    constexpr std::size_t kChunk = 1 << 16;
    ProgressTicker residualTicker(progress, "Registration: residual of every point", (n + kChunk - 1) / kChunk);
    std::vector<Eigen::Vector3d> chunk;
    Correspondences last;
    for (std::size_t begin = 0; begin < n; begin += kChunk) {
        const std::size_t end = std::min(n, begin + kChunk);
        chunk.resize(end - begin);
        for (std::size_t i = begin; i < end; ++i)
            chunk[i - begin] = moving.positions()[i].allFinite()
                                   ? Eigen::Vector3d(motion * (moving.globalPosition(i) - origin))
                                   : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
        correspond(surface, chunk, final, finalThreshold, last, final.maxDistance.value_or(kInfinity));
        for (std::size_t i = begin; i < end; ++i) {
            const std::size_t k = i - begin;
            if (std::isfinite(last.residual[k]))
                result.residual.setValue(i, last.residual[k]);
            result.excluded.setValue(i, last.used[k] ? 0.0 : 1.0);
            if (last.used[k])
                magnitudes.push_back(std::abs(last.residual[k]));
        }
        residualTicker.step();
    }
    return magnitudes;
}

IcpResult icpOnSurface(const PointCloud& moving, const ReferenceSurface& surface, const IcpParams& params, ProgressObserver* progress)
{
    checkParams(params);
    if (moving.empty())
        throw Error(ErrorCode::InvalidData, "registration: the moving cloud '" + moving.name + "' is empty");
    const bool plane = params.method == IcpMethod::PointToPlane;
    const Eigen::Vector3d origin = surface.frameOrigin();
    const IterationPoints points = iterationPoints(moving, origin, params);
    IcpResult result;
    RegistrationReport& report = result.report;
    report.method = std::string(plane ? "ICP point-to-plane" : "ICP point-to-point") + ", " + dofName(params.constraint.dof) + " DOF" +
                    (params.changeRobust ? ", change-robust" : "");
    if (!points.note.empty())
        report.notes.push_back(points.note);
    ProgressTicker ticker(progress, "Registration (ICP)", params.maxIterations);
    const Eigen::Isometry3d start = toLocal(params.initial, origin);
    IterationRun run = runIterations(surface, points, params, start, nullptr, ticker);
    // Directions the surfaces do not hold (a flat site's horizontal).
    const bool holding = holdOrSolveWeakDirections(surface, points, params, start, run, ticker, report);
    // The second phase (StableSelection::second), not after a first phase
    // that had to hold weak directions (a flat site: what its surfaces say
    // sideways was found not to be in the data).
    const bool secondPhase = points.secondPhase && !holding;
    const IterationPoints& used = secondPhase ? *points.secondPhase : points;
    if (secondPhase) {
        std::vector<RegistrationIteration> trace = std::move(run.trace);
        run = runIterations(surface, used, params, run.motion, nullptr, ticker, run.threshold);
        for (RegistrationIteration& step : run.trace)
            step.iteration += trace.size();
        trace.insert(trace.end(), run.trace.begin(), run.trace.end());
        run.trace = std::move(trace);
    }
    report.trace = run.trace;
    report.iterations = run.trace.size();
    report.converged = run.converged;
    const Eigen::Isometry3d& motion = run.motion;
    const Eigen::MatrixXd& normalMatrix = run.normalMatrix;
    const double threshold = run.threshold;
    const Eigen::Vector3d& centroid = used.centroid;
    const double cutoff = run.cutoff;
    report.matrix = toGlobal(motion, origin);
    report.centre = centroid + origin;
    report.degeneracy = degeneracyWarning(normalMatrix, dofCount(params.constraint.dof), params.constraint.axis, report.eigenvalues);

    IcpParams final = params;
    final.overlap = 1.0; // the trimming of the last iteration is applied as its cutoff
    const double finalThreshold = std::min(threshold, cutoff);
    std::vector<double> magnitudes;
    if (!params.residualOfEveryPoint) {
        std::vector<Eigen::Vector3d> x(used.x0.size());
        for (std::size_t i = 0; i < x.size(); ++i)
            x[i] = motion * used.x0[i];
        Correspondences last;
        correspond(surface, x, final, finalThreshold, last, params.maxDistance.value_or(kInfinity), used.roughnessTolerated);
        for (std::size_t i = 0; i < x.size(); ++i)
            if (last.used[i])
                magnitudes.push_back(std::abs(last.residual[i]));
        summarise(magnitudes, x.size(), params, report);
        return result;
    }
    const std::vector<double> everyMagnitude =
        residualsOfEveryPoint(moving, surface, final, motion, origin, finalThreshold, result, progress);
    summarise(everyMagnitude, moving.size(), params, report);
    return result;
}

} // namespace detail

} // namespace scandiff::plugins
