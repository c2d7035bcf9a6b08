// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A synthetic pair of epochs with three known changes, for end-to-end tests
//! of the segmentation (core, io and CLI suites).
//!
//! Both epochs sample a 20 m x 20 m ground plane (z = 0) independently, about
//! every 0.1 m, with Gaussian noise of 5 mm on z. The compared epoch has:
//!  - change 1, a raised block: the ground of [3, 6] x [3, 6] lifted by 0.5 m
//!    (top and four vertical sides sampled);
//!  - change 2, a removed area: a pit 0.4 m deep dug in [12, 15] x [4, 7]
//!    (bottom and four walls);
//!  - change 3, an appeared object: a 1 m cube standing on [8, 9] x [14, 15]
//!    (top and sides; the ground under it is hidden).
//! The field "truth" of the compared cloud holds the change number (0: none).

#include <scandiff/core/PointCloud.h>

#include <cmath>
#include <random>

namespace scandiff::test {

struct Box2
{
    double x0, y0, x1, y1;
    bool contains(double x, double y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
};

inline const Box2 kRaisedBlock{3, 3, 6, 6};
inline const Box2 kPit{12, 4, 15, 7};
inline const Box2 kObject{8, 14, 9, 15};

class SceneBuilder
{
public:
    explicit SceneBuilder(unsigned seed) : rng_(seed) {}

    void add(double x, double y, double z, int truth)
    {
        cloud.positions().emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z + noise_(rng_)));
        truths_.push_back(static_cast<float>(truth));
    }

    //! Jittered grid samples of the rectangle [x0,x1] x [y0,y1] at height z.
    void horizontal(const Box2& b, double z, double step, int truth, const Box2* skip = nullptr)
    {
        for (double x = b.x0 + 0.5 * step; x < b.x1; x += step)
            for (double y = b.y0 + 0.5 * step; y < b.y1; y += step) {
                const double px = x + jitter_(rng_) * step, py = y + jitter_(rng_) * step;
                if (skip && skip->contains(px, py))
                    continue;
                add(px, py, z, truth);
            }
    }

    //! The four vertical sides of the box b between heights z0 and z1.
    void sides(const Box2& b, double z0, double z1, double step, int truth)
    {
        const double lo = std::min(z0, z1), hi = std::max(z0, z1);
        for (double z = lo + 0.5 * step; z < hi; z += step) {
            for (double x = b.x0 + 0.5 * step; x < b.x1; x += step) {
                add(x, b.y0, z, truth);
                add(x, b.y1, z, truth);
            }
            for (double y = b.y0 + 0.5 * step; y < b.y1; y += step) {
                add(b.x0, y, z, truth);
                add(b.x1, y, z, truth);
            }
        }
    }

    PointCloud finish()
    {
        ScalarField& truth = cloud.addField("truth");
        truth.values() = truths_;
        return std::move(cloud);
    }

    PointCloud cloud;

private:
    std::mt19937 rng_;
    std::normal_distribution<double> noise_{0.0, 0.005};
    std::uniform_real_distribution<double> jitter_{-0.3, 0.3};
    std::vector<float> truths_;
};

inline PointCloud referenceEpoch()
{
    SceneBuilder b(11);
    b.cloud.name = "reference";
    b.horizontal({0, 0, 20, 20}, 0.0, 0.1, 0);
    PointCloud c = b.finish();
    c.removeField("truth");
    return c;
}

inline PointCloud comparedEpoch()
{
    SceneBuilder b(12);
    b.cloud.name = "compared";
    // Ground except where a change replaces it (the pit and the block have their
    // own surfaces, the object hides the ground under it).
    struct Skip
    {
        bool contains(double x, double y) const
        {
            return kRaisedBlock.contains(x, y) || kPit.contains(x, y) || kObject.contains(x, y);
        }
    };
    const Skip skip;
    const double step = 0.1;
    for (double x = 0.5 * step; x < 20; x += step)
        for (double y = 0.5 * step; y < 20; y += step) {
            if (skip.contains(x, y))
                continue;
            b.add(x, y, 0.0, 0);
        }
    b.horizontal(kRaisedBlock, 0.5, step, 1);
    b.sides(kRaisedBlock, 0.0, 0.5, step, 1);
    b.horizontal(kPit, -0.4, step, 2);
    b.sides(kPit, 0.0, -0.4, step, 2);
    b.horizontal(kObject, 1.0, step, 3);
    b.sides(kObject, 0.0, 1.0, step, 3);
    return b.finish();
}

} // namespace scandiff::test
