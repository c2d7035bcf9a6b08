// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/plugins/registration/GlobalAlignment.h>

#include "FeatureMatching.h"

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/SplitMix.h>
#include <scandiff/core/processing/MeshSampling.h>
#include <scandiff/core/processing/Normals.h>
#include <scandiff/core/processing/Subsampling.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace scandiff::plugins {

namespace {

//! The spacing at which the reference keeps about `target` points: its
//! surface area (non-empty cells of a fine octree level times their face)
//! over the target, as a spacing s keeps about one point per s x s of surface.
double automaticSpacing(const PointCloud& reference, std::size_t target)
{
    constexpr int kLevel = 8; // cells 1/256 of the cloud's cube
    Eigen::Vector3f low = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), high = -low;
    for (const auto& p : reference.positions())
        if (p.allFinite()) {
            low = low.cwiseMin(p);
            high = high.cwiseMax(p);
        }
    const double side = static_cast<double>((high - low).maxCoeff());
    if (!(side > 0))
        throw Error(ErrorCode::InvalidData, "global alignment: the reference '" + reference.name + "' has no extent");
    const double cell = side / (1 << kLevel);
    const double cells = static_cast<double>(octreeSubsample(reference, kLevel).size());
    return std::max(cell, std::sqrt(cells * cell * cell / static_cast<double>(std::max<std::size_t>(target, 100))));
}

} // namespace

//! A cloud thinned to the spacing, with normals and descriptors; positions
//! relative to its centroid (double), which `centre` holds in global coordinates.
struct AlignmentFeatures
{
    double spacing = 0;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> points;
    std::vector<Eigen::Vector3d> normals; //!< unit
    std::vector<detail::Descriptor> descriptors;
    PointCloud thin; //!< every thinned point (global coordinates through its origin)
    std::vector<Eigen::Vector3f> thinNormals; //!< of every thinned point, zero where none
};

namespace {

AlignmentFeatures describe(const PointCloud& cloud, double spacing, ProgressObserver* progress)
{
    PointCloud thin = cloud.subset(spatialSubsample(cloud, spacing, progress));
    // Normals turned away from the centroid: a rule that moves with the cloud,
    // so both clouds' normals (and the descriptors, which depend on their
    // sides) agree whatever the motion between them.
    NormalParams normalParams;
    normalParams.radius = 2 * spacing;
    normalParams.orientation.kind = NormalOrientation::Kind::AwayFromCentroid;
    const NormalResult normals = computeNormals(thin, normalParams, progress);
    std::vector<Eigen::Vector3f> points, unitNormals;
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < thin.size(); ++i)
        if (normals.normals[i].squaredNorm() > 0) {
            points.push_back(thin.positions()[i]);
            unitNormals.push_back(normals.normals[i]);
            kept.push_back(i);
        }
    std::vector<detail::Descriptor> descriptors;
    std::vector<char> valid;
    detail::fpfhDescriptors(points, unitNormals, 5 * spacing, descriptors, valid);
    AlignmentFeatures d;
    d.spacing = spacing;
    for (std::size_t k = 0; k < kept.size(); ++k)
        if (valid[k]) {
            d.points.push_back(thin.globalPosition(kept[k]));
            d.normals.push_back(unitNormals[k].cast<double>());
            d.descriptors.push_back(descriptors[k]);
        }
    for (const auto& p : d.points)
        d.centre += p / static_cast<double>(d.points.size());
    for (auto& p : d.points)
        p -= d.centre;
    d.thin = std::move(thin);
    d.thinNormals = normals.normals;
    return d;
}

//! Matches as point pairs (moving, reference), each relative to its cloud's
//! centre, with their normals.
struct Matches
{
    std::vector<Eigen::Vector3d> x, y, nx, ny;
};

struct Hypothesis
{
    std::size_t inliers = 0;
    double squares = std::numeric_limits<double>::infinity();
    std::uint64_t index = std::numeric_limits<std::uint64_t>::max();
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    std::array<std::size_t, 3> picks{}; //!< the minimal set

