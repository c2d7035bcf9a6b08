// SPDX-License-Identifier: GPL-3.0-or-later
#include "EfficientRansac.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Random.h>
#include <CGAL/Shape_detection/Efficient_RANSAC.h>
#include <CGAL/property_map.h>

#include <algorithm>
#include <cmath>
#include <tuple>

namespace scandiff::plugins::detail {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
// Each point carries its position in the caller's vectors: CGAL reorders
// the range it is given while it builds its subsets.
using Item = std::tuple<Kernel::Point_3, Kernel::Vector_3, std::uint32_t>;
using Items = std::vector<Item>;
using PointMap = CGAL::Nth_of_tuple_property_map<0, Item>;
using NormalMap = CGAL::Nth_of_tuple_property_map<1, Item>;
using Traits = CGAL::Shape_detection::Efficient_RANSAC_traits<Kernel, Items, PointMap, NormalMap>;
using Ransac = CGAL::Shape_detection::Efficient_RANSAC<Traits>;

//! One of CGAL's shapes with a bound on the memory of its connected parts.
//! CGAL finds a candidate's parts on a bitmap of its unrolled surface at the
//! cluster epsilon's resolution (4 bytes a cell): a candidate spanning a huge
//! range of its own coordinates (a cylinder or a sphere of kilometres through
//! a few walls) asks for hundreds of millions of cells, 607 MB of the 819 MB
//! peak on the 1 M-point benchmark scene, while CloudCompare's plugin peaks at
//! 254 MB. Past 16 cells a point (and 4 M cells), such a candidate's parts are
//! found by CGAL's other path instead, the one it takes for tori: a k-d tree on
//! the candidate's points, linked within the cluster epsilon, whose memory
//! follows the points. A real shape's bitmap stays far below the bound (a
//! plane of 10 m x 10 m holding 20,000 points at 2 cm: 250,000 cells).
template <class Shape>
class BoundedComponents : public Shape
{
    using FT = typename Shape::FT;

protected:
    std::size_t connected_component(std::vector<std::size_t>& indices, FT clusterEpsilon) override
    {
        if (!indices.empty() && this->supports_connected_component()) {
            std::vector<std::pair<FT, FT>> coordinates(indices.size());
            FT low[] = {0, 0}, high[] = {0, 0};
            FT epsilon = clusterEpsilon; // parameters() may widen it, as in CGAL's bitmap path
            this->parameters(this->m_indices, coordinates, epsilon, low, high);
            const double cells = std::max(1.0, std::ceil((high[0] - low[0]) / epsilon)) * std::max(1.0, std::ceil((high[1] - low[1]) / epsilon));
            if (!(cells <= std::max(16.0 * static_cast<double>(indices.size()), 4.0 * (1 << 20))))
                return this->connected_component_kdTree(indices, clusterEpsilon);
        }
        return Shape::connected_component(indices, clusterEpsilon);
    }
};

Eigen::Vector3d toEigen(const Kernel::Point_3& p) { return {p.x(), p.y(), p.z()}; }
Eigen::Vector3d toEigen(const Kernel::Vector_3& v) { return {v.x(), v.y(), v.z()}; }

} // namespace

std::vector<RansacShape> efficientRansac(const std::vector<Eigen::Vector3d>& points, std::vector<Eigen::Vector3d> normals,
                                         const RansacSettings& settings, const std::function<bool(double)>& keepGoing)
{
    Items items;
    items.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        items.emplace_back(Kernel::Point_3(points[i].x(), points[i].y(), points[i].z()),
                           Kernel::Vector_3(normals[i].x(), normals[i].y(), normals[i].z()), static_cast<std::uint32_t>(i));
    std::vector<Eigen::Vector3d>().swap(normals); // in the items now: given up before CGAL's search peaks
    // CGAL draws every random number from this thread's default generator:
    // seeded here, the same seed and input give the same shapes.
    CGAL::get_default_random() = CGAL::Random(static_cast<unsigned>(settings.seed ^ (settings.seed >> 32)));
    Ransac ransac;
    ransac.set_input(items);
    if (settings.kinds.count(PrimitiveKind::Plane))
        ransac.add_shape_factory<BoundedComponents<CGAL::Shape_detection::Plane<Traits>>>();
    if (settings.kinds.count(PrimitiveKind::Sphere))
        ransac.add_shape_factory<BoundedComponents<CGAL::Shape_detection::Sphere<Traits>>>();
    if (settings.kinds.count(PrimitiveKind::Cylinder))
        ransac.add_shape_factory<BoundedComponents<CGAL::Shape_detection::Cylinder<Traits>>>();
    if (settings.kinds.count(PrimitiveKind::Cone))
        ransac.add_shape_factory<BoundedComponents<CGAL::Shape_detection::Cone<Traits>>>();
    if (settings.kinds.count(PrimitiveKind::Torus))
        ransac.add_shape_factory<BoundedComponents<CGAL::Shape_detection::Torus<Traits>>>();
    Ransac::Parameters parameters;
    parameters.probability = settings.probability;
    parameters.min_points = settings.minPoints;
    parameters.epsilon = settings.epsilon;
    parameters.cluster_epsilon = settings.clusterEpsilon;
    parameters.normal_threshold = settings.normalCosine;
    ransac.detect(parameters, keepGoing);

    std::vector<RansacShape> shapes;
    for (const auto& shape : ransac.shapes()) {
        RansacShape out;
        Primitive& p = out.primitive;
        if (const auto* plane = dynamic_cast<const CGAL::Shape_detection::Plane<Traits>*>(shape.get())) {
            p.kind = PrimitiveKind::Plane;
            p.direction = toEigen(plane->plane_normal()).normalized();
            // n . x + d = 0 with the normal CGAL gives (unit length).
            p.point = -plane->d() * p.direction;
        } else if (const auto* sphere = dynamic_cast<const CGAL::Shape_detection::Sphere<Traits>*>(shape.get())) {
            p.kind = PrimitiveKind::Sphere;
            p.point = toEigen(sphere->center());
            p.radius = sphere->radius();
        } else if (const auto* cylinder = dynamic_cast<const CGAL::Shape_detection::Cylinder<Traits>*>(shape.get())) {
            p.kind = PrimitiveKind::Cylinder;
            const Kernel::Line_3 axis = cylinder->axis();
            p.point = toEigen(axis.point(0));
            p.direction = toEigen(axis.to_vector()).normalized();
            p.radius = cylinder->radius();
        } else if (const auto* cone = dynamic_cast<const CGAL::Shape_detection::Cone<Traits>*>(shape.get())) {
            p.kind = PrimitiveKind::Cone;
            p.point = toEigen(cone->apex());
            p.direction = toEigen(cone->axis()).normalized();
            p.halfAngle = cone->angle();
        } else if (const auto* torus = dynamic_cast<const CGAL::Shape_detection::Torus<Traits>*>(shape.get())) {
            p.kind = PrimitiveKind::Torus;
            p.point = toEigen(torus->center());
            p.direction = toEigen(torus->axis()).normalized();
            p.radius = torus->major_radius();
            p.minorRadius = torus->minor_radius();
        } else {
            continue;
        }
        for (std::size_t k : shape->indices_of_assigned_points())
            out.members.push_back(std::get<2>(items[k]));
        shapes.push_back(std::move(out));
    }
    return shapes;
}

} // namespace scandiff::plugins::detail
