// SPDX-License-Identifier: GPL-3.0-or-later
// Connected components on the octree grid (thesis 000 §3.2.4).

#include <scandiff/core/Error.h>
#include <scandiff/core/segmentation/ConnectedComponents.h>

#include "TestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

using namespace scandiff;

namespace {

//! A cloud whose octree cube is [0, 8]^3 (two unselected anchor points at its
//! corners), so at level 3 the cells are unit cubes. Each call adds one
//! selected point at the centre of cell (x, y, z).
struct UnitGrid
{
    PointCloud cloud;
    std::vector<std::uint8_t> selected;
    UnitGrid()
    {
        add(0, 0, 0, false, 0.0f);
        add(8, 8, 8, false, 0.0f);
    }
    void add(float x, float y, float z, bool select = true, float centre = 0.5f)
    {
        cloud.positions().emplace_back(x + centre, y + centre, z + centre);
        selected.push_back(select);
    }
    void cube(int x0, int y0, int z0, int side)
    {
        for (int x = x0; x < x0 + side; ++x)
            for (int y = y0; y < y0 + side; ++y)
                for (int z = z0; z < z0 + side; ++z)
                    add(x, y, z);
    }
    std::size_t regions(octree::Connectivity connectivity, int level = 3)
    {
        ConnectedComponentsParams p;
        p.level = level;
        p.connectivity = connectivity;
        return connectedComponents(cloud, selected, p).regionCount;
    }
};

} // namespace

TEST(ConnectedComponents, CubesTouchingAtAnEdgeMergeUnder18And26Only)
{
    UnitGrid g;
    g.cube(0, 0, 0, 2);
    g.cube(2, 2, 0, 2); // shares the edge x = y = 2 with the first
    EXPECT_EQ(g.regions(octree::Connectivity::Faces6), 2u);
    EXPECT_EQ(g.regions(octree::Connectivity::Edges18), 1u);
    EXPECT_EQ(g.regions(octree::Connectivity::Corners26), 1u);
}

TEST(ConnectedComponents, CubesTouchingAtACornerMergeUnder26Only)
{
    UnitGrid g;
    g.cube(0, 0, 0, 2);
    g.cube(2, 2, 2, 2); // shares the corner (2, 2, 2) with the first
    EXPECT_EQ(g.regions(octree::Connectivity::Faces6), 2u);
    EXPECT_EQ(g.regions(octree::Connectivity::Edges18), 2u);
    EXPECT_EQ(g.regions(octree::Connectivity::Corners26), 1u);
}

TEST(ConnectedComponents, IdsBySizeMinimumSizeAndCoarserLevels)
{
    UnitGrid g;
    g.cube(0, 0, 0, 2);  // 8 points
    g.cube(5, 5, 5, 3);  // 27 points, two cells away from nothing
    g.add(0, 6, 0);      // a lone point
    ConnectedComponentsParams p;
    p.level = 3;
    ConnectedComponentsResult r = connectedComponents(g.cloud, g.selected, p);
    ASSERT_EQ(r.regionCount, 3u);
    EXPECT_EQ(r.regionSizes, (std::vector<std::size_t>{27, 8, 1}));
    EXPECT_NEAR(r.cellSize, 1.0, 1e-3);
    // Point 2 is the first of the 2-cube: region 2; unselected anchors: no region.
    EXPECT_EQ(r.regionId.values()[2], 2.0f);
    EXPECT_TRUE(std::isnan(r.regionId.values()[0]));
    EXPECT_EQ(r.regionId.values().back(), 3.0f);

    p.minPoints = 2;
    r = connectedComponents(g.cloud, g.selected, p);
    EXPECT_EQ(r.regionCount, 2u);
    EXPECT_EQ(r.droppedComponents, 1u);
    EXPECT_EQ(r.droppedPoints, 1u);
    EXPECT_TRUE(std::isnan(r.regionId.values().back()));

    // At level 1 (cells of 4 m) the three land in cells (0,0,0), (1,1,1) and
    // (0,1,0), adjacent under 26-connectivity: one region.
    p.level = 1;
    p.minPoints = 1;
    r = connectedComponents(g.cloud, g.selected, p);
    EXPECT_EQ(r.regionCount, 1u);
}

TEST(ConnectedComponents, EmptySelectionAndBadInput)
{
    UnitGrid g;
    g.cube(0, 0, 0, 2);
    std::vector<std::uint8_t> none(g.cloud.size(), 0);
    const ConnectedComponentsResult r = connectedComponents(g.cloud, none);
    EXPECT_EQ(r.regionCount, 0u);
    EXPECT_GT(r.level, 0);
    EXPECT_EQ(test::errorCodeOf([&] { connectedComponents(g.cloud, std::vector<std::uint8_t>(3, 1)); }),
              ErrorCode::InvalidArgument);
    ConnectedComponentsParams p;
    p.level = 22;
    EXPECT_EQ(test::errorCodeOf([&] { connectedComponents(g.cloud, g.selected, p); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { connectedComponents(PointCloud{}, {}); }), ErrorCode::InvalidData);
    EXPECT_EQ(test::errorCodeOf([] { parseConnectivity(8); }), ErrorCode::InvalidArgument);
}

TEST(ConnectedComponents, MatchesABruteForceLabellingOnRandomCells)
{
    // Random occupied unit cells of an 8^3 grid, labelled again here by a
    // flood fill over all pairs of cells: both partitions must be equal.
    std::mt19937 rng(9);
    std::bernoulli_distribution occupied(0.25);
    UnitGrid g;
    std::vector<std::array<int, 3>> cells;
    for (int x = 0; x < 8; ++x)
        for (int y = 0; y < 8; ++y)
            for (int z = 0; z < 8; ++z)
                if (occupied(rng)) {
                    g.add(x, y, z);
                    cells.push_back({x, y, z});
                }
    for (auto connectivity : {octree::Connectivity::Faces6, octree::Connectivity::Edges18, octree::Connectivity::Corners26}) {
        const int maxNonZero = connectivity == octree::Connectivity::Faces6 ? 1 : connectivity == octree::Connectivity::Edges18 ? 2 : 3;
        std::vector<int> label(cells.size(), -1);
        int labels = 0;
        for (std::size_t s = 0; s < cells.size(); ++s) {
            if (label[s] >= 0)
                continue;
            std::vector<std::size_t> stack{s};
            label[s] = labels;
            while (!stack.empty()) {
                const std::size_t a = stack.back();
                stack.pop_back();
                for (std::size_t b = 0; b < cells.size(); ++b) {
                    if (label[b] >= 0)
                        continue;
                    int nonZero = 0, far = 0;
                    for (int d = 0; d < 3; ++d) {
                        const int diff = std::abs(cells[a][d] - cells[b][d]);
                        nonZero += diff != 0;
                        far += diff > 1;
                    }
                    if (far == 0 && nonZero <= maxNonZero) {
                        label[b] = labels;
                        stack.push_back(b);
                    }
                }
            }
            ++labels;
        }
        ConnectedComponentsParams p;
        p.level = 3;
        p.connectivity = connectivity;
        const ConnectedComponentsResult r = connectedComponents(g.cloud, g.selected, p);
        EXPECT_EQ(r.regionCount, static_cast<std::size_t>(labels));
        // Same partition: a bijection between our labels and the region ids.
        std::set<std::pair<int, float>> pairs;
        for (std::size_t s = 0; s < cells.size(); ++s)
            pairs.insert({label[s], r.regionId.values()[s + 2]});
        EXPECT_EQ(pairs.size(), static_cast<std::size_t>(labels));
    }
}
