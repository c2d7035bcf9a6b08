// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/geometry/PointTriangleDistance.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace scandiff::geometry;
using Eigen::Vector3d;

namespace {

const Vector3d A(0, 0, 0), B(1, 0, 0), C(0, 1, 0);

void expectResult(const PointTriangleResult& r, double squaredDistance, const Vector3d& closest, TriangleRegion region)
{
    EXPECT_NEAR(r.squaredDistance, squaredDistance, 1e-14);
    EXPECT_NEAR((r.closestPoint - closest).norm(), 0.0, 1e-14) << r.closestPoint.transpose();
    EXPECT_EQ(r.region, region);
}

//! Ericson's closest point (RTCD §5.1.5), an independent oracle for ordinary triangles.
Vector3d ericsonClosest(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c)
{
    const Vector3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0)
        return a;
    const Vector3d bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3)
        return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0)
        return a + d1 / (d1 - d3) * ab;
    const Vector3d cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6)
        return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0)
        return a + d2 / (d2 - d6) * ac;
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

} // namespace

TEST(PointTriangleDistance, FaceRegionAboveAndBelow)
{
    expectResult(pointTriangleDistance({0.25, 0.25, 2}, A, B, C), 4.0, {0.25, 0.25, 0}, TriangleRegion::Face);
    expectResult(pointTriangleDistance({0.25, 0.5, -3}, A, B, C), 9.0, {0.25, 0.5, 0}, TriangleRegion::Face);
    const auto r = pointTriangleDistance({0.2, 0.3, 0}, A, B, C);
    EXPECT_EQ(r.squaredDistance, 0.0);
    EXPECT_FALSE(r.degenerate);
}

TEST(PointTriangleDistance, EveryEdgeRegion)
{
    // Below edge AB (y < 0), beyond hypotenuse BC, left of edge CA (x < 0).
    expectResult(pointTriangleDistance({0.5, -1, 1}, A, B, C), 2.0, {0.5, 0, 0}, TriangleRegion::Edge01);
    expectResult(pointTriangleDistance({1, 1, 1}, A, B, C), 1.5, {0.5, 0.5, 0}, TriangleRegion::Edge12);
    expectResult(pointTriangleDistance({-1, 0.5, 0}, A, B, C), 1.0, {0, 0.5, 0}, TriangleRegion::Edge20);
    // Edge region in the triangle's plane and off it.
    expectResult(pointTriangleDistance({0.75, 0.75, 0}, A, B, C), 0.125, {0.5, 0.5, 0}, TriangleRegion::Edge12);
    expectResult(pointTriangleDistance({0.3, -2, -2}, A, B, C), 8.0, {0.3, 0, 0}, TriangleRegion::Edge01);
}

TEST(PointTriangleDistance, EveryVertexRegion)
{
    expectResult(pointTriangleDistance({-1, -1, 0}, A, B, C), 2.0, A, TriangleRegion::Vertex0);
    expectResult(pointTriangleDistance({2, -1, 1}, A, B, C), 3.0, B, TriangleRegion::Vertex1);
    expectResult(pointTriangleDistance({-0.5, 2, 0}, A, B, C), 1.25, C, TriangleRegion::Vertex2);
    // A vertex returns the vertex itself, bit for bit.
    const Vector3d a(0.1, 0.2, 0.3), b(1.7, 0.05, 0.4), c(0.3, 1.9, -0.2);
    EXPECT_EQ(pointTriangleDistance({3, -1, 0.5}, a, b, c).closestPoint, b);
}

TEST(PointTriangleDistance, RegionsFollowTheVertexOrder)
{
    // Same triangle, vertices rotated: the region names follow the arguments.
    expectResult(pointTriangleDistance({0.5, -1, 1}, B, C, A), 2.0, {0.5, 0, 0}, TriangleRegion::Edge20);
    expectResult(pointTriangleDistance({-1, -1, 0}, C, A, B), 2.0, A, TriangleRegion::Vertex1);
}

TEST(PointTriangleDistance, SharedEdgesGiveBitIdenticalDistances)
{
    // Two triangles sharing the edge (b, c), traversed in opposite directions.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-3, 3);
    for (int i = 0; i < 1000; ++i) {
        const Vector3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng)),
            d(u(rng), u(rng), u(rng));
        const Vector3d p(u(rng), u(rng), u(rng));
        const auto r1 = pointTriangleDistance(p, a, b, c);
        const auto r2 = pointTriangleDistance(p, d, c, b);
        if (r1.region == TriangleRegion::Edge12 && r2.region == TriangleRegion::Edge12) {
            EXPECT_EQ(r1.squaredDistance, r2.squaredDistance);
            EXPECT_EQ(r1.closestPoint, r2.closestPoint);
        }
    }
}

