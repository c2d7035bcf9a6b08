// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToMesh.h>
#include <scandiff/core/distance/DistanceStatistics.h>
#include <scandiff/core/geometry/PointTriangleDistance.h>

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <random>

using namespace scandiff;
using Eigen::Vector3d;
using Eigen::Vector3f;

namespace {

const float kNaNf = std::numeric_limits<float>::quiet_NaN();

std::uint32_t addVertex(Mesh& mesh, const Vector3d& p)
{
    mesh.vertices.positions().push_back(p.cast<float>());
    return static_cast<std::uint32_t>(mesh.vertices.size() - 1);
}

//! A UV sphere (outward normals) whose vertex radii are perturbed by up to
//! +-noise: rings x segments quads, 2 x segments x (rings - 1) triangles.
Mesh noisySphere(int rings, int segments, double radius, double noise, std::mt19937& rng)
{
    std::uniform_real_distribution<double> jitter(-noise, noise);
    Mesh mesh;
    mesh.name = "noisy sphere";
    const double pi = std::acos(-1.0);
    const auto r = [&] { return radius * (1.0 + jitter(rng)); };
    const std::uint32_t north = addVertex(mesh, {0, 0, r()});
    std::vector<std::vector<std::uint32_t>> ring(static_cast<std::size_t>(rings - 1));
    for (int i = 1; i < rings; ++i) {
        const double theta = pi * i / rings;
        for (int j = 0; j < segments; ++j) {
            const double phi = 2 * pi * j / segments;
            const double rr = r();
            ring[static_cast<std::size_t>(i - 1)].push_back(
                addVertex(mesh, {rr * std::sin(theta) * std::cos(phi), rr * std::sin(theta) * std::sin(phi), rr * std::cos(theta)}));
        }
    }
    const std::uint32_t south = addVertex(mesh, {0, 0, -r()});
    const auto at = [&](int i, int j) { return ring[static_cast<std::size_t>(i)][static_cast<std::size_t>(j % segments)]; };
    for (int j = 0; j < segments; ++j) {
        mesh.triangles.push_back({north, at(0, j), at(0, j + 1)});
        for (int i = 0; i + 1 < rings - 1; ++i) {
            mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
        mesh.triangles.push_back({at(rings - 2, j), south, at(rings - 2, j + 1)});
    }
    return mesh;
}

//! An icosphere of radius r (vertices on the sphere, outward normals): 20 x 4^subdivisions triangles.
Mesh icosphere(int subdivisions, double r)
{
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                               {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    for (auto& p : v)
        p.normalize();
    std::vector<std::array<std::uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                                   {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                                   {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                                   {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int s = 0; s < subdivisions; ++s) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middle;
        const auto mid = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::minmax(a, b);
            const auto it = middle.find(key);
            if (it != middle.end())
                return it->second;
            v.push_back((v[a] + v[b]).normalized());
            return middle[key] = static_cast<std::uint32_t>(v.size() - 1);
        };
        std::vector<std::array<std::uint32_t, 3>> next;
        for (const auto& tri : f) {
            const std::uint32_t a = mid(tri[0], tri[1]), b = mid(tri[1], tri[2]), c = mid(tri[2], tri[0]);
            next.push_back({tri[0], a, c});
            next.push_back({tri[1], b, a});
            next.push_back({tri[2], c, b});
            next.push_back({a, b, c});
        }
        f = next;
    }
    Mesh mesh;
    mesh.name = "icosphere";
    for (const auto& p : v)
        addVertex(mesh, p * r);
    for (const auto& tri : f)
        mesh.triangles.push_back(tri);
    return mesh;
}

//! A flat grid of nx x ny squares of edge `step` at height z (local frame),
//! counter-clockwise seen from +z (normal +z).
Mesh planeGrid(int nx, int ny, double step, double z)
{
    Mesh mesh;
    mesh.name = "plane";
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i)
            addVertex(mesh, {i * step, j * step, z});
    const auto at = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    return mesh;
}

//! Points in the cube [-extent, extent]^3, plus points near the unit-ish sphere
//! and a few far away (they exercise the descent).
PointCloud testCloud(std::size_t n, double extent, std::mt19937& rng)
{
    PointCloud cloud;
    cloud.name = "compared";
    std::uniform_real_distribution<double> u(-extent, extent);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> near(0.9, 1.1);
    for (std::size_t i = 0; i < n; ++i) {
        Vector3d p(u(rng), u(rng), u(rng));
        if (i % 3 == 0)
            p = Vector3d(g(rng), g(rng), g(rng)).normalized() * near(rng);
        if (i % 97 == 0)
            p = Vector3d(g(rng), g(rng), g(rng)).normalized() * 25.0;
        cloud.positions().push_back(p.cast<float>());
    }
    return cloud;
}

//! The specification: the minimum over all triangles of pointTriangleDistance,
//! in the mesh frame; signed ties by the largest alignment, then the smallest
//! index. Distances in double (NaN for non-finite points), before maxDistance.
std::vector<double> bruteForceDistances(const PointCloud& cloud, const Mesh& mesh, bool signedDistances)
{
    const Vector3d offset = cloud.origin() - mesh.vertices.origin();
    const auto& v = mesh.vertices.positions();
    std::vector<double> out(cloud.size(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.positions()[i].allFinite())
            continue;
        const Vector3d q = offset + cloud.positions()[i].cast<double>();
        double best2 = std::numeric_limits<double>::infinity(), bestAlign = -2.0, bestSide = 1.0;
        for (const auto& t : mesh.triangles) {
            const Vector3d a = v[t[0]].cast<double>(), b = v[t[1]].cast<double>(), c = v[t[2]].cast<double>();
            const auto r = geometry::pointTriangleDistance(q, a, b, c);
            double align = -1.0, side = 1.0;
            if (signedDistances && !r.degenerate) {
                const Vector3d n = (b - a).cross(c - a);
                const double dot = (q - r.closestPoint).dot(n / n.norm());
                align = std::abs(dot);
                side = dot >= 0.0 ? 1.0 : -1.0;
            }
            if (r.squaredDistance < best2 || (r.squaredDistance == best2 && align > bestAlign)) {
                best2 = r.squaredDistance;
                bestAlign = align;
                bestSide = side;
            }
        }
        out[i] = bestSide * std::sqrt(best2);
    }
    return out;
}

//! The expected field values: maxDistance applied, rounded to float.
std::vector<float> expectedValues(const std::vector<double>& distances, const CloudToMeshParams& params)
{
    std::vector<float> out(distances.size(), kNaNf);
    for (std::size_t i = 0; i < distances.size(); ++i) {
        const double d = distances[i];
        if (std::isnan(d))
            continue;
        if (params.maxDistance && std::abs(d) > *params.maxDistance)
            out[i] = params.clampBeyondMax ? static_cast<float>(*params.maxDistance) : kNaNf;
        else
            out[i] = static_cast<float>(d);
    }
    return out;
}

std::vector<float> bruteForce(const PointCloud& cloud, const Mesh& mesh, const CloudToMeshParams& params)
{
    return expectedValues(bruteForceDistances(cloud, mesh, params.signedDistances), params);
}

//! Exact equality, NaN matching NaN; reports the first few differences.
void expectSameValues(const std::vector<float>& actual, const std::vector<float>& expected, const std::string& what)
{
    ASSERT_EQ(actual.size(), expected.size());
    int failures = 0;
    for (std::size_t i = 0; i < actual.size() && failures < 5; ++i) {
        const bool same = (std::isnan(actual[i]) && std::isnan(expected[i])) || actual[i] == expected[i];
        if (!same) {
            ++failures;
            ADD_FAILURE() << what << ": point " << i << " got " << actual[i] << ", brute force " << expected[i];
        }
    }
}

class CancellingObserver : public ProgressObserver
{
public:
    void beginStage(const std::string& title) override { stage = title; }
    void report(double fraction) override
    {
        ++reports;
        if (stage.find("distances") != std::string::npos && fraction > 0.1)
            cancel = true;
    }
    bool cancelRequested() const override { return cancel.load(); }

    std::string stage;
    std::atomic<int> reports{0};
    std::atomic<bool> cancel{false};
};

} // namespace

class CloudToMeshSphere : public ::testing::Test
{
protected:
    void SetUp() override
    {
        std::mt19937 rng(2006);
        mesh = noisySphere(24, 42, 1.0, 0.03, rng);
        cloud = testCloud(3000, 1.6, rng);
    }
    Mesh mesh;
    PointCloud cloud;
};

TEST_F(CloudToMeshSphere, MeshHasAboutTwoThousandTriangles)
{
    EXPECT_EQ(mesh.triangles.size(), 1932u);
    EXPECT_NO_THROW(mesh.checkConsistency());
}

TEST_F(CloudToMeshSphere, UnsignedEqualsBruteForceAtEveryLevel)
{
    const CloudToMeshParams base;
    const auto expected = bruteForce(cloud, mesh, base);
    for (int level : {1, 2, 3, 4, 5, 6, 7, 8, 10, 0}) {
        CloudToMeshParams params;
        params.octreeLevel = level;
        const auto result = cloudToMesh(cloud, mesh, params);
        EXPECT_EQ(result.distance.name(), "c2m_distance");
        if (level != 0) {
            EXPECT_EQ(result.level, level);
        }
        expectSameValues(result.distance.values(), expected, "level " + std::to_string(level));
        EXPECT_EQ(result.statistics.count, cloud.size());
        EXPECT_GE(result.statistics.min, 0.0);
        EXPECT_EQ(result.degenerateTriangles, 0u);
    }
}

TEST_F(CloudToMeshSphere, AutomaticLevelFollowsTheTriangleSize)
{
    const auto result = cloudToMesh(cloud, mesh, CloudToMeshParams{});
    // Mean edge ~0.12 in a 50 m cube (the far points): cell ~0.24 -> level ~8.
    EXPECT_GE(result.level, 7);
    EXPECT_LE(result.level, 9);
}

TEST_F(CloudToMeshSphere, TooDeepALevelIsLoweredAndStaysExact)
{
    CloudToMeshParams params;
    params.octreeLevel = 21;
    const auto result = cloudToMesh(cloud, mesh, params);
    EXPECT_LT(result.level, 21);
    expectSameValues(result.distance.values(), bruteForce(cloud, mesh, params), "level 21");
}

TEST_F(CloudToMeshSphere, SignedEqualsBruteForce)
{
    CloudToMeshParams params;
    params.signedDistances = true;
    const auto expected = bruteForce(cloud, mesh, params);
    std::size_t negative = 0;
    for (float v : expected)
        negative += v < 0;
    EXPECT_GT(negative, 300u); // points inside the sphere
    for (int level : {1, 3, 5, 8, 0}) {
        params.octreeLevel = level;
        const auto result = cloudToMesh(cloud, mesh, params);
        expectSameValues(result.distance.values(), expected, "signed, level " + std::to_string(level));
        EXPECT_LT(result.statistics.min, 0.0);
    }
}

TEST_F(CloudToMeshSphere, MaxDistanceGivesNaNOrClampsBeyond)
{
    for (bool signedDistances : {false, true}) {
        const auto exact = bruteForceDistances(cloud, mesh, signedDistances);
        for (bool clamp : {false, true})
            for (int level : {2, 6, 0}) {
                CloudToMeshParams params;
                params.signedDistances = signedDistances;
                params.maxDistance = 0.2;
                params.clampBeyondMax = clamp;
                params.octreeLevel = level;
                const auto expected = expectedValues(exact, params);
                const auto result = cloudToMesh(cloud, mesh, params);
                const std::string what = std::string(signedDistances ? "signed" : "unsigned") + (clamp ? ", clamped" : ", NaN") +
                                         ", level " + std::to_string(level);
                expectSameValues(result.distance.values(), expected, what);
                std::size_t beyond = 0;
                for (float v : result.distance.values())
                    beyond += clamp ? v == 0.2f : std::isnan(v);
                EXPECT_GT(beyond, 500u) << what;
                EXPECT_EQ(result.statistics.count, clamp ? cloud.size() : cloud.size() - beyond) << what;
                EXPECT_LE(result.statistics.max, 0.2 + 1e-7) << what;
            }
    }
}

TEST(CloudToMesh, PlaneAtOffsetHGivesExactlyH)
{
    const Mesh mesh = planeGrid(20, 20, 0.5, 0.0);
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(0.0, 10.0);
    PointCloud cloud;
    cloud.name = "offset points";
    const double h = 0.375;
    for (int i = 0; i < 2000; ++i)
        cloud.positions().push_back(Vector3f(static_cast<float>(u(rng)), static_cast<float>(u(rng)),
                                             static_cast<float>(i % 2 == 0 ? h : -h)));
    for (bool signedDistances : {false, true}) {
        CloudToMeshParams params;
        params.signedDistances = signedDistances;
        const auto result = cloudToMesh(cloud, mesh, params);
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            const double expected = signedDistances && i % 2 == 1 ? -h : h;
            ASSERT_EQ(result.distance.value(i), expected) << i;
        }
        EXPECT_EQ(result.statistics.count, 2000u);
        EXPECT_DOUBLE_EQ(result.statistics.rms, h);
        EXPECT_NEAR(result.statistics.mean, signedDistances ? 0.0 : h, 1e-12);
    }
}

