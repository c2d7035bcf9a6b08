// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToCloud.h>
#include <scandiff/core/distance/Visibility.h>
#include <scandiff/core/geometry/PointTriangleDistance.h>

#include "TestSupport.h"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

using namespace scandiff;

namespace {

PointCloud randomCloud(std::size_t n, std::mt19937& rng, float extent = 10.0f, const Eigen::Vector3d& origin = Eigen::Vector3d::Zero())
{
    PointCloud c;
    c.setOrigin(origin);
    c.resize(n);
    std::uniform_real_distribution<float> u(0.0f, extent);
    for (auto& p : c.positions())
        p = {u(rng), u(rng), u(rng)};
    return c;
}

//! Uniform (Poisson) samples of the square [0, side]^2 at height z.
PointCloud planeSamples(std::size_t n, double side, float z, std::mt19937& rng)
{
    PointCloud c;
    c.resize(n);
    std::uniform_real_distribution<float> u(0.0f, static_cast<float>(side));
    for (auto& p : c.positions())
        p = {u(rng), u(rng), z};
    return c;
}

PointCloud sphereSamples(std::size_t n, double radius, std::mt19937& rng)
{
    PointCloud c;
    c.resize(n);
    std::normal_distribution<double> g(0.0, 1.0);
    for (auto& p : c.positions()) {
        Eigen::Vector3d d(g(rng), g(rng), g(rng));
        p = (d.normalized() * radius).cast<float>();
    }
    return c;
}

double rms(const ScalarField& f)
{
    double sum = 0;
    std::size_t count = 0;
    for (float v : f.values())
        if (!std::isnan(v)) {
            sum += static_cast<double>(v) * v;
            ++count;
        }
    return std::sqrt(sum / static_cast<double>(count));
}

} // namespace

TEST(CloudToCloud, NearestNeighbourEqualsBruteForceAcrossOrigins)
{
    std::mt19937 rng(1);
    const PointCloud reference = randomCloud(3000, rng, 10.0f, {512000, 5423000, 100});
    PointCloud compared = randomCloud(500, rng, 12.0f, {511999, 5422999, 101});
    compared.positions()[7] = {std::nanf(""), 0, 0};
    CloudToCloudParams params;
    params.splitComponents = true;
    params.closestPoints = true;
    for (int level : {0, 2, 5, 9, 14}) {
        params.octreeLevel = level;
        const CloudToCloudResult r = cloudToCloud(compared, reference, params);
        ASSERT_EQ(r.distance.size(), compared.size());
        EXPECT_TRUE(std::isnan(r.distance.values()[7]));
        for (std::size_t i = 0; i < compared.size(); ++i) {
            if (i == 7)
                continue;
            const Eigen::Vector3d q = compared.globalPosition(i);
            double best = std::numeric_limits<double>::infinity();
            Eigen::Vector3d bestPoint;
            for (std::size_t j = 0; j < reference.size(); ++j) {
                const double d = (reference.globalPosition(j) - q).norm();
                if (d < best) {
                    best = d;
                    bestPoint = reference.globalPosition(j);
                }
            }
            ASSERT_NEAR(r.distance.values()[i], best, 2e-5) << "level " << level << " point " << i;
            EXPECT_NEAR(r.dx->values()[i], q.x() - bestPoint.x(), 2e-5);
            EXPECT_NEAR(r.dz->values()[i], q.z() - bestPoint.z(), 2e-5);
        }
        ASSERT_TRUE(r.closest);
        EXPECT_EQ(r.closest->size(), compared.size() - 1);
        EXPECT_EQ(r.statistics.count, compared.size() - 1);
    }
}