TEST(PointTriangleDistance, MatchesEricsonOnRandomTriangles)
{
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> u(-2, 2);
    for (int i = 0; i < 20000; ++i) {
        const Vector3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
        const Vector3d p(u(rng), u(rng), u(rng));
        const auto r = pointTriangleDistance(p, a, b, c);
        const Vector3d expected = ericsonClosest(p, a, b, c);
        ASSERT_NEAR(r.squaredDistance, (p - expected).squaredNorm(), 1e-10) << i;
        ASSERT_NEAR((r.closestPoint - expected).norm(), 0.0, 1e-7) << i;
        // Distance is invariant under the 6 orderings of the vertices.
        EXPECT_NEAR(pointTriangleDistance(p, c, b, a).squaredDistance, r.squaredDistance, 1e-12);
        EXPECT_NEAR(pointTriangleDistance(p, b, c, a).squaredDistance, r.squaredDistance, 1e-12);
    }
}

TEST(PointTriangleDistance, RepeatedVerticesCollapseToASegmentOrAPoint)
{
    const Vector3d p(0.5, 2, 0);
    // a == b: the segment [a, c] = [(0,0,0), (2,0,0)].
    auto r = pointTriangleDistance(p, A, A, {2, 0, 0});
    EXPECT_TRUE(r.degenerate);
    expectResult(r, 4.0, {0.5, 0, 0}, TriangleRegion::Edge12);
    // Beyond the end of the segment: the end vertex.
    r = pointTriangleDistance({3, 1, 0}, A, {2, 0, 0}, A);
    EXPECT_TRUE(r.degenerate);
    EXPECT_DOUBLE_EQ(r.squaredDistance, 2.0);
    EXPECT_EQ(r.closestPoint, Vector3d(2, 0, 0));
    EXPECT_EQ(r.region, TriangleRegion::Vertex1);
    // All three equal: a point.
    const Vector3d v(1, 2, 3);
    r = pointTriangleDistance({1, 2, 5}, v, v, v);
    EXPECT_TRUE(r.degenerate);
    EXPECT_EQ(r.squaredDistance, 4.0);
    EXPECT_EQ(r.closestPoint, v);
    EXPECT_EQ(r.region, TriangleRegion::Vertex0);
    // The point on it.
    EXPECT_EQ(pointTriangleDistance(v, v, v, v).squaredDistance, 0.0);
}

TEST(PointTriangleDistance, CollinearVerticesCollapseToTheirSpan)
{
    // b between a and c; then c between a and b (the long edge is not the first one).
    const Vector3d a(0, 0, 0), b(1, 1, 1), c(3, 3, 3);
    for (const auto& t : {std::array<Vector3d, 3>{a, b, c}, std::array<Vector3d, 3>{a, c, b}, std::array<Vector3d, 3>{c, a, b}}) {
        // Perpendicular foot at (2,2,2): inside the span.
        const Vector3d p = Vector3d(2, 2, 2) + Vector3d(1, -1, 0);
        auto r = pointTriangleDistance(p, t[0], t[1], t[2]);
        EXPECT_TRUE(r.degenerate);
        EXPECT_TRUE(std::isfinite(r.squaredDistance));
        EXPECT_NEAR(r.squaredDistance, 2.0, 1e-14);
        EXPECT_NEAR((r.closestPoint - Vector3d(2, 2, 2)).norm(), 0.0, 1e-14);
        // Beyond c: distance to c.
        r = pointTriangleDistance({5, 3, 3}, t[0], t[1], t[2]);
        EXPECT_NEAR(r.squaredDistance, 4.0, 1e-14);
        EXPECT_EQ(r.closestPoint, c);
        // Before a.
        r = pointTriangleDistance({-1, -1, 0}, t[0], t[1], t[2]);
        EXPECT_EQ(r.squaredDistance, 2.0);
        EXPECT_EQ(r.closestPoint, a);
    }
}

TEST(PointTriangleDistance, ZeroAreaAndSliverTrianglesNeverGiveNaN)
{
    // Collinear in double after rounding, with a point exactly on the line.
    const Vector3d a(0.1, 0.2, 0.3), c(0.7, 1.4, 2.1);
    const Vector3d b = a + (c - a) * (1.0 / 3.0);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-3, 3);
    for (int i = 0; i < 1000; ++i) {
        const Vector3d p(u(rng), u(rng), u(rng));
        const auto r = pointTriangleDistance(p, a, b, c);
        ASSERT_TRUE(std::isfinite(r.squaredDistance));
        ASSERT_TRUE(r.closestPoint.allFinite());
        // The distance to the segment [a, c].
        const double t = std::clamp((p - a).dot(c - a) / (c - a).squaredNorm(), 0.0, 1.0);
        EXPECT_NEAR(r.squaredDistance, (p - (a + t * (c - a))).squaredNorm(), 1e-12);
    }
    // A sliver of width 1e-13: the answer stays finite and within its width of the exact one.
    const Vector3d s0(0, 0, 0), s1(1, 0, 0), s2(0.5, 1e-13, 0);
    const auto r = pointTriangleDistance({0.5, 1, 0}, s0, s1, s2);
    EXPECT_TRUE(std::isfinite(r.squaredDistance));
    EXPECT_NEAR(std::sqrt(r.squaredDistance), 1.0, 1e-12);
    EXPECT_FALSE(isDegenerateTriangle(A, B, C));
    EXPECT_TRUE(isDegenerateTriangle(A, A, C));
    EXPECT_TRUE(isDegenerateTriangle(A, B, Vector3d(3, 0, 0)));
}
