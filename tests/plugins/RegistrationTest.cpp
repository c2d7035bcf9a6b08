// SPDX-License-Identifier: GPL-3.0-or-later
// Registration against known motions: ICP from a 25 degree start, the 4-DOF
// constraint, changed scenes, meshes, UTM coordinates, degenerate geometry.
#include "PrimitiveScene.h"
#include "StageWatcher.h"
#include "SyntheticSite.h"
#include "TestSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/processing/CloudEditing.h>
#include <scandiff/io/FileIO.h>
#include <scandiff/plugins/PluginRegistry.h>
#include <scandiff/plugins/registration/GlobalAlignment.h>
#include <scandiff/plugins/registration/Icp.h>
#include <scandiff/plugins/registration/PointPairs.h>
#include <scandiff/plugins/registration/PrimitiveAlignment.h>
#include <scandiff/plugins/registration/Stations.h>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

using namespace scandiff;
using namespace scandiff::plugins;

namespace {

//! The angle (degrees) and the largest point displacement over the site (m)
//! between the found and the true motion.
struct MotionError
{
    double degrees;
    double metres;
};

MotionError errorOf(const Eigen::Matrix4d& found, const Eigen::Matrix4d& truth, const Eigen::Vector3d& centre)
{
    const Eigen::Matrix4d delta = found * truth.inverse();
    MotionError e;
    e.degrees = rotationDegrees(delta.topLeftCorner<3, 3>());
    e.metres = 0;
    // Corners of the site's box (60 x 60 x 12 m around its centre).
    for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d p = centre + Eigen::Vector3d((k & 1) ? 30 : -30, (k & 2) ? 30 : -30, (k & 4) ? 12 : 0);
        e.metres = std::max(e.metres, ((delta * p.homogeneous()).head<3>() - p).norm());
    }
    return e;
}

struct Scene
{
    PointCloud reference, moving;
    Eigen::Matrix4d truth; //!< moving -> reference
};

//! Two samplings of the site; the second (changed or not) moved by the inverse of `truth`.
Scene makeScene(const Eigen::Matrix4d& truth, std::size_t points, bool changed, const Eigen::Vector3d& origin)
{
    test::SiteOptions a;
    a.points = points;
    a.seed = 1;
    a.origin = origin;
    test::SiteOptions b = a;
    b.seed = 2;
    b.changed = changed;
    b.markChanges = true;
    Scene s;
    s.reference = test::syntheticSite(a);
    s.moving = transformCloud(test::syntheticSite(b), truth.inverse(), "test");
    s.moving.transformHistory().clear();
    s.truth = truth;
    return s;
}

} // namespace

TEST(Icp, ConvergesFromA25DegreeStart)
{
    const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    const Eigen::Matrix4d truth = test::rigidMotionAbout(25, 3, -2, Eigen::Vector3d(1.5, -2.0, 0.4), origin);
    const Scene scene = makeScene(truth, 60000, false, origin);
    IcpParams params; // point-to-plane
    params.kernel = RobustKernel::Cauchy;
    const IcpResult result = icpRegister(scene.moving, &scene.reference, nullptr, params);
    const MotionError e = errorOf(result.report.matrix, scene.truth, origin);
    EXPECT_TRUE(result.report.converged);
    EXPECT_LT(e.degrees, 0.002);
    EXPECT_LT(e.metres, 0.002);
    EXPECT_TRUE(result.report.degeneracy.empty()) << result.report.degeneracy;
    // Point-to-point gets there too, more slowly and less closely (the two
    // samplings' points never coincide).
    params.method = IcpMethod::PointToPoint;
    params.maxIterations = 300;
    const MotionError p2p = errorOf(icpRegister(scene.moving, &scene.reference, nullptr, params).report.matrix, scene.truth, origin);
    EXPECT_LT(p2p.degrees, 0.05);
    EXPECT_LT(p2p.metres, 0.05);
}

TEST(Icp, FourDegreesOfFreedomLeaveTheTiltExactlyAsItWas)
{
    // A levelled scanner: the truth turns about Z only; the moving scan starts
    // 35 degrees off (from farther, --global finds the heading first). The
    // 4-DOF solution's rotation is about Z to the last bit.
    const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    const Eigen::Matrix4d truth = test::rigidMotionAbout(35, 0, 0, Eigen::Vector3d(2, 1, -0.3), origin);
    const Scene scene = makeScene(truth, 60000, false, origin);
    IcpParams params;
    params.kernel = RobustKernel::Cauchy;
    params.constraint.dof = Dof::Four;
    const IcpResult result = icpRegister(scene.moving, &scene.reference, nullptr, params);
    const Eigen::Matrix3d r = result.report.matrix.topLeftCorner<3, 3>();
    EXPECT_EQ(r(2, 2), 1.0);
    EXPECT_EQ(r(0, 2), 0.0);
    EXPECT_EQ(r(1, 2), 0.0);
    EXPECT_EQ(r(2, 0), 0.0);
    EXPECT_EQ(r(2, 1), 0.0);
    const MotionError e = errorOf(result.report.matrix, scene.truth, origin);
    EXPECT_LT(e.degrees, 0.002);
    EXPECT_LT(e.metres, 0.002);
    // Translation only: a pure shift is found, the rotation stays the identity.
    const Eigen::Matrix4d shift = test::rigidMotionAbout(0, 0, 0, Eigen::Vector3d(0.8, -0.5, 0.2), origin);
    const Scene shifted = makeScene(shift, 40000, false, origin);
    params.constraint.dof = Dof::Translation;
    const IcpResult translated = icpRegister(shifted.moving, &shifted.reference, nullptr, params);
    const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d rotation = translated.report.matrix.topLeftCorner<3, 3>();
    EXPECT_TRUE(rotation == identity);
    EXPECT_LT(errorOf(translated.report.matrix, shift, origin).metres, 0.002);
}

