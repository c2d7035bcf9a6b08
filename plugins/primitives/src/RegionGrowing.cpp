// SPDX-License-Identifier: GPL-3.0-or-later
#include "RegionGrowing.h"

#include <scandiff/core/RobustStatistics.h>
#include <scandiff/core/segmentation/RunningMoments.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Shape_detection/Region_growing/Region_growing.h>
#include <CGAL/Shape_detection/Region_growing/Region_growing_on_point_set/Least_squares_plane_fit_region.h>
#include <CGAL/Shape_detection/Region_growing/Region_growing_on_point_set/Least_squares_plane_fit_sorting.h>
#include <CGAL/property_map.h>

#include <Eigen/Eigenvalues>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <atomic>
#include <iterator>
#include <mutex>
#include <utility>

namespace scandiff::plugins::detail {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Item = std::pair<Kernel::Point_3, Kernel::Vector_3>;
using Items = std::vector<Item>;
using PointMap = CGAL::First_of_pair_property_map<Item>;
using NormalMap = CGAL::Second_of_pair_property_map<Item>;
namespace PointSet = CGAL::Shape_detection::Point_set;
using PlaneRegion = PointSet::Least_squares_plane_fit_region<Kernel, Items, PointMap, NormalMap>;

struct StopTheRun
{
};

//! CGAL's NeighborQuery concept answered from the octree: the points within
//! the radius of every point (itself included, as CGAL's sphere query), at
//! most the kMaxNeighbours nearest, found once for all by the octree's
//! parallel batch query, since the seed sorting and the growing each ask for
//! every point. The cap keeps the lists to 128 bytes a point whatever radius
//! a user gives (a wide one on a dense scan would list thousands), and is
//! above what the default radius (3 spacings: about 28 points on a plane)
//! holds. The caller is asked every 4096 points whether to go on, during the
//! batch and during CGAL's growing, which has no cancellation of its own.
class OctreeQuery
{
public:
    static constexpr std::size_t kMaxNeighbours = 32;

    OctreeQuery(const octree::Octree& tree, double radius, const std::function<bool()>& keepGoing)
        : keepGoing_(keepGoing), lists_(tree.size() * kMaxNeighbours), counts_(tree.size(), 0)
    {
        std::atomic<std::size_t> visited{0};
        std::mutex asking;
        tree.withinRadiusBatch(tree.points(), tree.size(), static_cast<float>(radius),
                               [&](std::uint32_t q, const octree::Neighbour* found, std::size_t count) {
                                   std::uint32_t* list = lists_.data() + std::size_t(q) * kMaxNeighbours;
                                   if (count <= kMaxNeighbours) {
                                       for (std::size_t k = 0; k < count; ++k)
                                           list[k] = found[k].index;
                                   } else {
                                       std::vector<octree::Neighbour> nearest(found, found + count);
                                       std::nth_element(nearest.begin(), nearest.begin() + kMaxNeighbours - 1, nearest.end());
                                       for (std::size_t k = 0; k < kMaxNeighbours; ++k)
                                           list[k] = nearest[k].index;
                                   }
                                   counts_[q] = static_cast<std::uint8_t>(std::min(count, kMaxNeighbours));
                                   if (++visited % 4096 == 0) {
                                       const std::lock_guard<std::mutex> lock(asking);
                                       if (!keepGoing_())
                                           throw StopTheRun{};
                                   }
                               });
    }
    //! The neighbours of point i (itself included), at most kMaxNeighbours.
    const std::uint32_t* begin(std::size_t i) const { return lists_.data() + i * kMaxNeighbours; }
    const std::uint32_t* end(std::size_t i) const { return begin(i) + counts_[i]; }

    void operator()(std::size_t index, std::vector<std::size_t>& neighbours)
    {
        if (++calls_ % 4096 == 0 && !keepGoing_())
            throw StopTheRun{};
        const std::uint32_t* list = lists_.data() + index * kMaxNeighbours;
        neighbours.assign(list, list + counts_[index]);
    }

private:
    const std::function<bool()>& keepGoing_;
    std::vector<std::uint32_t> lists_; //!< kMaxNeighbours slots a point
    std::vector<std::uint8_t> counts_;
    std::size_t calls_ = 0;
};

using Sorting = PointSet::Least_squares_plane_fit_sorting<Kernel, Items, OctreeQuery, PointMap>;
using Growing = CGAL::Shape_detection::Region_growing<Items, OctreeQuery, PlaneRegion, Sorting::Seed_map>;

} // namespace