TEST(CloudToCloud, PlaneOffsetByHWithEveryModel)
{
    std::mt19937 rng(2);
    const PointCloud reference = planeSamples(20000, 1.0, 0.0f, rng);
    PointCloud compared = planeSamples(2000, 1.0, 0.0f, rng);
    const float h = 0.05f;
    for (auto& p : compared.positions())
        p.z() = h;
    CloudToCloudParams params;
    const CloudToCloudResult plain = cloudToCloud(compared, reference, params);
    for (float v : plain.distance.values())
        EXPECT_GE(v, h - 1e-6f); // the NN distance can only be larger
    for (LocalModel model : {LocalModel::Plane, LocalModel::Delaunay, LocalModel::Quadric}) {
        params.model = model;
        const CloudToCloudResult r = cloudToCloud(compared, reference, params);
        for (std::size_t i = 0; i < compared.size(); ++i) {
            if (model == LocalModel::Delaunay) {
                // The triangles cover the neighbours of the nearest point; a query
                // projecting just outside them meets an edge: between h and the NN distance.
                ASSERT_GE(r.distance.values()[i], h - 1e-6f) << "point " << i;
                ASSERT_LE(r.distance.values()[i], plain.distance.values()[i] + 1e-6f) << "point " << i;
            } else {
                ASSERT_NEAR(r.distance.values()[i], h, 1e-5) << localModelName(model) << " point " << i;
            }
        }
        EXPECT_NEAR(r.statistics.mean, h, 1e-4) << localModelName(model);
        EXPECT_EQ(r.modelFallbacks, 0u);
    }
}

TEST(CloudToCloud, SphereOfRadiusRWithAQuadric)
{
    std::mt19937 rng(3);
    const double r = 2.0, h = 0.1;
    const PointCloud reference = sphereSamples(60000, r, rng);
    PointCloud compared = sphereSamples(1000, r + h, rng);
    CloudToCloudParams params;
    params.model = LocalModel::Quadric;
    params.neighbours = 20;
    const CloudToCloudResult quadric = cloudToCloud(compared, reference, params);
    params.model = LocalModel::None;
    const CloudToCloudResult plain = cloudToCloud(compared, reference, params);
    // The quadric follows the curvature: distances within 2 mm of h; plain NN is
    // biased upwards by the sampling.
    for (float v : quadric.distance.values())
        ASSERT_NEAR(v, h, 2e-3);
    EXPECT_GT(plain.statistics.mean, quadric.statistics.mean);
}

TEST(CloudToCloud, SamplingBiasOfTwoSamplingsOfOnePlane)
{
    // Thesis 000 §2.3.1, Fig. 2.5: a 100 mm square, N reference points, K = 10,000
    // queries on the same plane. The NN distance has RMS 1/sqrt(pi * lambda)
    // (eq. 2.5; lambda = N / area) and mean 1/(2 sqrt(lambda)) (the digest's
    // corrected Rayleigh mean); a local plane removes the bias.
    std::mt19937 rng(4);
    const double side = 0.1;
    for (std::size_t N : {20000u, 200000u}) {
        const PointCloud reference = planeSamples(N, side, 0.0f, rng);
        const PointCloud compared = planeSamples(10000, side, 0.0f, rng);
        const double lambda = static_cast<double>(N) / (side * side);
        CloudToCloudParams params;
        const CloudToCloudResult plain = cloudToCloud(compared, reference, params);
        EXPECT_NEAR(rms(plain.distance), 1.0 / std::sqrt(M_PI * lambda), 0.03 / std::sqrt(M_PI * lambda)) << "N " << N;
        EXPECT_NEAR(plain.statistics.mean, 0.5 / std::sqrt(lambda), 0.03 * 0.5 / std::sqrt(lambda)) << "N " << N;
        params.model = LocalModel::Plane;
        const CloudToCloudResult modelled = cloudToCloud(compared, reference, params);
        EXPECT_LT(rms(modelled.distance), 1e-7) << "N " << N;
    }
}

