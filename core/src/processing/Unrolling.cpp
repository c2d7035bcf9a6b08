// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/processing/Unrolling.h>

#include <scandiff/core/Error.h>

#include <Eigen/Geometry>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace scandiff {

namespace {

constexpr double kPi = 3.14159265358979323846;

struct AxisFrame
{
    Eigen::Vector3d apex, w, e1, e2;
};

AxisFrame frameOf(const Primitive& s, double startAngleDegrees)
{
    if (s.kind != PrimitiveKind::Cylinder && s.kind != PrimitiveKind::Cone)
        throw Error(ErrorCode::InvalidArgument, std::string("unroll: the surface must be a cylinder or a cone, not a ") +
                                                    primitiveKindName(s.kind));
    if (!std::isfinite(startAngleDegrees))
        throw Error(ErrorCode::InvalidArgument, "unroll: the start angle must be finite");
    AxisFrame f;
    f.apex = s.point;
    f.w = s.direction.normalized();
    const Eigen::Vector3d reference = std::abs(f.w.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d e1 = (reference - reference.dot(f.w) * f.w).normalized();
    f.e1 = Eigen::AngleAxisd(startAngleDegrees * kPi / 180.0, f.w) * e1;
    f.e2 = f.w.cross(f.e1);
    return f;
}

template <typename Body>
void forEachPoint(std::size_t n, Body&& body)
{
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
            body(i);
    });
}

//! Positions from global coordinates computed in double, with an origin chosen for them.
void storeGlobal(PointCloud& out, const std::vector<Eigen::Vector3d>& global)
{
    BoundingBox box;
    for (const auto& g : global) {
        if (!g.allFinite())
            continue; // a point that was not finite stays so, and must not move the origin
        if (box.empty) {
            box.min = box.max = g;
            box.empty = false;
        }
        box.min = box.min.cwiseMin(g);
        box.max = box.max.cwiseMax(g);
    }
    out.setOrigin(suggestOrigin(box));
    forEachPoint(global.size(), [&](std::size_t i) { out.positions()[i] = (global[i] - out.origin()).cast<float>(); });
}

} // namespace

PointCloud unrollCloud(const PointCloud& cloud, const Primitive& s, double startAngleDegrees, ProgressObserver* progress)
{
    const AxisFrame f = frameOf(s, startAngleDegrees);
    const std::size_t n = cloud.size();
    PointCloud out = cloud.clone();
    out.dropPositionResiduals(); // its positions are rewritten below
    out.removeNormals();
    out.name = cloud.name + "_unrolled";
    ScalarField deviation(fields::kUnrollDeviation, n), angle(fields::kUnrollAngle, n);
    std::vector<Eigen::Vector3d> global(n);
    const bool cone = s.kind == PrimitiveKind::Cone;
    const double sinA = std::sin(s.halfAngle), cosA = std::cos(s.halfAngle);
    ProgressTicker ticker(progress, "Unrolling", n);
    forEachPoint(n, [&](std::size_t i) {
        const Eigen::Vector3d v = cloud.globalPosition(i) - f.apex;
        const double h = v.dot(f.w), x1 = v.dot(f.e1), x2 = v.dot(f.e2);
        double theta = std::atan2(x2, x1);
        if (theta < 0)
            theta += 2 * kPi;
        const double rho = std::hypot(x1, x2);
        double d;
        if (cone) {
            d = rho * cosA - h * sinA;
            const double along = rho * sinA + h * cosA; // s, along the generator
            const double phi = theta * sinA;
            global[i] = Eigen::Vector3d(along * std::cos(phi), along * std::sin(phi), d);
        } else {
            d = rho - s.radius;
            global[i] = Eigen::Vector3d(s.radius * theta, h, d);
        }
        deviation.setValue(i, d);
        angle.setValue(i, theta * 180.0 / kPi);
    });
    storeGlobal(out, global);
    out.addField(std::move(deviation));
    out.addField(std::move(angle));
    ticker.step(n);
    return out;
}

PointCloud rollCloud(const PointCloud& unrolled, const Primitive& s, double startAngleDegrees, ProgressObserver* progress)
{
    const AxisFrame f = frameOf(s, startAngleDegrees);
    const std::size_t n = unrolled.size();
    PointCloud out = unrolled.clone();
    out.dropPositionResiduals(); // its positions are rewritten below
    out.removeNormals();
    out.name = unrolled.name + "_rolled";
    std::vector<Eigen::Vector3d> global(n);
    const bool cone = s.kind == PrimitiveKind::Cone;
    const double sinA = std::sin(s.halfAngle), cosA = std::cos(s.halfAngle);
    ProgressTicker ticker(progress, "Rolling back", n);
    forEachPoint(n, [&](std::size_t i) {
        const Eigen::Vector3d u = unrolled.globalPosition(i);
        if (cone) {
            const double along = std::hypot(u.x(), u.y());
            double phi = std::atan2(u.y(), u.x());
            if (phi < 0)
                phi += 2 * kPi;
            const double theta = phi / sinA;
            const Eigen::Vector3d radial = std::cos(theta) * f.e1 + std::sin(theta) * f.e2;
            const Eigen::Vector3d generator = cosA * f.w + sinA * radial, outward = -sinA * f.w + cosA * radial;
            global[i] = f.apex + along * generator + u.z() * outward;
        } else {
            const double theta = u.x() / s.radius;
            const Eigen::Vector3d radial = std::cos(theta) * f.e1 + std::sin(theta) * f.e2;
            global[i] = f.apex + u.y() * f.w + (s.radius + u.z()) * radial;
        }
    });
    storeGlobal(out, global);
    ticker.step(n);
    return out;
}

} // namespace scandiff
