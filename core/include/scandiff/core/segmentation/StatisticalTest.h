// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Local statistical classification of thesis 000 §3.2.3: a noise model
//! (Gaussian or Weibull) is fitted on distances known to be unchanged, then
//! each point's neighbourhood is tested against it with a chi-square
//! goodness-of-fit test; neighbourhoods that do not look like noise are changed.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/ScalarField.h>

#include <optional>
#include <string>
#include <vector>

namespace scandiff {

//! Regularized lower incomplete gamma P(a, x) = gamma(a, x) / Gamma(a), a > 0, x >= 0.
double regularizedGammaP(double a, double x);
//! P(X <= x) for X ~ chi-square with `dof` degrees of freedom (dof >= 1).
double chiSquareCdf(double x, int dof);
//! The x with chiSquareCdf(x, dof) = p, for p in (0, 1): the test threshold at
//! confidence p. Relative accuracy ~1e-10 (bisection-safeguarded Newton on the CDF).
//! Throws Error(InvalidArgument) for p outside (0, 1) or dof < 1.
double chiSquareQuantile(double p, int dof);

enum class NoiseModel { Gaussian, Weibull };

//! "gaussian", "weibull"; throws Error(InvalidArgument) otherwise.
NoiseModel parseNoiseModel(const std::string& name);
const char* noiseModelName(NoiseModel model);

//! A fitted noise distribution.
//! Gaussian: N(mean, sigma^2) of the values.
//! Weibull (eq. 3.4, shift x0 = 0): P(x) = (a/b) (x/b)^(a-1) exp(-(x/b)^a) of the
//! *absolute* values, since the thesis's distances are unsigned.
struct NoiseDistribution
{
    NoiseModel model = NoiseModel::Gaussian;
    double mean = 0.0, sigma = 1.0; //!< Gaussian parameters
    double shape = 2.0, scale = 1.0; //!< Weibull a and b

    //! P(X <= x), x being the field value (Weibull: its absolute value).
    double cdf(double x) const;
    //! Mean and variance of the modelled quantity (Weibull: eq. 3.5-3.6).
    double distributionMean() const;
    double distributionVariance() const;
};

//! Maximum-likelihood fits. Gaussian: sample mean and (population) standard
//! deviation. Weibull: the profile-likelihood equation for the shape solved by
//! bracketed Newton, then the scale in closed form; zero values are skipped
//! (their log-likelihood is undefined) with a warning.
//! Throws Error(InvalidData) for fewer than 2 usable finite samples or a zero spread.
NoiseDistribution fitNoise(const std::vector<double>& samples, NoiseModel model);
//! Fits on the valid values of `field`, or only on those of `points` if given
//! (the indices of a zone the user knows to be unchanged).
NoiseDistribution fitNoise(const ScalarField& field, NoiseModel model, const std::vector<std::size_t>* points = nullptr);

struct LocalChiSquareParams
{
    NoiseModel model = NoiseModel::Weibull;
    //! The noise model; when absent it is fitted on the whole field (the changed
    //! points then inflate it: give a fit on an unchanged zone when possible).
    std::optional<NoiseDistribution> noise;
    //! n, the neighbourhood size (the point itself included), in [4, 1024].
    //! The thesis gives no value; 16 keeps k = 4 classes and the test local.
    int neighbours = 16;
    //! Confidence p of the test, in (0, 1): the threshold is the p-quantile of
    //! chi-square with k - 1 degrees of freedom.
    double confidence = 0.99;
    //! Overrides the quantile threshold (the user moves the cut, thesis §3.2.3).
    std::optional<double> threshold;
    //! Octree level for the neighbour search, 0 = automatic. Speed only.
    int octreeLevel = 0;
};

struct LocalChiSquareResult
{
    ScalarField chiSquare;     //!< "chi2": d_k per point; NaN without a value or with < 4 valid neighbours
    ScalarField changed;       //!< "changed": 1 when d_k > threshold, 0 otherwise, NaN where chi2 is NaN
    NoiseDistribution noise;   //!< the model used
    int classes = 0;           //!< k = floor(sqrt(n))
    double threshold = 0.0;    //!< the cut applied
    double quantileThreshold = 0.0; //!< the tabulated value at the confidence (= threshold unless overridden)
    std::size_t changedCount = 0;
};

//! The local chi-square test (eq. 3.1): for every point, the histogram of the
//! field over its n nearest neighbours in k = floor(sqrt(n)) classes is
//! compared with the noise model. Classes are equiprobable under the model
//! (bounds at its k-quantiles), so every class expects n/k values and d_k ranges
//! from 0 to n(k-1); the tabulated chi-square quantile is the default threshold.
//! Neighbours without a value are left out of the histogram.
//! Throws Error(InvalidArgument) for bad parameters or a missing field,
//! Error(InvalidData) for an empty cloud or non-finite coordinates, Error(Cancelled).
LocalChiSquareResult localChiSquareTest(const PointCloud& cloud, const std::string& fieldName,
                                        const LocalChiSquareParams& params = {}, ProgressObserver* progress = nullptr);

} // namespace scandiff
