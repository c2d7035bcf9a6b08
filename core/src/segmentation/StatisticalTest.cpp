// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/segmentation/Classification.h>
#include <scandiff/core/segmentation/StatisticalTest.h>

#include "Neighbourhoods.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace scandiff {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

//! Series gamma(a, x) x^-a e^x Gamma(a)^-1 summed term by term: converges fast for x < a + 1.
double gammaPSeries(double a, double x)
{
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 1000; ++n) {
        term *= x / (a + n);
        sum += term;
        if (std::abs(term) < std::abs(sum) * 1e-16)
            break;
    }
    return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

//! Upper tail Q(a, x) by its continued fraction (modified Lentz evaluation):
//! converges fast for x >= a + 1, where the series would need many terms.
double gammaQContinuedFraction(double a, double x)
{
    constexpr double tiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
    for (int i = 1; i < 1000; ++i) {
        const double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (std::abs(d) < tiny)
            d = tiny;
        c = b + an / c;
        if (std::abs(c) < tiny)
            c = tiny;
        d = 1.0 / d;
        const double delta = d * c;
        h *= delta;
        if (std::abs(delta - 1.0) < 1e-16)
            break;
    }
    return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

double normalCdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

} // namespace

double regularizedGammaP(double a, double x)
{
    if (!(a > 0.0) || std::isnan(x))
        return kNaN;
    if (x <= 0.0)
        return 0.0;
    if (std::isinf(x))
        return 1.0;
    return x < a + 1.0 ? gammaPSeries(a, x) : 1.0 - gammaQContinuedFraction(a, x);
}

double chiSquareCdf(double x, int dof)
{
    if (dof < 1)
        return kNaN;
    return regularizedGammaP(0.5 * dof, 0.5 * x);
}

double chiSquareQuantile(double p, int dof)
{
    if (!(p > 0.0 && p < 1.0))
        throw Error(ErrorCode::InvalidArgument, "chi-square quantile: the confidence must be in (0, 1), got " + std::to_string(p));
    if (dof < 1)
        throw Error(ErrorCode::InvalidArgument, "chi-square quantile: at least 1 degree of freedom is needed");
    // Bracket the root: the CDF is increasing, and the mean dof plus many
    // standard deviations sqrt(2 dof) is far in the tail; double until above.
    double lo = 0.0, hi = dof + 10.0 * std::sqrt(2.0 * dof) + 10.0;
    while (chiSquareCdf(hi, dof) < p)
        hi *= 2.0;
    // Newton steps on the CDF (its derivative is the chi-square density), kept
    // inside the bracket; a step that leaves it is replaced by bisection.
    const double k = 0.5 * dof;
    double x = 0.5 * (lo + hi);
    for (int it = 0; it < 200; ++it) {
        const double f = chiSquareCdf(x, dof) - p;
        if (f < 0)
            lo = x;
        else
            hi = x;
        const double density = std::exp((k - 1.0) * std::log(x) - 0.5 * x - k * std::log(2.0) - std::lgamma(k));
        double next = density > 0 ? x - f / density : 0.5 * (lo + hi);
        if (!(next > lo && next < hi))
            next = 0.5 * (lo + hi);
        if (std::abs(next - x) <= 1e-13 * std::max(1.0, x))
            return next;
        x = next;
    }
    return x;
}

NoiseModel parseNoiseModel(const std::string& name)
{
    if (name == "gaussian" || name == "gauss" || name == "normal")
        return NoiseModel::Gaussian;
    if (name == "weibull")
        return NoiseModel::Weibull;
    throw Error(ErrorCode::InvalidArgument, "unknown noise model '" + name + "' (expected gaussian or weibull)");
}

const char* noiseModelName(NoiseModel model) { return model == NoiseModel::Gaussian ? "gaussian" : "weibull"; }

double NoiseDistribution::cdf(double x) const
{
    if (model == NoiseModel::Gaussian)
        return normalCdf((x - mean) / sigma);
    const double t = std::abs(x) / scale;
    return -std::expm1(-std::pow(t, shape));
}

double NoiseDistribution::distributionMean() const
{
    if (model == NoiseModel::Gaussian)
        return mean;
    return scale * std::tgamma(1.0 + 1.0 / shape);
}

double NoiseDistribution::distributionVariance() const
{
    if (model == NoiseModel::Gaussian)
        return sigma * sigma;
    const double g1 = std::tgamma(1.0 + 1.0 / shape);
    return scale * scale * (std::tgamma(1.0 + 2.0 / shape) - g1 * g1);
}

