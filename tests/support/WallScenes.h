// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Synthetic walls with known outlines, for the contour tests and benchmark:
//! a masonry wall whose stones differ from their joints in intensity (thesis
//! 003 §7.2, the team's proposed benchmark) and a façade with rectangular and
//! arched openings (thesis 001 §5.6). Both stand in a vertical plane turned
//! `yawDegrees` about z, far from the origin (UTM-like coordinates).

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/geometry/PlanarRings.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace scandiff::test {

using Outline = std::vector<Eigen::Vector2d>; //!< closed, counter-clockwise, in the wall's (along, up) frame

struct WallFrame
{
    Eigen::Vector3d origin{500000.0, 5400000.0, 200.0};
    double yawDegrees = 30.0;
    Eigen::Vector3d along() const
    {
        const double a = yawDegrees * 3.14159265358979323846 / 180.0;
        return {std::cos(a), std::sin(a), 0.0};
    }
    Eigen::Vector3d world(const Eigen::Vector2d& q, double depth = 0.0) const
    {
        const Eigen::Vector3d u = along(), v = Eigen::Vector3d::UnitZ();
        return origin + q.x() * u + q.y() * v + depth * u.cross(v);
    }
};

//! A jittered grid over [0, width] x [0, height], each point kept if `keep` says so.
template <class Keep>
std::vector<Eigen::Vector2d> jitteredGrid(double width, double height, double spacing, std::mt19937& rng, Keep&& keep)
{
    std::uniform_real_distribution<double> jitter(-0.3 * spacing, 0.3 * spacing);
    std::vector<Eigen::Vector2d> out;
    const int nx = static_cast<int>(width / spacing), ny = static_cast<int>(height / spacing);
    out.reserve(static_cast<std::size_t>(nx + 1) * static_cast<std::size_t>(ny + 1));
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) {
            const Eigen::Vector2d q((i + 0.5) * spacing + jitter(rng), (j + 0.5) * spacing + jitter(rng));
            if (keep(q))
                out.push_back(q);
        }
    return out;
}

struct StoneWallOptions
{
    int courses = 4, stonesPerCourse = 5;
    double stoneWidth = 0.30, stoneHeight = 0.18;
    double jointMin = 0.010, jointMax = 0.020;
    double spacing = 0.004;
    double noise = 0.002;    //!< across the wall
    bool brightStones = false;
    double stoneIntensity = -1400, jointIntensity = -900, intensitySigma = 40; //!< swapped when bright
    int isolatedPoints = 17; //!< joint points given a stone's intensity (thesis 003 Fig. 59)
    int rubbleEvery = 3;     //!< every n-th stone is a polygon with cut corners (0: none)
    unsigned seed = 3;
    WallFrame frame;
};

struct StoneWallScene
{
    PointCloud cloud; //!< with an "intensity" field
    std::vector<Outline> stones;
    std::vector<std::uint8_t> isStone; //!< the truth, per point
    WallFrame frame;
};

