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

//! A fit on values of which some are changes, not noise: the maximum-likelihood
//! fit above is pulled by them (a tail of 1 % of 0.3 m values turns the
//! Rayleigh-like Weibull of nearest-neighbour distances, shape 2, into an
//! exponential one, shape 1.1, and the test then flags a quarter of the
//! unchanged points). Fitted instead on the probability plot (least squares
//! of the sorted values against the model's quantiles) over its central part
//! (Gaussian: the quartiles; Weibull: 5-75 %), which holds while changes are
//! fewer than a quarter of the values; then, without the values beyond the
//! fit's 0.9999 quantile (two-sided for the Gaussian), over 5-90 % (10-90 %),
//! twice more: the classes of the test lie at the model's quantiles, and these
//! are what the fit matches. `rejected`, when given, receives the number of
//! values left out as not noise. Fewer than 20 values: fitNoise.
//! Throws as fitNoise.
NoiseDistribution fitNoiseRobust(const std::vector<double>& samples, NoiseModel model, std::size_t* rejected = nullptr);

//! How the cut on the chi-square distance is set.
//! Tabulated: the textbook quantile of chi-square with k - 1 degrees of
//! freedom (thesis 000 eq. 3.2), right when the n values of a neighbourhood
//! are independent draws. They are not in a distance field: neighbouring
//! points share their closest reference points and the surface between them,
//! so their distances move together and the classes' counts spread more than
//! a multinomial's (on two independent samplings of one terrain, d is about
//! 1.35 times chi-square with 3 degrees of freedom, and the tabulated cut at
//! 99 % flags 3.6 % of the unchanged points instead of 1 %).
//! Spatial: the null distribution is taken from the data themselves, as the
//! overdispersed multinomial gives it, d ~ lambda x chi-square(k - 1)
//! (lambda = 1 + (n - 1) rho, rho the correlation of neighbours' classes):
//! lambda is fitted on the points whose neighbourhoods hold no value beyond
//! the model's 0.9999 quantile (clear changes are left out: the quiet points),
//! by matching the lower three quarters of their d's distribution, and the cut
//! is lambda times the tabulated one (never lower: lambda >= 1), or the quiet
//! points' own quantile at the confidence when that is higher (the tail of d
//! is heavier than the scaled law's in large neighbourhoods, and d takes
//! discrete values) and rests on at least 10 values beyond it.
enum class NullCalibration { Spatial, Tabulated };
NullCalibration parseNullCalibration(const std::string& name); //!< "spatial", "tabulated"
const char* nullCalibrationName(NullCalibration calibration);

struct LocalChiSquareParams
{
    NoiseModel model = NoiseModel::Weibull;
    //! The noise model; when absent it is fitted on the whole field by
    //! fitNoiseRobust (a fit on a zone known to be unchanged is still better).
    std::optional<NoiseDistribution> noise;
    //! n, the neighbourhood size (the point itself included), in [4, 1024].
    //! The thesis gives no value; 16 keeps k = 4 classes and the test local.
    int neighbours = 16;
    //! Confidence p of the test, in (0, 1): the threshold is the p-quantile of
    //! chi-square with k - 1 degrees of freedom.
    double confidence = 0.99;
    //! Overrides the quantile threshold (the user moves the cut, thesis §3.2.3).
    std::optional<double> threshold;
    NullCalibration calibration = NullCalibration::Spatial;
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
    double quantileThreshold = 0.0;   //!< the tabulated value at the confidence
    double calibratedThreshold = 0.0; //!< the calibration's cut (= quantileThreshold when tabulated)
    double empiricalThreshold = 0.0;  //!< the quiet points' quantile (0 when not used)
    //! lambda of the spatial calibration (1 when tabulated), and the number of
    //! points it was fitted on.
    double nullScale = 1.0;
    std::size_t nullScalePoints = 0;
    //! Values the robust fit left out as not noise (0 when a model was given).
    std::size_t fitRejected = 0;
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
