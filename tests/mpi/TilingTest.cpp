// SPDX-License-Identifier: GPL-3.0-or-later
// The tile arithmetic of scandiff-mpi, without MPI.
#include "Tiling.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace scandiff::mpi {
namespace {

TEST(Tiling, TilesAreAnchoredAtTheWorldOrigin)
{
    const TileGrid grid(10.0);
    EXPECT_EQ(grid.tileOf(0.0, 0.0), (TileKey{0, 0}));
    EXPECT_EQ(grid.tileOf(-0.001, 9.999), (TileKey{-1, 0}));
    EXPECT_EQ(grid.tileOf(500012.5, 5400000.0), (TileKey{50001, 540000}));
    // 2 m inside the tile [0, 10): 2 + 3 m of halo from the grown square's edge.
    EXPECT_DOUBLE_EQ(grid.depthInGrownTile({0, 0}, 3.0, 2.0, 5.0), 5.0);
    EXPECT_DOUBLE_EQ(grid.depthInGrownTile({0, 0}, 3.0, 5.0, 9.5), 3.5);
}

TEST(Tiling, LargestTilesGoFirstToTheLeastLoadedRank)
{
    std::map<TileKey, std::uint64_t> counts{{{0, 0}, 10}, {{1, 0}, 40}, {{2, 0}, 30}, {{3, 0}, 20}, {{4, 0}, 10}};
    const auto owners = assignTiles(counts, 2);
    // 40 -> rank 0; 30 -> 1; 20 -> 1 (30 < 40); 10 (key 0) -> 0 (40 < 50); 10 (key 4) -> 0 (50 = 50: lower rank).
    EXPECT_EQ(owners.at({1, 0}), 0);
    EXPECT_EQ(owners.at({2, 0}), 1);
    EXPECT_EQ(owners.at({3, 0}), 1);
    EXPECT_EQ(owners.at({0, 0}), 0);
    EXPECT_EQ(owners.at({4, 0}), 0);
    // More ranks than tiles: some ranks own nothing.
    const auto spread = assignTiles({{{0, 0}, 5}}, 4);
    EXPECT_EQ(spread.at({0, 0}), 0);
}

TEST(Tiling, HaloRegionHoldsWhatLiesWithinTheHaloOfAnOwnedTile)
{
    const TileGrid grid(10.0);
    const HaloRegion region(grid, {{0, 0}, {1, 0}}, 2.5);
    EXPECT_TRUE(region.contains(5, 5));     // owned
    EXPECT_TRUE(region.contains(19, 12.4)); // above tile (1, 0), within 2.5 m
    EXPECT_FALSE(region.contains(19, 12.6));
    EXPECT_TRUE(region.contains(-2.5, -2.5)); // the corner of the grown square
    EXPECT_FALSE(region.contains(-2.6, 5));
    EXPECT_FALSE(region.contains(50, 50));
    // A halo wider than a tile reaches two tiles out.
    const HaloRegion wide(grid, {{0, 0}}, 15.0);
    EXPECT_TRUE(wide.contains(24.9, 0));
    EXPECT_FALSE(wide.contains(25.1, 0));
}

TEST(Tiling, ReachIndexFindsTheSquaresABoxTouchesAsBruteForceDoes)
{
    std::mt19937 random(5);
    std::uniform_real_distribution<double> along(-100.0, 100.0), side(0.0, 12.0);
    std::vector<Eigen::Vector2d> centres;
    std::vector<double> halfSides;
    for (int m = 0; m < 60; ++m) {
        centres.emplace_back(along(random), along(random));
        halfSides.push_back(side(random));
    }
    const ReachIndex index(centres, halfSides, 10.0);
    int touched = 0;
    for (int k = 0; k < 4000; ++k) {
        const Eigen::Vector2d a(along(random), along(random));
        // Points (the reference points c2c widens on) and boxes (c2m's triangles).
        const Eigen::Vector2d b = k % 2 ? a : a + Eigen::Vector2d(side(random), side(random) / 4);
        bool expected = false;
        for (std::size_t m = 0; m < centres.size(); ++m)
            expected = expected || (a.x() <= centres[m].x() + halfSides[m] && b.x() >= centres[m].x() - halfSides[m] &&
                                    a.y() <= centres[m].y() + halfSides[m] && b.y() >= centres[m].y() - halfSides[m]);
        ASSERT_EQ(index.touches(a, b), expected) << k;
        touched += expected;
    }
    EXPECT_GT(touched, 400);
    EXPECT_LT(touched, 3600);
    // An unknown reach (infinite) reaches everywhere.
    halfSides.back() = std::numeric_limits<double>::infinity();
    EXPECT_TRUE(ReachIndex(centres, halfSides, 10.0).touches({1e6, 1e6}, {1e6, 1e6}));
}

} // namespace
} // namespace scandiff::mpi
