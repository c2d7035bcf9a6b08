// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! k-nearest neighbourhoods of every point of a cloud, in parallel, for the
//! segmentation algorithms (internal to core).

#include <scandiff/core/Progress.h>
#include <scandiff/octree/Octree.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace scandiff::detail {

//! Calls visit(i, neighbours, count) for every point i of the octree's array,
//! with its k nearest points (itself first, closest first; count < k only when
//! the cloud is smaller than k). Runs in Morton-ordered chunks so the neighbour
//! lists of a chunk fit in memory; visit is called from several threads.
template <typename Visit>
void forEachNeighbourhood(const octree::Octree& tree, std::size_t k, int level, ProgressTicker& ticker, Visit&& visit)
{
    const std::size_t n = tree.size();
    const auto& order = tree.sortedIndices();
    const Eigen::Vector3f* points = tree.points();
    constexpr std::size_t kChunk = 1 << 15;
    std::vector<Eigen::Vector3f> queries;
    std::vector<octree::Neighbour> neighbours;
    for (std::size_t begin = 0; begin < n; begin += kChunk) {
        const std::size_t end = std::min(n, begin + kChunk);
        queries.resize(end - begin);
        for (std::size_t j = begin; j < end; ++j)
            queries[j - begin] = points[order[j]];
        tree.nearestBatch(queries.data(), queries.size(), k, level, neighbours);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, 512), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t j = range.begin(); j != range.end(); ++j) {
                const octree::Neighbour* list = neighbours.data() + (j - begin) * k;
                std::size_t count = 0;
                while (count < k && list[count].index != std::numeric_limits<std::uint32_t>::max())
                    ++count;
                visit(static_cast<std::size_t>(order[j]), list, count);
            }
            ticker.step(range.size());
        });
    }
}

} // namespace scandiff::detail