inline StoneWallScene makeStoneWall(const StoneWallOptions& o)
{
    StoneWallScene scene;
    scene.frame = o.frame;
    std::mt19937 rng(o.seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    auto between = [&](double a, double b) { return a + (b - a) * unit(rng); };
    // Courses of stones separated by joints of random width.
    std::vector<std::pair<double, double>> courseSpan;
    std::vector<std::vector<std::size_t>> stonesOfCourse;
    double y = between(o.jointMin, o.jointMax), width = 0.0;
    for (int c = 0; c < o.courses; ++c) {
        const double h = o.stoneHeight * between(0.8, 1.2);
        courseSpan.emplace_back(y, y + h);
        stonesOfCourse.emplace_back();
        double x = between(o.jointMin, o.jointMax);
        for (int s = 0; s < o.stonesPerCourse; ++s) {
            const double w = o.stoneWidth * between(0.7, 1.3);
            Outline stone{{x, y}, {x + w, y}, {x + w, y + h}, {x, y + h}};
            if (o.rubbleEvery > 0 && scene.stones.size() % static_cast<std::size_t>(o.rubbleEvery) == 1) {
                // Rubble: the corners cut by 2-6 cm, an octagon.
                Outline cut;
                for (int k = 0; k < 4; ++k) {
                    const Eigen::Vector2d& a = stone[static_cast<std::size_t>(k)];
                    const Eigen::Vector2d& prev = stone[static_cast<std::size_t>((k + 3) % 4)];
                    const Eigen::Vector2d& next = stone[static_cast<std::size_t>((k + 1) % 4)];
                    cut.push_back(a + (prev - a).normalized() * between(0.02, 0.06));
                    cut.push_back(a + (next - a).normalized() * between(0.02, 0.06));
                }
                stone = cut;
            }
            stonesOfCourse.back().push_back(scene.stones.size());
            scene.stones.push_back(stone);
            x += w + between(o.jointMin, o.jointMax);
        }
        width = std::max(width, x);
        y += h + between(o.jointMin, o.jointMax);
    }
    const double height = y;
    auto stoneAt = [&](const Eigen::Vector2d& q) {
        for (std::size_t c = 0; c < courseSpan.size(); ++c)
            if (q.y() >= courseSpan[c].first && q.y() <= courseSpan[c].second)
                for (std::size_t s : stonesOfCourse[c])
                    if (containsPoint(scene.stones[s], q))
                        return true;
        return false;
    };
    const std::vector<Eigen::Vector2d> grid = jitteredGrid(width, height, o.spacing, rng, [](const Eigen::Vector2d&) { return true; });
    std::normal_distribution<double> noise(0.0, o.noise), intensityNoise(0.0, o.intensitySigma);
    const double stoneMean = o.brightStones ? o.jointIntensity : o.stoneIntensity;
    const double jointMean = o.brightStones ? o.stoneIntensity : o.jointIntensity;
    scene.cloud.setOrigin(o.frame.origin);
    scene.cloud.resize(grid.size());
    ScalarField& intensity = scene.cloud.addField("intensity");
    scene.isStone.resize(grid.size());
    std::vector<std::size_t> joints;
    for (std::size_t i = 0; i < grid.size(); ++i) {
        scene.isStone[i] = stoneAt(grid[i]);
        scene.cloud.positions()[i] = (o.frame.world(grid[i], noise(rng)) - o.frame.origin).cast<float>();
        intensity.values()[i] = static_cast<float>((scene.isStone[i] ? stoneMean : jointMean) + intensityNoise(rng));
        if (!scene.isStone[i])
            joints.push_back(i);
    }
    for (int k = 0; k < o.isolatedPoints && !joints.empty(); ++k)
        intensity.values()[joints[static_cast<std::size_t>(unit(rng) * static_cast<double>(joints.size() - 1))]] =
            static_cast<float>(stoneMean + intensityNoise(rng));
    return scene;
}

struct FacadeScene
{
    PointCloud cloud;
    std::vector<Outline> openings;
    std::vector<std::vector<Eigen::Vector2d>> corners; //!< the true corners of the rectangular openings
    WallFrame frame;
    double width = 0, height = 0;
};

//! A 6 m x 4 m façade, three rectangular windows, a door reaching the ground
//! (a notch in the outline) and an arched window (a 1 m x 0.9 m rectangle
//! under a half circle of radius 0.5 m).
inline FacadeScene makeFacade(double spacing = 0.015, unsigned seed = 5, double noise = 0.003)
{
    FacadeScene scene;
    scene.width = 6.0;
    scene.height = 4.0;
    auto rectangle = [&](double x0, double y0, double x1, double y1) {
        scene.openings.push_back({{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}});
        scene.corners.push_back(scene.openings.back());
    };
    rectangle(0.6, 2.2, 1.6, 3.6);
    rectangle(2.4, 2.2, 3.4, 3.6);
    rectangle(0.6, 0.6, 1.6, 1.8);
    Outline arch{{4.5, 1.0}, {5.5, 1.0}};
    for (int k = 0; k <= 180; k += 2) {
        const double a = k * 3.14159265358979323846 / 180.0;
        arch.push_back({5.0 + 0.5 * std::cos(a), 1.9 + 0.5 * std::sin(a)});
    }
    scene.openings.push_back(arch);
    const Outline door{{2.5, 0.0}, {3.4, 0.0}, {3.4, 1.9}, {2.5, 1.9}};
    std::mt19937 rng(seed);
    const std::vector<Eigen::Vector2d> grid = jitteredGrid(scene.width, scene.height, spacing, rng, [&](const Eigen::Vector2d& q) {
        if (q.x() > scene.width || q.y() > scene.height || containsPoint(door, q))
            return false;
        for (const Outline& opening : scene.openings)
            if (containsPoint(opening, q))
                return false;
        return true;
    });
    std::normal_distribution<double> across(0.0, noise);
    scene.cloud.setOrigin(scene.frame.origin);
    scene.cloud.resize(grid.size());
    for (std::size_t i = 0; i < grid.size(); ++i)
        scene.cloud.positions()[i] = (scene.frame.world(grid[i], across(rng)) - scene.frame.origin).cast<float>();
    return scene;
}

} // namespace scandiff::test