    bool betterThan(const Hypothesis& o) const
    {
        if (inliers != o.inliers)
            return inliers > o.inliers;
        if (squares != o.squares)
            return squares < o.squares;
        return index < o.index;
    }
};

std::size_t minimalSetSize(Dof dof)
{
    return dof == Dof::Six ? 3 : dof == Dof::Four ? 2 : 1;
}

//! Counts the matches the motion brings within `tolerance`, and their squared distances.
void score(const Matches& m, const Eigen::Isometry3d& motion, double tolerance, Hypothesis& h)
{
    const double t2 = tolerance * tolerance;
    h.inliers = 0;
    h.squares = 0;
    for (std::size_t i = 0; i < m.x.size(); ++i) {
        const double d2 = (motion * m.x[i] - m.y[i]).squaredNorm();
        if (d2 < t2) {
            ++h.inliers;
            h.squares += d2;
        }
    }
}

//! The largest difference of the cosines between normals, and between
//! normals and the segment joining the points, that a right pair of matches
//! shows (normals fitted on thinned, noisy points: about 15 degrees). Compared
//! without sign: a normal's side may differ between the clouds.
constexpr double kCosineTolerance = 0.25;

//! Whether two matches can both be right: a rigid motion keeps the distance
//! between their points (and, about an axis, the height difference along it),
//! the angle between their normals and the normals' angles to the segment
//! (the pairwise consistency TEASER and spectral matching build on; Leordeanu
//! and Hebert 2005). Short segments fix the rotation poorly and are left out.
bool compatible(const Matches& m, std::size_t i, std::size_t j, const DofConstraint& constraint, double tolerance, double shortest)
{
    if (constraint.dof == Dof::Translation)
        return ((m.x[i] - m.y[i]) - (m.x[j] - m.y[j])).norm() <= tolerance;
    Eigen::Vector3d dx = m.x[j] - m.x[i], dy = m.y[j] - m.y[i];
    if (constraint.dof == Dof::Four) {
        const Eigen::Vector3d a = constraint.axis.normalized();
        if (std::abs(dx.dot(a) - dy.dot(a)) > tolerance)
            return false;
        const Eigen::Vector3d hx = dx - dx.dot(a) * a, hy = dy - dy.dot(a) * a;
        if (std::min(hx.norm(), hy.norm()) < shortest || std::abs(hx.norm() - hy.norm()) > tolerance)
            return false;
    }
    const double lx = dx.norm(), ly = dy.norm();
    if (std::min(lx, ly) < shortest || std::abs(lx - ly) > tolerance)
        return false;
    dx /= lx;
    dy /= ly;
    const auto differ = [](double a, double b) { return std::abs(std::abs(a) - std::abs(b)) > kCosineTolerance; };
    return !differ(m.nx[i].dot(m.nx[j]), m.ny[i].dot(m.ny[j])) && !differ(m.nx[i].dot(dx), m.ny[i].dot(dy)) &&
           !differ(m.nx[j].dot(dx), m.ny[j].dot(dy));
}

//! For each match, the matches it is compatible with (sorted).
std::vector<std::vector<std::uint32_t>> compatibilityLists(const Matches& m, const DofConstraint& constraint, double tolerance,
                                                           double shortest)
{
    const std::size_t n = m.x.size();
    std::vector<std::vector<std::uint32_t>> lists(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
        for (std::size_t j = 0; j < n; ++j)
            if (j != i && compatible(m, i, j, constraint, tolerance, shortest))
                lists[i].push_back(static_cast<std::uint32_t>(j));
    });
    return lists;
}