TEST(CloudToMesh, IcosphereMatchesTheSphereWithinItsSagitta)
{
    const double r = 2.0;
    const Mesh mesh = icosphere(3, r);
    ASSERT_EQ(mesh.triangles.size(), 1280u);
    // Deepest gap between the sphere and the polyhedron: r minus the smallest
    // distance from the centre to a face plane (also checks the orientation).
    double sagitta = 0;
    const auto& v = mesh.vertices.positions();
    for (const auto& t : mesh.triangles) {
        const Vector3d a = v[t[0]].cast<double>(), b = v[t[1]].cast<double>(), c = v[t[2]].cast<double>();
        const Vector3d n = (b - a).cross(c - a).normalized();
        ASSERT_GT(n.dot(a), 0.0) << "icosphere triangles must face outwards";
        sagitta = std::max(sagitta, r - n.dot(a));
    }
    ASSERT_GT(sagitta, 0.0);
    ASSERT_LT(sagitta, 0.05);
    std::mt19937 rng(5);
    std::normal_distribution<double> g(0.0, 1.0);
    PointCloud cloud;
    cloud.name = "shells";
    const double radii[2] = {3.0, 1.0};
    for (int i = 0; i < 2000; ++i)
        cloud.positions().push_back((Vector3d(g(rng), g(rng), g(rng)).normalized() * radii[i % 2]).cast<float>());
    CloudToMeshParams params;
    params.signedDistances = true;
    const auto result = cloudToMesh(cloud, mesh, params);
    expectSameValues(result.distance.values(), bruteForce(cloud, mesh, params), "icosphere");
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const double d = result.distance.value(i);
        const double tolerance = 1e-5; // float positions
        if (i % 2 == 0) { // outside, R = 3: d in [R - r, R - r + sagitta], positive
            EXPECT_GE(d, 1.0 - tolerance);
            EXPECT_LE(d, 1.0 + sagitta + tolerance);
        } else { // inside, R = 1: -d in [r - sagitta - R, r - R], negative
            EXPECT_LE(d, -(1.0 - sagitta) + tolerance);
            EXPECT_GE(d, -1.0 - tolerance);
        }
    }
}