NoiseDistribution fitNoise(const std::vector<double>& samples, NoiseModel model)
{
    NoiseDistribution d;
    d.model = model;
    if (model == NoiseModel::Gaussian) {
        double sum = 0.0;
        std::size_t n = 0;
        for (double v : samples)
            if (std::isfinite(v)) {
                sum += v;
                ++n;
            }
        if (n < 2)
            throw Error(ErrorCode::InvalidData, "Gaussian fit: fewer than 2 finite samples");
        d.mean = sum / static_cast<double>(n);
        double squares = 0.0;
        for (double v : samples)
            if (std::isfinite(v))
                squares += (v - d.mean) * (v - d.mean);
        d.sigma = std::sqrt(squares / static_cast<double>(n));
        if (!(d.sigma > 0.0))
            throw Error(ErrorCode::InvalidData, "Gaussian fit: all samples are equal (zero spread)");
        return d;
    }

    // Weibull maximum likelihood. With y = x / max(x) (the shape does not depend
    // on the unit, and y <= 1 keeps y^a from overflowing) the shape a solves
    //   g(a) = sum(y^a ln y) / sum(y^a) - 1/a - mean(ln y) = 0,
    // g increasing in a; then b = max(x) * mean(y^a)^(1/a).
    std::vector<double> x;
    x.reserve(samples.size());
    std::size_t zeros = 0;
    for (double v : samples) {
        if (!std::isfinite(v))
            continue;
        const double a = std::abs(v);
        if (a > 0.0)
            x.push_back(a);
        else
            ++zeros;
    }
    if (zeros > 0)
        logWarning("Weibull fit: " + std::to_string(zeros) + " zero values skipped (the Weibull log-likelihood is undefined at 0)");
    if (x.size() < 2)
        throw Error(ErrorCode::InvalidData, "Weibull fit: fewer than 2 finite non-zero samples");
    const double top = *std::max_element(x.begin(), x.end());
    std::vector<double> logs(x.size());
    double meanLog = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        logs[i] = std::log(x[i] / top);
        meanLog += logs[i];
    }
    meanLog /= static_cast<double>(x.size());
    if (meanLog > -1e-12)
        throw Error(ErrorCode::InvalidData, "Weibull fit: all samples are equal (zero spread)");
    auto equation = [&](double a, double* slope) {
        double s0 = 0.0, s1 = 0.0, s2 = 0.0;
        for (double l : logs) {
            const double w = std::exp(a * l);
            s0 += w;
            s1 += w * l;
            s2 += w * l * l;
        }
        const double m1 = s1 / s0;
        if (slope)
            *slope = s2 / s0 - m1 * m1 + 1.0 / (a * a);
        return m1 - 1.0 / a - meanLog;
    };
    double lo = 1e-3, hi = 1e3;
    if (equation(hi, nullptr) < 0)
        throw Error(ErrorCode::InvalidData, "Weibull fit: the samples are too concentrated (shape above 1000)");
    double a = 2.0;
    for (int it = 0; it < 200; ++it) {
        double slope = 0.0;
        const double g = equation(a, &slope);
        if (g < 0)
            lo = a;
        else
            hi = a;
        double next = slope > 0 ? a - g / slope : 0.5 * (lo + hi);
        if (!(next > lo && next < hi))
            next = 0.5 * (lo + hi);
        const bool done = std::abs(next - a) < 1e-12 * a;
        a = next;
        if (done)
            break;
    }
    double meanPower = 0.0;
    for (double l : logs)
        meanPower += std::exp(a * l);
    meanPower /= static_cast<double>(logs.size());
    d.shape = a;
    d.scale = top * std::pow(meanPower, 1.0 / a);
    return d;
}

NoiseDistribution fitNoise(const ScalarField& field, NoiseModel model, const std::vector<std::size_t>* points)
{
    std::vector<double> samples;
    if (points) {
        samples.reserve(points->size());
        for (std::size_t i : *points) {
            if (i >= field.size())
                throw Error(ErrorCode::InvalidArgument, "noise fit: point index " + std::to_string(i) + " beyond the field");
            if (field.hasValue(i))
                samples.push_back(field.value(i));
        }
    } else {
        samples.reserve(field.size());
        for (std::size_t i = 0; i < field.size(); ++i)
            if (field.hasValue(i))
                samples.push_back(field.value(i));
    }
    try {
        return fitNoise(samples, model);
    } catch (const Error& e) {
        throw Error(e.code(), "field '" + field.name() + "': " + e.what());
    }
}