//! Hypothesis `index`: a minimal set of mutually compatible matches (the
//! first at random, each next one among those compatible with all before),
//! fitted and scored. Drawing within the compatibility graph is what makes
//! RANSAC work when only a few matches in a hundred are right: given a right
//! first match, the next is right far more often than a random one.
bool tryHypothesis(const Matches& m, const std::vector<std::vector<std::uint32_t>>& lists, const GlobalAlignmentParams& params,
                   double tolerance, std::uint64_t index, Hypothesis& h)
{
    const std::size_t size = minimalSetSize(params.constraint.dof);
    SplitMix64 rng(params.seed, index);
    const std::size_t first = static_cast<std::size_t>(rng.below(m.x.size()));
    h.picks = {first, first, first};
    if (size > 1) {
        const auto& candidates = lists[first];
        if (candidates.size() < size - 1)
            return false;
        h.picks[1] = candidates[static_cast<std::size_t>(rng.below(candidates.size()))];
        if (size > 2) {
            h.picks[2] = candidates[static_cast<std::size_t>(rng.below(candidates.size()))];
            const auto& second = lists[h.picks[1]];
            if (h.picks[2] == h.picks[1] ||
                !std::binary_search(second.begin(), second.end(), static_cast<std::uint32_t>(h.picks[2])))
                return false;
        }
    }
    std::vector<Eigen::Vector3d> x, y;
    for (std::size_t k = 0; k < size; ++k) {
        x.push_back(m.x[h.picks[k]]);
        y.push_back(m.y[h.picks[k]]);
    }
    if (!fitPointToPoint(x, y, std::vector<double>(size, 1.0), params.constraint, h.motion))
        return false;
    for (std::size_t k = 0; k < size; ++k)
        if ((h.motion * x[k] - y[k]).norm() > tolerance)
            return false;
    h.index = index;
    score(m, h.motion, tolerance, h);
    return true;
}

//! The best hypotheses so far, one per family of motions, best first. Two
//! motions are of one family when they move the moving cloud's points apart
//! by less than `separation` (the rotation's effect at `radius` plus the
//! translation's): a wrong motion that many matches nearly agree on then fills
//! one place, not all of them.
class Leaderboard
{
public:
    Leaderboard(std::size_t capacity, double radius, double separation)
        : capacity_(capacity), radius_(radius), separation_(separation)
    {
    }

    void offer(const Hypothesis& h)
    {
        constexpr double kRadiansPerDegree = 3.14159265358979323846 / 180.0;
        for (Hypothesis& t : top_)
            if (rotationDegrees(t.motion.linear().transpose() * h.motion.linear()) * kRadiansPerDegree * radius_ +
                    (t.motion.translation() - h.motion.translation()).norm() <
                separation_) {
                if (h.betterThan(t))
                    t = h;
                sort();
                return;
            }
        if (top_.size() < capacity_)
            top_.push_back(h);
        else if (h.betterThan(top_.back()))
            top_.back() = h;
        else
            return;
        sort();
    }
    const std::vector<Hypothesis>& top() const { return top_; }

private:
    void sort()
    {
        std::sort(top_.begin(), top_.end(), [](const Hypothesis& a, const Hypothesis& b) { return a.betterThan(b); });
    }
    std::size_t capacity_;
    double radius_, separation_;
    std::vector<Hypothesis> top_;
};

