// SPDX-License-Identifier: GPL-3.0-or-later
// The visibility test of thesis 000 §2.3.3 with a depth map that represents
// the surface between its samples. The thesis's map keeps the smallest range
// per cell and compares a point's range with it, plus a tolerance; at grazing
// incidence (ground a few tens of metres from a tripod) the range changes by
// metres across one cell, so a point of the ground that the scanner saw is
// found "behind" the nearest sample of its cell and called hidden (24 % of the
// visible ground at 0.1 m, 49 % with a map step equal to the scan's). Here
// each cell keeps its samples, and a point's direction gets the range of the
// surface through the samples around it: the inverse range of a plane is
// linear in the direction (1/r = n.d / c), so it is fitted by least squares
// over the nearest samples of one surface (a jump in 1/r larger than a
// surface can make between them is an edge: the samples across it are left
// out), and the tolerance, a distance across the surface, is taken along the
// ray: tau / sin(grazing angle), the angle read off the same fit.
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/Visibility.h>

#include <tbb/parallel_for.h>

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace scandiff {

namespace {

constexpr double kPi = 3.14159265358979323846;

//! The nearest surface a ray can meet, seen from the scanner: the largest
//! change of 1/r per radian a surface at distance c from the scanner's
//! centre makes is 1/c, so a jump larger than this between two samples (per
//! radian between them) is an edge between two surfaces.
constexpr double kNearestSurface = 0.25; // m

//! A grazing angle below this does not widen the tolerance further: a
//! surface met at less than half a degree hides nothing a tripod could see.
constexpr double kSmallestGrazingSine = 0.0087; // sin 0.5 deg

//! Samples taken around a direction for the fit.
constexpr std::size_t kFitSamples = 8;

struct Angular
{
    double yaw, pitch, range;
};

Angular toAngular(const Eigen::Matrix3d& worldToSensor, const Eigen::Vector3d& sensorPosition, const Eigen::Vector3d& p)
{
    const Eigen::Vector3d local = worldToSensor * (p - sensorPosition);
    return {std::atan2(local.y(), local.x()), std::atan2(local.z(), std::hypot(local.x(), local.y())), local.norm()};
}

//! A sample of the reference scan near a direction: its angular offset from
//! the direction (radians, yaw scaled by the cosine of the pitch: lengths on
//! the unit sphere) and its inverse range.
struct Neighbour
{
    double x, y, inverseRange, distance2;
};

//! Whether the samples lie all around the direction (the origin of their
//! offsets): it is inside their convex hull when no half-plane through it
//! holds them all, i.e. no gap between their bearings reaches half a turn.
bool surrounds(const Neighbour* const* samples, std::size_t count)
{
    if (count < 3)
        return count > 0 && samples[0]->distance2 < 1e-18;
    std::array<double, 16> bearing{};
    for (std::size_t k = 0; k < count; ++k) {
        if (samples[k]->distance2 < 1e-18)
            return true; // on a sample
        bearing[k] = std::atan2(samples[k]->y, samples[k]->x);
    }
    std::sort(bearing.begin(), bearing.begin() + static_cast<std::ptrdiff_t>(count));
    double largestGap = bearing[0] + 2 * kPi - bearing[count - 1];
    for (std::size_t k = 1; k < count; ++k)
        largestGap = std::max(largestGap, bearing[k] - bearing[k - 1]);
    return largestGap < kPi;
}

} // namespace

DepthMap::DepthMap(const PointCloud& reference, const SensorPose& pose, const VisibilityParams& params,
                   const std::vector<std::uint32_t>* pointsOfScan)
    : pose_(pose), worldToSensor_(pose.orientation.normalized().toRotationMatrix().transpose()), tolerance_(params.tolerance),
      interpolate_(params.fillHoles)
{
    if (!(params.tolerance >= 0))
        throw Error(ErrorCode::InvalidArgument, "visibility tolerance must be >= 0 m");
    if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite())
        throw Error(ErrorCode::InvalidArgument, "a viewpoint's position or orientation is not finite");
    const std::vector<Sample> samples = collectSamples(reference, pointsOfScan);
    if (samples.empty())
        throw Error(ErrorCode::InvalidData, "cloud '" + reference.name + "': no reference point lies in the viewpoint's field of view");
    layOutGrid(samples);
    bucketSamples(samples);
}