namespace {

//! The standard normal quantile, by Newton steps on the CDF from a logistic guess.
double normalQuantile(double p)
{
    double z = std::log(p / (1 - p)) / 1.702;
    for (int it = 0; it < 50; ++it) {
        const double density = std::exp(-0.5 * z * z) / std::sqrt(2 * 3.14159265358979323846);
        const double step = (normalCdf(z) - p) / density;
        z -= step;
        if (std::abs(step) < 1e-12)
            break;
    }
    return z;
}

//! The model fitted to the sorted values' probability plot by least squares
//! over the plotting positions [low, high] (Bernard's median ranks
//! (i - 0.3) / (m + 0.4)): the Gaussian's x against the normal quantile
//! (slope sigma, intercept the mean), the Weibull's ln x against
//! ln(-ln(1 - F)) (slope 1 / shape). Only the values between those positions
//! count, so a minority of changed values beyond them does not move the fit.
NoiseDistribution fitProbabilityPlot(const std::vector<double>& sorted, NoiseModel model, double low, double high)
{
    const double m = static_cast<double>(sorted.size());
    double sx = 0, sy = 0, sxx = 0, sxy = 0, count = 0; // x: the model's ordinate, y: the data
    for (std::size_t i = 0; i < sorted.size(); ++i) {
        const double f = (static_cast<double>(i) + 0.7) / (m + 0.4);
        if (f < low || f > high)
            continue;
        const double x = model == NoiseModel::Gaussian ? normalQuantile(f) : std::log(-std::log1p(-f));
        const double y = model == NoiseModel::Gaussian ? sorted[i] : std::log(sorted[i]);
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
        ++count;
    }
    NoiseDistribution d;
    d.model = model;
    const double spread = sxx - sx * sx / count;
    const double slope = count >= 2 && spread > 0 ? (sxy - sx * sy / count) / spread : 0.0;
    if (!(slope > 0))
        throw Error(ErrorCode::InvalidData, std::string(noiseModelName(model)) + " fit: the central values are all equal (zero spread)");
    const double intercept = (sy - slope * sx) / count;
    if (model == NoiseModel::Gaussian) {
        d.mean = intercept;
        d.sigma = slope;
    } else {
        d.shape = 1.0 / slope;
        d.scale = std::exp(intercept);
    }
    return d;
}

//! The values the model counts as noise: within its 0.9999 quantile
//! (the Gaussian: within 3.89 sigma either side).
bool withinNoise(const NoiseDistribution& d, double v)
{
    if (d.model == NoiseModel::Gaussian)
        return std::abs(v - d.mean) <= 3.8906 * d.sigma;
    return std::abs(v) <= d.scale * std::pow(-std::log(1e-4), 1.0 / d.shape);
}

} // namespace

NoiseDistribution fitNoiseRobust(const std::vector<double>& samples, NoiseModel model, std::size_t* rejected)
{
    std::vector<double> values;
    values.reserve(samples.size());
    for (double v : samples)
        if (std::isfinite(v) && (model == NoiseModel::Gaussian || v != 0.0))
            values.push_back(model == NoiseModel::Gaussian ? v : std::abs(v));
    if (values.size() < 20)
        return fitNoise(samples, model); // too few to tell noise from change: the plain fit and its errors
    std::sort(values.begin(), values.end());
    // The bulk first (the quartiles for the Gaussian, whose changes may lie
    // either side; 5-75 % for the Weibull of unsigned values, whose changes
    // are large), then, without the values beyond it, the plot over 5-90 %
    // (10-90 % for the Gaussian), which the test's outer classes need.
    NoiseDistribution d = model == NoiseModel::Gaussian ? fitProbabilityPlot(values, model, 0.25, 0.75)
                                                        : fitProbabilityPlot(values, model, 0.05, 0.75);
    std::vector<double> noise;
    for (int round = 0; round < 3; ++round) {
        noise.clear();
        for (double v : values)
            if (withinNoise(d, v))
                noise.push_back(v);
        if (noise.size() < 20)
            break;
        d = fitProbabilityPlot(noise, model, model == NoiseModel::Gaussian ? 0.1 : 0.05, 0.9);
    }
    if (rejected)
        *rejected = values.size() - noise.size();
    return d;
}

NullCalibration parseNullCalibration(const std::string& name)
{
    if (name == "spatial")
        return NullCalibration::Spatial;
    if (name == "tabulated")
        return NullCalibration::Tabulated;
    throw Error(ErrorCode::InvalidArgument, "unknown calibration '" + name + "' (expected spatial or tabulated)");
}

const char* nullCalibrationName(NullCalibration calibration)
{
    return calibration == NullCalibration::Spatial ? "spatial" : "tabulated";
}