//! RANSAC in rounds of hypotheses scored in parallel, offered to the
//! leaderboard in index order, so the result does not depend on the number of
//! threads. Agreement among descriptor matches is a weak score where few
//! matches are right and the site repeats itself (boxes turned a quarter turn
//! match many corners): the leaders are verified on the whole geometry after.
std::vector<Hypothesis> ransac(const Matches& m, const std::vector<std::vector<std::uint32_t>>& lists,
                               const GlobalAlignmentParams& params, double tolerance, ProgressObserver* progress, std::uint64_t& drawn)
{
    constexpr std::uint64_t kRound = 4096;
    const std::size_t size = minimalSetSize(params.constraint.dof);
    ProgressTicker ticker(progress, "Global alignment: matching", params.maxIterations);
    // The moving points' RMS radius about their centre (the frame's origin).
    double spread = 0;
    for (const auto& p : m.x)
        spread += p.squaredNorm() / static_cast<double>(m.x.size());
    Leaderboard leaders(64, std::sqrt(spread), 5 * tolerance);
    drawn = 0;
    while (drawn < params.maxIterations) {
        const std::uint64_t count = std::min<std::uint64_t>(kRound, params.maxIterations - drawn);
        std::vector<Hypothesis> results(count);
        std::vector<char> scored(count, 0);
        tbb::parallel_for(std::uint64_t(0), count,
                          [&](std::uint64_t k) { scored[k] = tryHypothesis(m, lists, params, tolerance, drawn + k, results[k]); });
        for (std::uint64_t k = 0; k < count; ++k)
            if (scored[k] && results[k].inliers >= 2 * size)
                leaders.offer(results[k]);
        drawn += count;
        ticker.step(count);
    }
    return leaders.top();
}

//! The moving points a motion is verified on, spread evenly over the
//! directions of their normals (normal-space sampling, Rusinkiewicz and Levoy
//! 2001): at most `perBin` from each of 6 x 12 bins of the half sphere. On a
//! site that is mostly ground, a wrong turn about the vertical still lands
//! most points on ground; what tells it from the right one is the walls, and
//! this gives each orientation of wall as much say as the ground.
std::vector<std::size_t> normalSpaceSample(const AlignmentFeatures& d, std::size_t perBin)
{
    constexpr int kPolar = 6, kAzimuth = 12;
    constexpr double kPi = 3.14159265358979323846;
    std::vector<std::vector<std::size_t>> bins(kPolar * kAzimuth);
    for (std::size_t i = 0; i < d.points.size(); ++i) {
        Eigen::Vector3d n = d.normals[i];
        if (n.z() < 0)
            n = -n;
        const int polar = std::min(kPolar - 1, static_cast<int>(std::acos(std::min(1.0, n.z())) / (kPi / 2) * kPolar));
        const int azimuth = polar == 0 ? 0 : std::min(kAzimuth - 1, static_cast<int>((std::atan2(n.y(), n.x()) + kPi) / (2 * kPi) * kAzimuth));
        auto& bin = bins[static_cast<std::size_t>(polar * kAzimuth + azimuth)];
        // Every k-th point of a bin rather than its first ones: spread over the cloud.
        bin.push_back(i);
    }
    std::vector<std::size_t> sample;
    for (const auto& bin : bins) {
        const std::size_t step = std::max<std::size_t>(1, bin.size() / perBin);
        for (std::size_t k = 0; k < bin.size() && k / step < perBin; k += step)
            sample.push_back(bin[k]);
    }
    std::sort(sample.begin(), sample.end());
    return sample;
}

//! Verifies candidate motions on the geometry: the moving points of a
//! normal-space sample, matched on the reference's thinned points (nearest,
//! within the tolerance, normals agreeing within 30 degrees either side).
class Verifier
{
public:
    Verifier(const AlignmentFeatures& moving, const AlignmentFeatures& reference, double spacing, double tolerance, const DofConstraint& constraint)
        : moving_(moving), reference_(reference), spacing_(spacing), tolerance_(tolerance), constraint_(constraint),
          tree_(buildOctree(reference.thin)), level_(tree_.levelNearestMeanPopulation(8.0)), sample_(normalSpaceSample(moving, 200)),
          shift_(reference.centre - reference.thin.origin())
    {
        double spread = 0;
        for (std::size_t i : sample_)
            spread += moving.points[i].squaredNorm();
        length_ = std::max(std::sqrt(spread / static_cast<double>(std::max<std::size_t>(sample_.size(), 1))), spacing);
    }

