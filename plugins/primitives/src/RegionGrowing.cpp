// SPDX-License-Identifier: GPL-3.0-or-later
#include "RegionGrowing.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Shape_detection/Region_growing/Region_growing.h>
#include <CGAL/Shape_detection/Region_growing/Region_growing_on_point_set/Least_squares_plane_fit_region.h>
#include <CGAL/Shape_detection/Region_growing/Region_growing_on_point_set/Least_squares_plane_fit_sorting.h>
#include <CGAL/property_map.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
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
        shape.primitive.kind = PrimitiveKind::Plane;
        // The plane is fitted again by the caller; a first one from the members.
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (std::size_t i : members)
            mean += points[i];
        mean /= static_cast<double>(members.size());
        Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
        for (std::size_t i : members)
            covariance.noalias() += (points[i] - mean) * (points[i] - mean).transpose();
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
        shape.primitive.point = mean;
        shape.primitive.direction = solver.eigenvectors().col(0).normalized();
        shape.members.reserve(members.size());
        for (std::size_t i : members)
            shape.members.push_back(static_cast<std::uint32_t>(i));
        shapes.push_back(std::move(shape));
    }
    return shapes;
}

} // namespace scandiff::plugins::detail