namespace {

//! lambda such that d ~ lambda chi-square(dof) best matches the lower three
//! quarters of the observed distances' distribution: least squares between
//! their mid-distribution function (d takes discrete values: at a value, the
//! mean of the distribution just below and at it) and the scaled chi-square's,
//! minimised over log lambda by golden section.
double fitNullScale(const std::vector<float>& d, int dof)
{
    if (d.size() < 50)
        return 1.0;
    struct Step
    {
        double value, midCdf, weight;
    };
    std::vector<Step> steps;
    const double m = static_cast<double>(d.size());
    for (std::size_t i = 0; i < d.size();) {
        std::size_t j = i;
        while (j < d.size() && d[j] == d[i])
            ++j;
        const double below = static_cast<double>(i) / m, at = static_cast<double>(j) / m;
        const double mid = 0.5 * (below + at);
        if (mid > 0.75)
            break;
        steps.push_back({d[i], mid, at - below});
        i = j;
    }
    if (steps.size() < 2)
        return 1.0;
    const auto misfit = [&](double logScale) {
        const double scale = std::exp(logScale);
        double sum = 0;
        for (const Step& s : steps) {
            const double e = s.midCdf - chiSquareCdf(s.value / scale, dof);
            sum += s.weight * e * e;
        }
        return sum;
    };
    double lo = std::log(0.1), hi = std::log(100.0);
    const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
    double a = hi - golden * (hi - lo), b = lo + golden * (hi - lo), fa = misfit(a), fb = misfit(b);
    for (int it = 0; it < 80 && hi - lo > 1e-6; ++it) {
        if (fa < fb) {
            hi = b;
            b = a;
            fb = fa;
            a = hi - golden * (hi - lo);
            fa = misfit(a);
        } else {
            lo = a;
            a = b;
            fa = fb;
            b = lo + golden * (hi - lo);
            fb = misfit(b);
        }
    }
    return std::exp(0.5 * (lo + hi));
}

} // namespace