TEST(Icp, ChangeRobustModeIgnoresWhatChanged)
{
    // 30 % of the moving epoch is on changed surfaces (a building moved 0.3 m,
    // a new block, a new wall). Plain ICP is pulled by them; the change-robust
    // mode is not, and marks them.
    const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    const Eigen::Matrix4d truth = test::rigidMotionAbout(8, 1, 0.5, Eigen::Vector3d(0.6, 0.4, 0.1), origin);
    const Scene scene = makeScene(truth, 80000, true, origin);
    const ScalarField& changed = *scene.moving.field("changed");
    std::size_t changedCount = 0;
    for (std::size_t i = 0; i < changed.size(); ++i)
        changedCount += changed.value(i) > 0;
    EXPECT_GT(changedCount, scene.moving.size() / 4);
    IcpParams params;
    params.kernel = RobustKernel::Cauchy;
    params.changeRobust = true;
    const IcpResult result = icpRegister(scene.moving, &scene.reference, nullptr, params);
    const MotionError e = errorOf(result.report.matrix, scene.truth, origin);
    EXPECT_LT(e.degrees, 0.01);
    EXPECT_LT(e.metres, 0.001);
    // The excluded points are, for the most part, the changed ones.
    std::size_t excludedChanged = 0, excluded = 0;
    for (std::size_t i = 0; i < changed.size(); ++i)
        if (result.excluded.value(i) > 0) {
            ++excluded;
            excludedChanged += changed.value(i) > 0;
        }
    EXPECT_GT(excludedChanged, changedCount / 2);
    EXPECT_GT(excludedChanged, excluded * 8 / 10);
    // Without the mode, plain point-to-plane ICP is biased by the moved building.
    IcpParams plain;
    plain.maxIterations = 40;
    const MotionError biased = errorOf(icpRegister(scene.moving, &scene.reference, nullptr, plain).report.matrix, scene.truth, origin);
    EXPECT_GT(biased.metres, 10 * e.metres);
}

TEST(Icp, UtmCoordinatesGiveTheResultOfTheOrigin)
{
    const Eigen::Vector3d utm(500000, 5400000, 120);
    const Eigen::Matrix4d truthNear = test::rigidMotionAbout(10, 0, 0, Eigen::Vector3d(0.5, 0.2, 0), Eigen::Vector3d::Zero());
    const Eigen::Matrix4d truthUtm = test::rigidMotionAbout(10, 0, 0, Eigen::Vector3d(0.5, 0.2, 0), utm);
    const Scene near = makeScene(truthNear, 40000, false, Eigen::Vector3d::Zero());
    const Scene far = makeScene(truthUtm, 40000, false, utm);
    IcpParams params;
    params.kernel = RobustKernel::Cauchy;
    const MotionError eNear = errorOf(icpRegister(near.moving, &near.reference, nullptr, params).report.matrix, truthNear, Eigen::Vector3d::Zero());
    const MotionError eFar = errorOf(icpRegister(far.moving, &far.reference, nullptr, params).report.matrix, truthUtm, utm);
    EXPECT_LT(eNear.metres, 0.002);
    EXPECT_LT(eFar.metres, 0.002);
    EXPECT_NEAR(eFar.degrees, eNear.degrees, 0.001);
}

TEST(Icp, OnAMeshAndOnASinglePlane)
{
    // The reference as a mesh: a terrain grid; the moving cloud sampled on it, moved.
    Mesh mesh;
    const int n = 101;
    mesh.vertices.resize(static_cast<std::size_t>(n * n));
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double x = -25 + 0.5 * i, y = -25 + 0.5 * j;
            mesh.vertices.positions()[static_cast<std::size_t>(i * n + j)] =
                Eigen::Vector3f(float(x), float(y), float(2 * std::sin(x / 6) * std::cos(y / 5) + 0.05 * x));
        }
    for (int i = 0; i + 1 < n; ++i)
        for (int j = 0; j + 1 < n; ++j) {
            const auto a = static_cast<std::uint32_t>(i * n + j), b = a + 1, c = a + static_cast<std::uint32_t>(n), d = c + 1;
            mesh.triangles.push_back({a, b, d});
            mesh.triangles.push_back({a, d, c});
        }
    PointCloud onMesh;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-20, 20);
    onMesh.resize(20000);
    for (auto& p : onMesh.positions()) {
        const double x = u(rng), y = u(rng);
        p = Eigen::Vector3f(float(x), float(y), float(2 * std::sin(x / 6) * std::cos(y / 5) + 0.05 * x));
    }
    const Eigen::Matrix4d truth = test::rigidMotionAbout(4, 0, 0, Eigen::Vector3d(0.3, -0.2, 0.1), Eigen::Vector3d::Zero());
    const PointCloud moving = transformCloud(onMesh, truth.inverse(), "test");
    IcpParams params;
    const IcpResult result = icpRegister(moving, nullptr, &mesh, params);
    // The mesh's triangles cut the surface's curvature: within a few mm.
    EXPECT_LT(errorOf(result.report.matrix, truth, Eigen::Vector3d::Zero()).metres, 0.01);
    EXPECT_LT(result.report.rms, 0.01);
    // With a maximum distance the mesh search is bounded: the same motion.
    params.maxDistance = 1.0;
    const IcpResult bounded = icpRegister(moving, nullptr, &mesh, params);
    EXPECT_LT(errorOf(bounded.report.matrix, truth, Eigen::Vector3d::Zero()).metres, 0.01);

    // A single plane holds only three directions: the warning says so.
    PointCloud plane, planeMoved;
    plane.resize(5000);
    planeMoved.resize(5000);
    for (std::size_t i = 0; i < plane.size(); ++i) {
        plane.positions()[i] = Eigen::Vector3f(float(u(rng)), float(u(rng)), 0.0f);
        planeMoved.positions()[i] = Eigen::Vector3f(float(u(rng)), float(u(rng)), 0.1f);
    }
    const IcpResult flat = icpRegister(planeMoved, &plane, nullptr, IcpParams{});
    EXPECT_NE(flat.report.degeneracy.find("degenerate"), std::string::npos);
    EXPECT_NE(flat.report.degeneracy.find("translation along"), std::string::npos);
    EXPECT_NEAR(flat.report.matrix(2, 3), -0.1, 1e-6); // what the plane holds is found
}