    //! The share of the sample a motion lands on the reference: within the
    //! tolerance, or, with `planeTolerance`, also within it of the matched
    //! point's tangent plane.
    //! `rms`, when given, receives the RMS distance to the planes of the landed points.
    double share(const Eigen::Isometry3d& motion, double planeTolerance, double* rms = nullptr) const
    {
        match(motion);
        std::size_t landed = 0;
        double sum2 = 0;
        for (std::size_t k = 0; k < sample_.size(); ++k) {
            const double r = normals_[k].dot(x_[k] - y_[k]);
            if (found_[k] && std::abs(r) <= planeTolerance) {
                ++landed;
                sum2 += r * r;
            }
        }
        if (rms)
            *rms = landed ? std::sqrt(sum2 / static_cast<double>(landed)) : std::numeric_limits<double>::quiet_NaN();
        return static_cast<double>(landed) / static_cast<double>(std::max<std::size_t>(sample_.size(), 1));
    }

    //! A few point-to-plane ICP steps on the sample: a right candidate,
    //! within about a spacing, settles on the surfaces; a wrong one does not.
    Eigen::Isometry3d refine(Eigen::Isometry3d motion, int steps) const
    {
        for (int step = 0; step < steps; ++step) {
            match(motion);
            std::vector<Eigen::Vector3d> xs, ys, ns;
            for (std::size_t k = 0; k < sample_.size(); ++k)
                if (found_[k]) {
                    xs.push_back(x_[k]);
                    ys.push_back(y_[k]);
                    ns.push_back(normals_[k]);
                }
            Eigen::Isometry3d delta;
            Eigen::MatrixXd normalMatrix;
            if (xs.size() < 12 ||
                !stepPointToPlane(xs, ys, ns, std::vector<double>(xs.size(), 1.0), constraint_, length_, delta, normalMatrix))
                break;
            motion = delta * motion;
        }
        return motion;
    }

private:
    void match(const Eigen::Isometry3d& motion) const
    {
        const std::size_t n = sample_.size();
        queries_.resize(n);
        x_.resize(n);
        y_.resize(n);
        normals_.resize(n);
        found_.assign(n, 0);
        for (std::size_t k = 0; k < n; ++k) {
            x_[k] = motion * moving_.points[sample_[k]];
            queries_[k] = (x_[k] + shift_).cast<float>();
        }
        tree_.nearestBatch(queries_.data(), n, 1, level_, nearest_);
        const float t2 = static_cast<float>(tolerance_ * tolerance_);
        for (std::size_t k = 0; k < n; ++k) {
            const std::uint32_t j = nearest_[k].index;
            if (j == std::numeric_limits<std::uint32_t>::max() || nearest_[k].squaredDistance > t2)
                continue;
            const Eigen::Vector3d n = reference_.thinNormals[j].cast<double>();
            if (std::abs(n.dot(motion.linear() * moving_.normals[sample_[k]])) < 0.866)
                continue;
            y_[k] = reference_.thin.positions()[j].cast<double>() - shift_;
            normals_[k] = n;
            found_[k] = 1;
        }
    }

    const AlignmentFeatures& moving_;
    const AlignmentFeatures& reference_;
    double spacing_, tolerance_;
    DofConstraint constraint_;
    octree::Octree tree_;
    int level_;
    std::vector<std::size_t> sample_;
    Eigen::Vector3d shift_;
    double length_ = 1;
    mutable std::vector<Eigen::Vector3f> queries_;
    mutable std::vector<octree::Neighbour> nearest_;
    mutable std::vector<Eigen::Vector3d> x_, y_, normals_;
    mutable std::vector<char> found_;
};

} // namespace