std::vector<DepthMap::Sample> DepthMap::collectSamples(const PointCloud& reference, const std::vector<std::uint32_t>* pointsOfScan) const
{
    const std::size_t count = pointsOfScan ? pointsOfScan->size() : reference.size();
    std::vector<Sample> samples;
    samples.reserve(count);
    for (std::size_t j = 0; j < count; ++j) {
        const std::size_t i = pointsOfScan ? (*pointsOfScan)[j] : j;
        if (!reference.positions()[i].allFinite())
            continue;
        const Angular a = toAngular(worldToSensor_, pose_.position, reference.globalPosition(i));
        if (a.range <= 0 || a.yaw < pose_.yawMin || a.yaw > pose_.yawMax || a.pitch < pose_.pitchMin || a.pitch > pose_.pitchMax)
            continue;
        samples.push_back({a.yaw, a.pitch, static_cast<float>(1.0 / a.range)});
    }
    return samples;
}

void DepthMap::layOutGrid(const std::vector<Sample>& samples)
{
    double yawLo = std::numeric_limits<double>::infinity(), yawHi = -yawLo, pitchLo = yawLo, pitchHi = -yawLo;
    for (const Sample& s : samples) {
        yawLo = std::min(yawLo, s.yaw);
        yawHi = std::max(yawHi, s.yaw);
        pitchLo = std::min(pitchLo, s.pitch);
        pitchHi = std::max(pitchHi, s.pitch);
    }
    yawStep_ = pose_.yawStep;
    pitchStep_ = pose_.pitchStep;
    if (!(yawStep_ > 0) || !(pitchStep_ > 0)) {
        // Without the scanner's steps, one cell per point over the covered angles.
        const double area = std::max(yawHi - yawLo, 1e-6) * std::max(pitchHi - pitchLo, 1e-6);
        const double step = std::sqrt(area / static_cast<double>(samples.size()));
        yawStep_ = yawStep_ > 0 ? yawStep_ : step;
        pitchStep_ = pitchStep_ > 0 ? pitchStep_ : step;
    }
    // The map covers the scan's own angular extent (its "arbitrary crop") plus
    // half a step; a scan all around wraps, so the cells either side of the
    // back direction are neighbours.
    wraps_ = yawHi - yawLo + 2 * yawStep_ >= 2 * kPi;
    yawMin_ = wraps_ ? -kPi : yawLo - 0.5 * yawStep_;
    pitchMin_ = pitchLo - 0.5 * pitchStep_;
    // Sizes in double first: a tiny step must give an error, not an int overflow.
    const double columns = wraps_ ? std::ceil(2 * kPi / yawStep_) : std::ceil((yawHi - yawLo) / yawStep_) + 1;
    const double rows = std::ceil((pitchHi - pitchLo) / pitchStep_) + 1;
    if (!(columns * rows <= 4e8))
        throw Error(ErrorCode::InvalidArgument, "the depth map would need more than 4e8 cells: give larger angular steps");
    width_ = std::max(1, static_cast<int>(columns));
    height_ = std::max(1, static_cast<int>(rows));
    if (wraps_)
        yawStep_ = 2 * kPi / width_; // whole cells round the turn
}

int DepthMap::column(double yaw) const
{
    const int u = static_cast<int>(std::floor((yaw - yawMin_) / yawStep_));
    return wraps_ ? (u % width_ + width_) % width_ : u;
}

int DepthMap::row(double pitch) const { return static_cast<int>(std::floor((pitch - pitchMin_) / pitchStep_)); }

void DepthMap::bucketSamples(const std::vector<Sample>& samples)
{
    // Counting sort by cell: each cell's samples contiguous, cellStart_[c] to cellStart_[c + 1].
    const std::size_t cells = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
    cellStart_.assign(cells + 1, 0);
    std::vector<std::uint32_t> cellOf(samples.size());
    for (std::size_t i = 0; i < samples.size(); ++i) {
        const int u = std::clamp(column(samples[i].yaw), 0, width_ - 1), v = std::clamp(row(samples[i].pitch), 0, height_ - 1);
        cellOf[i] = static_cast<std::uint32_t>(static_cast<std::size_t>(v) * width_ + u);
        ++cellStart_[cellOf[i] + 1];
    }
    for (std::size_t c = 0; c < cells; ++c)
        cellStart_[c + 1] += cellStart_[c];
    samples_.resize(samples.size());
    std::vector<std::uint32_t> next(cellStart_.begin(), cellStart_.end() - 1);
    for (std::size_t i = 0; i < samples.size(); ++i)
        samples_[next[cellOf[i]]++] = samples[i];
}

