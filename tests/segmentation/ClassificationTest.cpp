// SPDX-License-Identifier: GPL-3.0-or-later
// Thresholds and K-means (thesis 000 §3.2.1-3.2.2).

#include <scandiff/core/Error.h>
#include <scandiff/core/segmentation/Classification.h>

#include "TestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace scandiff;

namespace {

ScalarField fieldOf(const std::vector<float>& values)
{
    ScalarField f("d", values.size());
    f.values() = values;
    return f;
}

} // namespace

TEST(Classification, RangeLabelsEveryValueAndKeepsNaN)
{
    const float nan = std::nanf("");
    const ScalarField f = fieldOf({0.0f, 1.0f, 1.5f, nan, 2.0f, 5.0f});
    const ScalarField c = classifyByRange(f, 1.0, 2.0);
    EXPECT_EQ(c.name(), "changed");
    const std::vector<float> expected{0, 1, 1, nan, 1, 0};
    for (std::size_t i = 0; i < expected.size(); ++i) {
        if (std::isnan(expected[i]))
            EXPECT_TRUE(std::isnan(c.values()[i]));
        else
            EXPECT_EQ(c.values()[i], expected[i]) << i;
    }
    const ScalarField above = classifyByRange(f, 1.5, std::numeric_limits<double>::infinity());
    EXPECT_EQ(above.values()[1], 0.0f);
    EXPECT_EQ(above.values()[5], 1.0f);
    EXPECT_EQ(test::errorCodeOf([&] { classifyByRange(f, 2.0, 1.0); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { classifyByRange(f, std::nan(""), 1.0); }), ErrorCode::InvalidArgument);
}

TEST(Classification, KMeansSplitsBimodalDistancesAtTheGap)
{
    // 90 % unchanged (|N(0, 1 cm)|) and 10 % changed (N(0.5 m, 2 cm)), shuffled.
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 0.01), changed(0.5, 0.02);
    std::vector<float> values;
    std::vector<int> truth;
    for (int i = 0; i < 20000; ++i) {
        const bool isChanged = i % 10 == 3;
        values.push_back(static_cast<float>(isChanged ? changed(rng) : std::abs(noise(rng))));
        truth.push_back(isChanged);
    }
    values.push_back(std::nanf(""));
    truth.push_back(-1);
    const KMeansResult r = kMeans(fieldOf(values));
    ASSERT_EQ(r.centres.size(), 2u);
    EXPECT_TRUE(r.converged);
    EXPECT_LE(r.iterations, 20);
    EXPECT_NEAR(r.centres[0], 0.01 * std::sqrt(2.0 / M_PI), 1e-3); // mean of the folded normal
    EXPECT_NEAR(r.centres[1], 0.5, 2e-3);
    EXPECT_EQ(r.counts[0], 18000u);
    EXPECT_EQ(r.counts[1], 2000u);
    ASSERT_EQ(r.thresholds.size(), 1u);
    EXPECT_NEAR(r.thresholds[0], 0.5 * (r.centres[0] + r.centres[1]), 1e-12);
    for (std::size_t i = 0; i < truth.size(); ++i) {
        if (truth[i] < 0) {
            EXPECT_TRUE(std::isnan(r.changed.values()[i]));
            EXPECT_TRUE(std::isnan(r.classes.values()[i]));
            continue;
        }
        ASSERT_EQ(r.changed.values()[i], static_cast<float>(truth[i])) << i;
        ASSERT_EQ(r.classes.values()[i], static_cast<float>(truth[i])) << i;
    }
}

TEST(Classification, KMeansOnSignedValuesMarksBothSidesOfZeroChanged)
{
    std::vector<float> values;
    for (int i = 0; i < 30; ++i)
        values.push_back(static_cast<float>(i % 3 - 1) + 0.01f * static_cast<float>(i % 5));
    KMeansParams params;
    params.classes = 3;
    const KMeansResult r = kMeans(fieldOf(values), params);
    for (std::size_t i = 0; i < values.size(); ++i) {
        const int group = static_cast<int>(i % 3); // 0: -1, 1: 0, 2: +1
        EXPECT_EQ(r.classes.values()[i], static_cast<float>(group)) << i;
        EXPECT_EQ(r.changed.values()[i], group == 1 ? 0.0f : 1.0f) << i;
    }
}

TEST(Classification, KMeansRejectsBadInputWithoutCrashing)
{
    const float nan = std::nanf("");
    EXPECT_EQ(test::errorCodeOf([&] { kMeans(fieldOf({nan, nan, 1.0f})); }), ErrorCode::InvalidData);
    EXPECT_EQ(test::errorCodeOf([&] { kMeans(fieldOf({})); }), ErrorCode::InvalidData);
    KMeansParams one;
    one.classes = 1;
    EXPECT_EQ(test::errorCodeOf([&] { kMeans(fieldOf({1, 2, 3}), one); }), ErrorCode::InvalidArgument);
    // Identical values: one class takes everything, nothing is "changed".
    const KMeansResult same = kMeans(fieldOf({3, 3, 3, 3}));
    EXPECT_EQ(same.counts[0] + same.counts[1], 4u);
    for (float v : same.changed.values())
        EXPECT_EQ(v, 0.0f);
}

TEST(Classification, SelectionFromLabelsTakesOnesOnly)
{
    const auto s = selectionFromLabels(fieldOf({1, 0, std::nanf(""), 2, 0.4f}));
    EXPECT_EQ(s, (std::vector<std::uint8_t>{1, 0, 0, 1, 0}));
}