namespace {

//! The least-squares plane of the members (a first shape the caller refits).
Primitive leastSquaresPlane(const std::vector<Eigen::Vector3d>& points, const std::vector<std::uint32_t>& members)
{
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (std::uint32_t i : members)
        mean += points[i];
    mean /= static_cast<double>(std::max<std::size_t>(members.size(), 1));
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (std::uint32_t i : members)
        covariance.noalias() += (points[i] - mean) * (points[i] - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    Primitive plane;
    plane.kind = PrimitiveKind::Plane;
    plane.point = mean;
    plane.direction = solver.eigenvectors().col(0).normalized();
    return plane;
}

} // namespace

std::vector<RansacShape> growPlanarRegions(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals,
                                           const octree::Octree& tree, const RegionGrowingSettings& settings,
                                           const std::function<bool()>& keepGoing)
{
    if (points.empty())
        return {};
    Items items;
    items.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        items.emplace_back(Kernel::Point_3(points[i].x(), points[i].y(), points[i].z()),
                           Kernel::Vector_3(normals[i].x(), normals[i].y(), normals[i].z()));
    PlaneRegion region(items, settings.epsilon, settings.normalDegrees, settings.minPoints);
    std::vector<std::vector<std::size_t>> regions;
    try {
        OctreeQuery query(tree, settings.neighbourRadius, keepGoing);
        Sorting sorting(items, query);
        sorting.sort();
        Growing growing(items, query, region, sorting.seed_map());
        growing.detect(std::back_inserter(regions));
    } catch (const StopTheRun&) {
        return {};
    }

    std::vector<RansacShape> shapes;
    shapes.reserve(regions.size());
    for (const std::vector<std::size_t>& members : regions) {
        RansacShape shape;
        shape.members.reserve(members.size());
        for (std::size_t i : members)
            shape.members.push_back(static_cast<std::uint32_t>(i));
        // The plane is fitted again by the caller; a first one from the members.
        shape.primitive = leastSquaresPlane(points, shape.members);
        shapes.push_back(std::move(shape));
    }
    return shapes;
}

namespace {

//! Members grouped by region label, regions smaller than minPoints dropped,
//! in the order of their first seed.
std::vector<RansacShape> regionsOf(const std::vector<std::int32_t>& label, std::int32_t count, std::size_t minPoints)
{
    std::vector<std::vector<std::uint32_t>> members(static_cast<std::size_t>(count));
    for (std::size_t i = 0; i < label.size(); ++i)
        if (label[i] >= 0)
            members[static_cast<std::size_t>(label[i])].push_back(static_cast<std::uint32_t>(i));
    std::vector<RansacShape> out;
    for (auto& m : members)
        if (m.size() >= minPoints) {
            RansacShape shape;
            shape.members = std::move(m);
            out.push_back(std::move(shape));
        }
    return out;
}

} // namespace

GrowingOutcome growSmoothRegions(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals,
                                 const octree::Octree& tree, const RegionGrowingSettings& settings, const std::function<bool()>& keepGoing)
{
    GrowingOutcome outcome;
    const std::size_t n = points.size();
    if (n == 0)
        return outcome;
    try {
        // Wide enough for the noise (10 sigma, epsilon being 3 sigma) that a
        // plane's variation stays well below an edge's: on a dense, noisy scan
        // the connectivity radius holds too few points for that.
        const OctreeQuery query(tree, std::max(settings.neighbourRadius, 3.5 * settings.epsilon), keepGoing);
        // Each point's surface variation over its neighbourhood.
        std::vector<double> variation(n, 1.0);
        std::vector<Eigen::Vector3d> local(normals);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                const std::size_t count = static_cast<std::size_t>(query.end(i) - query.begin(i));
                if (count < 3)
                    continue;
                Eigen::Vector3d mean = Eigen::Vector3d::Zero();
                for (const std::uint32_t* j = query.begin(i); j != query.end(i); ++j)
                    mean += points[*j];
                mean /= static_cast<double>(count);
                Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
                for (const std::uint32_t* j = query.begin(i); j != query.end(i); ++j)
                    covariance.noalias() += (points[*j] - mean) * (points[*j] - mean).transpose();
                const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
                const Eigen::Vector3d values = solver.eigenvalues();
                const double sum = values.sum();
                variation[i] = sum > 0 ? std::max(values[0], 0.0) / sum : 0.0;
                local[i] = solver.eigenvectors().col(0).normalized();
            }
        });
        outcome.curvature = settings.curvature ? *settings.curvature : 2.0 * medianOf(variation);
        std::vector<std::uint32_t> order(n);
        for (std::size_t i = 0; i < n; ++i)
            order[i] = static_cast<std::uint32_t>(i);
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
            return variation[a] != variation[b] ? variation[a] < variation[b] : a < b;
        });
        const double cosine = std::cos(settings.smoothnessDegrees * M_PI / 180.0);
        std::vector<std::int32_t> label(n, -1);
        std::int32_t regions = 0;
        std::vector<std::uint32_t> front;
        std::size_t visited = 0;
        for (std::uint32_t seed : order) {
            if (label[seed] >= 0)
                continue;
            const std::int32_t id = regions++;
            label[seed] = id;
            front.assign(1, seed);
            while (!front.empty()) {
                const std::uint32_t at = front.back();
                front.pop_back();
                if (++visited % 65536 == 0 && !keepGoing())
                    throw StopTheRun{};
                for (const std::uint32_t* j = query.begin(at); j != query.end(at); ++j) {
                    // Its normal close to this point's, and the point itself on this
                    // point's tangent plane (within epsilon: PCL's residual test), so a
                    // panel a few centimetres before a wall stays apart.
                    if (label[*j] >= 0 || std::abs(local[at].dot(local[*j])) < cosine ||
                        std::abs(local[at].dot(points[*j] - points[at])) > settings.epsilon)
                        continue;
                    label[*j] = id;
                    if (variation[*j] <= outcome.curvature)
                        front.push_back(*j);
                }
            }
        }
        outcome.regions = regionsOf(label, regions, settings.minPoints);
    } catch (const StopTheRun&) {
        return {};
    }
    return outcome;
}