DepthMap::SurfaceAlong DepthMap::surfaceAlong(double yaw, double pitch, int u, int v) const
{
    // The samples of the 3 x 3 cells around the direction, nearest first.
    std::array<Neighbour, 64> near;
    std::size_t count = 0;
    const double cosPitch = std::max(std::cos(pitch), 1e-6);
    bool ownCell = false;
    for (int dv = -1; dv <= 1; ++dv) {
        const int vv = v + dv;
        if (vv < 0 || vv >= height_)
            continue;
        for (int du = -1; du <= 1; ++du) {
            int uu = u + du;
            if (wraps_)
                uu = (uu + width_) % width_;
            else if (uu < 0 || uu >= width_)
                continue;
            const std::size_t cell = static_cast<std::size_t>(vv) * width_ + uu;
            for (std::uint32_t k = cellStart_[cell]; k < cellStart_[cell + 1]; ++k) {
                const Sample& s = samples_[k];
                const double x = std::remainder(s.yaw - yaw, 2 * kPi) * cosPitch, y = s.pitch - pitch;
                const Neighbour n{x, y, s.inverseRange, x * x + y * y};
                ownCell = ownCell || (du == 0 && dv == 0);
                if (count < near.size()) {
                    near[count++] = n;
                } else {
                    auto worst = std::max_element(near.begin(), near.end(), [](const Neighbour& a, const Neighbour& b) {
                        return a.distance2 < b.distance2;
                    });
                    if (n.distance2 < worst->distance2)
                        *worst = n;
                }
            }
        }
    }
    SurfaceAlong surface;
    if (count == 0)
        return surface;
    std::sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(count),
              [](const Neighbour& a, const Neighbour& b) { return a.distance2 < b.distance2; });
    // Within reach: a direction past a surface's last samples (above a wall's
    // top, beside its end) by more than about half a step sees beyond it.
    const double reach = 0.75 * std::hypot(yawStep_ * cosPitch, pitchStep_);
    if (interpolate_ ? near[0].distance2 > reach * reach : !ownCell)
        return surface;
    // The surface of the nearest sample: the samples whose inverse range a
    // surface could join to it, plus the tolerance's own share of 1/r. It
    // covers the direction only when its samples lie all around it: past its
    // last samples (a wall's top seen edge-on, narrower than a step) the ray
    // may pass by; then the next surface around, nearest first, is tried.
    std::array<const Neighbour*, kFitSamples> same;
    std::size_t used = 0;
    std::array<bool, 64> tried{};
    const Neighbour* anchor = nullptr;
    for (std::size_t first = 0; first < count && !anchor; ++first) {
        if (tried[first])
            continue;
        const Neighbour& candidate = near[first];
        const double slack = tolerance_ * candidate.inverseRange * candidate.inverseRange;
        used = 0;
        for (std::size_t k = first; k < count; ++k) {
            const double apart = std::hypot(near[k].x - candidate.x, near[k].y - candidate.y);
            if (std::abs(near[k].inverseRange - candidate.inverseRange) <= apart / kNearestSurface + slack) {
                tried[k] = true;
                if (used < kFitSamples)
                    same[used++] = &near[k];
            }
        }
        if (surrounds(same.data(), used))
            anchor = &candidate;
    }
    if (!anchor)
        return surface;
    // 1/r = a + b x + c y by least squares on those samples; with fewer than
    // three, or three in a line, the nearest one's value.
    double inverse = anchor->inverseRange, gradient = 0.0;
    if (used >= 3) {
        Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
        Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
        for (std::size_t k = 0; k < used; ++k) {
            const Eigen::Vector3d row(1.0, same[k]->x, same[k]->y);
            normal += row * row.transpose();
            rhs += row * same[k]->inverseRange;
        }
        const Eigen::LDLT<Eigen::Matrix3d> solver(normal);
        const Eigen::Vector3d fit = solver.solve(rhs);
        // A fit from samples in a line would extrapolate across it: kept
        // only when the three unknowns are well determined.
        const Eigen::Vector3d eigen = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(normal, Eigen::EigenvaluesOnly).eigenvalues();
        if (solver.info() == Eigen::Success && fit.allFinite() && eigen(0) > 1e-6 * eigen(2) && fit(0) > 0) {
            inverse = fit(0);
            gradient = std::hypot(fit(1), fit(2));
        }
    }
    surface.seen = true;
    surface.range = 1.0 / inverse;
    // |grad(1/r)| r = tan of the angle between the ray and the surface's
    // normal, so 1 / sin(grazing angle) = sqrt(1 + (|grad(1/r)| r)^2).
    const double tangent = gradient * surface.range;
    surface.alongRay = std::min(std::sqrt(1.0 + tangent * tangent), 1.0 / kSmallestGrazingSine);
    return surface;
}