TEST(CloudToMesh, SignAtSharpEdgesOfAClosedMeshIsOutward)
{
    // A regular tetrahedron: normals of adjacent faces are 109.5 degrees apart,
    // so a point near an edge can be behind one of the two planes; the tie rule
    // must take the sign from the face that faces it.
    Mesh mesh;
    mesh.name = "tetrahedron";
    const Vector3d p[4] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
    for (const auto& x : p)
        addVertex(mesh, x);
    mesh.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
    for (const auto& t : mesh.triangles) {
        const Vector3d n = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
        ASSERT_GT(n.dot(p[t[0]]), 0.0);
    }
    std::mt19937 rng(9);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> s(0.0, 1.0);
    PointCloud cloud;
    cloud.name = "around";
    // Outside: edge midpoints and vertices pushed outwards in random directions.
    for (int i = 0; i < 3000; ++i) {
        const int a = i % 4, b = (i / 4) % 4;
        const Vector3d base = a == b ? p[a] : (p[a] + p[b]) / 2;
        Vector3d dir(g(rng), g(rng), g(rng));
        if (dir.dot(base) < 0)
            dir = -dir;
        cloud.positions().push_back((base + dir.normalized() * (0.05 + s(rng))).cast<float>());
    }
    CloudToMeshParams params;
    params.signedDistances = true;
    const auto result = cloudToMesh(cloud, mesh, params);
    expectSameValues(result.distance.values(), bruteForce(cloud, mesh, params), "tetrahedron");
    // Only points truly outside the solid (in front of some face plane) count.
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Vector3d q = cloud.positions()[i].cast<double>();
        bool outside = false;
        for (const auto& t : mesh.triangles) {
            const Vector3d n = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).normalized();
            outside = outside || n.dot(q - p[t[0]]) > 1e-6;
        }
        if (outside) {
            EXPECT_GT(result.distance.value(i), 0.0) << i;
        }
    }
}

