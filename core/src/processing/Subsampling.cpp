// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/processing/Subsampling.h>

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <unordered_set>

namespace scandiff {

std::vector<std::size_t> randomSubsample(const PointCloud& cloud, std::size_t count, std::uint64_t seed)
{
    const std::size_t n = cloud.size();
    std::vector<std::size_t> kept;
    if (count >= n) {
        kept.resize(n);
        for (std::size_t i = 0; i < n; ++i)
            kept[i] = i;
        return kept;
    }
    // Floyd's algorithm: `count` distinct indices in `count` draws, whatever n.
    std::mt19937_64 rng(seed);
    std::unordered_set<std::size_t> chosen;
    chosen.reserve(count * 2);
    for (std::size_t j = n - count; j < n; ++j) {
        const std::size_t t = std::uniform_int_distribution<std::size_t>(0, j)(rng);
        if (!chosen.insert(t).second)
            chosen.insert(j);
    }
    kept.assign(chosen.begin(), chosen.end());
    std::sort(kept.begin(), kept.end());
    return kept;
}

std::vector<std::size_t> spatialSubsample(const PointCloud& cloud, double minDistance, ProgressObserver* progress)
{
    if (!(minDistance > 0) || !std::isfinite(minDistance))
        throw Error(ErrorCode::InvalidArgument, "spatial subsampling: the minimum distance must be > 0");
    if (cloud.empty())
        return {};
    const octree::Octree tree = buildOctree(cloud);
    const std::size_t n = cloud.size();
    const auto& order = tree.sortedIndices();
    const auto& positions = cloud.positions();
    const auto radius = static_cast<float>(minDistance);
    std::vector<char> removed(n, 0);
    std::vector<std::size_t> kept;
    ProgressTicker ticker(progress, "Spatial subsampling", n);
    // Chunks of the Morton order: the neighbourhoods of a chunk's points are
    // found in parallel, then the chunk is decided in order (the greedy rule
    // is sequential). A point already removed needs no neighbourhood.
    constexpr std::size_t kChunk = 1 << 16;
    std::vector<Eigen::Vector3f> queries;
    std::vector<std::uint32_t> queryPoint;
    std::vector<std::vector<std::uint32_t>> within;
    for (std::size_t begin = 0; begin < n; begin += kChunk) {
        const std::size_t end = std::min(n, begin + kChunk);
        queries.clear();
        queryPoint.clear();
        for (std::size_t j = begin; j < end; ++j)
            if (!removed[order[j]]) {
                queries.push_back(positions[order[j]]);
                queryPoint.push_back(order[j]);
            }
        within.resize(queries.size());
        tree.withinRadiusBatch(queries.data(), queries.size(), radius, [&](std::uint32_t q, const octree::Neighbour* list, std::size_t count) {
            std::vector<std::uint32_t>& w = within[q];
            w.clear();
            for (std::size_t j = 0; j < count; ++j)
                w.push_back(list[j].index);
        });
        for (std::size_t q = 0; q < queries.size(); ++q) {
            const std::uint32_t i = queryPoint[q];
            if (removed[i])
                continue;
            kept.push_back(i);
            for (std::uint32_t j : within[q])
                if (j != i)
                    removed[j] = 1;
        }
        ticker.step(end - begin);
    }
    std::sort(kept.begin(), kept.end());
    return kept;
}

std::vector<std::size_t> octreeSubsample(const PointCloud& cloud, int level, ProgressObserver* progress)
{
    if (level < 1 || level > octree::kMaxLevel)
        throw Error(ErrorCode::InvalidArgument, "octree subsampling: the level must be in [1, 21]");
    if (cloud.empty())
        return {};
    const octree::Octree tree = buildOctree(cloud);
    const auto& order = tree.sortedIndices();
    const auto& positions = cloud.positions();
    const double size = tree.cellSize(level);
    const Eigen::Vector3d boxMin = tree.box().min;
    std::vector<std::size_t> kept;
    kept.reserve(tree.levelStatistics(level).nonEmptyCells);
    ProgressTicker ticker(progress, "Octree subsampling", cloud.size());
    tree.forEachCell(level, [&](octree::MortonCode code, std::size_t first, std::size_t last) {
        const octree::CellCoordinates c = octree::decodeCell(code);
        const Eigen::Vector3d centre = boxMin + (Eigen::Vector3d(c.x, c.y, c.z).array() + 0.5).matrix() * size;
        std::size_t best = order[first];
        double bestDistance = std::numeric_limits<double>::infinity();
        for (std::size_t j = first; j < last; ++j) {
            const std::size_t i = order[j];
            const double d = (positions[i].cast<double>() - centre).squaredNorm();
            if (d < bestDistance || (d == bestDistance && i < best)) {
                bestDistance = d;
                best = i;
            }
        }
        kept.push_back(best);
        ticker.step(last - first);
    });
    std::sort(kept.begin(), kept.end());
    return kept;
}

} // namespace scandiff
