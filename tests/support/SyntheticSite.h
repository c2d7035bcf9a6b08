// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A synthetic site for the registration tests and benchmarks: an undulating
//! ground of 60 x 60 m, four buildings (walls and roofs), a tank (a cylinder)
//! and a mound, sampled at random in proportion to area with Gaussian noise.
//! Every direction of motion is held by some surface, as on a real site.
//! The "changed" epoch moves the largest building by 0.3 m along x and adds
//! a block and a long wall: about 30 % of its points are on changed surfaces.
//! Header-only: the tests and bench/MakeSyntheticScan.cpp both use it.

#include <scandiff/core/PointCloud.h>

#include <Eigen/Geometry>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

namespace scandiff::test {

struct SiteOptions
{
    std::size_t points = 50000;
    unsigned seed = 1;
    double noise = 0.002;      //!< standard deviation (m)
    bool changed = false;      //!< the second epoch, with its changes
    Eigen::Vector3d origin = Eigen::Vector3d::Zero(); //!< the cloud's global shift
    //! Mark the points of changed surfaces in a field "changed" (1) for tests.
    bool markChanges = false;
};

namespace site {

//! One sampled surface: a function from two uniforms to a point and a weight (area).
struct Patch
{
    double area;
    std::function<Eigen::Vector3d(double, double)> at;
    bool changed = false;
};

inline double groundHeight(double x, double y)
{
    return 0.3 * std::sin(x / 7.0) * std::cos(y / 9.0) + 0.004 * x;
}

//! The walls and roof of an axis-aligned box standing on z = base.
inline void addBox(std::vector<Patch>& patches, Eigen::Vector3d low, Eigen::Vector3d size, bool changed)
{
    const double sx = size.x(), sy = size.y(), sz = size.z();
    patches.push_back({sx * sy, [=](double u, double v) -> Eigen::Vector3d { return low + Eigen::Vector3d(u * sx, v * sy, sz); }, changed}); // roof
    patches.push_back({sx * sz, [=](double u, double v) -> Eigen::Vector3d { return low + Eigen::Vector3d(u * sx, 0, v * sz); }, changed});
    patches.push_back({sx * sz, [=](double u, double v) -> Eigen::Vector3d { return low + Eigen::Vector3d(u * sx, sy, v * sz); }, changed});
    patches.push_back({sy * sz, [=](double u, double v) -> Eigen::Vector3d { return low + Eigen::Vector3d(0, u * sy, v * sz); }, changed});
    patches.push_back({sy * sz, [=](double u, double v) -> Eigen::Vector3d { return low + Eigen::Vector3d(sx, u * sy, v * sz); }, changed});
}

inline std::vector<Patch> patches(bool changedEpoch)
{
    std::vector<Patch> p;
    p.push_back({3600.0, [](double u, double v) -> Eigen::Vector3d {
                     const double x = -30 + 60 * u, y = -30 + 60 * v;
                     return Eigen::Vector3d(x, y, groundHeight(x, y));
                 }});
    // The largest building moves 0.3 m along x in the changed epoch.
    const Eigen::Vector3d shift = changedEpoch ? Eigen::Vector3d(0.3, 0, 0) : Eigen::Vector3d::Zero();
    addBox(p, Eigen::Vector3d(-20, -18, 0) + shift, Eigen::Vector3d(16, 12, 11), changedEpoch);
    addBox(p, Eigen::Vector3d(8, -22, 0), Eigen::Vector3d(10, 7, 6), false);
    addBox(p, Eigen::Vector3d(10, 8, 0), Eigen::Vector3d(7, 14, 12), false);
    addBox(p, Eigen::Vector3d(-24, 12, 0), Eigen::Vector3d(9, 6, 4), false);
    // A tank: a vertical cylinder of radius 3 and height 6, centred at (0, 4).
    p.push_back({2 * 3.14159265358979 * 3 * 6, [](double u, double v) -> Eigen::Vector3d {
                     const double a = 2 * 3.14159265358979 * u;
                     return Eigen::Vector3d(3 * std::cos(a), 4 + 3 * std::sin(a), 6 * v);
                 }});
    // A mound (a spherical cap of radius 5, 2 m high) at (20, -2).
    p.push_back({2 * 3.14159265358979 * 5 * 2, [](double u, double v) -> Eigen::Vector3d {
                     const double a = 2 * 3.14159265358979 * u, h = 2 * v; // uniform in height: uniform on the cap
                     const double z = 5 - h, r = std::sqrt(std::max(0.0, 25 - z * z));
                     return Eigen::Vector3d(20 + r * std::cos(a), -2 + r * std::sin(a), z - 3);
                 }});
    if (changedEpoch) {
        addBox(p, Eigen::Vector3d(-6, -28, 0), Eigen::Vector3d(14, 12, 11), true); // a new block
        p.push_back({40 * 12, [](double u, double v) -> Eigen::Vector3d { return Eigen::Vector3d(-28 + 40 * u, 26, 12 * v); }, true}); // a new wall
    }
    return p;
}

} // namespace site

//! The site sampled as a cloud, in local coordinates around `origin`.
inline PointCloud syntheticSite(const SiteOptions& options)
{
    const std::vector<site::Patch> patches = site::patches(options.changed);
    double total = 0;
    for (const auto& p : patches)
        total += p.area;
    std::mt19937_64 rng(options.seed);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, options.noise);
    PointCloud cloud;
    cloud.name = options.changed ? "site_changed" : "site";
    cloud.setOrigin(options.origin);
    cloud.resize(options.points);
    ScalarField* changed = options.markChanges ? &cloud.addField("changed") : nullptr;
    std::vector<double> cumulative;
    for (const auto& p : patches)
        cumulative.push_back((cumulative.empty() ? 0.0 : cumulative.back()) + p.area / total);
    for (std::size_t i = 0; i < options.points; ++i) {
        const double pick = uniform(rng);
        std::size_t k = 0;
        while (k + 1 < cumulative.size() && pick > cumulative[k])
            ++k;
        const Eigen::Vector3d p = patches[k].at(uniform(rng), uniform(rng)) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
        cloud.positions()[i] = p.cast<float>();
        if (changed)
            changed->setValue(i, patches[k].changed ? 1.0 : 0.0);
    }
    return cloud;
}

//! A rigid motion from Euler angles (degrees, about z then y then x) and a translation.
inline Eigen::Matrix4d rigidMotion(double yawDeg, double pitchDeg, double rollDeg, const Eigen::Vector3d& t)
{
    constexpr double toRad = 3.14159265358979323846 / 180.0;
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = (Eigen::AngleAxisd(yawDeg * toRad, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(pitchDeg * toRad, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(rollDeg * toRad, Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
    m.topRightCorner<3, 1>() = t;
    return m;
}

//! The same motion turning about `centre` (global coordinates) instead of the origin.
inline Eigen::Matrix4d rigidMotionAbout(double yawDeg, double pitchDeg, double rollDeg, const Eigen::Vector3d& t,
                                        const Eigen::Vector3d& centre)
{
    Eigen::Matrix4d m = rigidMotion(yawDeg, pitchDeg, rollDeg, t);
    m.topRightCorner<3, 1>() = centre - m.topLeftCorner<3, 3>() * centre + t;
    return m;
}

} // namespace scandiff::test