TEST(CloudToCloud, MaximumDistanceGivesNaNOrTheMaximum)
{
    std::mt19937 rng(5);
    const PointCloud reference = planeSamples(5000, 1.0, 0.0f, rng);
    PointCloud compared = planeSamples(100, 1.0, 0.0f, rng);
    for (std::size_t i = 0; i < compared.size(); ++i)
        compared.positions()[i].z() = i % 2 ? 0.5f : 0.01f;
    CloudToCloudParams params;
    params.model = LocalModel::Plane;
    params.maxDistance = 0.1;
    CloudToCloudResult r = cloudToCloud(compared, reference, params);
    for (std::size_t i = 0; i < compared.size(); ++i) {
        if (i % 2)
            EXPECT_TRUE(std::isnan(r.distance.values()[i]));
        else
            EXPECT_NEAR(r.distance.values()[i], 0.01, 1e-5);
    }
    params.clampBeyondMax = true;
    r = cloudToCloud(compared, reference, params);
    for (std::size_t i = 1; i < compared.size(); i += 2)
        EXPECT_FLOAT_EQ(r.distance.values()[i], 0.1f);
}

TEST(CloudToCloud, SignedByReferenceNormalsOrModel)
{
    std::mt19937 rng(6);
    PointCloud reference = planeSamples(5000, 1.0, 0.0f, rng);
    for (auto& n : reference.enableNormals())
        n = {0, 0, 1};
    PointCloud compared = planeSamples(200, 1.0, 0.0f, rng);
    for (std::size_t i = 0; i < compared.size(); ++i)
        compared.positions()[i].z() = i % 2 ? 0.02f : -0.03f;
    CloudToCloudParams params;
    params.signedDistances = true;
    for (LocalModel model : {LocalModel::None, LocalModel::Plane, LocalModel::Delaunay, LocalModel::Quadric}) {
        params.model = model;
        const CloudToCloudResult r = cloudToCloud(compared, reference, params);
        for (std::size_t i = 0; i < compared.size(); ++i) {
            if (i % 2)
                EXPECT_GT(r.distance.values()[i], 0.0f) << localModelName(model);
            else
                EXPECT_LT(r.distance.values()[i], 0.0f) << localModelName(model);
        }
    }
    reference.removeNormals();
    params.model = LocalModel::None;
    EXPECT_EQ(test::errorCodeOf([&] { cloudToCloud(compared, reference, params); }), ErrorCode::InvalidArgument);
}

namespace {

//! The wall of thesis 000 Fig. 2.8: x = 10 m, y and z in [-2, 2] on a 5 cm grid.
PointCloud wallOfFigure28()
{
    PointCloud wall;
    for (int i = -40; i <= 40; ++i)
        for (int j = -40; j <= 40; ++j) {
            wall.resize(wall.size() + 1);
            wall.positions().back() = {10.0f, i * 0.05f, j * 0.05f};
        }
    return wall;
}

} // namespace

TEST(CloudToCloud, VisibilityOnTheWallScenario)
{
    // Thesis 000 Fig. 2.8: a scanner at the origin looks at a wall 10 m away
    // (x = 10, y and z in [-2, 2]); the reference never saw what is behind it.
    PointCloud reference = wallOfFigure28();
    SensorPose scanner;
    scanner.maxRange = 30.0;
    PointCloud compared;
    compared.resize(5);
    compared.positions() = {
        {10.0f, 0.3f, 0.2f},   // on the wall: visible
        {12.0f, 0.5f, -0.4f},  // behind the wall: hidden
        {10.0f, 6.0f, 0.0f},   // beside the wall, outside the scanned angles: out of field
        {40.0f, 0.1f, 0.1f},   // behind, and beyond the scanner's range: out of range
        {9.0f, -1.0f, 1.0f},   // in front of the wall: visible (something appeared)
    };
    CloudToCloudParams params;
    params.viewpoints = {scanner};
    const CloudToCloudResult r = cloudToCloud(compared, reference, params);
    ASSERT_TRUE(r.visibility);
    const std::vector<float> expected = {0, 1, 3, 2, 0};
    for (std::size_t i = 0; i < 5; ++i)
        EXPECT_EQ(r.visibility->values()[i], expected[i]) << "point " << i;
    EXPECT_FALSE(std::isnan(r.distance.values()[0]));
    EXPECT_TRUE(std::isnan(r.distance.values()[1]));
    EXPECT_TRUE(std::isnan(r.distance.values()[2]));
    EXPECT_TRUE(std::isnan(r.distance.values()[3]));
    EXPECT_NEAR(r.distance.values()[4], 1.0, 1e-5);

    // A second scanner, beyond the wall and looking back at it, scanned a surface
    // at x = 11.5: the point at x = 12 lies in front of that surface, so the
    // second viewpoint sees it, and "visible in any map" wins.
    PointCloud behind;
    behind.resize(1);
    behind.positions()[0] = {12.0f, 0.5f, -0.4f};
    SensorPose second;
    second.position = {20, 0, 0};
    second.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()));
    PointCloud both = reference.clone();
    ScalarField& scan = both.addField("scan_index");
    std::fill(scan.values().begin(), scan.values().end(), 0.0f);
    const std::size_t base = both.size();
    for (int i = -40; i <= 40; ++i)
        for (int j = -40; j <= 40; ++j) {
            both.resize(both.size() + 1);
            both.positions().back() = {11.5f, i * 0.05f, j * 0.05f};
            both.field("scan_index")->values().back() = 1.0f;
        }
    ASSERT_GT(both.size(), base);
    params.viewpoints = {scanner, second};
    const CloudToCloudResult twoViews = cloudToCloud(behind, both, params);
    EXPECT_EQ(twoViews.visibility->values()[0], 0.0f);
}

