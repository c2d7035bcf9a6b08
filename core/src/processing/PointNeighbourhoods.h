// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The neighbourhood of every point of a cloud, by radius or by count, for the
//! processing tools (internal to core).

#include "segmentation/Neighbourhoods.h"

#include <scandiff/core/Progress.h>
#include <scandiff/octree/Octree.h>

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <optional>

namespace scandiff::detail {

//! Calls visit(i, neighbours, count) for every point i of the octree's array,
//! from several threads: with a radius, every point within it (the point
//! itself included, in no particular order); without, its k nearest (itself
//! first, closest first). The ticker counts one step per point and may throw
//! Error(Cancelled) from any thread, which stops the whole pass.
template <typename Visit>
void forEachPointNeighbourhood(const octree::Octree& tree, std::optional<double> radius, std::size_t k, ProgressTicker& ticker,
                               Visit&& visit)
{
    if (!radius) {
        const int level = tree.levelNearestMeanPopulation(std::max(8.0, 3.0 * static_cast<double>(k)));
        forEachNeighbourhood(tree, k, level, ticker, visit);
        return;
    }
    // Steps are counted per thread and passed on by the thousand: one atomic
    // update per point would cost more than a small neighbourhood's work.
    tbb::enumerable_thread_specific<std::uint64_t> pending(0);
    tree.withinRadiusBatch(tree.points(), tree.size(), static_cast<float>(*radius),
                           [&](std::uint32_t i, const octree::Neighbour* list, std::size_t count) {
                               visit(static_cast<std::size_t>(i), list, count);
                               std::uint64_t& steps = pending.local();
                               if (++steps == 1024) {
                                   ticker.step(steps);
                                   steps = 0;
                               }
                           });
    for (std::uint64_t steps : pending)
        ticker.step(steps);
}

} // namespace scandiff::detail