TEST(Icp, BadInput)
{
    PointCloud empty, some;
    some.resize(10);
    EXPECT_EQ(test::errorCodeOf([&] { icpRegister(empty, &some, nullptr, IcpParams{}); }), ErrorCode::InvalidData);
    EXPECT_EQ(test::errorCodeOf([&] { icpRegister(some, &empty, nullptr, IcpParams{}); }), ErrorCode::InvalidData);
    IcpParams bad;
    bad.overlap = 0;
    EXPECT_EQ(test::errorCodeOf([&] { icpRegister(some, &some, nullptr, bad); }), ErrorCode::InvalidArgument);
    // Two clouds 100 m apart with a 1 m limit: no correspondence, a clear error.
    PointCloud far = test::syntheticSite(test::SiteOptions{2000, 1, 0.002, false, Eigen::Vector3d(100, 0, 0), false});
    PointCloud here = test::syntheticSite(test::SiteOptions{2000, 2, 0.002, false, Eigen::Vector3d::Zero(), false});
    IcpParams limited;
    limited.maxDistance = 1.0;
    EXPECT_EQ(test::errorCodeOf([&] { icpRegister(far, &here, nullptr, limited); }), ErrorCode::InvalidData);
}

TEST(Icp, CancelIsHeardWhileEveryPointGetsItsResidual)
{
    // After the iterations, every moving point is matched once more for its
    // residual: on 2 M points that took 3 s with no poll. It now goes by
    // chunks of 65 536 points, each a poll; Cancel there stops the run.
    const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    const Scene scene = makeScene(test::rigidMotionAbout(2, 0, 0, Eigen::Vector3d(0.1, 0, 0), origin), 300000, false, origin);
    IcpParams params;
    test::StageWatcher watch("residual of every point", 0);
    icpRegister(scene.moving, &scene.reference, nullptr, params, &watch);
    EXPECT_GE(watch.polls(), 4u);
    test::StageWatcher cancel("residual of every point", 2);
    EXPECT_EQ(test::errorCodeOf([&] { icpRegister(scene.moving, &scene.reference, nullptr, params, &cancel); }),
              ErrorCode::Cancelled);
    // And the reference's octree, built before the first iteration, hears it too.
    test::CancelAtOnce atOnce;
    EXPECT_EQ(test::errorCodeOf([&] { icpRegister(scene.moving, &scene.reference, nullptr, params, &atOnce); }),
              ErrorCode::Cancelled);
}

TEST(PointPairs, ExactFromThreePairsAndClosedFormFromTenNoisyOnes)
{
    // Three picked targets at UTM magnitudes, moved by a known motion: the
    // motion comes back to rounding, the residuals are zero.
    const Eigen::Vector3d utm(500000, 5400000, 120);
    const Eigen::Matrix4d truth = test::rigidMotionAbout(37, 5, -3, Eigen::Vector3d(4, -7, 1.5), utm);
    const std::vector<Eigen::Vector3d> targets = {utm + Eigen::Vector3d(10, 0, 0), utm + Eigen::Vector3d(0, 25, 3),
                                                  utm + Eigen::Vector3d(-12, -8, 9)};
    std::vector<PointPair> pairs;
    for (const auto& reference : targets)
        pairs.push_back({(truth.inverse() * reference.homogeneous()).head<3>(), reference});
    const RegistrationReport exact = fitPointPairs(pairs, DofConstraint{});
    // (The matrix's translation is R x 5.4e6 m plus a shift: compared through
    // what it does to the site, within a nanometre, not entry by entry.)
    EXPECT_LT((exact.matrix.topLeftCorner<3, 3>() - truth.topLeftCorner<3, 3>()).cwiseAbs().maxCoeff(), 1e-10);
    const auto displacement = [&](const Eigen::Matrix4d& a, const Eigen::Matrix4d& b) {
        double worst = 0;
        for (const auto& p : targets)
            worst = std::max(worst, ((a - b) * p.homogeneous()).norm());
        return worst;
    };
    EXPECT_LT(displacement(exact.matrix, truth), 1e-8);
    ASSERT_EQ(exact.pairResiduals.size(), 3u);
    for (double r : exact.pairResiduals)
        EXPECT_LT(r, 1e-7);
    EXPECT_TRUE(exact.notes.empty()); // three pairs check each other through their distances

    // Ten pairs with 5 mm noise: the result is the least-squares motion in
    // closed form. Checked by its optimality: no small motion about it lowers
    // the sum of squares (the gradient is zero to rounding).
    std::mt19937 rng(11);
    std::normal_distribution<double> noise(0, 0.005);
    std::uniform_real_distribution<double> u(-30, 30);
    std::vector<PointPair> noisy;
    for (int i = 0; i < 10; ++i) {
        const Eigen::Vector3d reference = utm + Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng));
        noisy.push_back({(truth.inverse() * reference.homogeneous()).head<3>() + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)),
                         reference});
    }
    const RegistrationReport fit = fitPointPairs(noisy, DofConstraint{});
    const auto sumOfSquares = [&](const Eigen::Matrix4d& m) {
        double s = 0;
        for (const auto& p : noisy)
            s += ((m * p.moving.homogeneous()).head<3>() - p.reference).squaredNorm();
        return s;
    };
    const double best = sumOfSquares(fit.matrix);
    for (int k = 0; k < 6; ++k)
        for (double sign : {-1.0, 1.0}) {
            Eigen::Vector3d rotation = Eigen::Vector3d::Zero(), translation = Eigen::Vector3d::Zero();
            (k < 3 ? rotation[k] : translation[k - 3]) = sign * (k < 3 ? 1e-5 : 1e-4);
            const Eigen::Matrix4d nudge = test::rigidMotionAbout(0, 0, 0, translation, Eigen::Vector3d::Zero()) *
                                          [&] {
                                              Eigen::Affine3d a = Eigen::Affine3d::Identity();
                                              a.translate(utm);
                                              a.rotate(Eigen::AngleAxisd(rotation.norm(), rotation.normalized()));
                                              a.translate(-utm);
                                              return a.matrix();
                                          }();
            EXPECT_GE(sumOfSquares(nudge * fit.matrix), best);
        }
    // The RMS equals the residuals' and the motion is within the noise.
    double sum2 = 0;
    for (double r : fit.pairResiduals)
        sum2 += r * r;
    EXPECT_NEAR(fit.rms, std::sqrt(sum2 / 10), 1e-12);
    EXPECT_NEAR(fit.rms * fit.rms * 10, best, 1e-9);
    EXPECT_LT(rotationDegrees((fit.matrix * truth.inverse()).topLeftCorner<3, 3>()), 0.05);

    // Four degrees of freedom: two pairs fix a turn about Z; the tilt stays exact.
    const Eigen::Matrix4d heading = test::rigidMotionAbout(-75, 0, 0, Eigen::Vector3d(3, 2, -1), utm);
    std::vector<PointPair> two;
    for (std::size_t i = 0; i < 2; ++i)
        two.push_back({(heading.inverse() * targets[i].homogeneous()).head<3>(), targets[i]});
    DofConstraint levelled;
    levelled.dof = Dof::Four;
    const RegistrationReport four = fitPointPairs(two, levelled);
    EXPECT_EQ(four.matrix(2, 2), 1.0);
    EXPECT_EQ(four.matrix(2, 0), 0.0);
    EXPECT_LT(displacement(four.matrix, heading), 1e-8);
}