TEST(DepthMap, FreeSpaceIsWhereTheScannerLookedThrough)
{
    // The wall of thesis 000 Fig. 2.8 (x = 10 m, 5 cm grid): the scanner at
    // the origin looked through everything nearer than the wall, within the
    // wall's angles, less the tolerance along the ray (at normal incidence,
    // the tolerance itself).
    const PointCloud wall = wallOfFigure28();
    SensorPose scanner;
    scanner.maxRange = 30.0;
    VisibilityParams params;
    params.tolerance = 0.05;
    const DepthMap map(wall, scanner, params);
    EXPECT_TRUE(map.inFreeSpace({5.0, 0.3, 0.2}));      // halfway along a ray
    EXPECT_TRUE(map.inFreeSpace({9.9, -1.0, 1.0}));     // 10 cm before the wall
    EXPECT_FALSE(map.inFreeSpace({9.97, -1.0, 1.0}));   // within the tolerance
    EXPECT_FALSE(map.inFreeSpace({10.0, 0.3, 0.2}));    // on the wall
    EXPECT_FALSE(map.inFreeSpace({12.0, 0.5, -0.4}));   // behind it: hidden, not seen through
    EXPECT_FALSE(map.inFreeSpace({5.0, 6.0, 0.0}));     // beside it: no ray went there
    EXPECT_FALSE(map.inFreeSpace({-5.0, 0.0, 0.0}));    // behind the scanner: outside the scanned angles
    // A turned and moved scanner: the same wall, the same answers.
    SensorPose moved;
    moved.position = {100, 200, 3};
    moved.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(2.0, Eigen::Vector3d::UnitZ()));
    moved.maxRange = 30.0;
    PointCloud placed = wall.clone();
    for (auto& p : placed.positions())
        p = (moved.orientation * p.cast<double>() + moved.position).cast<float>();
    const DepthMap placedMap(placed, moved, params);
    EXPECT_TRUE(placedMap.inFreeSpace(moved.orientation * Eigen::Vector3d(5.0, 0.3, 0.2) + moved.position));
    EXPECT_FALSE(placedMap.inFreeSpace(moved.orientation * Eigen::Vector3d(12.0, 0.5, -0.4) + moved.position));
}

