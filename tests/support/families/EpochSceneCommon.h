// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Shared helpers of the two-epoch scene families (AirborneEpochsFamily.h,
//! TerrainChangeFamily.h): seeded draws that give the same numbers on every
//! platform (SplitMix64 and our own Box-Muller, never std::normal_distribution),
//! building a cloud from global coordinates with the project's origin rule,
//! rigid motions about a pivot, percentiles and a smooth value-noise field.
//!
//! Depends only on Eigen, the standard library and the data-model headers.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/SplitMix.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace scandiff::test::family::epochscene {

constexpr double kPi = 3.14159265358979323846;

inline double degToRad(double d) { return d * kPi / 180.0; }
inline double radToDeg(double r) { return r * 180.0 / kPi; }

inline double uniform(SplitMix64& rng, double a, double b) { return a + (b - a) * rng.uniform(); }

//! Log-uniform in [a, b] (a, b > 0): spacing and sizes span decades.
inline double logUniform(SplitMix64& rng, double a, double b) { return a * std::pow(b / a, rng.uniform()); }

//! Standard normal by Box-Muller (one value per call; the second is dropped so
//! the draw sequence does not depend on call history).
inline double gaussian(SplitMix64& rng)
{
    const double u1 = 1.0 - rng.uniform(); // (0, 1]: log is finite
    const double u2 = rng.uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

//! Unit vector uniform on the sphere.
inline Eigen::Vector3d randomUnitVector(SplitMix64& rng)
{
    const double z = uniform(rng, -1.0, 1.0);
    const double a = uniform(rng, 0.0, 2.0 * kPi);
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {r * std::cos(a), r * std::sin(a), z};
}

//! The origin rule of scandiff::suggestOrigin: zero while every coordinate is
//! below 1e4 m in magnitude, else the minimum rounded down to 1000 m per axis.
inline Eigen::Vector3d originFor(const std::vector<Eigen::Vector3d>& global)
{
    if (global.empty())
        return Eigen::Vector3d::Zero();
    Eigen::Vector3d lo = global.front(), hi = global.front();
    for (const auto& p : global) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    if (lo.cwiseAbs().maxCoeff() < 1e4 && hi.cwiseAbs().maxCoeff() < 1e4)
        return Eigen::Vector3d::Zero();
    return {std::floor(lo.x() / 1000.0) * 1000.0, std::floor(lo.y() / 1000.0) * 1000.0,
            std::floor(lo.z() / 1000.0) * 1000.0};
}

//! A cloud holding `global` (double) as float positions around the origin chosen
//! by originFor(), the way a reader stores georeferenced data.
inline PointCloud makeCloud(const std::vector<Eigen::Vector3d>& global, const std::string& name)
{
    PointCloud cloud;
    cloud.name = name;
    const Eigen::Vector3d origin = originFor(global);
    cloud.setOrigin(origin);
    cloud.resize(global.size());
    auto& pos = cloud.positions();
    for (std::size_t i = 0; i < global.size(); ++i)
        pos[i] = (global[i] - origin).cast<float>();
    return cloud;
}

//! Adds a scalar field filled from `values` (one per point).
inline void addFieldValues(PointCloud& cloud, const std::string& name, const std::vector<float>& values)
{
    ScalarField& f = cloud.addField(name);
    f.values() = values;
}

//! Rotation by `angleDeg` about `axis` through `pivot`, then translation:
//! p' = R (p - pivot) + pivot + t. Acts on global coordinates.
inline Eigen::Matrix4d rigidMotion(const Eigen::Vector3d& axis, double angleDeg, const Eigen::Vector3d& pivot,
                                   const Eigen::Vector3d& translation)
{
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    const Eigen::Matrix3d r = axis.norm() > 0 ? Eigen::AngleAxisd(degToRad(angleDeg), axis.normalized()).toRotationMatrix()
                                              : Eigen::Matrix3d::Identity();
    m.topLeftCorner<3, 3>() = r;
    m.topRightCorner<3, 1>() = pivot + translation - r * pivot;
    return m;
}

//! Inverse of a rigid 4x4 (exact for rotation + translation).
inline Eigen::Matrix4d rigidInverse(const Eigen::Matrix4d& m)
{
    Eigen::Matrix4d inv = Eigen::Matrix4d::Identity();
    const Eigen::Matrix3d rt = m.topLeftCorner<3, 3>().transpose();
    inv.topLeftCorner<3, 3>() = rt;
    inv.topRightCorner<3, 1>() = -rt * m.topRightCorner<3, 1>();
    return inv;
}

//! A matrix that a tool expressed on coordinates relative to `origin` (local =
//! global - origin), re-expressed on global coordinates.
inline Eigen::Matrix4d globalFromLocal(const Eigen::Matrix4d& local, const Eigen::Vector3d& origin)
{
    Eigen::Matrix4d toLocal = Eigen::Matrix4d::Identity(), toGlobal = Eigen::Matrix4d::Identity();
    toLocal.topRightCorner<3, 1>() = -origin;
    toGlobal.topRightCorner<3, 1>() = origin;
    return toGlobal * local * toLocal;
}

inline Eigen::Vector3d apply(const Eigen::Matrix4d& m, const Eigen::Vector3d& p)
{
    return m.topLeftCorner<3, 3>() * p + m.topRightCorner<3, 1>();
}

//! Angle (degrees) of the rotation taking one rigid matrix's rotation to the other's.
inline double rotationDifferenceDeg(const Eigen::Matrix4d& a, const Eigen::Matrix4d& b)
{
    const Eigen::Matrix3d d = a.topLeftCorner<3, 3>() * b.topLeftCorner<3, 3>().transpose();
    const double c = std::clamp((d.trace() - 1.0) / 2.0, -1.0, 1.0);
    return radToDeg(std::acos(c));
}

//! The q-quantile (0..1) by nearest rank of a copy of `v` (NaN if empty).
inline double quantile(std::vector<double> v, double q)
{
    if (v.empty())
        return std::nan("");
    const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(std::floor(q * (v.size() - 1) + 0.5)));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
}

//! Smooth 2D value noise: random values on an integer lattice, interpolated
//! with a C1 quintic fade. Deterministic from (seed, lattice cell): a surface
//! both epochs share (micro-relief is the terrain, not measurement noise).
class ValueNoise2
{
public:
    explicit ValueNoise2(std::uint64_t seed = 0) : seed_(seed) {}

    //! Value in [-1, 1] at (x, y) in lattice units.
    double operator()(double x, double y) const
    {
        const double fx = std::floor(x), fy = std::floor(y);
        const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
        const double tx = fade(x - fx), ty = fade(y - fy);
        const double a = lattice(ix, iy), b = lattice(ix + 1, iy);
        const double c = lattice(ix, iy + 1), d = lattice(ix + 1, iy + 1);
        return (a + (b - a) * tx) * (1.0 - ty) + (c + (d - c) * tx) * ty;
    }

private:
    static double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }
    double lattice(std::int64_t ix, std::int64_t iy) const
    {
        const std::uint64_t h = splitMix(seed_ ^ splitMix(static_cast<std::uint64_t>(ix) * 0x9e3779b97f4a7c15ULL
                                                          ^ static_cast<std::uint64_t>(iy)));
        return static_cast<double>(h >> 11) * 0x1.0p-52 - 1.0;
    }
    std::uint64_t seed_;
};

//! printf-style formatting for describe() strings.
template <typename... Args>
std::string format(const char* fmt, Args... args)
{
    char buf[512];
    std::snprintf(buf, sizeof buf, fmt, args...);
    return buf;
}

} // namespace scandiff::test::family::epochscene