TEST(CloudToMesh, GeoreferencedInputsWithDifferentOrigins)
{
    const Vector3d meshOrigin(512000, 5423000, 0);
    Mesh mesh = planeGrid(40, 40, 2.5, 100.0); // 100 m x 100 m at z = 100 m
    mesh.vertices.setOrigin(meshOrigin);
    const double h = 0.125;
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(1.0, 99.0);
    std::vector<Vector3d> globals;
    for (int i = 0; i < 400; ++i)
        globals.push_back(meshOrigin + Vector3d(u(rng), u(rng), 100.0 + (i % 2 == 0 ? h : -h)));
    for (const Vector3d& cloudOrigin : {meshOrigin, Vector3d(511950, 5422980, 95), Vector3d(512100, 5423050, 110)}) {
        PointCloud cloud;
        cloud.name = "survey";
        cloud.setOrigin(cloudOrigin);
        for (const auto& x : globals)
            cloud.positions().push_back((x - cloudOrigin).cast<float>());
        CloudToMeshParams params;
        params.signedDistances = true;
        const auto result = cloudToMesh(cloud, mesh, params);
        expectSameValues(result.distance.values(), bruteForce(cloud, mesh, params), "georeferenced");
        for (std::size_t i = 0; i < cloud.size(); ++i)
            EXPECT_NEAR(result.distance.value(i), i % 2 == 0 ? h : -h, 1e-5) << i;
    }
}