TEST(CloudToCloud, BadInputs)
{
    std::mt19937 rng(7);
    const PointCloud cloud = randomCloud(10, rng);
    PointCloud empty;
    CloudToCloudParams params;
    EXPECT_EQ(test::errorCodeOf([&] { cloudToCloud(cloud, empty, params); }), ErrorCode::InvalidData);
    PointCloud withNan = cloud.clone();
    withNan.positions()[3] = {std::nanf(""), 0, 0};
    EXPECT_EQ(test::errorCodeOf([&] { cloudToCloud(cloud, withNan, params); }), ErrorCode::InvalidData);
    const CloudToCloudResult none = cloudToCloud(empty, cloud, params);
    EXPECT_EQ(none.distance.size(), 0u);
    EXPECT_EQ(none.statistics.count, 0u);
    params.maxDistance = -1.0;
    EXPECT_EQ(test::errorCodeOf([&] { cloudToCloud(cloud, cloud, params); }), ErrorCode::InvalidArgument);
    params.maxDistance.reset();
    params.neighbours = 2;
    EXPECT_EQ(test::errorCodeOf([&] { cloudToCloud(cloud, cloud, params); }), ErrorCode::InvalidArgument);
}

TEST(CloudToCloud, CancellationLeavesInputsUntouched)
{
    struct CancelAtOnce : ProgressObserver
    {
        void beginStage(const std::string&) override {}
        void report(double) override {}
        bool cancelRequested() const override { return true; }
    } cancel;
    std::mt19937 rng(8);
    const PointCloud reference = randomCloud(1000, rng);
    PointCloud compared = randomCloud(1000, rng);
    const auto before = compared.positions();
    EXPECT_EQ(test::errorCodeOf([&] { cloudToCloud(compared, reference, {}, &cancel); }), ErrorCode::Cancelled);
    EXPECT_EQ(compared.positions(), before);
    EXPECT_TRUE(compared.fields().empty());
}

namespace {

//! A gently curved, randomly sampled surface over [0, 3]^2.
PointCloud wavySamples(std::size_t n, double offset, std::mt19937& rng)
{
    PointCloud c;
    c.resize(n);
    std::uniform_real_distribution<float> u(0.0f, 3.0f);
    std::uniform_real_distribution<double> o(-offset, offset);
    for (auto& p : c.positions()) {
        const float x = u(rng), y = u(rng);
        p = {x, y, static_cast<float>(0.2 * std::sin(2.0 * x) * std::cos(y) + o(rng))};
    }
    return c;
}

//! Brute force of the documented neighbourhoods, closest first (ties by index):
//! with k, the k nearest reference points of q; with a radius, the reference
//! points within it of q's nearest reference point.
std::vector<Eigen::Vector3d> neighbourhood(const PointCloud& reference, const Eigen::Vector3f& q, std::size_t k,
                                           std::optional<float> radius = std::nullopt)
{
    const auto& r = reference.positions();
    Eigen::Vector3f centre = q;
    if (radius) {
        std::size_t nearest = 0;
        for (std::size_t j = 1; j < r.size(); ++j)
            if ((r[j] - q).squaredNorm() < (r[nearest] - q).squaredNorm())
                nearest = j;
        centre = r[nearest];
    }
    std::vector<std::pair<float, std::size_t>> all;
    for (std::size_t j = 0; j < r.size(); ++j)
        all.emplace_back((r[j] - centre).squaredNorm(), j);
    std::sort(all.begin(), all.end());
    std::vector<Eigen::Vector3d> points;
    for (std::size_t m = 0; m < all.size() && (radius ? all[m].first <= *radius * *radius : m < k); ++m)
        points.push_back(r[all[m].second].cast<double>());
    return points;
}

struct Plane
{
    Eigen::Vector3d centroid, normal, u, v;
};

Plane leastSquaresPlane(const std::vector<Eigen::Vector3d>& points)
{
    Plane plane;
    plane.centroid = Eigen::Vector3d::Zero();
    for (const auto& p : points)
        plane.centroid += p;
    plane.centroid /= static_cast<double>(points.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const auto& p : points)
        covariance += (p - plane.centroid) * (p - plane.centroid).transpose();
    // The model's frame: normal towards +Z (no normals, no sensor), u the main axis.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(covariance);
    plane.normal = solver.eigenvectors().col(0).normalized();
    if (plane.normal.z() < 0)
        plane.normal = -plane.normal;
    plane.u = solver.eigenvectors().col(2).normalized();
    plane.v = plane.normal.cross(plane.u);
    return plane;
}

} // namespace