VisibilityLabel DepthMap::classify(const Eigen::Vector3d& globalPoint) const
{
    const Angular a = toAngular(worldToSensor_, pose_.position, globalPoint);
    const int u = column(a.yaw), v = row(a.pitch);
    if (u < 0 || v < 0 || u >= width_ || v >= height_ || !std::isfinite(a.range))
        return VisibilityLabel::OutOfField;
    if (a.range > pose_.maxRange)
        return VisibilityLabel::OutOfRange;
    const SurfaceAlong surface = surfaceAlong(a.yaw, a.pitch, u, v);
    if (!surface.seen)
        return VisibilityLabel::Visible; // the ray met nothing the scanner saw: no echo there, or beyond an edge
    return a.range <= surface.range + tolerance_ * surface.alongRay ? VisibilityLabel::Visible : VisibilityLabel::Hidden;
}

bool DepthMap::inFreeSpace(const Eigen::Vector3d& globalPoint) const
{
    const Angular a = toAngular(worldToSensor_, pose_.position, globalPoint);
    const int u = column(a.yaw), v = row(a.pitch);
    if (u < 0 || v < 0 || u >= width_ || v >= height_ || !std::isfinite(a.range) || a.range > pose_.maxRange)
        return false;
    const SurfaceAlong surface = surfaceAlong(a.yaw, a.pitch, u, v);
    return surface.seen && a.range < surface.range - tolerance_ * surface.alongRay;
}

std::vector<VisibilityLabel> visibilityLabels(const PointCloud& compared, const PointCloud& reference,
                                              const std::vector<SensorPose>& viewpoints, const VisibilityParams& params,
                                              ProgressObserver* progress)
{
    if (viewpoints.empty())
        throw Error(ErrorCode::InvalidArgument, "the visibility test needs at least one reference viewpoint");
    // Which reference points belong to which scan, when the reference says so.
    std::vector<std::vector<std::uint32_t>> members(viewpoints.size());
    const ScalarField* scan = viewpoints.size() > 1 ? reference.field(params.scanIndexField) : nullptr;
    if (scan) {
        for (std::size_t i = 0; i < reference.size(); ++i) {
            const double s = scan->value(i);
            if (s >= 0 && s < static_cast<double>(viewpoints.size()))
                members[static_cast<std::size_t>(s)].push_back(static_cast<std::uint32_t>(i));
        }
    }
    std::vector<DepthMap> maps;
    for (std::size_t v = 0; v < viewpoints.size(); ++v) {
        if (scan && members[v].empty())
            throw Error(ErrorCode::InvalidData, "cloud '" + reference.name + "': no point has " + params.scanIndexField + " = " +
                                                    std::to_string(v) + ", the index of viewpoint " + std::to_string(v));
        maps.emplace_back(reference, viewpoints[v], params, scan ? &members[v] : nullptr);
    }

    std::vector<VisibilityLabel> labels(compared.size(), VisibilityLabel::OutOfField);
    ProgressTicker ticker(progress, "Visibility", compared.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, compared.size(), 8192), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            if (!compared.positions()[i].allFinite())
                continue;
            const Eigen::Vector3d p = compared.globalPosition(i);
            VisibilityLabel best = VisibilityLabel::OutOfField;
            for (const DepthMap& map : maps) {
                const VisibilityLabel label = map.classify(p);
                best = std::min(best, label);
                if (best == VisibilityLabel::Visible)
                    break;
            }
            labels[i] = best;
        }
        ticker.step(r.size());
    });
    return labels;
}

} // namespace scandiff