TEST(PointPairs, BadPairs)
{
    EXPECT_EQ(test::errorCodeOf([] { fitPointPairs({}, DofConstraint{}); }), ErrorCode::InvalidArgument);
    // Collinear pairs do not fix the rotation about their line.
    std::vector<PointPair> line;
    for (int i = 0; i < 4; ++i)
        line.push_back({Eigen::Vector3d(i, 0, 0), Eigen::Vector3d(i, 1, 0)});
    EXPECT_EQ(test::errorCodeOf([&] { fitPointPairs(line, DofConstraint{}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([] { parsePointPairs("1,2,3,4,5"); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([] { parsePointPairs("1,2,3,4,5,6;1,2,x,4,5,6"); }), ErrorCode::InvalidArgument);
    const std::vector<PointPair> parsed = parsePointPairs("1 2 3 4 5 6\n7,8,9,10,11,12;");
    ASSERT_EQ(parsed.size(), 2u);
    EXPECT_EQ(parsed[1].reference, Eigen::Vector3d(10, 11, 12));
}

TEST(Icp, EveryRegistrationToolStopsAtAnyPollAndLeavesBothCloudsAsTheyWere)
{
    // Each registration tool runs once to count its polls, then with Cancel
    // pressed at the first, a third, two thirds and the last: Error(Cancelled)
    // every time, and neither cloud changed.
    const Eigen::Vector3d origin(500000, 5400000, 120);
    const Scene scene = makeScene(test::rigidMotionAbout(20, 3, -2, Eigen::Vector3d(1, -0.5, 0.2), origin), 40000, true, origin);
    const PointCloud referenceBefore = scene.reference.clone();
    const PointCloud movingBefore = scene.moving.clone();
    const PluginRegistry registry = makePluginRegistry();
    const std::vector<std::pair<std::string, std::map<std::string, std::string>>> runs = {
        {"register", {{"global", "true"}, {"exclude-changes", "true"}}},
        {"register-global", {}},
    };
    for (const auto& [name, text] : runs) {
        const ToolSpec& spec = *registry.tools.find(name);
        const ParameterValues values = spec.resolve(text);
        const ToolInputs inputs = ToolInputs().add("moving", scene.moving).add("reference", scene.reference);
        test::PollCounter counting;
        ASSERT_NO_THROW(spec.execute(inputs, values, &counting)) << name;
        const std::size_t polls = counting.polls();
        ASSERT_GE(polls, 3u) << name;
        // "The last" is 95 % of the counted polls: the parallel stages poll per
        // worker, so another run may poll a few times less (this test failed
        // once under load when it waited for the exact count).
        for (const std::size_t at : {std::size_t(1), polls / 3, 2 * polls / 3, polls - polls / 20}) {
            test::PollCounter cancel(std::max<std::size_t>(at, 1));
            EXPECT_EQ(test::errorCodeOf([&] { spec.execute(inputs, values, &cancel); }), ErrorCode::Cancelled)
                << name << ", Cancel at poll " << at << " of " << polls;
        }
        ASSERT_EQ(scene.moving.positions(), movingBefore.positions()) << name;
        ASSERT_EQ(scene.reference.positions(), referenceBefore.positions()) << name;
        ASSERT_EQ(scene.moving.fields().size(), movingBefore.fields().size()) << name;
        ASSERT_EQ(scene.moving.transformHistory().size(), movingBefore.transformHistory().size()) << name;
    }
}

TEST(GlobalAlignment, Recovers140DegreesFromAnyStartThenIcpFinishes)
{
    // Turned 140 degrees about a tilted axis and shifted: far outside ICP's
    // basin. The descriptors' consensus lands within the feature spacing;
    // ICP from there lands on the truth.
    const Eigen::Vector3d origin(500000, 5400000, 120);
    const Eigen::Matrix4d truth = test::rigidMotionAbout(140, 25, -15, Eigen::Vector3d(6, -4, 1), origin);
    const Scene scene = makeScene(truth, 80000, false, origin);
    const GlobalAlignmentResult coarse = globalAlign(scene.moving, &scene.reference, nullptr, GlobalAlignmentParams{});
    const MotionError e = errorOf(coarse.report.matrix, scene.truth, origin);
    EXPECT_LT(e.degrees, 2.0) << coarse.report.notes.front();
    EXPECT_LT(e.metres, 2 * coarse.spacing) << coarse.report.notes.front();
    EXPECT_GT(coarse.inliers, 20u);
    IcpParams params;
    params.kernel = RobustKernel::Cauchy;
    params.initial = coarse.report.matrix;
    const MotionError fine = errorOf(icpRegister(scene.moving, &scene.reference, nullptr, params).report.matrix, scene.truth, origin);
    EXPECT_LT(fine.degrees, 0.002);
    EXPECT_LT(fine.metres, 0.002);
}

//! Two independent samplings of analytic shapes at `origin`, the moving one
//! moved by the inverse of a 140° turn about a tilted axis (scene.truth).
Scene twoSamplings(const std::vector<test::SceneShape>& shapes, std::size_t points, double noise, double clutter, unsigned seed,
                   const Eigen::Vector3d& origin)
{
    auto sample = [&](unsigned s) {
        test::PrimitiveScene scene = test::makePrimitiveScene(shapes, points, noise, clutter, s, false);
        scene.cloud.setOrigin(origin);
        return std::move(scene.cloud);
    };
    Scene scene;
    scene.reference = sample(seed);
    scene.truth = test::rigidMotionAbout(140, 25, -15, Eigen::Vector3d(6, -4, 1), origin);
    scene.moving = transformCloud(sample(seed + 1), scene.truth.inverse(), "the truth's inverse");
    return scene;
}

TEST(PrimitiveAlignment, TwoSamplingsOfAFacadeRegisterOnTheirPlanesFromAnyStart)
{
    // Thesis 004: two independent samplings of a façade (wall, windows' glass,
    // sign, pilasters, cornice, string course, roof; 3 mm of noise) at UTM
    // coordinates, the moving one turned 140° about a tilted axis and
    // shifted. Its planes matched with the reference's give the motion
    // within 0.05° and 1 cm over the site; ICP from there lands on the truth.
    const Eigen::Vector3d origin(512300.0, 5401200.0, 150.0);
    const Scene scene = twoSamplings(test::facadeSceneShapes(0.6, Eigen::Vector3d::Zero()), 120000, 0.003, 0.02, 21, origin);
    const PointCloud& reference = scene.reference;
    const PointCloud& moving = scene.moving;
    const Eigen::Matrix4d& truth = scene.truth;
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("register-primitives");
    const ToolInputs inputs = ToolInputs().add("moving", moving).add("reference", reference);
    ToolResult coarse = tool.execute(inputs, tool.resolve({{"refine", "false"}}), nullptr);
    const MotionError e = errorOf(std::get<Eigen::Matrix4d>(coarse.find("matrix")->data), truth, origin);
    EXPECT_LT(e.degrees, 0.05) << coarse.summary;
    EXPECT_LT(e.metres, 0.01) << coarse.summary;
    EXPECT_GE(std::get<Table>(coarse.find("matches")->data).rows.size(), 6u) << coarse.summary;
    ToolResult fine = tool.execute(inputs, tool.resolve({}), nullptr);
    const MotionError f = errorOf(std::get<Eigen::Matrix4d>(fine.find("matrix")->data), truth, origin);
    EXPECT_LT(f.degrees, 0.005) << fine.summary;
    EXPECT_LT(f.metres, 0.002) << fine.summary;

    // A scan of one plane cannot be aligned on planes: a clear error.
    PointCloud flat;
    flat.resize(5000);
    for (std::size_t i = 0; i < flat.size(); ++i)
        flat.positions()[i] = Eigen::Vector3f(float(i % 100) * 0.05f, float(i / 100) * 0.05f, 0.0f);
    EXPECT_EQ(test::errorCodeOf([&] { tool.execute(ToolInputs().add("moving", flat).add("reference", reference), tool.resolve({}), nullptr); }),
              ErrorCode::InvalidData);
}

TEST(PrimitiveAlignment, SphereTargetsRegisterTwoStationsFromAnyStart)
{
    // Five sphere targets (radii 10 to 20 cm) on a 6 x 6 m floor, sampled
    // twice (2 mm of noise) at UTM coordinates; the moving scan turned 140°
    // about a tilted axis. The targets matched by radius and distances give
    // the motion within 0.05°, and 2 cm over the 60 m box (ten times the
    // targets' spread: 1.3 cm here, their centres agreeing within 0.3 mm).
    const Eigen::Vector3d origin(512300.0, 5401200.0, 150.0);
    std::vector<test::SceneShape> shapes = {
        test::scene::rectangle("floor", Eigen::Vector3d(-3, -3, 0), Eigen::Vector3d(6, 0, 0), Eigen::Vector3d(0, 6, 0)),
        test::scene::sphere("target 1", Eigen::Vector3d(-2.0, -1.5, 0.8), 0.10),
        test::scene::sphere("target 2", Eigen::Vector3d(2.2, -2.0, 1.2), 0.15),
        test::scene::sphere("target 3", Eigen::Vector3d(1.5, 2.3, 0.6), 0.20),
        test::scene::sphere("target 4", Eigen::Vector3d(-1.8, 2.0, 1.5), 0.12),
        test::scene::sphere("target 5", Eigen::Vector3d(0.3, 0.2, 1.0), 0.18),
    };
    const Scene scene = twoSamplings(shapes, 60000, 0.002, 0.0, 31, origin);
    const Eigen::Matrix4d& truth = scene.truth;
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("register-primitives");
    const ToolInputs inputs = ToolInputs().add("moving", scene.moving).add("reference", scene.reference);
    ToolResult result = tool.execute(inputs, tool.resolve({{"on", "spheres"}, {"refine", "false"}, {"min-points", "100"}}), nullptr);
    const MotionError e = errorOf(std::get<Eigen::Matrix4d>(result.find("matrix")->data), truth, origin);
    EXPECT_LT(e.degrees, 0.05) << result.summary;
    EXPECT_LT(e.metres, 0.02) << result.summary;
    EXPECT_GE(std::get<Table>(result.find("matches")->data).rows.size(), 4u) << result.summary;
}

TEST(PrimitiveAlignment, PipesAloneRegisterTwoScansOfAPipeRackFromAnyStart)
{
    // A pipe rack: pipes of 10 to 20 cm along two directions at several
    // heights and a column, over a floor (2 mm of noise, UTM coordinates),
    // sampled twice, the moving scan turned 140° about a tilted axis. Two
    // pipes that are not parallel fix the motion: matched by their radii and
    // the angle between them, the cylinders alone give it within 0.05° and
    // 1 cm over the rack.
    const Eigen::Vector3d origin(512300.0, 5401200.0, 150.0);
    using V = Eigen::Vector3d;
    const std::vector<test::SceneShape> shapes = {
        test::scene::rectangle("floor", V(-1, -1, 0), V(10, 0, 0), V(0, 10, 0)),
        test::scene::cylinder("pipe x1", V(0, 2, 1.0), V(1, 0, 0), 0.15, 8),
        test::scene::cylinder("pipe x2", V(0, 3.5, 2.0), V(1, 0, 0), 0.10, 8),
        test::scene::cylinder("pipe y1", V(2, 0, 2.6), V(0, 1, 0), 0.20, 8),
        test::scene::cylinder("pipe y2", V(5.5, 0, 1.6), V(0, 1, 0), 0.12, 8),
        test::scene::cylinder("column", V(7.5, 7.5, 0), V(0, 0, 1), 0.25, 3),
    };
    const Scene scene = twoSamplings(shapes, 120000, 0.002, 0.0, 41, origin);
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("register-primitives");
    const ToolInputs inputs = ToolInputs().add("moving", scene.moving).add("reference", scene.reference);
    ToolResult result = tool.execute(inputs, tool.resolve({{"on", "cylinders"}, {"refine", "false"}, {"min-points", "300"}}), nullptr);
    const MotionError e = errorOf(std::get<Eigen::Matrix4d>(result.find("matrix")->data), scene.truth, origin);
    EXPECT_LT(e.degrees, 0.05) << result.summary;
    EXPECT_LT(e.metres, 0.01) << result.summary;
    const Table& matches = std::get<Table>(result.find("matches")->data);
    EXPECT_GE(matches.rows.size(), 4u) << result.summary;
    for (const auto& row : matches.rows)
        EXPECT_EQ(std::get<std::string>(row[2]), "cylinder"); // cylinders only

    // The moving scan seeing only part of the rack (x < 5.5 m: the pipes along
    // y and the column cut off or absent, its box centre metres from the
    // reference's): the shapes are matched where their points are.
    {
        test::PrimitiveScene part = test::makePrimitiveScene(shapes, 120000, 0.002, 0.0, 45, false);
        std::vector<std::size_t> kept;
        for (std::size_t i = 0; i < part.cloud.size(); ++i)
            if (part.cloud.positions()[i].x() < 5.5f)
                kept.push_back(i);
        PointCloud cropped = part.cloud.subset(kept);
        cropped.setOrigin(origin);
        const PointCloud movedPart = transformCloud(cropped, scene.truth.inverse(), "the truth's inverse");
        ToolResult partial = tool.execute(ToolInputs().add("moving", movedPart).add("reference", scene.reference),
                                          tool.resolve({{"on", "cylinders"}, {"refine", "false"}, {"min-points", "300"}}), nullptr);
        const MotionError p = errorOf(std::get<Eigen::Matrix4d>(partial.find("matrix")->data), scene.truth, origin);
        EXPECT_LT(p.degrees, 0.05) << partial.summary;
        EXPECT_LT(p.metres, 0.01) << partial.summary;
    }

    // Pipes all parallel leave the shift along them free: a clear error.
    const Scene parallel = twoSamplings({shapes[0], shapes[1], shapes[2]}, 60000, 0.002, 0.0, 43, origin);
    EXPECT_EQ(test::errorCodeOf([&] {
                  tool.execute(ToolInputs().add("moving", parallel.moving).add("reference", parallel.reference),
                               tool.resolve({{"on", "cylinders"}, {"refine", "false"}, {"min-points", "300"}}), nullptr);
              }),
              ErrorCode::InvalidData);
}

TEST(PrimitiveAlignment, TwoParallelColumnsAndTheFloorFixTheHeading)
{
    // Two vertical columns and a floor: every direction is vertical, and only
    // the vector across the columns' axes holds the rotation about it. From a
    // 140° turn about a tilted axis, within 0.05° and 1 cm.
    const Eigen::Vector3d origin(512300.0, 5401200.0, 150.0);
    using V = Eigen::Vector3d;
    const std::vector<test::SceneShape> shapes = {
        test::scene::rectangle("floor", V(-1, -1, 0), V(10, 0, 0), V(0, 10, 0)),
        test::scene::cylinder("column A", V(2, 2, 0), V(0, 0, 1), 0.25, 3),
        test::scene::cylinder("column B", V(6, 4.5, 0), V(0, 0, 1), 0.20, 3),
    };
    const Scene scene = twoSamplings(shapes, 80000, 0.002, 0.0, 61, origin);
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("register-primitives");
    ToolResult result = tool.execute(ToolInputs().add("moving", scene.moving).add("reference", scene.reference),
                                     tool.resolve({{"on", "all"}, {"refine", "false"}, {"min-points", "300"}}), nullptr);
    const MotionError e = errorOf(std::get<Eigen::Matrix4d>(result.find("matrix")->data), scene.truth, origin);
    EXPECT_LT(e.degrees, 0.05) << result.summary;
    EXPECT_LT(e.metres, 0.01) << result.summary;
}

TEST(PrimitiveAlignment, PlanesCylindersAndSpheresTogetherRegisterTheTestScene)
{
    // The 15-shape scene of the primitives tests (planes, a column, a tilted
    // pipe, a sphere, a cone and a torus; 3 mm of noise), sampled twice at UTM
    // coordinates and turned 140°: planes, cylinders and the sphere matched
    // together give the motion within 0.05° and 1 cm; ICP then lands on the truth.
    const Eigen::Vector3d origin(512300.0, 5401200.0, 150.0);
    const Scene scene = twoSamplings(test::testSceneShapes(), 120000, 0.003, 0.02, 51, origin);
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("register-primitives");
    const ToolInputs inputs = ToolInputs().add("moving", scene.moving).add("reference", scene.reference);
    ToolResult coarse = tool.execute(inputs, tool.resolve({{"on", "all"}, {"refine", "false"}, {"min-points", "300"}}), nullptr);
    const MotionError e = errorOf(std::get<Eigen::Matrix4d>(coarse.find("matrix")->data), scene.truth, origin);
    EXPECT_LT(e.degrees, 0.05) << coarse.summary;
    EXPECT_LT(e.metres, 0.01) << coarse.summary;
    std::set<std::string> kinds;
    for (const auto& row : std::get<Table>(coarse.find("matches")->data).rows)
        kinds.insert(std::get<std::string>(row[2]));
    EXPECT_EQ(kinds, (std::set<std::string>{"plane", "sphere", "cylinder"})) << coarse.summary;
    ToolResult fine = tool.execute(inputs, tool.resolve({{"on", "all"}, {"min-points", "300"}}), nullptr);
    const MotionError f = errorOf(std::get<Eigen::Matrix4d>(fine.find("matrix")->data), scene.truth, origin);
    EXPECT_LT(f.degrees, 0.005) << fine.summary;
    EXPECT_LT(f.metres, 0.002) << fine.summary;
}

TEST(GlobalAlignment, FourDegreesOfFreedomSearchOnlyTheHeading)
{
    const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    const Eigen::Matrix4d truth = test::rigidMotionAbout(-140, 0, 0, Eigen::Vector3d(-5, 7, 0.5), origin);
    const Scene scene = makeScene(truth, 80000, false, origin);
    GlobalAlignmentParams params;
    params.constraint.dof = Dof::Four;
    const GlobalAlignmentResult coarse = globalAlign(scene.moving, &scene.reference, nullptr, params);
    EXPECT_EQ(coarse.report.matrix(2, 2), 1.0);
    EXPECT_EQ(coarse.report.matrix(2, 0), 0.0);
    EXPECT_EQ(coarse.report.matrix(0, 2), 0.0);
    const MotionError e = errorOf(coarse.report.matrix, scene.truth, origin);
    EXPECT_LT(e.degrees, 2.0) << coarse.report.notes.front();
    EXPECT_LT(e.metres, 2 * coarse.spacing);
    // The same seed gives the same motion.
    EXPECT_EQ(globalAlign(scene.moving, &scene.reference, nullptr, params).report.matrix, coarse.report.matrix);
}

namespace {

//! Four stations around the site, each seeing a 40 x 40 m quarter (so each
//! overlaps its two neighbours in a strip 20 m wide: a loop 0-1-2-3-0),
//! each an independent sampling moved by its own small error.
std::vector<PointCloud> fourStations(const std::vector<Eigen::Matrix4d>& errors, const Eigen::Vector3d& origin)
{
    const double lowX[4] = {-30, -10, -10, -30}, lowY[4] = {-30, -30, -10, -10};
    std::vector<PointCloud> stations;
    for (std::size_t k = 0; k < 4; ++k) {
        test::SiteOptions o;
        o.points = 60000;
        o.seed = static_cast<unsigned>(10 + k);
        o.origin = origin;
        const PointCloud site = test::syntheticSite(o);
        std::vector<std::size_t> seen;
        for (std::size_t i = 0; i < site.size(); ++i) {
            const Eigen::Vector3d p = site.globalPosition(i) - origin;
            if (p.x() >= lowX[k] && p.x() <= lowX[k] + 40 && p.y() >= lowY[k] && p.y() <= lowY[k] + 40)
                seen.push_back(i);
        }
        PointCloud station = transformCloud(site.subset(seen), errors[k], "test");
        station.transformHistory().clear();
        station.name = "station" + std::to_string(k);
        stations.push_back(std::move(station));
    }
    return stations;
}

} // namespace

TEST(Stations, FourStationsCloseTheirLoopAndFindEveryPose)
{
    const Eigen::Vector3d origin(500000, 5400000, 120);
    const std::vector<Eigen::Matrix4d> errors = {Eigen::Matrix4d::Identity(),
                                                 test::rigidMotionAbout(2.0, 0.5, -0.3, Eigen::Vector3d(0.3, -0.2, 0.05), origin),
                                                 test::rigidMotionAbout(-1.5, -0.4, 0.6, Eigen::Vector3d(-0.25, 0.3, -0.1), origin),
                                                 test::rigidMotionAbout(1.0, 0.3, 0.2, Eigen::Vector3d(0.2, 0.35, 0.08), origin)};
    const std::vector<PointCloud> stations = fourStations(errors, origin);
    std::vector<const PointCloud*> pointers;
    for (const auto& s : stations)
        pointers.push_back(&s);
    const StationResult result = adjustStations(pointers, StationParams{});
    ASSERT_EQ(result.poses.size(), 4u);
    EXPECT_EQ(result.poses[0], Eigen::Matrix4d::Identity());
    for (std::size_t k = 1; k < 4; ++k) {
        // The pose undoes the station's error.
        const MotionError e = errorOf(result.poses[k], errors[k].inverse(), origin);
        EXPECT_LT(e.degrees, 0.005) << "station " << k;
        EXPECT_LT(e.metres, 0.003) << "station " << k;
    }
    // The ring's four neighbour pairs (the diagonals share only the centre)
    // and at least one loop, whose pairwise motions close within millimetres.
    EXPECT_GE(result.pairs.size(), 4u);
    ASSERT_GE(result.loops.size(), 1u);
    for (const auto& loop : result.loops) {
        EXPECT_EQ(loop.stations.front(), loop.stations.back());
        EXPECT_LT(loop.translationMetres, 0.01);
    }
    EXPECT_TRUE(result.report.converged);
    EXPECT_LT(result.report.median, 0.003);

    // Levelled stations: errors about Z only, four unknowns a station; the
    // poses keep the tilt exactly.
    const std::vector<Eigen::Matrix4d> headings = {Eigen::Matrix4d::Identity(),
                                                   test::rigidMotionAbout(3.0, 0, 0, Eigen::Vector3d(0.3, -0.2, 0.05), origin),
                                                   test::rigidMotionAbout(-2.0, 0, 0, Eigen::Vector3d(-0.25, 0.3, -0.1), origin),
                                                   test::rigidMotionAbout(1.5, 0, 0, Eigen::Vector3d(0.2, 0.35, 0.08), origin)};
    const std::vector<PointCloud> levelled = fourStations(headings, origin);
    std::vector<const PointCloud*> levelledPointers;
    for (const auto& s : levelled)
        levelledPointers.push_back(&s);
    StationParams four;
    four.constraint.dof = Dof::Four;
    const StationResult fourResult = adjustStations(levelledPointers, four);
    for (std::size_t k = 1; k < 4; ++k) {
        EXPECT_EQ(fourResult.poses[k](2, 2), 1.0);
        EXPECT_EQ(fourResult.poses[k](2, 0), 0.0);
        EXPECT_EQ(fourResult.poses[k](0, 2), 0.0);
        const MotionError e = errorOf(fourResult.poses[k], headings[k].inverse(), origin);
        EXPECT_LT(e.metres, 0.003) << "station " << k;
    }
}

TEST(Stations, BadInput)
{
    PointCloud one = test::syntheticSite(test::SiteOptions{2000, 1, 0.002, false, Eigen::Vector3d::Zero(), false});
    PointCloud far = test::syntheticSite(test::SiteOptions{2000, 2, 0.002, false, Eigen::Vector3d(500, 0, 0), false});
    PointCloud empty;
    EXPECT_EQ(test::errorCodeOf([&] { adjustStations({&one}, StationParams{}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { adjustStations({&one, &empty}, StationParams{}); }), ErrorCode::InvalidData);
    // A station that overlaps nothing: named, not silently left in place.
    try {
        adjustStations({&one, &far}, StationParams{});
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidData);
        EXPECT_NE(std::string(e.what()).find("station 1"), std::string::npos) << e.what();
    }
}

namespace {

//! Two independent samplings of a real scan: its points shared at random
//! between two clouds, the second moved by the inverse of `truth`.
std::pair<PointCloud, PointCloud> splitAndMove(const PointCloud& scan, const Eigen::Matrix4d& truth)
{
    std::vector<std::size_t> order(scan.size());
    for (std::size_t i = 0; i < order.size(); ++i)
        order[i] = i;
    std::mt19937 rng(12);
    std::shuffle(order.begin(), order.end(), rng);
    std::vector<std::size_t> a(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(order.size() / 2)),
        b(order.begin() + static_cast<std::ptrdiff_t>(order.size() / 2), order.end());
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    PointCloud moved = transformCloud(scan.subset(b), truth.inverse(), "test");
    moved.transformHistory().clear();
    return {scan.subset(a), std::move(moved)};
}

//! The largest displacement, over the corners of the scan's box, between two motions.
double displacementOver(const PointCloud& scan, const Eigen::Matrix4d& a, const Eigen::Matrix4d& b)
{
    const BoundingBox box = scan.bounds();
    double worst = 0;
    for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d p((k & 1) ? box.max.x() : box.min.x(), (k & 2) ? box.max.y() : box.min.y(),
                                (k & 4) ? box.max.z() : box.min.z());
        worst = std::max(worst, ((a - b) * p.homogeneous()).norm());
    }
    return worst;
}

} // namespace

TEST(RealScans, TwoSamplingsOfARealScanRegisterBack)
{
    // Real scans of PCL's data repository (data/pcl-data): a terrestrial scan
    // in millimetres, and an airborne LiDAR sample in UTM coordinates. Each
    // split in two samplings, one moved by a known motion; registered back,
    // fine from 20 degrees off, global from 120 degrees off.
    const PluginRegistry registry = makePluginRegistry();
    struct Case
    {
        const char* file;
        //! At the corners of the scan's box, in its unit: a tenth of the
        //! median spacing within a half or less (9 mm on the terrestrial scan, 1.1 m
        //! on the airborne one, where the halves share no point).
        double tolerance;
    };
    for (const Case& c : {Case{"region_growing_tutorial.pcd", 1.0}, Case{"samp11-utm.pcd", 0.1}}) {
        const PointCloud scan = io::readPointCloud(registry.formats, std::filesystem::path(SCANDIFF_SAMPLE_DATA_DIR) / "pcl-data" / c.file);
        const BoundingBox box = scan.bounds();
        const Eigen::Vector3d centre = (box.min + box.max) / 2;
        const double size = (box.max - box.min).norm();
        const Eigen::Matrix4d fine = test::rigidMotionAbout(20, 2, -1, Eigen::Vector3d(0.01, -0.02, 0.005) * size, centre);
        const auto [reference, moving] = splitAndMove(scan, fine);
        IcpParams params;
        params.kernel = RobustKernel::Cauchy;
        const IcpResult icp = icpRegister(moving, &reference, nullptr, params);
        EXPECT_LT(displacementOver(scan, icp.report.matrix, fine), c.tolerance) << c.file << " " << reportSummary(icp.report);

        const Eigen::Matrix4d far = test::rigidMotionAbout(120, 0, 0, Eigen::Vector3d(0.05, 0.03, 0) * size, centre);
        const auto [reference2, moving2] = splitAndMove(scan, far);
        GlobalAlignmentParams global;
        global.constraint.dof = Dof::Four;
        params.initial = globalAlign(moving2, &reference2, nullptr, global).report.matrix;
        const IcpResult icp2 = icpRegister(moving2, &reference2, nullptr, params);
        EXPECT_LT(displacementOver(scan, icp2.report.matrix, far), c.tolerance) << c.file << " " << reportSummary(icp2.report);
    }
}
