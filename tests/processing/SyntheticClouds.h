// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Analytic shapes sampled for the processing tests: the exact normal,
//! curvature or area of each is known.

#include <scandiff/core/PointCloud.h>

#include <cmath>
#include <random>

namespace scandiff::test {

constexpr double kPi = 3.14159265358979323846;

//! n points spread evenly over a sphere (Fibonacci lattice).
inline PointCloud sphereCloud(std::size_t n, double radius, const Eigen::Vector3d& centre = Eigen::Vector3d::Zero())
{
    PointCloud c;
    c.name = "sphere";
    c.resize(n);
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    for (std::size_t i = 0; i < n; ++i) {
        const double z = 1.0 - 2.0 * (static_cast<double>(i) + 0.5) / static_cast<double>(n);
        const double r = std::sqrt(1.0 - z * z), theta = golden * static_cast<double>(i);
        c.positions()[i] = (centre + radius * Eigen::Vector3d(r * std::cos(theta), r * std::sin(theta), z)).cast<float>();
    }
    return c;
}

//! A torus about the z axis: the ring of radius `major`, the tube of radius `minor`, on an nu x nv grid.
inline PointCloud torusCloud(int nu, int nv, double major, double minor)
{
    PointCloud c;
    c.name = "torus";
    c.resize(static_cast<std::size_t>(nu * nv));
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const double u = 2 * kPi * (i + 0.5 * (j % 2)) / nu, v = 2 * kPi * j / nv;
            const double ring = major + minor * std::cos(v);
            c.positions()[static_cast<std::size_t>(i * nv + j)] =
                Eigen::Vector3f(float(ring * std::cos(u)), float(ring * std::sin(u)), float(minor * std::sin(v)));
        }
    return c;
}

//! The outward normal of that torus at p.
inline Eigen::Vector3d torusOutward(const Eigen::Vector3d& p, double major)
{
    const Eigen::Vector2d xy(p.x(), p.y());
    const Eigen::Vector2d ring = xy.normalized() * major;
    return (p - Eigen::Vector3d(ring.x(), ring.y(), 0)).normalized();
}

//! A regular grid of nx x ny points with spacing `step` in the plane z = 0,
//! then rotated by `rotation` and moved to `origin` (the cloud's global shift).
inline PointCloud gridCloud(int nx, int ny, double step, const Eigen::Matrix3d& rotation = Eigen::Matrix3d::Identity(),
                            const Eigen::Vector3d& origin = Eigen::Vector3d::Zero())
{
    PointCloud c;
    c.name = "grid";
    c.setOrigin(origin);
    c.resize(static_cast<std::size_t>(nx * ny));
    for (int i = 0; i < nx; ++i)
        for (int j = 0; j < ny; ++j)
            c.positions()[static_cast<std::size_t>(i * ny + j)] = (rotation * Eigen::Vector3d(i * step, j * step, 0)).cast<float>();
    return c;
}

//! n points uniformly at random in [0, size]^2 x {0}.
inline PointCloud randomPlaneCloud(std::size_t n, double size, std::uint32_t seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, size);
    PointCloud c;
    c.name = "plane";
    c.resize(n);
    for (auto& p : c.positions())
        p = Eigen::Vector3f(float(u(rng)), float(u(rng)), 0.0f);
    return c;
}

} // namespace scandiff::test
