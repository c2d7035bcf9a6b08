// SPDX-License-Identifier: GPL-3.0-or-later
// Chi-square quantiles, noise fits and the local chi-square test (thesis 000 §3.2.3).

#include <scandiff/core/Error.h>
#include <scandiff/core/segmentation/StatisticalTest.h>

#include "TestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace scandiff;

TEST(ChiSquare, QuantilesMatchPublishedTables)
{
    // Values from the usual chi-square tables (e.g. Abramowitz & Stegun 26.8, NIST).
    struct Row { double p; int dof; double value; };
    const Row rows[] = {{0.95, 1, 3.841459}, {0.99, 1, 6.634897}, {0.95, 2, 5.991465}, {0.99, 3, 11.344867},
                        {0.999, 3, 16.266236}, {0.95, 10, 18.307038}, {0.99, 24, 42.979780}, {0.05, 5, 1.145476},
                        {0.5, 2, 2.0 * std::log(2.0)}, {0.999, 30, 59.703223}};
    for (const Row& r : rows)
        EXPECT_NEAR(chiSquareQuantile(r.p, r.dof), r.value, 1e-5 * r.value) << "p " << r.p << " dof " << r.dof;
}

TEST(ChiSquare, CdfHasItsClosedFormsAndRoundTrips)
{
    for (double x : {0.0, 0.1, 1.0, 3.0, 10.0, 50.0}) {
        EXPECT_NEAR(chiSquareCdf(x, 2), 1.0 - std::exp(-x / 2.0), 1e-14) << x;
        EXPECT_NEAR(regularizedGammaP(1.0, x), 1.0 - std::exp(-x), 1e-14) << x;
        EXPECT_NEAR(chiSquareCdf(x, 1), std::erf(std::sqrt(x / 2.0)), 1e-13) << x;
    }
    for (int dof : {1, 2, 7, 99})
        for (double p : {1e-4, 0.3, 0.9, 0.9999})
            EXPECT_NEAR(chiSquareCdf(chiSquareQuantile(p, dof), dof), p, 1e-11) << dof << " " << p;
    EXPECT_EQ(test::errorCodeOf([] { chiSquareQuantile(1.0, 3); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([] { chiSquareQuantile(0.5, 0); }), ErrorCode::InvalidArgument);
}

TEST(NoiseFit, WeibullFitRecoversShapeAndScale)
{
    std::mt19937 rng(3);
    for (double a : {1.0, 2.0, 3.0, 5.0}) {
        const double b = 0.7;
        std::weibull_distribution<double> w(a, b);
        std::vector<double> samples(20000);
        for (double& s : samples)
            s = w(rng);
        const NoiseDistribution d = fitNoise(samples, NoiseModel::Weibull);
        EXPECT_NEAR(d.shape, a, 0.03 * a) << "a " << a;
        EXPECT_NEAR(d.scale, b, 0.02 * b) << "a " << a;
        // Moments of eq. 3.5-3.6 against the sample.
        double mean = 0, squares = 0;
        for (double s : samples)
            mean += s;
        mean /= samples.size();
        for (double s : samples)
            squares += (s - mean) * (s - mean);
        EXPECT_NEAR(d.distributionMean(), mean, 0.01 * mean);
        EXPECT_NEAR(d.distributionVariance(), squares / samples.size(), 0.05 * squares / samples.size());
        EXPECT_NEAR(d.cdf(b), 1.0 - std::exp(-std::pow(b / d.scale, d.shape)), 1e-12);
    }
}

TEST(NoiseFit, GaussianFitAndBadSamples)
{
    std::mt19937 rng(4);
    std::normal_distribution<double> g(0.2, 0.05);
    std::vector<double> samples(10000);
    for (double& s : samples)
        s = g(rng);
    samples.push_back(std::nan(""));
    const NoiseDistribution d = fitNoise(samples, NoiseModel::Gaussian);
    EXPECT_NEAR(d.mean, 0.2, 2e-3);
    EXPECT_NEAR(d.sigma, 0.05, 1e-3);
    EXPECT_NEAR(d.cdf(0.2), 0.5, 0.02);
    EXPECT_EQ(test::errorCodeOf([] { fitNoise(std::vector<double>{1.0}, NoiseModel::Gaussian); }), ErrorCode::InvalidData);
    EXPECT_EQ(test::errorCodeOf([] { fitNoise(std::vector<double>{2.0, 2.0, 2.0}, NoiseModel::Weibull); }), ErrorCode::InvalidData);
    EXPECT_EQ(test::errorCodeOf([] { fitNoise(std::vector<double>{0.0, 0.0, std::nan("")}, NoiseModel::Weibull); }),
              ErrorCode::InvalidData);
    EXPECT_EQ(test::errorCodeOf([] { parseNoiseModel("poisson"); }), ErrorCode::InvalidArgument);
}

namespace {

//! A 6 m x 6 m jittered plane carrying a noise field, with a disc of radius
//! 1.2 m whose values are offset by 5 sigma. Returns the truth per point.
std::vector<int> noisyPlaneWithDisc(PointCloud& cloud, bool folded, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> jitter(-0.015f, 0.015f);
    std::normal_distribution<double> noise(0.0, 0.01);
    const double sigma = 0.01;
    std::vector<int> truth;
    std::vector<float> values;
    for (int i = 0; i < 200; ++i)
        for (int j = 0; j < 200; ++j) {
            const float x = 0.03f * i + jitter(rng), y = 0.03f * j + jitter(rng);
            cloud.positions().emplace_back(x, y, 0.0f);
            const bool inDisc = std::hypot(x - 3.0, y - 3.0) < 1.2;
            double v = noise(rng) + (inDisc ? 5.0 * sigma : 0.0);
            if (folded)
                v = std::abs(v);
            values.push_back(static_cast<float>(v));
            truth.push_back(inDisc);
        }
    ScalarField& f = cloud.addField("distance");
    f.values() = values;
    return truth;
}

double f1Score(const ScalarField& changed, const std::vector<int>& truth)
{
    double tp = 0, fp = 0, fn = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
        const bool c = changed.hasValue(i) && changed.value(i) > 0.5;
        tp += c && truth[i];
        fp += c && !truth[i];
        fn += !c && truth[i];
    }
    return 2 * tp / (2 * tp + fp + fn);
}

} // namespace

TEST(LocalChiSquare, LabelsADiscOffsetByFiveSigma)
{
    for (NoiseModel model : {NoiseModel::Gaussian, NoiseModel::Weibull}) {
        PointCloud cloud;
        // Weibull models unsigned distances: give it folded noise, as the thesis does.
        const std::vector<int> truth = noisyPlaneWithDisc(cloud, model == NoiseModel::Weibull, 21);
        // Fit on a zone known to be unchanged: the points outside the disc.
        std::vector<std::size_t> unchanged;
        for (std::size_t i = 0; i < truth.size(); ++i)
            if (!truth[i])
                unchanged.push_back(i);
        LocalChiSquareParams params;
        params.model = model;
        params.noise = fitNoise(*cloud.field("distance"), model, &unchanged);
        params.neighbours = 16;
        params.confidence = 0.999;
        const LocalChiSquareResult r = localChiSquareTest(cloud, "distance", params);
        EXPECT_EQ(r.classes, 4);
        // The tabulated quantile, and the calibrated cut: independent noise
        // values spread as chi-square says (lambda near 1), never below it.
        EXPECT_NEAR(r.quantileThreshold, 16.266236, 1e-4);
        EXPECT_GE(r.threshold, r.quantileThreshold);
        EXPECT_LT(r.nullScale, 1.1) << noiseModelName(model);
        LocalChiSquareParams tabulated = params;
        tabulated.calibration = NullCalibration::Tabulated;
        EXPECT_NEAR(localChiSquareTest(cloud, "distance", tabulated).threshold, 16.266236, 1e-4);
        EXPECT_EQ(r.chiSquare.name(), "chi2");
        const double f1 = f1Score(r.changed, truth);
        EXPECT_GE(f1, 0.95) << noiseModelName(model);
        // d_k lies in [0, n (k - 1)] with equiprobable classes.
        const ValueRange range = r.chiSquare.range();
        EXPECT_GE(range.min, 0.0);
        EXPECT_LE(range.max, 16.0 * 3.0 + 1e-3);
    }
}

TEST(LocalChiSquare, FitsTheWholeFieldWhenNoModelIsGivenAndSkipsNaN)
{
    PointCloud cloud;
    const std::vector<int> truth = noisyPlaneWithDisc(cloud, false, 5);
    ScalarField& f = *cloud.field("distance");
    for (std::size_t i = 0; i < f.size(); i += 97)
        f.values()[i] = std::nanf("");
    LocalChiSquareParams params;
    params.model = NoiseModel::Gaussian;
    const LocalChiSquareResult r = localChiSquareTest(cloud, "distance", params);
    // Every point without a value has no statistic and no label; the others have both.
    for (std::size_t i = 0; i < f.size(); ++i) {
        ASSERT_EQ(std::isnan(r.chiSquare.values()[i]), i % 97 == 0) << i;
        ASSERT_EQ(r.changed.hasValue(i), i % 97 != 0) << i;
    }
    // The model fitted on the whole field, disc included (a fifth of the
    // points 5 sigma off), still finds the disc.
    std::vector<int> valued = truth;
    for (std::size_t i = 0; i < valued.size(); i += 97)
        valued[i] = 0;
    EXPECT_GE(f1Score(r.changed, valued), 0.9);
    // A user threshold overrides the quantile and moves the cut: what the
    // stricter test labels changed, the looser one did too.
    params.threshold = 40.0;
    const LocalChiSquareResult strict = localChiSquareTest(cloud, "distance", params);
    EXPECT_EQ(strict.threshold, 40.0);
    EXPECT_LT(strict.changedCount, r.changedCount);
    for (std::size_t i = 0; i < f.size(); ++i)
        if (strict.changed.hasValue(i) && strict.changed.value(i) > 0.5)
            ASSERT_GT(r.changed.value(i), 0.5) << i;
}

TEST(LocalChiSquare, BadInputIsAnErrorNotACrash)
{
    PointCloud cloud;
    noisyPlaneWithDisc(cloud, false, 1);
    EXPECT_EQ(test::errorCodeOf([&] { localChiSquareTest(cloud, "nope"); }), ErrorCode::InvalidArgument);
    LocalChiSquareParams params;
    params.neighbours = 2;
    EXPECT_EQ(test::errorCodeOf([&] { localChiSquareTest(cloud, "distance", params); }), ErrorCode::InvalidArgument);
    params.neighbours = 16;
    params.confidence = 1.5;
    EXPECT_EQ(test::errorCodeOf([&] { localChiSquareTest(cloud, "distance", params); }), ErrorCode::InvalidArgument);
    PointCloud empty;
    empty.addField("distance");
    EXPECT_EQ(test::errorCodeOf([&] { localChiSquareTest(empty, "distance"); }), ErrorCode::InvalidData);
    PointCloud allNaN;
    allNaN.resize(10);
    allNaN.addField("distance");
    EXPECT_EQ(test::errorCodeOf([&] { localChiSquareTest(allNaN, "distance"); }), ErrorCode::InvalidData);
    PointCloud badPoint;
    badPoint.resize(10);
    badPoint.positions()[3].x() = std::nanf("");
    ScalarField& f = badPoint.addField("distance");
    for (std::size_t i = 0; i < 10; ++i)
        f.values()[i] = 0.1f * static_cast<float>(i + 1);
    EXPECT_EQ(test::errorCodeOf([&] { localChiSquareTest(badPoint, "distance"); }), ErrorCode::InvalidData);
}
