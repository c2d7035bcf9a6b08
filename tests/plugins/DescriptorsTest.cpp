// SPDX-License-Identifier: GPL-3.0-or-later
// The FPFH descriptors of the global alignment: their closed form on a plane,
// their invariance under rigid motions, and the matching of descriptors.
#include "FeatureMatching.h"

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <random>

using namespace scandiff::plugins::detail;

namespace {

//! Points on a sphere of radius 2 with their outward normals, and a box corner.
void curvedScene(std::vector<Eigen::Vector3f>& points, std::vector<Eigen::Vector3f>& normals)
{
    std::mt19937 rng(5);
    std::normal_distribution<float> g(0, 1);
    std::uniform_real_distribution<float> u(0, 1);
    for (int i = 0; i < 1500; ++i) {
        const Eigen::Vector3f n = Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized();
        points.push_back(2 * n);
        normals.push_back(n);
    }
    for (int i = 0; i < 1500; ++i) { // three faces of a box at (3, 3, 0)
        const int face = i % 3;
        Eigen::Vector3f p(3 + 2 * u(rng), 3 + 2 * u(rng), 2 * u(rng)), n = Eigen::Vector3f::Zero();
        p[face] = face == 2 ? 0.0f : 3.0f;
        n[face] = -1;
        points.push_back(p);
        normals.push_back(n);
    }
}

} // namespace

TEST(Descriptors, APlaneFillsTheMiddleBinsOnly)
{
    // Every pair on a plane with parallel normals: the three angles are 0, so
    // each histogram holds its 100 in the middle bin (bin 5 of 11).
    std::vector<Eigen::Vector3f> points, normals;
    for (int i = 0; i < 30; ++i)
        for (int j = 0; j < 30; ++j) {
            points.emplace_back(0.1f * static_cast<float>(i), 0.1f * static_cast<float>(j), 0.0f);
            normals.emplace_back(0.0f, 0.0f, 1.0f);
        }
    std::vector<Descriptor> d;
    std::vector<char> valid;
    fpfhDescriptors(points, normals, 0.35, d, valid);
    for (std::size_t i = 0; i < points.size(); ++i) {
        ASSERT_TRUE(valid[i]);
        for (int part = 0; part < 3; ++part)
            for (int b = 0; b < 11; ++b)
                EXPECT_NEAR(d[i][static_cast<std::size_t>(part * 11 + b)], b == 5 ? 200.0f : 0.0f, 1e-3) << i;
    }
}

TEST(Descriptors, InvariantUnderRigidMotionsAndMatchedBack)
{
    std::vector<Eigen::Vector3f> points, normals;
    curvedScene(points, normals);
    const Eigen::Affine3f motion = Eigen::Translation3f(5, -2, 1) * Eigen::AngleAxisf(2.4f, Eigen::Vector3f(1, 2, 3).normalized());
    std::vector<Eigen::Vector3f> moved, movedNormals;
    for (std::size_t i = 0; i < points.size(); ++i) {
        moved.push_back(motion * points[i]);
        movedNormals.push_back(motion.linear() * normals[i]);
    }
    std::vector<Descriptor> a, b;
    std::vector<char> va, vb;
    fpfhDescriptors(points, normals, 0.6, a, va);
    fpfhDescriptors(moved, movedNormals, 0.6, b, vb);
    // The same histograms, but for a bin edge crossed by rounding here and there.
    std::size_t same = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        EXPECT_EQ(va[i], vb[i]);
        float difference = 0;
        for (std::size_t k = 0; k < 33; ++k)
            difference += std::abs(a[i][k] - b[i][k]);
        same += difference < 1.0f;
    }
    EXPECT_GT(same, points.size() * 99 / 100);
    // Mutual nearest descriptors pair most points with themselves.
    const auto matches = matchDescriptors(a, b, 10);
    std::size_t right = 0;
    for (const auto& [i, j] : matches)
        right += i == j;
    EXPECT_GT(right, matches.size() / 2);
}
