// SPDX-License-Identifier: GPL-3.0-or-later
// Gradient, fast marching and gradient-constrained propagation (thesis 000 §3.3).

#include <scandiff/core/Error.h>
#include <scandiff/core/segmentation/FastMarching.h>

#include "TestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace scandiff;

namespace {

//! A jittered grid on the plane z = 0 over [0, side]^2.
PointCloud plane(int cells, double step, unsigned seed = 1)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> jitter(-0.25 * step, 0.25 * step);
    PointCloud c;
    for (int i = 0; i < cells; ++i)
        for (int j = 0; j < cells; ++j)
            c.positions().emplace_back(static_cast<float>((i + 0.5) * step + jitter(rng)),
                                       static_cast<float>((j + 0.5) * step + jitter(rng)), 0.0f);
    return c;
}

} // namespace

TEST(Gradient, LinearFieldGivesItsSlopeExactly)
{
    PointCloud c = plane(60, 0.05);
    ScalarField& f = c.addField("f");
    for (std::size_t i = 0; i < c.size(); ++i)
        f.setValue(i, 0.3 * c.positions()[i].x() - 0.4 * c.positions()[i].y() + 2.0);
    GradientParams params;
    params.radius = 0.15;
    const GradientResult g = gradientNorm(c, "f", params);
    EXPECT_EQ(g.radius, 0.15);
    for (std::size_t i = 0; i < c.size(); ++i)
        ASSERT_NEAR(g.norm.value(i), 0.5, 1e-4) << i; // least squares is exact on a linear field, even at the border

    // A constant field has no gradient; a steep one is clamped to 1 unless asked not to.
    for (std::size_t i = 0; i < c.size(); ++i)
        f.setValue(i, 7.0);
    EXPECT_NEAR(gradientNorm(c, "f", params).norm.range().max, 0.0, 1e-6);
    for (std::size_t i = 0; i < c.size(); ++i)
        f.setValue(i, 2.0 * c.positions()[i].x());
    EXPECT_NEAR(gradientNorm(c, "f", params).norm.range().max, 1.0, 1e-6);
    params.clampToOne = false;
    EXPECT_NEAR(gradientNorm(c, "f", params).norm.range().min, 2.0, 1e-3);
    // Smoothing keeps a constant norm as it is.
    params.smoothingSigma = 0.1;
    const GradientResult smooth = gradientNorm(c, "f", params);
    EXPECT_NEAR(smooth.norm.range().min, 2.0, 1e-3);
    EXPECT_NEAR(smooth.norm.range().max, 2.0, 1e-3);
}

TEST(Gradient, NaNValuesAndBadParameters)
{
    PointCloud c = plane(10, 0.1);
    ScalarField& f = c.addField("f");
    for (std::size_t i = 0; i < c.size(); ++i)
        f.setValue(i, c.positions()[i].x());
    f.values()[5] = std::nanf("");
    GradientParams params;
    params.radius = 0.25;
    const GradientResult g = gradientNorm(c, "f", params);
    EXPECT_TRUE(std::isnan(g.norm.values()[5]));
    EXPECT_NEAR(g.norm.values()[50], 1.0, 1e-4);
    EXPECT_EQ(test::errorCodeOf([&] { gradientNorm(c, "g"); }), ErrorCode::InvalidArgument);
    params.radius = -1;
    EXPECT_EQ(test::errorCodeOf([&] { gradientNorm(c, "f", params); }), ErrorCode::InvalidArgument);
}

TEST(FastMarching, OnAPlaneTimesAreEuclideanDistancesWithinTheGridError)
{
    const PointCloud c = plane(150, 0.02); // 3 m x 3 m
    const std::size_t seed = 75 * 150 + 75;
    for (int level : {0, 5, 6}) {
        FastMarchingParams params;
        params.level = level;
        const FastMarchingResult r = fastMarching(c, {seed}, params);
        if (level > 0) {
            EXPECT_EQ(r.level, level);
        }
        const Eigen::Vector3f s = c.positions()[seed];
        double worst = 0.0, sum = 0.0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            ASSERT_TRUE(r.arrivalTime.hasValue(i));
            const double exact = (c.positions()[i] - s).norm();
            const double error = r.arrivalTime.value(i) - exact;
            worst = std::max(worst, std::abs(error));
            sum += std::abs(error);
            // A front cannot arrive much before the straight line allows (the
            // second-order scheme may undershoot by a fraction of a cell).
            ASSERT_GE(error, -0.25 * r.cellSize) << i;
        }
        // The grid error: a cell and a half at worst (about one cell at a
        // grid node plus the step from the node to the point), a small
        // fraction of a cell on average.
        EXPECT_LE(worst, 1.5 * r.cellSize) << "level " << r.level << " cell " << r.cellSize;
        EXPECT_LE(sum / c.size(), 0.2 * r.cellSize) << "level " << r.level;
        EXPECT_EQ(r.arrivalTime.values()[seed], 0.0f);
    }
}