GlobalAlignmentResult globalAlign(const PointCloud& moving, const PointCloud* referenceCloud, const Mesh* referenceMesh,
                                  const GlobalAlignmentParams& params, ProgressObserver* progress)
{
    if (!(params.inlierSpacings > 0) || params.maxIterations == 0 ||
        (params.spacing && !(*params.spacing > 0 && std::isfinite(*params.spacing))))
        throw Error(ErrorCode::InvalidArgument, "global alignment: the spacing, inlier spacings and hypotheses are > 0");
    if (moving.empty())
        throw Error(ErrorCode::InvalidData, "global alignment: the moving cloud '" + moving.name + "' is empty");
    PointCloud sampled;
    if (referenceMesh) {
        // Dense enough that the thinning, not the sampling, sets the spacing.
        MeshSamplingParams sampling;
        sampling.count = std::max<std::size_t>(20 * params.targetPoints, 100000);
        sampling.normals = false;
        sampled = sampleMesh(*referenceMesh, sampling, progress);
        referenceCloud = &sampled;
    }
    if (referenceCloud->empty())
        throw Error(ErrorCode::InvalidData, "global alignment: the reference cloud '" + referenceCloud->name + "' is empty");
    const double spacing = params.spacing ? *params.spacing : automaticSpacing(*referenceCloud, params.targetPoints);
    const auto a = describeForAlignment(moving, spacing, progress), b = describeForAlignment(*referenceCloud, spacing, progress);
    return globalAlign(*a, *b, params, progress);
}

double alignmentSpacing(const PointCloud& reference, std::size_t targetPoints)
{
    return automaticSpacing(reference, targetPoints);
}

std::shared_ptr<const AlignmentFeatures> describeForAlignment(const PointCloud& cloud, double spacing, ProgressObserver* progress)
{
    if (!(spacing > 0 && std::isfinite(spacing)))
        throw Error(ErrorCode::InvalidArgument, "global alignment: the spacing must be > 0");
    if (cloud.empty())
        throw Error(ErrorCode::InvalidData, "global alignment: the cloud '" + cloud.name + "' is empty");
    return std::make_shared<const AlignmentFeatures>(describe(cloud, spacing, progress));
}

