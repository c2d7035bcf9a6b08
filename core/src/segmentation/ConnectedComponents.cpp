// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/segmentation/Classification.h>
#include <scandiff/core/segmentation/ConnectedComponents.h>

#include "GridCells.h"

#include <algorithm>
#include <numeric>
#include <string>

namespace scandiff {

octree::Connectivity parseConnectivity(int value)
{
    switch (value) {
    case 6: return octree::Connectivity::Faces6;
    case 18: return octree::Connectivity::Edges18;
    case 26: return octree::Connectivity::Corners26;
    default: throw Error(ErrorCode::InvalidArgument, "connectivity must be 6, 18 or 26, got " + std::to_string(value));
    }
}

ConnectedComponentsResult connectedComponents(const PointCloud& cloud, const std::vector<std::uint8_t>& selected,
                                              const ConnectedComponentsParams& params, ProgressObserver* progress)
{
    if (selected.size() != cloud.size())
        throw Error(ErrorCode::InvalidArgument, "connected components: the selection has " + std::to_string(selected.size()) +
                                                    " entries for " + std::to_string(cloud.size()) + " points");
    if (params.level < 0 || params.level > octree::kMaxLevel)
        throw Error(ErrorCode::InvalidArgument, "connected components: the level must be in [1, 21] (0: automatic), got " +
                                                    std::to_string(params.level));
    if (params.minPoints < 1)
        throw Error(ErrorCode::InvalidArgument, "connected components: the minimum size must be at least 1 point");
    if (cloud.empty())
        throw Error(ErrorCode::InvalidData, "connected components: cloud '" + cloud.name + "' is empty");

    // The grid is the octree of the whole cloud, so its cells (and the level's
    // meaning) do not depend on the selection.
    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    ConnectedComponentsResult result;
    result.level = params.level > 0 ? params.level : tree.levelForMeanPopulation(10.0);
    result.cellSize = tree.cellSize(result.level);
    result.regionId = ScalarField(fields::kRegionId, cloud.size());

    ProgressTicker ticker(progress, "Connected components", 3);
    // Occupied cells: those holding at least one selected point.
    const int shift = 3 * (octree::kMaxLevel - result.level);
    const auto& codes = tree.sortedCodes();
    const auto& indices = tree.sortedIndices();
    std::vector<octree::MortonCode> cells;
    std::vector<std::size_t> cellPoints; // selected points per cell
    for (std::size_t s = 0; s < codes.size(); ++s) {
        if (!selected[indices[s]])
            continue;
        const octree::MortonCode cell = codes[s] >> shift;
        if (cells.empty() || cells.back() != cell) {
            cells.push_back(cell);
            cellPoints.push_back(0);
        }
        ++cellPoints.back();
    }
    ticker.step();
    if (cells.empty())
        return result;

    // The thesis labels 2D slices and merges them along the stacking axis with
    // an equivalence table; a union-find over the occupied cells, each looking
    // at the neighbours "before" it, is the same equivalence computed directly in 3D.
    const std::vector<std::size_t> parent = detail::cellComponents(cells, params.connectivity, result.level);
    ticker.step();

    std::vector<std::size_t> componentPoints(cells.size(), 0);
    for (std::size_t c = 0; c < cells.size(); ++c)
        componentPoints[parent[c]] += cellPoints[c];
    std::vector<std::size_t> roots;
    for (std::size_t c = 0; c < cells.size(); ++c)
        if (parent[c] == c) {
            if (componentPoints[c] >= params.minPoints)
                roots.push_back(c);
            else {
                ++result.droppedComponents;
                result.droppedPoints += componentPoints[c];
            }
        }
    // Biggest first; a root is its component's first cell in Morton order, which breaks ties.
    std::stable_sort(roots.begin(), roots.end(),
                     [&](std::size_t a, std::size_t b) { return componentPoints[a] > componentPoints[b]; });
    std::vector<std::size_t> idOfRoot(cells.size(), 0);
    for (std::size_t r = 0; r < roots.size(); ++r) {
        idOfRoot[roots[r]] = r + 1;
        result.regionSizes.push_back(componentPoints[roots[r]]);
    }
    result.regionCount = roots.size();

    std::size_t c = 0;
    for (std::size_t s = 0; s < codes.size(); ++s) {
        if (!selected[indices[s]])
            continue;
        const octree::MortonCode cell = codes[s] >> shift;
        while (cells[c] != cell)
            ++c;
        const std::size_t id = idOfRoot[parent[c]];
        if (id > 0)
            result.regionId.values()[indices[s]] = static_cast<float>(id);
    }
    ticker.step();
    return result;
}

} // namespace scandiff