TEST(CloudToCloud, PlaneIsFittedOnTheDocumentedNeighbourhood)
{
    // --knn: the compared point's k nearest reference points; --radius: the
    // reference points within the radius of its nearest reference point. In
    // the second case compared points with the same nearest point share one
    // fit: each must still get the distance to the model of its own nearest point.
    std::mt19937 rng(9);
    const PointCloud reference = wavySamples(3000, 0.0, rng);
    PointCloud compared = wavySamples(400, 0.03, rng);
    // Several compared points on one reference point's doorstep: one shared model.
    for (std::size_t i = 0; i < 20; ++i)
        compared.positions()[i] = reference.positions()[7] + Eigen::Vector3f(0.002f * static_cast<float>(i % 5), 0.001f, 0.01f);
    CloudToCloudParams params;
    params.model = LocalModel::Plane;
    for (int k : {6, 12, 0}) {
        std::optional<float> radius;
        if (k == 0)
            radius = 0.15f;
        params.neighbours = k == 0 ? 12 : k;
        if (radius)
            params.radius = *radius;
        const CloudToCloudResult r = cloudToCloud(compared, reference, params);
        EXPECT_EQ(r.modelFallbacks, 0u);
        for (std::size_t i = 0; i < compared.size(); ++i) {
            const Eigen::Vector3f& q = compared.positions()[i];
            const Plane plane = leastSquaresPlane(neighbourhood(reference, q, static_cast<std::size_t>(k), radius));
            const double expected = std::abs((q.cast<double>() - plane.centroid).dot(plane.normal));
            ASSERT_NEAR(r.distance.values()[i], expected, 1e-6) << "k " << k << " point " << i;
        }
    }
}

TEST(CloudToCloud, DelaunayModelEqualsTheNearestTriangleOfABruteForceTriangulation)
{
    // The Delaunay model's triangles come from the Voronoi cell of the nearest
    // reference point (or of the planar point nearest to the projection) when
    // they decide, else from the whole triangulation; all must give the distance
    // to the nearest triangle of the Delaunay triangulation of the neighbourhood
    // projected on its plane, built here by brute force (every triangle whose
    // circumcircle holds no other site).
    std::mt19937 rng(10);
    const PointCloud reference = wavySamples(3000, 0.0, rng);
    PointCloud compared = wavySamples(300, 0.05, rng);
    // Farther points, which the triangles around the nearest point cannot settle alone.
    for (std::size_t i = 0; i < 30; ++i)
        compared.positions()[i].z() += 0.3f;
    CloudToCloudParams params;
    params.model = LocalModel::Delaunay;
    params.signedDistances = true;
    for (int k : {5, 12, 20}) {
        params.neighbours = k;
        const CloudToCloudResult r = cloudToCloud(compared, reference, params);
        EXPECT_EQ(r.modelFallbacks, 0u);
        for (std::size_t i = 0; i < compared.size(); ++i) {
            const Eigen::Vector3d q = compared.positions()[i].cast<double>();
            const auto points = neighbourhood(reference, compared.positions()[i], static_cast<std::size_t>(k));
            const Plane plane = leastSquaresPlane(points);
            std::vector<Eigen::Vector2d> planar;
            for (const auto& p : points)
                planar.emplace_back((p - plane.centroid).dot(plane.u), (p - plane.centroid).dot(plane.v));
            // The triangulation is built inside a super-triangle whose vertices
            // count as sites (a very flat hull triangle whose circle reaches one
            // of them is not in it): the same three sites here.
            Eigen::Vector2d lo = planar[0], hi = planar[0];
            for (const auto& x : planar) {
                lo = lo.cwiseMin(x);
                hi = hi.cwiseMax(x);
            }
            const double span = (hi - lo).maxCoeff();
            const Eigen::Vector2d mid = 0.5 * (lo + hi);
            std::vector<Eigen::Vector2d> sites = planar;
            sites.emplace_back(mid.x() - 20 * span, mid.y() - span);
            sites.emplace_back(mid.x(), mid.y() + 20 * span);
            sites.emplace_back(mid.x() + 20 * span, mid.y() - span);
            double best = std::numeric_limits<double>::infinity();
            Eigen::Vector3d closest = Eigen::Vector3d::Zero();
            const std::size_t m = points.size();
            for (std::size_t a = 0; a < m; ++a)
                for (std::size_t b = a + 1; b < m; ++b)
                    for (std::size_t c = b + 1; c < m; ++c) {
                        const Eigen::Vector2d pa = planar[a], pb = planar[b], pc = planar[c];
                        const double area = (pb - pa).x() * (pc - pa).y() - (pb - pa).y() * (pc - pa).x();
                        if (std::abs(area) < 1e-12)
                            continue;
                        bool empty = true;
                        for (std::size_t d = 0; d < sites.size() && empty; ++d) {
                            if (d == a || d == b || d == c)
                                continue;
                            const Eigen::Vector2d x = pa - sites[d], y = pb - sites[d], z = pc - sites[d];
                            const double det = x.squaredNorm() * (y.x() * z.y() - z.x() * y.y()) -
                                               y.squaredNorm() * (x.x() * z.y() - z.x() * x.y()) +
                                               z.squaredNorm() * (x.x() * y.y() - y.x() * x.y());
                            empty = area > 0 ? det <= 0 : det >= 0;
                        }
                        if (!empty)
                            continue;
                        const auto t = geometry::pointTriangleDistance(q, points[a], points[b], points[c]);
                        if (t.squaredDistance < best) {
                            best = t.squaredDistance;
                            closest = t.closestPoint;
                        }
                    }
            const double expected = std::sqrt(best) * ((q - closest).dot(plane.normal) < 0 ? -1.0 : 1.0);
            ASSERT_NEAR(r.distance.values()[i], expected, 1e-6) << "k " << k << " point " << i;
        }
    }
}

