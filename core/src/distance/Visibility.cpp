// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/Visibility.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace scandiff {

namespace {

struct Angular
{
    double yaw, pitch, range;
};

Angular toAngular(const Eigen::Matrix3d& worldToSensor, const Eigen::Vector3d& sensorPosition, const Eigen::Vector3d& p)
{
    const Eigen::Vector3d local = worldToSensor * (p - sensorPosition);
    return {std::atan2(local.y(), local.x()), std::atan2(local.z(), std::hypot(local.x(), local.y())), local.norm()};
}

} // namespace

DepthMap::DepthMap(const PointCloud& reference, const SensorPose& pose, const VisibilityParams& params,
                   const std::vector<std::uint32_t>* pointsOfScan)
    : pose_(pose), worldToSensor_(pose.orientation.normalized().toRotationMatrix().transpose()), tolerance_(params.tolerance)
{
    if (!(params.tolerance >= 0))
        throw Error(ErrorCode::InvalidArgument, "visibility tolerance must be >= 0 m");
    if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite())
        throw Error(ErrorCode::InvalidArgument, "a viewpoint's position or orientation is not finite");
    const std::size_t count = pointsOfScan ? pointsOfScan->size() : reference.size();
    std::vector<Angular> angles;
    angles.reserve(count);
    double yawLo = std::numeric_limits<double>::infinity(), yawHi = -yawLo, pitchLo = yawLo, pitchHi = -yawLo;
    for (std::size_t j = 0; j < count; ++j) {
        const std::size_t i = pointsOfScan ? (*pointsOfScan)[j] : j;
        if (!reference.positions()[i].allFinite())
            continue;
        const Angular a = toAngular(worldToSensor_, pose.position, reference.globalPosition(i));
        if (a.range <= 0 || a.yaw < pose.yawMin || a.yaw > pose.yawMax || a.pitch < pose.pitchMin || a.pitch > pose.pitchMax)
            continue;
        angles.push_back(a);
        yawLo = std::min(yawLo, a.yaw);
        yawHi = std::max(yawHi, a.yaw);
        pitchLo = std::min(pitchLo, a.pitch);
        pitchHi = std::max(pitchHi, a.pitch);
    }
    if (angles.empty())
        throw Error(ErrorCode::InvalidData, "cloud '" + reference.name + "': no reference point lies in the viewpoint's field of view");
    yawStep_ = pose.yawStep;
    pitchStep_ = pose.pitchStep;
    if (!(yawStep_ > 0) || !(pitchStep_ > 0)) {
        // Without the scanner's steps, one cell per point over the covered angles.
        const double area = std::max(yawHi - yawLo, 1e-6) * std::max(pitchHi - pitchLo, 1e-6);
        const double step = std::sqrt(area / static_cast<double>(angles.size()));
        yawStep_ = yawStep_ > 0 ? yawStep_ : step;
        pitchStep_ = pitchStep_ > 0 ? pitchStep_ : step;
    }
    // The map covers the scan's own angular extent (its "arbitrary crop") plus half a step.
    yawMin_ = yawLo - 0.5 * yawStep_;
    pitchMin_ = pitchLo - 0.5 * pitchStep_;
    // Sizes in double first: a tiny step must give an error, not an int overflow.
    const double columns = std::ceil((yawHi - yawLo) / yawStep_) + 1, rows = std::ceil((pitchHi - pitchLo) / pitchStep_) + 1;
    if (!(columns * rows <= 4e8))
        throw Error(ErrorCode::InvalidArgument, "the depth map would need more than 4e8 cells: give larger angular steps");
    width_ = std::max(1, static_cast<int>(columns));
    height_ = std::max(1, static_cast<int>(rows));
    const float empty = -1.0f;
    range_.assign(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), empty);
    for (const Angular& a : angles) {
        const int u = std::clamp(static_cast<int>((a.yaw - yawMin_) / yawStep_), 0, width_ - 1);
        const int v = std::clamp(static_cast<int>((a.pitch - pitchMin_) / pitchStep_), 0, height_ - 1);
        float& cell = range_[static_cast<std::size_t>(v) * width_ + u];
        if (cell < 0 || a.range < cell)
            cell = static_cast<float>(a.range);
    }
    if (params.fillHoles) {
        std::vector<float> filled = range_;
        for (int v = 0; v < height_; ++v)
            for (int u = 0; u < width_; ++u) {
                if (range_[static_cast<std::size_t>(v) * width_ + u] >= 0)
                    continue;
                double sum = 0;
                int n = 0;
                for (int dv = -1; dv <= 1; ++dv)
                    for (int du = -1; du <= 1; ++du) {
                        const int uu = u + du, vv = v + dv;
                        if ((du || dv) && uu >= 0 && vv >= 0 && uu < width_ && vv < height_) {
                            const float r = range_[static_cast<std::size_t>(vv) * width_ + uu];
                            if (r >= 0) {
                                sum += r;
                                ++n;
                            }
                        }
                    }
                if (n >= 4)
                    filled[static_cast<std::size_t>(v) * width_ + u] = static_cast<float>(sum / n);
            }
        range_.swap(filled);
    }
    // Cells with no echo: the maximum range when known, else 0 ([ISPRS05] §4).
    const float noEcho = std::isfinite(pose.maxRange) ? static_cast<float>(pose.maxRange) : 0.0f;
    for (float& r : range_)
        if (r < 0)
            r = noEcho;
}

VisibilityLabel DepthMap::classify(const Eigen::Vector3d& globalPoint) const
{
    const Angular a = toAngular(worldToSensor_, pose_.position, globalPoint);
    const double u = (a.yaw - yawMin_) / yawStep_, v = (a.pitch - pitchMin_) / pitchStep_;
    if (!(u >= 0 && v >= 0 && u < width_ && v < height_))
        return VisibilityLabel::OutOfField;
    if (a.range > pose_.maxRange)
        return VisibilityLabel::OutOfRange;
    const float depth = range_[static_cast<std::size_t>(v) * width_ + static_cast<std::size_t>(u)];
    return a.range <= static_cast<double>(depth) + tolerance_ ? VisibilityLabel::Visible : VisibilityLabel::Hidden;
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