TEST(CloudToMesh, RejectsEmptyInputsAndBadParameters)
{
    const Mesh mesh = planeGrid(2, 2, 1.0, 0.0);
    PointCloud cloud;
    cloud.name = "scan";
    cloud.positions().push_back({0.5f, 0.5f, 1.0f});
    const auto code = [](auto&& f) {
        try {
            f();
        } catch (const Error& e) {
            return e.code();
        }
        return ErrorCode::Internal;
    };
    PointCloud empty;
    empty.name = "nothing";
    EXPECT_EQ(code([&] { cloudToMesh(empty, mesh, {}); }), ErrorCode::InvalidData);
    try {
        cloudToMesh(empty, mesh, {});
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("nothing"), std::string::npos) << e.what();
    }
    Mesh noTriangles = mesh.clone();
    noTriangles.triangles.clear();
    EXPECT_EQ(code([&] { cloudToMesh(cloud, noTriangles, {}); }), ErrorCode::InvalidData);
    Mesh missingVertex = mesh.clone();
    missingVertex.triangles.push_back({0, 1, 999});
    EXPECT_EQ(code([&] { cloudToMesh(cloud, missingVertex, {}); }), ErrorCode::InvalidData);
    Mesh nanVertex = mesh.clone();
    nanVertex.vertices.positions()[0].x() = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(code([&] { cloudToMesh(cloud, nanVertex, {}); }), ErrorCode::InvalidData);

    CloudToMeshParams params;
    params.octreeLevel = 22;
    EXPECT_EQ(code([&] { cloudToMesh(cloud, mesh, params); }), ErrorCode::InvalidArgument);
    params.octreeLevel = -1;
    EXPECT_EQ(code([&] { cloudToMesh(cloud, mesh, params); }), ErrorCode::InvalidArgument);
    params = {};
    params.maxDistance = 0.0;
    EXPECT_EQ(code([&] { cloudToMesh(cloud, mesh, params); }), ErrorCode::InvalidArgument);
    params.maxDistance = std::numeric_limits<double>::quiet_NaN();
    EXPECT_EQ(code([&] { cloudToMesh(cloud, mesh, params); }), ErrorCode::InvalidArgument);
    params = {};
    params.clampBeyondMax = true;
    EXPECT_EQ(code([&] { cloudToMesh(cloud, mesh, params); }), ErrorCode::InvalidArgument);
}