TEST(CloudToCloud, PlaneAxesOfVolumetricNeighbourhoods)
{
    // Neighbourhoods of a volume have three eigenvalues of one order, where the
    // plane fit's Newton iteration (tuned for surfaces, one eigenvalue far
    // below the others) takes more steps or hands over to Eigen's closed form:
    // the plane must still be the least-squares plane of brute force.
    std::mt19937 rng(11);
    const PointCloud reference = randomCloud(3000, rng, 1.0f);
    const PointCloud compared = randomCloud(300, rng, 1.0f);
    CloudToCloudParams params;
    params.model = LocalModel::Plane;
    params.signedDistances = true;
    const CloudToCloudResult r = cloudToCloud(compared, reference, params);
    EXPECT_EQ(r.modelFallbacks, 0u);
    for (std::size_t i = 0; i < compared.size(); ++i) {
        const Eigen::Vector3f& q = compared.positions()[i];
        const Plane plane = leastSquaresPlane(neighbourhood(reference, q, 12));
        ASSERT_NEAR(r.distance.values()[i], (q.cast<double>() - plane.centroid).dot(plane.normal), 1e-6) << "point " << i;
    }
    // The corners of a cube: three equal eigenvalues (a triple root, which
    // Newton's method approaches too slowly), so Eigen decides, and every
    // axis is as good as another; its choice is brute force's too.
    PointCloud cube;
    cube.resize(8);
    for (int corner = 0; corner < 8; ++corner)
        cube.positions()[static_cast<std::size_t>(corner)] = {float(corner & 1), float((corner >> 1) & 1), float((corner >> 2) & 1)};
    PointCloud inside;
    inside.resize(2);
    inside.positions()[0] = {0.6f, 0.45f, 0.3f};
    inside.positions()[1] = {0.2f, 0.7f, 0.55f};
    params.neighbours = 8;
    const CloudToCloudResult corners = cloudToCloud(inside, cube, params);
    for (std::size_t i = 0; i < inside.size(); ++i) {
        const Eigen::Vector3f& q = inside.positions()[i];
        const Plane plane = leastSquaresPlane(neighbourhood(cube, q, 8));
        EXPECT_NEAR(corners.distance.values()[i], (q.cast<double>() - plane.centroid).dot(plane.normal), 1e-6) << "point " << i;
    }
}