TEST(FastMarching, SeveralSeedsAndUnreachableParts)
{
    PointCloud c = plane(50, 0.02);
    // A far island the front cannot reach.
    for (int i = 0; i < 10; ++i)
        c.positions().emplace_back(5.0f + 0.02f * i, 5.0f, 5.0f);
    const FastMarchingResult r = fastMarching(c, {0, 49 * 50 + 49});
    EXPECT_TRUE(std::isnan(r.arrivalTime.values().back()));
    // The middle of the diagonal is equally far from both corner seeds.
    const Eigen::Vector3f a = c.positions()[0], b = c.positions()[49 * 50 + 49];
    const std::size_t middle = 25 * 50 + 25;
    const double expected = std::min((c.positions()[middle] - a).norm(), (c.positions()[middle] - b).norm());
    EXPECT_NEAR(r.arrivalTime.value(middle), expected, r.cellSize);
    EXPECT_EQ(test::errorCodeOf([&] { fastMarching(c, {}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { fastMarching(c, {c.size()}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { fastMarching(PointCloud{}, {0}); }), ErrorCode::InvalidArgument);
}

namespace {

//! Ground z = 0 over [0, 4]^2 (spacing 2 cm) with a 1 m x 1 m x 0.3 m box on
//! [1.5, 2.5]^2 (top and sides); the field is the height above the ground
//! (the distance to the reference ground plane). truth: 1 on the box.
PointCloud boxOnPlane(std::vector<int>& truth)
{
    PointCloud c;
    std::mt19937 rng(2);
    std::normal_distribution<double> noise(0.0, 0.002);
    auto add = [&](double x, double y, double z, int t) {
        c.positions().emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z + noise(rng)));
        truth.push_back(t);
    };
    const double step = 0.02;
    auto onBox = [](double x, double y) { return x > 1.5 && x < 2.5 && y > 1.5 && y < 2.5; };
    for (double x = 0.01; x < 4; x += step)
        for (double y = 0.01; y < 4; y += step)
            add(x, y, onBox(x, y) ? 0.3 : 0.0, onBox(x, y));
    for (double z = 0.01; z < 0.3; z += step)
        for (double t = 1.51; t < 2.5; t += step) {
            add(t, 1.5, z, 1);
            add(t, 2.5, z, 1);
            add(1.5, t, z, 1);
            add(2.5, t, z, 1);
        }
    ScalarField& f = c.addField("height");
    for (std::size_t i = 0; i < c.size(); ++i)
        f.setValue(i, std::max(0.0f, c.positions()[i].z()));
    return c;
}

} // namespace

TEST(Propagation, SegmentsABoxOnAPlaneAndStopsAtItsBorder)
{
    std::vector<int> truth;
    const PointCloud c = boxOnPlane(truth);
    PropagationParams params;
    params.minSeedValue = 0.1;
    params.gradient.radius = 0.06;
    params.minPoints = 50;
    const PropagationResult r = propagationSegmentation(c, "height", params);
    ASSERT_GE(r.regionCount, 1u);
    // One region: the box, its sides down to the ground, and no ground beyond
    // the gradient's reach (its radius) plus a cell.
    EXPECT_EQ(r.regionCount, 1u);
    std::size_t boxPoints = 0, boxInRegion = 0;
    const double reach = params.gradient.radius + r.cellSize;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const bool in = r.regionId.hasValue(i) && r.regionId.value(i) == 1.0;
        boxPoints += truth[i];
        boxInRegion += in && truth[i];
        if (in && !truth[i]) {
            const Eigen::Vector3f p = c.positions()[i];
            const double outside = std::max({1.5 - p.x(), p.x() - 2.5, 1.5 - p.y(), p.y() - 2.5});
            ASSERT_LE(outside, reach) << p.transpose();
        }
    }
    EXPECT_GE(static_cast<double>(boxInRegion), 0.98 * boxPoints);
    // Arrival times grow from the seed and exist on the region only.
    EXPECT_GE(r.arrivalTime.range().min, 0.0);
    for (std::size_t i = 0; i < c.size(); ++i)
        ASSERT_EQ(r.arrivalTime.hasValue(i), r.regionId.hasValue(i));
}

TEST(Propagation, TheThesisRuleAloneSplitsPlateausButNeverLeaks)
{
    std::vector<int> truth;
    const PointCloud c = boxOnPlane(truth);
    PropagationParams params;
    params.minSeedValue = 0.1;
    params.gradient.radius = 0.06;
    params.enterAboveSeedValue = false;
    const PropagationResult r = propagationSegmentation(c, "height", params);
    EXPECT_GE(r.regionCount, 1u);
    for (std::size_t i = 0; i < c.size(); ++i)
        if (r.regionId.hasValue(i) && !truth[i]) {
            const Eigen::Vector3f p = c.positions()[i];
            ASSERT_LE(std::max({1.5 - p.x(), p.x() - 2.5, 1.5 - p.y(), p.y() - 2.5}), 0.06 + r.cellSize);
        }
}

TEST(Propagation, BadParameters)
{
    std::vector<int> truth;
    const PointCloud c = boxOnPlane(truth);
    PropagationParams params; // no minimum seed value
    EXPECT_EQ(test::errorCodeOf([&] { propagationSegmentation(c, "height", params); }), ErrorCode::InvalidArgument);
    params.minSeedValue = 0.1;
    params.stopSpeed = 0;
    EXPECT_EQ(test::errorCodeOf([&] { propagationSegmentation(c, "height", params); }), ErrorCode::InvalidArgument);
    params.stopSpeed = 0.1;
    EXPECT_EQ(test::errorCodeOf([&] { propagationSegmentation(c, "nope", params); }), ErrorCode::InvalidArgument);
}