LocalChiSquareResult localChiSquareTest(const PointCloud& cloud, const std::string& fieldName,
                                        const LocalChiSquareParams& params, ProgressObserver* progress)
{
    const ScalarField* field = cloud.field(fieldName);
    if (!field)
        throw Error(ErrorCode::InvalidArgument, "chi-square test: cloud '" + cloud.name + "' has no field '" + fieldName + "'");
    if (params.neighbours < 4 || params.neighbours > 1024)
        throw Error(ErrorCode::InvalidArgument, "chi-square test: the neighbourhood size must be in [4, 1024], got " +
                                                    std::to_string(params.neighbours));
    if (!(params.confidence > 0.0 && params.confidence < 1.0))
        throw Error(ErrorCode::InvalidArgument, "chi-square test: the confidence must be in (0, 1)");
    if (params.threshold && !(*params.threshold >= 0.0 && std::isfinite(*params.threshold)))
        throw Error(ErrorCode::InvalidArgument, "chi-square test: the threshold must be a finite value >= 0");
    if (params.octreeLevel < 0 || params.octreeLevel > octree::kMaxLevel)
        throw Error(ErrorCode::InvalidArgument, "chi-square test: the octree level must be in [0, 21]");
    if (cloud.empty())
        throw Error(ErrorCode::InvalidData, "chi-square test: cloud '" + cloud.name + "' is empty");

    LocalChiSquareResult result;
    if (params.noise) {
        result.noise = *params.noise;
    } else {
        std::vector<double> samples;
        samples.reserve(field->size());
        for (std::size_t i = 0; i < field->size(); ++i)
            if (field->hasValue(i))
                samples.push_back(field->value(i));
        try {
            result.noise = fitNoiseRobust(samples, params.model, &result.fitRejected);
        } catch (const Error& e) {
            throw Error(e.code(), "field '" + field->name() + "': " + e.what());
        }
    }
    if (result.noise.model == NoiseModel::Gaussian ? !(result.noise.sigma > 0) : !(result.noise.shape > 0 && result.noise.scale > 0))
        throw Error(ErrorCode::InvalidArgument, "chi-square test: the noise model's spread and scale must be positive");
    const auto n = static_cast<std::size_t>(params.neighbours);
    const auto k = static_cast<std::size_t>(std::floor(std::sqrt(static_cast<double>(n))));
    result.classes = static_cast<int>(k);
    result.quantileThreshold = chiSquareQuantile(params.confidence, result.classes - 1);
    result.calibratedThreshold = result.quantileThreshold;

    // Each value's class under the model, computed once: with equiprobable
    // classes it is floor(k * F(v)).
    const std::size_t size = cloud.size();
    std::vector<std::int8_t> valueClass(size, -1);
    // Values beyond the model's 0.9999 quantile (two-sided for the Gaussian):
    // a neighbourhood holding one is left out of the calibration (1.6 % of
    // unchanged neighbourhoods of 16 hold one by chance: the bias is small).
    std::vector<std::uint8_t> beyondNoise(size, 0);
    for (std::size_t i = 0; i < size; ++i) {
        if (!field->hasValue(i))
            continue;
        const double f = result.noise.cdf(field->value(i));
        valueClass[i] = static_cast<std::int8_t>(std::min<std::size_t>(k - 1, static_cast<std::size_t>(std::max(0.0, f) * k)));
        beyondNoise[i] = result.noise.model == NoiseModel::Gaussian ? (f > 0.99995 || f < 0.00005) : f > 0.9999;
    }

    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    const int level = params.octreeLevel > 0 ? params.octreeLevel
                                             : tree.levelNearestMeanPopulation(std::max(8.0, 1.5 * static_cast<double>(n)));
    result.chiSquare = ScalarField(fields::kChiSquare, size);
    result.changed = ScalarField(fields::kChanged, size);
    std::vector<std::uint8_t> calm(size, 0); // the neighbourhood holds no value beyond the noise
    ProgressTicker ticker(progress, "Local chi-square test", size);
    detail::forEachNeighbourhood(tree, n, level, ticker, [&](std::size_t i, const octree::Neighbour* list, std::size_t count) {
        if (valueClass[i] < 0)
            return;
        std::size_t histogram[32] = {};
        std::size_t used = 0;
        bool quiet = true;
        for (std::size_t r = 0; r < count; ++r) {
            const std::int8_t c = valueClass[list[r].index];
            if (c < 0)
                continue;
            ++histogram[c];
            ++used;
            quiet = quiet && !beyondNoise[list[r].index];
        }
        if (used < 4)
            return; // too few values to say anything: no decision
        // eq. 3.1 with P_i = 1/k for every class.
        const double expected = static_cast<double>(used) / static_cast<double>(k);
        double d = 0.0;
        for (std::size_t c = 0; c < k; ++c) {
            const double diff = static_cast<double>(histogram[c]) - expected;
            d += diff * diff / expected;
        }
        result.chiSquare.values()[i] = static_cast<float>(d);
        calm[i] = quiet;
    });

    if (params.calibration == NullCalibration::Spatial) {
        std::vector<float> quietDistances;
        for (std::size_t i = 0; i < size; ++i)
            if (calm[i] && result.chiSquare.hasValue(i))
                quietDistances.push_back(result.chiSquare.values()[i]);
        result.nullScalePoints = quietDistances.size();
        std::sort(quietDistances.begin(), quietDistances.end());
        result.nullScale = std::max(1.0, fitNullScale(quietDistances, result.classes - 1));
        result.calibratedThreshold = result.nullScale * result.quantileThreshold;
        // The scaled law is fitted on the bulk; where the tail is heavier (large
        // neighbourhoods) or d's discrete values put the cut on a step, the
        // quiet points' own quantile is the higher cut. Only where it rests on
        // at least 10 exceedances.
        const double tail = (1.0 - params.confidence) * static_cast<double>(quietDistances.size());
        if (tail >= 10.0) {
            const auto at = static_cast<std::size_t>(std::ceil(params.confidence * static_cast<double>(quietDistances.size()))) - 1;
            result.empiricalThreshold = quietDistances[std::min(at, quietDistances.size() - 1)];
            result.calibratedThreshold = std::max(result.calibratedThreshold, result.empiricalThreshold);
        }
    }
    result.threshold = params.threshold.value_or(result.calibratedThreshold);
    // d is at most n (k - 1), every value in one class.
    if (result.threshold >= static_cast<double>(n * (k - 1)))
        logWarning("chi-square test: the cut " + std::to_string(result.threshold) + " is above the largest distance " +
                   std::to_string(n * (k - 1)) + " a neighbourhood of " + std::to_string(n) +
                   " can reach: nothing can be flagged. The field's neighbouring values are too alike for this test (" +
                   std::to_string(result.nullScale) +
                   " times the spread of independent draws): compute the distances with a local model, use more neighbours, "
                   "or segment by thresholds");
    for (std::size_t i = 0; i < size; ++i) {
        if (!result.chiSquare.hasValue(i))
            continue;
        const bool isChanged = result.chiSquare.values()[i] > result.threshold;
        result.changed.values()[i] = isChanged ? 1.0f : 0.0f;
        result.changedCount += isChanged;
    }
    return result;
}

} // namespace scandiff
