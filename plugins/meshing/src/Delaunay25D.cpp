// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/plugins/meshing/Delaunay25D.h>

#include <scandiff/core/Error.h>

#include "BiasedInsertion.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

namespace scandiff::plugins {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, Kernel>;
using DataStructure = CGAL::Triangulation_data_structure_2<VertexBase>;
using Triangulation = CGAL::Delaunay_triangulation_2<Kernel, DataStructure>;
using Point2 = Kernel::Point_2;

//! The two in-plane axes and the normal of the projection plane.
struct PlaneAxes
{
    Eigen::Vector3d u, v, normal;
};

PlaneAxes axesFor(const PointCloud& cloud, ProjectionPlane projection)
{
    switch (projection) {
    case ProjectionPlane::AlongZ: return {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
    case ProjectionPlane::AlongX: return {Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX()};
    case ProjectionPlane::AlongY: return {Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()};
    case ProjectionPlane::BestFit: break;
    }
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : cloud.positions())
        mean += p.cast<double>();
    mean /= static_cast<double>(cloud.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const auto& p : cloud.positions()) {
        const Eigen::Vector3d d = p.cast<double>() - mean;
        covariance.noalias() += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    Eigen::Vector3d normal = solver.eigenvectors().col(0);
    if (normal.z() < 0 || (normal.z() == 0 && normal.y() < 0))
        normal = -normal;
    const Eigen::Vector3d u = solver.eigenvectors().col(2).normalized();
    return {u, normal.cross(u), normal};
}

} // namespace

Delaunay25DResult delaunay25D(const PointCloud& cloud, const Delaunay25DParams& params, ProgressObserver* progress)
{
    if (params.maxEdgeLength && !(*params.maxEdgeLength > 0 && std::isfinite(*params.maxEdgeLength)))
        throw Error(ErrorCode::InvalidArgument, "mesh: the maximum edge length must be > 0");
    const std::size_t n = cloud.size();
    if (n < 3)
        throw Error(ErrorCode::InvalidData, "mesh: cloud '" + cloud.name + "' has fewer than 3 points");
    if (n > std::numeric_limits<std::uint32_t>::max())
        throw Error(ErrorCode::InvalidData, "mesh: at most 4,294,967,295 points can be meshed");
    for (const auto& p : cloud.positions())
        if (!p.allFinite())
            throw Error(ErrorCode::InvalidData, "mesh: cloud '" + cloud.name + "' has non-finite coordinates");
    const PlaneAxes axes = axesFor(cloud, params.projection);

    // Points on the plane (local coordinates: the origin's magnitude is not in them).
    std::vector<std::pair<Point2, std::uint32_t>> planar(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d p = cloud.positions()[i].cast<double>();
        planar[i] = {Point2(p.dot(axes.u), p.dot(axes.v)), static_cast<std::uint32_t>(i)};
    }
    // A duplicate keeps the later index: harmless, the earlier is unused.
    ProgressTicker inserting(progress, "Delaunay triangulation", 2 * n);
    Triangulation triangulation;
    detail::insertInBiasedRandomOrder(triangulation, planar, inserting);
    if (triangulation.dimension() < 2)
        throw Error(ErrorCode::InvalidData, "mesh: the points of '" + cloud.name + "' project onto a line");

    Delaunay25DResult result;
    result.duplicates = n - triangulation.number_of_vertices();
    result.mesh.name = cloud.name + "_mesh";
    result.mesh.vertices = cloud.clone();
    result.mesh.triangles.reserve(2 * n);
    const double limit2 = params.maxEdgeLength ? *params.maxEdgeLength * *params.maxEdgeLength : std::numeric_limits<double>::infinity();
    ProgressTicker ticker(progress, "Keeping triangles", triangulation.number_of_faces());
    std::size_t faces = 0;
    for (auto face = triangulation.finite_faces_begin(); face != triangulation.finite_faces_end(); ++face) {
        // CGAL's faces are counter-clockwise in (u, v), i.e. seen from +normal.
        const Triangle t{face->vertex(0)->info(), face->vertex(1)->info(), face->vertex(2)->info()};
        const Eigen::Vector3d a = cloud.positions()[t[0]].cast<double>(), b = cloud.positions()[t[1]].cast<double>(),
                              c = cloud.positions()[t[2]].cast<double>();
        if ((b - a).squaredNorm() > limit2 || (c - b).squaredNorm() > limit2 || (a - c).squaredNorm() > limit2) {
            ++result.dropped;
        } else {
            result.mesh.triangles.push_back(t);
            result.area += 0.5 * (b - a).cross(c - a).norm();
        }
        if ((++faces & 65535) == 0)
            ticker.step(65536);
    }
    return result;
}

} // namespace scandiff::plugins