TEST(CloudToMesh, NonFinitePointsGetNaN)
{
    std::mt19937 rng(17);
    const Mesh mesh = noisySphere(8, 12, 1.0, 0.0, rng);
    PointCloud cloud = testCloud(200, 1.5, rng);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    cloud.positions()[3] = {nan, 0.0f, 0.0f};
    cloud.positions()[50] = {0.0f, std::numeric_limits<float>::infinity(), 0.0f};
    const auto result = cloudToMesh(cloud, mesh, {});
    EXPECT_TRUE(std::isnan(result.distance.values()[3]));
    EXPECT_TRUE(std::isnan(result.distance.values()[50]));
    expectSameValues(result.distance.values(), bruteForce(cloud, mesh, {}), "NaN points");
    EXPECT_EQ(result.statistics.count, 198u);
    EXPECT_TRUE(std::isfinite(result.statistics.mean));
}

TEST(CloudToMesh, DegenerateTrianglesAreUsedAsSegmentsAndPointsAndCounted)
{
    Mesh mesh;
    mesh.name = "degenerate";
    for (const Vector3d& x : {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(2, 0, 0),
                              Vector3d(5, 5, 5), Vector3d(3, 1, 0), Vector3d(4, 2, 0)})
        addVertex(mesh, x);
    mesh.triangles = {{0, 1, 2}, {1, 3, 1}, {4, 4, 4}, {3, 5, 6}}; // a triangle, a segment, a point, collinear
    ASSERT_EQ(mesh.countDegenerateTriangles(), 3u);
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> u(-1.0, 6.0);
    PointCloud cloud;
    cloud.name = "probe";
    for (int i = 0; i < 1000; ++i)
        cloud.positions().push_back(Vector3f(static_cast<float>(u(rng)), static_cast<float>(u(rng)), static_cast<float>(u(rng))));
    cloud.positions().push_back({5.0f, 5.0f, 6.0f}); // 1 above the point triangle
    cloud.positions().push_back({1.5f, 0.0f, 2.0f}); // 2 above the segment
    for (bool signedDistances : {false, true})
        for (int level : {1, 4, 0}) {
            CloudToMeshParams params;
            params.signedDistances = signedDistances;
            params.octreeLevel = level;
            const auto result = cloudToMesh(cloud, mesh, params);
            EXPECT_EQ(result.degenerateTriangles, 3u);
            expectSameValues(result.distance.values(), bruteForce(cloud, mesh, params), "degenerate");
            EXPECT_EQ(result.distance.value(1000), 1.0);
            EXPECT_EQ(result.distance.value(1001), 2.0);
        }
}

