// SPDX-License-Identifier: GPL-3.0-or-later
// The 2D Delaunay triangulation, through CGAL (its headers stay in this file:
// they take seconds to compile). Exact predicates, so nearly collinear scan
// rows do not break it; spatial sorting before insertion keeps it at about a
// second per million points.
#include <scandiff/plugins/contours/PlanarContours.h>

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <utility>

namespace scandiff::plugins {

std::vector<std::array<std::uint32_t, 3>> delaunayTriangles(const std::vector<Eigen::Vector2d>& points)
{
    using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
    using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, Kernel>;
    using Structure = CGAL::Triangulation_data_structure_2<VertexBase>;
    using Delaunay = CGAL::Delaunay_triangulation_2<Kernel, Structure>;

    std::vector<std::pair<Kernel::Point_2, std::uint32_t>> input;
    input.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        input.emplace_back(Kernel::Point_2(points[i].x(), points[i].y()), static_cast<std::uint32_t>(i));
    // The range insertion sorts spatially; a point equal to one already in
    // keeps the vertex (and the index) of the first.
    Delaunay triangulation(input.begin(), input.end());

    std::vector<std::array<std::uint32_t, 3>> triangles;
    if (triangulation.dimension() < 2)
        return triangles;
    triangles.reserve(static_cast<std::size_t>(triangulation.number_of_faces()));
    for (auto face = triangulation.finite_faces_begin(); face != triangulation.finite_faces_end(); ++face)
        triangles.push_back({face->vertex(0)->info(), face->vertex(1)->info(), face->vertex(2)->info()});
    return triangles;
}

} // namespace scandiff::plugins
