// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/plugins/meshing/HeightAboveGround.h>

#include <scandiff/core/Error.h>

#include "BiasedInsertion.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Spatial_sort_traits_adapter_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/hilbert_sort.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <utility>

namespace scandiff::plugins {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<double, Kernel>; // the vertex's height
using DataStructure = CGAL::Triangulation_data_structure_2<VertexBase>;
using Triangulation = CGAL::Delaunay_triangulation_2<Kernel, DataStructure>;
using Point2 = Kernel::Point_2;

//! The TIN's height at (x, y) in the finite face f: the plane through its
//! three corners, by barycentric coordinates in XY.
double heightInFace(const Triangulation::Face_handle& f, double x, double y)
{
    const Point2& a = f->vertex(0)->point();
    const Point2& b = f->vertex(1)->point();
    const Point2& c = f->vertex(2)->point();
    const double det = (b.y() - c.y()) * (a.x() - c.x()) + (c.x() - b.x()) * (a.y() - c.y());
    const double la = ((b.y() - c.y()) * (x - c.x()) + (c.x() - b.x()) * (y - c.y())) / det;
    const double lb = ((c.y() - a.y()) * (x - c.x()) + (a.x() - c.x()) * (y - c.y())) / det;
    const double lc = 1.0 - la - lb;
    return la * f->vertex(0)->info() + lb * f->vertex(1)->info() + lc * f->vertex(2)->info();
}

//! The ground points of the cloud, with their heights, in file order.
std::vector<std::pair<Point2, double>> groundPoints(const PointCloud& cloud, const HeightAboveGroundParams& params)
{
    const ScalarField* classes = cloud.field(params.classField);
    if (!classes)
        throw Error(ErrorCode::InvalidArgument, "hag: '" + cloud.name + "' has no field '" + params.classField +
                                                    "'; classify the ground first (scandiff-cli ground)");
    if (params.groundClasses.empty())
        throw Error(ErrorCode::InvalidArgument, "hag: no ground class given");
    std::vector<std::pair<Point2, double>> ground;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!classes->hasValue(i))
            continue;
        const double c = classes->value(i);
        const Eigen::Vector3f& p = cloud.positions()[i];
        if (p.allFinite() &&
            std::find(params.groundClasses.begin(), params.groundClasses.end(), static_cast<int>(std::lround(c))) !=
                params.groundClasses.end() &&
            c == std::round(c))
            ground.emplace_back(Point2(p.x(), p.y()), static_cast<double>(p.z()));
    }
    if (ground.size() < 3)
        throw Error(ErrorCode::InvalidData, "hag: " + std::to_string(ground.size()) +
                                                " ground points in '" + cloud.name + "'; a terrain needs at least 3");
    return ground;
}

//! Their TIN (detail::insertInBiasedRandomOrder: Cancel is heard while it
//! grows, 16 M points take about 20 s). At one XY place, the height of the
//! last ground point inserted there.
void buildTin(Triangulation& tin, std::vector<std::pair<Point2, double>>& ground, const std::string& name, ProgressTicker& ticker)
{
    detail::insertInBiasedRandomOrder(tin, ground, ticker);
    if (tin.dimension() < 2)
        throw Error(ErrorCode::InvalidData, "hag: the ground points of '" + name + "' lie on a line");
}

} // namespace

HeightAboveGroundResult heightAboveGround(const PointCloud& cloud, const HeightAboveGroundParams& params, ProgressObserver* progress)
{
    HeightAboveGroundResult result;
    std::vector<std::pair<Point2, double>> ground = groundPoints(cloud, params);
    result.groundPoints = ground.size();
    const std::size_t n = cloud.size();
    ProgressTicker ticker(progress, "Height above ground", 2 * ground.size() + n);
    Triangulation tin;
    buildTin(tin, ground, cloud.name, ticker);
    result.height.assign(n, std::numeric_limits<float>::quiet_NaN());
    // The points in Hilbert order: each is located by a short walk from the
    // face of the one before (in file order, a walk across the TIN each:
    // 240 s for 2 M points of a shuffled file). Locating is a const walk, so
    // both cores share the TIN.
    std::vector<std::pair<Point2, std::size_t>> queries;
    queries.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3f& p = cloud.positions()[i];
        if (p.allFinite())
            queries.emplace_back(Point2(p.x(), p.y()), i);
    }
    using SortTraits = CGAL::Spatial_sort_traits_adapter_2<Kernel, CGAL::First_of_pair_property_map<std::pair<Point2, std::size_t>>>;
    CGAL::hilbert_sort(queries.begin(), queries.end(), SortTraits());
    ticker.step(n - queries.size()); // the points without coordinates
    std::atomic<std::size_t> outside{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, queries.size(), 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
        Triangulation::Face_handle hint;
        std::size_t beyond = 0;
        for (std::size_t k = r.begin(); k != r.end(); ++k) {
            const Point2& q = queries[k].first;
            const std::size_t i = queries[k].second;
            Triangulation::Locate_type type;
            int index = 0;
            Triangulation::Face_handle face = tin.locate(q, type, index, hint);
            if (type == Triangulation::EDGE && tin.is_infinite(face))
                face = face->neighbor(index); // on the outline: the finite face across the edge
            double groundZ;
            if (type == Triangulation::VERTEX) {
                groundZ = face->vertex(index)->info();
            } else if (type == Triangulation::OUTSIDE_CONVEX_HULL || type == Triangulation::OUTSIDE_AFFINE_HULL ||
                       tin.is_infinite(face)) {
                groundZ = tin.nearest_vertex(q, face)->info();
                ++beyond;
            } else {
                groundZ = heightInFace(face, q.x(), q.y());
            }
            if (!tin.is_infinite(face))
                hint = face;
            result.height[i] = static_cast<float>(static_cast<double>(cloud.positions()[i].z()) - groundZ);
        }
        outside += beyond;
        ticker.step(r.size());
    });
    result.outsideHull = outside;
    return result;
}

} // namespace scandiff::plugins