TEST(CloudToMesh, CancellationThrowsAndLeavesInputsUntouched)
{
    std::mt19937 rng(31);
    const Mesh mesh = noisySphere(24, 42, 1.0, 0.03, rng);
    PointCloud cloud = testCloud(20000, 1.6, rng);
    cloud.addField("intensity");
    const PointCloud before = cloud.clone();
    CancellingObserver observer;
    try {
        cloudToMesh(cloud, mesh, {}, &observer);
        FAIL() << "expected Error(Cancelled)";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::Cancelled);
    }
    EXPECT_GT(observer.reports.load(), 0);
    ASSERT_EQ(cloud.size(), before.size());
    EXPECT_EQ(cloud.positions(), before.positions());
    ASSERT_EQ(cloud.fields().size(), 1u);
    EXPECT_EQ(cloud.fields()[0].name(), "intensity");
    EXPECT_EQ(cloud.field("c2m_distance"), nullptr);
}

TEST(DistanceStatistics, OverTheValidValues)
{
    ScalarField field("d", 6);
    field.setOffset(10.0);
    const double values[6] = {11, 12, 13, std::nan(""), 14, std::nan("")};
    for (std::size_t i = 0; i < 6; ++i)
        if (!std::isnan(values[i]))
            field.setValue(i, values[i]);
    const DistanceStatistics s = computeStatistics(field);
    EXPECT_EQ(s.count, 4u);
    EXPECT_DOUBLE_EQ(s.mean, 12.5);
    EXPECT_DOUBLE_EQ(s.standardDeviation, std::sqrt(1.25));
    EXPECT_DOUBLE_EQ(s.min, 11.0);
    EXPECT_DOUBLE_EQ(s.max, 14.0);
    EXPECT_DOUBLE_EQ(s.rms, std::sqrt((121.0 + 144.0 + 169.0 + 196.0) / 4.0));
}

TEST(DistanceStatistics, NoValidValueGivesZeroCountAndNaN)
{
    const DistanceStatistics s = computeStatistics(ScalarField("d", 3));
    EXPECT_EQ(s.count, 0u);
    EXPECT_TRUE(std::isnan(s.mean));
    EXPECT_TRUE(std::isnan(s.standardDeviation));
    EXPECT_TRUE(std::isnan(s.min));
    EXPECT_TRUE(std::isnan(s.max));
    EXPECT_TRUE(std::isnan(s.rms));
    EXPECT_EQ(computeStatistics(ScalarField()).count, 0u);
}

TEST(CloudToMesh, ClosestTrianglesGiveTheDistance)
{
    // A mesh of two triangles and points around it: each point's closest
    // triangle, as reported, is at exactly the distance reported.
    Mesh mesh;
    mesh.vertices.resize(4);
    mesh.vertices.positions() = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 1}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    PointCloud points;
    points.resize(400);
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(-1.0f, 3.0f);
    for (auto& p : points.positions())
        p = {u(rng), u(rng), u(rng)};
    CloudToMeshParams params;
    params.closestTriangles = true;
    params.maxDistance = 1.5;
    const CloudToMeshResult result = cloudToMesh(points, mesh, params);
    ASSERT_EQ(result.closestTriangle.size(), points.size());
    std::size_t beyond = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (!result.distance.hasValue(i)) {
            EXPECT_EQ(result.closestTriangle[i], kNoClosestTriangle);
            ++beyond;
            continue;
        }
        const auto& t = mesh.triangles[result.closestTriangle[i]];
        const auto r = geometry::pointTriangleDistance(points.positions()[i].cast<double>(), mesh.vertices.positions()[t[0]].cast<double>(),
                                                       mesh.vertices.positions()[t[1]].cast<double>(),
                                                       mesh.vertices.positions()[t[2]].cast<double>());
        EXPECT_NEAR(std::sqrt(r.squaredDistance), result.distance.value(i), 1e-6) << i;
    }
    EXPECT_GT(beyond, 0u);
    EXPECT_TRUE(cloudToMesh(points, mesh, CloudToMeshParams{}).closestTriangle.empty());
}
