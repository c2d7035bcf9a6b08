// SPDX-License-Identifier: GPL-3.0-or-later
// The 2.5D Delaunay meshing plugin (CGAL) on shapes whose mesh is known.
#include "TestSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/plugins/PluginRegistry.h>
#include <scandiff/plugins/meshing/Delaunay25D.h>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <random>

using namespace scandiff;

namespace {

double area(const Mesh& mesh, std::size_t t)
{
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector3d a = mesh.vertices.positions()[tri[0]].cast<double>(), b = mesh.vertices.positions()[tri[1]].cast<double>(),
                          c = mesh.vertices.positions()[tri[2]].cast<double>();
    return 0.5 * (b - a).cross(c - a).norm();
}

double longestEdge(const Mesh& mesh, std::size_t t)
{
    const auto& tri = mesh.triangles[t];
    double longest = 0;
    for (int e = 0; e < 3; ++e)
        longest = std::max(longest, static_cast<double>((mesh.vertices.positions()[tri[static_cast<std::size_t>(e)]] -
                                                         mesh.vertices.positions()[tri[static_cast<std::size_t>((e + 1) % 3)]])
                                                            .norm()));
    return longest;
}

} // namespace

TEST(Meshing, ASampledPlaneMeshesIntoItsRegionWithoutLongTriangles)
{
    // A 10 m x 6 m tilted plane sampled on a 0.2 m grid, with a 2 m x 2 m hole.
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();
    PointCloud plane;
    plane.setOrigin(Eigen::Vector3d(512000, 5403000, 50));
    for (int i = 0; i <= 50; ++i)
        for (int j = 0; j <= 30; ++j) {
            const double x = 0.2 * i, y = 0.2 * j;
            if (x > 4 && x < 6 && y > 2 && y < 4)
                continue; // the hole: the nodes strictly inside it
            plane.positions().push_back((tilt * Eigen::Vector3d(x, y, 0)).cast<float>());
        }
    plane.resize(plane.positions().size());
    plugins::Delaunay25DParams params;
    params.maxEdgeLength = 0.3; // longer than the diagonal 0.283, shorter than across the hole
    const plugins::Delaunay25DResult result = plugins::delaunay25D(plane, params);
    double total = 0;
    for (std::size_t t = 0; t < result.mesh.triangles.size(); ++t) {
        ASSERT_LE(longestEdge(result.mesh, t), 0.3 + 1e-6) << t;
        total += area(result.mesh, t);
        // Normals face +Z (counter-clockwise seen from above).
        const auto& tri = result.mesh.triangles[t];
        const Eigen::Vector3f n = (plane.positions()[tri[1]] - plane.positions()[tri[0]]).cross(plane.positions()[tri[2]] - plane.positions()[tri[0]]);
        ASSERT_GT(n.z(), 0.0f) << t;
    }
    // The region's area in the plane's own measure: the rectangle less the
    // hole, 2 x 2 m between the kept nodes around it, whose four corners keep
    // a triangle each (two 0.2 m sides and the 0.28 m diagonal, under the limit).
    EXPECT_NEAR(total, 10.0 * 6.0 - 2.0 * 2.0 + 4 * 0.02, 1e-4);
    EXPECT_NEAR(result.area, total, 1e-9);
    EXPECT_GT(result.dropped, 0u);
    EXPECT_EQ(result.mesh.vertices.size(), plane.size());

    // Without a limit the hole is covered: the whole rectangle.
    const plugins::Delaunay25DResult whole = plugins::delaunay25D(plane, plugins::Delaunay25DParams{});
    EXPECT_NEAR(whole.area, 60.0, 1e-3);
    EXPECT_EQ(whole.dropped, 0u);
}

TEST(Meshing, AWallWithTheBestFitPlaneAndBadInput)
{
    // A vertical wall: along z it projects onto a line, with the best-fit plane it meshes.
    PointCloud wall;
    for (int i = 0; i <= 20; ++i)
        for (int k = 0; k <= 10; ++k)
            wall.positions().emplace_back(0.1f * i, 0.5f * 0.1f * i, 0.1f * k);
    wall.resize(wall.positions().size());
    EXPECT_EQ(test::errorCodeOf([&] { plugins::delaunay25D(wall, plugins::Delaunay25DParams{}); }), ErrorCode::InvalidData);
    plugins::Delaunay25DParams bestFit;
    bestFit.projection = plugins::ProjectionPlane::BestFit;
    const plugins::Delaunay25DResult result = plugins::delaunay25D(wall, bestFit);
    EXPECT_NEAR(result.area, 2.0 * std::sqrt(1.25) * 1.0, 1e-4);

    PointCloud two;
    two.resize(2);
    EXPECT_EQ(test::errorCodeOf([&] { plugins::delaunay25D(two, plugins::Delaunay25DParams{}); }), ErrorCode::InvalidData);
    plugins::Delaunay25DParams badLimit;
    badLimit.maxEdgeLength = -1;
    EXPECT_EQ(test::errorCodeOf([&] { plugins::delaunay25D(wall, badLimit); }), ErrorCode::InvalidArgument);
}

TEST(Meshing, TheToolGivesAMeshUnderItsInput)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec* tool = registry.tools.find("mesh");
    ASSERT_NE(tool, nullptr);
    EXPECT_EQ(tool->outputs.front().kind, DataKind::Mesh);
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> u(0, 5);
    PointCloud terrain;
    terrain.resize(2000);
    for (auto& p : terrain.positions())
        p = {u(rng), u(rng), 0.1f * u(rng)};
    const ToolResult result = tool->execute(ToolInputs().add("input", terrain), tool->resolve({{"max-edge", "0.5"}}), nullptr);
    EXPECT_GT(result.mesh().triangles.size(), 3000u);
    EXPECT_NE(result.summary.find("triangles"), std::string::npos);
}