TEST(CloudToCloud, DuplicatedReferencePointsCountOnceInTheModels)
{
    // Every reference point stored twice (a scan merged with itself): the 12
    // nearest are 6 distinct points, each twice. The plane is the same and
    // the triangulation skips the second copies, so both models give what
    // they give with the 6 nearest of the cloud without copies.
    std::mt19937 rng(12);
    const PointCloud single = wavySamples(2000, 0.0, rng);
    PointCloud doubled;
    doubled.resize(2 * single.size());
    for (std::size_t i = 0; i < single.size(); ++i)
        doubled.positions()[2 * i] = doubled.positions()[2 * i + 1] = single.positions()[i];
    PointCloud compared = wavySamples(300, 0.05, rng);
    for (std::size_t i = 0; i < 30; ++i)
        compared.positions()[i].z() += 0.3f; // beyond what one triangle settles
    for (LocalModel model : {LocalModel::Plane, LocalModel::Delaunay}) {
        CloudToCloudParams params;
        params.model = model;
        params.signedDistances = true;
        params.neighbours = 12;
        const CloudToCloudResult withCopies = cloudToCloud(compared, doubled, params);
        params.neighbours = 6;
        const CloudToCloudResult without = cloudToCloud(compared, single, params);
        EXPECT_EQ(withCopies.modelFallbacks, without.modelFallbacks) << localModelName(model);
        for (std::size_t i = 0; i < compared.size(); ++i)
            ASSERT_NEAR(withCopies.distance.values()[i], without.distance.values()[i], 1e-6)
                << localModelName(model) << " point " << i;
    }
}

// The reach of every point (what a tiled run checks its halo against) is the
// brute-force distance to the farthest reference point its value used.
TEST(CloudToCloudReach, IsTheDistanceToTheLastNeighbourUsed)
{
    std::mt19937 rng(11);
    const PointCloud reference = randomCloud(2000, rng);
    const PointCloud compared = randomCloud(300, rng);
    auto bruteForce = [&](std::size_t i, std::size_t k) {
        std::vector<double> d;
        for (const auto& q : reference.positions())
            d.push_back((compared.positions()[i] - q).cast<double>().norm());
        std::sort(d.begin(), d.end());
        return std::make_pair(d[0], d[k - 1]);
    };
    CloudToCloudParams params;
    params.reportReach = true;
    const CloudToCloudResult nn = cloudToCloud(compared, reference, params);
    params.maxDistance = 0.3;
    const CloudToCloudResult capped = cloudToCloud(compared, reference, params);
    params.maxDistance.reset();
    params.model = LocalModel::Plane;
    params.neighbours = 9;
    const CloudToCloudResult knn = cloudToCloud(compared, reference, params);
    params.radius = 0.7;
    const CloudToCloudResult radius = cloudToCloud(compared, reference, params);
    params.radius.reset();
    params.neighbours = 12;
    const CloudToCloudResult tooFew = cloudToCloud(compared, reference.subset({0, 1, 2, 3, 4}), params);
    for (std::size_t i = 0; i < compared.size(); ++i) {
        const auto [nearest, ninth] = bruteForce(i, 9);
        EXPECT_NEAR(nn.reach[i], nearest, 1e-5);
        EXPECT_NEAR(capped.reach[i], std::min(nearest, 0.3), 1e-5);
        EXPECT_NEAR(knn.reach[i], ninth, 1e-5);
        EXPECT_NEAR(radius.reach[i], nearest + 0.7, 1e-5);
        EXPECT_TRUE(std::isinf(tooFew.reach[i])); // 5 points cannot give 12 neighbours
    }
    EXPECT_TRUE(cloudToCloud(compared, reference, CloudToCloudParams{}).reach.empty()); // not asked: not kept
}