GrowingOutcome growValueRegions(const std::vector<Eigen::Vector3d>& points, const std::vector<float>& values, const octree::Octree& tree,
                                double radius, const RegionGrowingSettings& settings, const std::function<bool()>& keepGoing)
{
    GrowingOutcome outcome;
    const std::size_t n = points.size();
    if (n == 0)
        return outcome;
    std::vector<std::int32_t> label(n, -1);
    std::int32_t regions = 0;
    try {
        const OctreeQuery query(tree, radius, keepGoing);
        // The variance of the finite values in each point's disc (NaN when fewer than 3).
        std::vector<double> discVariance(n, std::numeric_limits<double>::quiet_NaN());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                if (!std::isfinite(values[i]))
                    continue;
                RunningMoments disc;
                for (const std::uint32_t* j = query.begin(i); j != query.end(i); ++j)
                    if (std::isfinite(values[*j]))
                        disc.add(values[*j]);
                if (disc.count >= 3)
                    discVariance[i] = std::max(0.0, disc.variance());
            }
        });
        std::vector<std::uint32_t> seeds;
        std::vector<double> finite;
        for (std::size_t i = 0; i < n; ++i)
            if (std::isfinite(discVariance[i])) {
                seeds.push_back(static_cast<std::uint32_t>(i));
                finite.push_back(discVariance[i]);
            }
        outcome.tolerance = settings.tolerance ? *settings.tolerance : 4.0 * medianOf(finite);
        const double tau = outcome.tolerance, band = 3.0 * std::sqrt(tau);
        // Variances from sums carry rounding (identical values may give 1e-13
        // rather than 0): a value joins at the tolerance, within that rounding,
        // so a tolerance of 0 (a quantised or uniform field) still grows regions
        // of equal values.
        auto within = [](double variance, double limit, double mean) { return variance <= limit + 1e-12 * (1.0 + mean * mean); };
        std::sort(seeds.begin(), seeds.end(), [&](std::uint32_t a, std::uint32_t b) {
            return discVariance[a] != discVariance[b] ? discVariance[a] < discVariance[b] : a < b;
        });
        std::deque<std::uint32_t> front;
        std::size_t visited = 0;
        for (std::uint32_t seed : seeds) {
            if (label[seed] >= 0 || !within(discVariance[seed], tau, values[seed]))
                continue;
            const std::int32_t id = regions++;
            RunningMoments region;
            auto join = [&](std::uint32_t j) {
                label[j] = id;
                region.add(values[j]);
                front.push_back(j);
            };
            join(seed);
            while (!front.empty()) {
                const std::uint32_t at = front.front();
                front.pop_front();
                if (++visited % 65536 == 0 && !keepGoing())
                    throw StopTheRun{};
                for (const std::uint32_t* j = query.begin(at); j != query.end(at); ++j) {
                    if (label[*j] >= 0 || !std::isfinite(values[*j]))
                        continue;
                    const double value = values[*j];
                    if (within(region.varianceWith(value), tau, region.meanWith(value)) &&
                        std::abs(value - region.mean()) <= band + 1e-9 * std::abs(value))
                        join(*j);
                }
            }
        }
    } catch (const StopTheRun&) {
        return {};
    }
    outcome.regions = regionsOf(label, regions, settings.minPoints);
    return outcome;
}

Primitive initialShape(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals,
                       const std::vector<std::uint32_t>& members)
{
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (std::uint32_t i : members)
        mean += points[i];
    mean /= static_cast<double>(std::max<std::size_t>(members.size(), 1));
    Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
    for (std::uint32_t i : members)
        spread.noalias() += normals[i] * normals[i].transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> turning(spread);
    if (turning.eigenvalues()[1] > 0.05 * turning.eigenvalues().sum()) {
        // The normals turn: a cylinder across them, its section the Kasa circle
        // of the points projected along the axis.
        std::vector<Eigen::Vector3d> offsets, memberNormals;
        offsets.reserve(members.size());
        memberNormals.reserve(members.size());
        for (std::uint32_t i : members) {
            offsets.push_back(points[i] - mean);
            memberNormals.push_back(normals[i]);
        }
        if (const std::optional<Primitive> cylinder = cylinderFromNormals(offsets, memberNormals, mean))
            return *cylinder;
    }
    return leastSquaresPlane(points, members);
}

} // namespace scandiff::plugins::detail
