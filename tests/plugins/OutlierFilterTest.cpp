// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/plugins/PluginRegistry.h>
#include <scandiff/plugins/outlier_filter/OutlierFilter.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace scandiff;

namespace {

PointCloud noisyPlaneWithOutliers(std::size_t n, std::mt19937& rng)
{
    PointCloud c;
    c.name = "plane";
    c.resize(n + 3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (std::size_t i = 0; i < n; ++i)
        c.positions()[i] = {u(rng), u(rng), 0.0f};
    c.positions()[n] = {0.5f, 0.5f, 3.0f};
    c.positions()[n + 1] = {5.0f, 5.0f, 0.0f};
    c.positions()[n + 2] = {-4.0f, 0.2f, 1.0f};
    c.addField("id");
    for (std::size_t i = 0; i < c.size(); ++i)
        c.field("id")->values()[i] = static_cast<float>(i);
    return c;
}

} // namespace

TEST(OutlierFilter, MeanDistancesEqualBruteForceAndOutliersGo)
{
    std::mt19937 rng(2024);
    const PointCloud cloud = noisyPlaneWithOutliers(2000, rng);
    plugins::OutlierFilterParams params;
    params.neighbours = 8;
    params.nSigma = 2.0;
    const auto result = plugins::statisticalOutliers(cloud, params);
    const auto& p = cloud.positions();
    for (std::size_t i = 0; i < cloud.size(); i += 37) {
        std::vector<float> d;
        for (std::size_t j = 0; j < cloud.size(); ++j)
            if (j != i)
                d.push_back((p[j] - p[i]).squaredNorm());
        std::sort(d.begin(), d.end());
        double sum = 0;
        for (int k = 0; k < 8; ++k)
            sum += std::sqrt(static_cast<double>(d[static_cast<std::size_t>(k)]));
        EXPECT_NEAR(result.meanDistances[i], sum / 8.0, 1e-6) << "point " << i;
    }
    // The three far points are removed, the plane is kept almost entirely.
    for (std::size_t i = 2000; i < 2003; ++i)
        EXPECT_FALSE(std::binary_search(result.inliers.begin(), result.inliers.end(), i)) << i;
    EXPECT_GT(result.inliers.size(), 1900u);
}

TEST(OutlierFilter, ToolKeepsAttributesAndLeavesInputUntouched)
{
    std::mt19937 rng(5);
    const PointCloud cloud = noisyPlaneWithOutliers(500, rng);
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec* tool = registry.tools.find("sor-filter");
    ASSERT_NE(tool, nullptr);
    const ToolResult result = tool->execute(ToolInputs().add("input", cloud), tool->resolve({{"k", "6"}, {"n-sigma", "1.5"}}), nullptr);
    const PointCloud& kept = result.cloud();
    EXPECT_EQ(cloud.size(), 503u);
    EXPECT_LT(kept.size(), 503u);
    ASSERT_NE(kept.field("id"), nullptr);
    ASSERT_NE(kept.field("sor_mean_distance"), nullptr);
    for (std::size_t i = 0; i < kept.size(); ++i) {
        const auto original = static_cast<std::size_t>(kept.field("id")->values()[i]);
        EXPECT_EQ(kept.positions()[i], cloud.positions()[original]);
    }
    EXPECT_NE(result.summary.find("kept"), std::string::npos);
}

TEST(OutlierFilter, RejectsBadInput)
{
    PointCloud empty;
    EXPECT_THROW(plugins::statisticalOutliers(empty, {}), Error);
    PointCloud withNan;
    withNan.resize(2);
    withNan.positions()[1] = {std::nanf(""), 0, 0};
    try {
        plugins::statisticalOutliers(withNan, {});
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidData);
    }
    PointCloud one;
    one.resize(1);
    plugins::OutlierFilterParams bad;
    bad.neighbours = 0;
    EXPECT_THROW(plugins::statisticalOutliers(one, bad), Error);
    // A single point has no neighbour: it is kept with a mean distance of 0.
    EXPECT_EQ(plugins::statisticalOutliers(one, {}).inliers.size(), 1u);
}
