// SPDX-License-Identifier: GPL-3.0-or-later
// The propagation on two samplings of one terrain with two changes, drawn over
// the conditions of real surveys: a noise point above the seed value must not
// turn the unchanged background into a "change" (issue 50, defect 13).
#include <scandiff/core/distance/CloudToCloud.h>
#include <scandiff/core/segmentation/SegmentationParameters.h>

#include "TestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

using namespace scandiff;

namespace {

struct Block
{
    double x0, y0, size, height;
    bool contains(double x, double y, double margin = 0.0) const
    {
        return x >= x0 - margin && x <= x0 + size + margin && y >= y0 - margin && y <= y0 + size + margin;
    }
};

struct Draw
{
    PointCloud reference, compared;
    std::vector<Block> blocks;
    std::vector<std::size_t> spikes; //!< compared points lifted above the seed value, alone
};

double ground(double x, double y, double amplitude) { return amplitude * std::sin(0.3 * x) * std::cos(0.25 * y) + 0.02 * x; }

//! A 24 m x 24 m wavy terrain sampled twice at a drawn spacing (3-8 cm) and
//! noise (1-10 mm), far from the origin; the compared epoch has two raised
//! blocks (2-4 m, 0.3-1 m high, tops and sides) and 1-4 lone noise points
//! 0.25-0.5 m above the ground (a bird, a flake of vegetation).
Draw drawScene(std::uint32_t seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double spacing = 0.03 + 0.05 * u(rng), noise = 0.001 + 0.009 * u(rng), amplitude = 0.5 * u(rng);
    Draw d;
    d.blocks.push_back({2 + 6 * u(rng), 2 + 16 * u(rng), 2 + 2 * u(rng), 0.3 + 0.7 * u(rng)});
    d.blocks.push_back({14 + 5 * u(rng), 2 + 16 * u(rng), 2 + 2 * u(rng), 0.3 + 0.7 * u(rng)});
    std::normal_distribution<double> gauss(0.0, noise);
    const Eigen::Vector3d origin(512000 + 1000 * u(rng), 5423000, 300);
    auto sample = [&](PointCloud& cloud, bool changed) {
        cloud.setOrigin(origin);
        const auto add = [&](double x, double y, double z) {
            cloud.positions().emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z + gauss(rng)));
        };
        for (double x = 0; x < 24; x += spacing)
            for (double y = 0; y < 24; y += spacing) {
                const double px = x + spacing * u(rng), py = y + spacing * u(rng);
                double z = ground(px, py, amplitude);
                if (changed)
                    for (const Block& b : d.blocks)
                        if (b.contains(px, py))
                            z += b.height;
                add(px, py, z);
            }
        if (!changed)
            return;
        for (const Block& b : d.blocks) // the blocks' sides
            for (double t = 0; t < 4 * b.size; t += spacing)
                for (double h = spacing; h < b.height; h += spacing) {
                    const int side = static_cast<int>(t / b.size);
                    const double s = t - side * b.size;
                    const double x = side == 0 ? b.x0 + s : side == 1 ? b.x0 + b.size : side == 2 ? b.x0 + b.size - s : b.x0;
                    const double y = side == 0 ? b.y0 : side == 1 ? b.y0 + s : side == 2 ? b.y0 + b.size : b.y0 + b.size - s;
                    add(x, y, ground(x, y, amplitude) + h);
                }
        const int spikes = 1 + static_cast<int>(rng() % 4);
        for (int k = 0; k < spikes; ++k) {
            double x = 0, y = 0;
            do {
                x = 1 + 22 * u(rng);
                y = 1 + 22 * u(rng);
            } while (d.blocks[0].contains(x, y, 2.0) || d.blocks[1].contains(x, y, 2.0));
            d.spikes.push_back(cloud.size());
            add(x, y, ground(x, y, amplitude) + 0.25 + 0.25 * u(rng));
        }
    };
    sample(d.reference, false);
    sample(d.compared, true);
    return d;
}

} // namespace

TEST(PropagationBackground, TwoChangesOfTwoSamplingsAreTheOnlyRegionsWhateverTheNoisePoints)
{
    for (std::uint32_t seed = 1; seed <= 24; ++seed) {
        Draw d = drawScene(seed);
        attachFields(d.compared, cloudToCloud(d.compared, d.reference, CloudToCloudParams{}));
        ParameterValues values = resolveParameters(segmentationParameters(),
                                                   {{"field", "c2c_distance"}, {"propagate", "true"}, {"min-seed", "0.2"}}, "test");
        const SegmentationRun run = runSegmentation(d.compared, values);
        EXPECT_EQ(run.regionCount, 2u) << "seed " << seed << ": " << run.summary << " sizes " << ::testing::PrintToString(run.regionSizes) << " of " << d.compared.size();
        if (run.regionCount != 2)
            continue;
        const ScalarField& region = run.fields.front();
        ASSERT_EQ(region.name(), "region_id");
        // Each region is one block: every point of its top clearly above the
        // seed value is in it, and it holds no ground farther than a cell or
        // two from the block (the front follows the gradient down the sides).
        std::map<int, int> regionOfBlock;
        for (std::size_t b = 0; b < 2; ++b) {
            const Block& block = d.blocks[b];
            std::size_t inside = 0, found = 0;
            std::map<int, std::size_t> votes;
            for (std::size_t i = 0; i < d.compared.size(); ++i) {
                const Eigen::Vector3f& p = d.compared.positions()[i];
                if (!block.contains(p.x(), p.y(), -0.2))
                    continue;
                ++inside;
                if (region.hasValue(i))
                    ++votes[static_cast<int>(region.value(i))];
            }
            for (const auto& [id, count] : votes)
                if (count > found) {
                    found = count;
                    regionOfBlock[static_cast<int>(b)] = id;
                }
            EXPECT_GE(found, inside * 98 / 100) << "seed " << seed << " block " << b;
        }
        ASSERT_EQ(regionOfBlock.size(), 2u);
        EXPECT_NE(regionOfBlock[0], regionOfBlock[1]) << "seed " << seed;
        for (std::size_t i = 0; i < d.compared.size(); ++i) {
            if (!region.hasValue(i))
                continue;
            const Eigen::Vector3f& p = d.compared.positions()[i];
            ASSERT_TRUE(d.blocks[0].contains(p.x(), p.y(), 0.5) || d.blocks[1].contains(p.x(), p.y(), 0.5))
                << "seed " << seed << ": point " << i << " at " << p.x() << ", " << p.y() << " in region " << region.value(i);
        }
        for (std::size_t spike : d.spikes)
            EXPECT_FALSE(region.hasValue(spike)) << "seed " << seed;
    }
}