GlobalAlignmentResult globalAlign(const AlignmentFeatures& a, const AlignmentFeatures& b, const GlobalAlignmentParams& params,
                                  ProgressObserver* progress)
{
    if (!(params.inlierSpacings > 0) || params.maxIterations == 0)
        throw Error(ErrorCode::InvalidArgument, "global alignment: the inlier spacings and hypotheses are > 0");
    if (a.spacing != b.spacing)
        throw Error(ErrorCode::InvalidArgument, "global alignment: both clouds must be described at one spacing");
    const double spacing = a.spacing;
    const std::size_t size = minimalSetSize(params.constraint.dof);
    const auto pairs = detail::matchDescriptors(a.descriptors, b.descriptors, 50);
    Matches m;
    for (const auto& [i, j] : pairs) {
        if (params.constraint.dof == Dof::Four) {
            // A turn about the axis keeps each normal's angle to it.
            const Eigen::Vector3d axis = params.constraint.axis.normalized();
            if (std::abs(std::abs(a.normals[i].dot(axis)) - std::abs(b.normals[j].dot(axis))) > kCosineTolerance)
                continue;
        }
        m.x.push_back(a.points[i]);
        m.y.push_back(b.points[j]);
        m.nx.push_back(a.normals[i]);
        m.ny.push_back(b.normals[j]);
    }
    if (m.x.size() < 3 * size)
        throw Error(ErrorCode::InvalidData, "global alignment: only " + std::to_string(m.x.size()) +
                                                " descriptor matches at a spacing of " + std::to_string(spacing) +
                                                " m; the clouds have too little shape at this scale (give --spacing)");
    const double tolerance = params.inlierSpacings * spacing;
    const auto lists = compatibilityLists(m, params.constraint, tolerance, 2 * spacing);
    std::uint64_t drawn = 0;
    const std::vector<Hypothesis> leaders = ransac(m, lists, params, tolerance, progress, drawn);
    if (leaders.empty() || leaders.front().inliers < std::max<std::size_t>(3 * size, 6))
        throw Error(ErrorCode::InvalidData, "global alignment: no motion is agreed on by more than " +
                                                std::to_string(leaders.empty() ? 0 : leaders.front().inliers) + " of " +
                                                std::to_string(m.x.size()) +
                                                " descriptor matches; the clouds may not overlap, or give a start with --initial");
    // The leaders verified on the geometry, not on the matches: each is
    // scored by the share of the moving points it lands on the reference; the
    // 16 best are refined by a few ICP steps and scored again, on the tangent
    // planes this time (a quarter spacing), and the best of those wins.
    const Verifier verifier(a, b, spacing, tolerance, params.constraint);
    std::vector<std::pair<double, std::size_t>> coarse;
    for (std::size_t i = 0; i < leaders.size(); ++i)
        coarse.emplace_back(-verifier.share(leaders[i].motion, tolerance), i);
    std::sort(coarse.begin(), coarse.end());
    struct Refined
    {
        Hypothesis h;
        double share, rms;
    };
    std::vector<Refined> refined;
    for (std::size_t k = 0; k < std::min<std::size_t>(16, coarse.size()); ++k) {
        Hypothesis h = leaders[coarse[k].second];
        h.motion = verifier.refine(h.motion, 10);
        double rms = 0;
        const double share = verifier.share(h.motion, 0.25 * spacing, &rms);
        refined.push_back({h, share, rms});
    }
    std::stable_sort(refined.begin(), refined.end(), [](const Refined& x, const Refined& y) { return x.share > y.share; });
    Hypothesis best = refined.front().h;
    const double bestShare = refined.front().share, bestRms = refined.front().rms;
    score(m, best.motion, tolerance, best);

    GlobalAlignmentResult result;
    result.spacing = spacing;
    result.matches = m.x.size();
    result.inliers = best.inliers;
    RegistrationReport& report = result.report;
    report.method = std::string("global (FPFH, RANSAC), ") + dofName(params.constraint.dof) + " DOF";
    // y + cb = R (x_global - ca) + t + cb  ->  global matrix T(cb) [R t] T(-ca).
    Eigen::Matrix4d toB = Eigen::Matrix4d::Identity(), fromA = Eigen::Matrix4d::Identity();
    toB.topRightCorner<3, 1>() = b.centre;
    fromA.topRightCorner<3, 1>() = -a.centre;
    const auto global = [&](const Eigen::Isometry3d& motion) { return Eigen::Matrix4d(toB * motion.matrix() * fromA); };
    report.matrix = global(best.motion);
    // The next distinct motions by share (a symmetric site lands most of its
    // points under a half turn too: the caller may weigh them on every point).
    std::vector<Eigen::Isometry3d> kept{best.motion};
    for (const Refined& r : refined) {
        if (result.alternatives.size() + 1 >= params.alternatives || r.share < 0.5 * bestShare)
            break;
        bool distinct = true;
        for (const Eigen::Isometry3d& k : kept)
            distinct = distinct && (rotationDegrees(k.linear().transpose() * r.h.motion.linear()) > 2.0 ||
                                    (k.translation() - r.h.motion.translation()).norm() > 2 * spacing);
        if (!distinct)
            continue;
        kept.push_back(r.h.motion);
        result.alternatives.push_back(global(r.h.motion));
    }
    report.centre = a.centre;
    report.rms = bestRms; // of the verification points that landed
    report.median = report.p90 = report.p95 = report.p99 = std::numeric_limits<double>::quiet_NaN();
    report.overlap = std::numeric_limits<double>::quiet_NaN(); // the matches' agreement is in the notes
    report.iterations = static_cast<std::size_t>(drawn);
    report.converged = true;
    report.notes.push_back(std::to_string(best.inliers) + " of " + std::to_string(m.x.size()) + " descriptor matches agree (within " +
                           std::to_string(tolerance) + " m), spacing " + std::to_string(spacing) + " m, " + std::to_string(drawn) +
                           " hypotheses; " + std::to_string(static_cast<int>(std::lround(100 * bestShare))) +
                           " % of the moving points (spread over normal directions) land on the reference's surface");
    return result;
}

} // namespace scandiff::plugins
