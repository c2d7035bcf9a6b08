// SPDX-License-Identifier: GPL-3.0-or-later
// M3C2's scales guessed from the epochs, as CloudCompare's plugin offers
// ("Guess params") and py4dgeo's users ask for, on the criteria of Lague,
// Brodu and Leroux (2013), §3.2-3.3: a projection cylinder holding enough
// points of each epoch for the level of detection (they use about 30), and a
// normal scale about 20-25 times the roughness measured at that scale, so
// that the normal's orientation error stays within a few degrees.
#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/RobustStatistics.h>
#include <scandiff/core/distance/M3C2.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace scandiff {

namespace {

//! Every step-th point of the cloud, so that about `count` are taken.
std::vector<Eigen::Vector3f> samplesOf(const PointCloud& cloud, std::size_t count)
{
    const std::size_t step = std::max<std::size_t>(1, cloud.size() / std::max<std::size_t>(1, count));
    std::vector<Eigen::Vector3f> samples;
    for (std::size_t i = 0; i < cloud.size(); i += step)
        samples.push_back(cloud.positions()[i]);
    return samples;
}

//! The median distance from a point of the cloud to its nearest other point.
double medianSpacing(const PointCloud& cloud, const octree::Octree& tree, std::size_t sampleCount)
{
    const std::vector<Eigen::Vector3f> samples = samplesOf(cloud, sampleCount);
    std::vector<octree::Neighbour> neighbours;
    tree.nearestBatch(samples.data(), samples.size(), 2, tree.levelNearestMeanPopulation(8.0), neighbours);
    std::vector<double> distances;
    for (std::size_t i = 0; i < samples.size(); ++i)
        if (std::isfinite(neighbours[2 * i + 1].squaredDistance))
            distances.push_back(std::sqrt(neighbours[2 * i + 1].squaredDistance));
    return medianOf(std::move(distances));
}

//! Per sample, the moments of the cloud's points within `radius`.
std::vector<octree::NeighbourhoodMoments> momentsAround(const octree::Octree& tree, const std::vector<Eigen::Vector3f>& samples,
                                                        double radius)
{
    std::vector<octree::NeighbourhoodMoments> moments(samples.size());
    tree.radiusMomentsBatch(samples.data(), samples.size(), static_cast<float>(radius),
                            [&](std::uint32_t query, const octree::NeighbourhoodMoments& m) { moments[query] = m; });
    return moments;
}

//! The standard deviation of the points' distances to their best-fit plane.
double planeResidual(const octree::NeighbourhoodMoments& m)
{
    if (m.count < 3)
        return std::numeric_limits<double>::quiet_NaN();
    const double n = m.count;
    const Eigen::Vector3d mean = m.sum / n;
    Eigen::Matrix3d covariance;
    covariance << m.products[0], m.products[1], m.products[2], m.products[1], m.products[3], m.products[4], m.products[2],
        m.products[4], m.products[5];
    covariance = covariance / n - mean * mean.transpose();
    const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly).eigenvalues()(0);
    return std::sqrt(std::max(0.0, smallest));
}

//! Rounded up to two significant digits: a value a user can type, never
//! below what the criteria asked for.
double roundedUp(double value)
{
    if (!(value > 0))
        return value;
    const double unit = std::pow(10.0, std::floor(std::log10(value)) - 1);
    return std::ceil(value / unit - 1e-9) * unit;
}

} // namespace

M3c2ScaleGuess guessM3c2Scales(const PointCloud& reference, const PointCloud& compared, const M3c2ScaleGuessParams& params,
                               ProgressObserver* progress)
{
    if (params.samples < 10 || params.pointsPerCylinder < 3 || !(params.roughnessRatio > 0))
        throw Error(ErrorCode::InvalidArgument, "m3c2 scales: at least 10 samples, 3 points per cylinder and a positive roughness ratio");
    ProgressTicker ticker(progress, "M3C2: guessing the scales", 4);
    const octree::Octree referenceTree = buildOctree(reference, std::nullopt, progress);
    const octree::Octree comparedTree = buildOctree(compared, std::nullopt, progress);
    ticker.step();
    M3c2ScaleGuess guess;
    guess.spacing = std::max(medianSpacing(reference, referenceTree, params.samples), medianSpacing(compared, comparedTree, params.samples));
    if (!(guess.spacing > 0))
        throw Error(ErrorCode::InvalidData, "m3c2 scales: the epochs' points coincide; no spacing to start from");
    ticker.step();

    // The samples where both epochs are measured: reference points, and the
    // same places in the compared epoch's local frame.
    const std::vector<Eigen::Vector3f> samples = samplesOf(reference, params.samples);
    std::vector<Eigen::Vector3f> inCompared(samples.size());
    const Eigen::Vector3d shift = reference.origin() - compared.origin();
    for (std::size_t i = 0; i < samples.size(); ++i)
        inCompared[i] = (samples[i].cast<double>() + shift).cast<float>();

    // Projection scale: on a surface sampled every s, a disc of diameter d
    // holds about pi d^2 / (4 s^2) points; start there and widen until the
    // median sample holds enough in both epochs.
    const double start = 2.0 * guess.spacing * std::sqrt(static_cast<double>(params.pointsPerCylinder) / 3.14159265358979323846);
    for (double factor : {1.0, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0}) {
        const double d = params.projectionScale ? *params.projectionScale : roundedUp(start * factor);
        std::vector<double> inReference, inOther;
        for (const auto& m : momentsAround(referenceTree, samples, d / 2))
            inReference.push_back(m.count);
        for (const auto& m : momentsAround(comparedTree, inCompared, d / 2))
            inOther.push_back(m.count);
        guess.projectionScale = d;
        guess.medianPointsReference = medianOf(std::move(inReference));
        guess.medianPointsCompared = medianOf(std::move(inOther));
        if (params.projectionScale ||
            std::min(guess.medianPointsReference, guess.medianPointsCompared) >= static_cast<double>(params.pointsPerCylinder))
            break;
    }
    ticker.step();

    // Normal scale: the smallest multiple of d at which the surface is smooth
    // enough, D / sigma(D) >= the ratio at the median sample; at most 5 d; a
    // scene rough at every scale (a town: buildings) would otherwise get a
    // normal as wide as the site, where Lague's criterion, made for natural
    // surfaces, no longer says what a normal should see.
    for (double factor : {1.0, 1.5, 2.0, 3.0, 4.0, 5.0}) {
        const double D = roundedUp(guess.projectionScale * factor);
        std::vector<double> ratios;
        for (const auto& m : momentsAround(referenceTree, samples, D / 2)) {
            const double sigma = planeResidual(m);
            if (!std::isnan(sigma))
                ratios.push_back(sigma > 0 ? D / sigma : std::numeric_limits<double>::infinity());
        }
        guess.normalScale = D;
        guess.medianRoughnessRatio = medianOf(std::move(ratios));
        guess.roughnessRatioReached = guess.medianRoughnessRatio >= params.roughnessRatio;
        if (guess.roughnessRatioReached)
            break;
    }
    ticker.step();
    return guess;
}

} // namespace scandiff
