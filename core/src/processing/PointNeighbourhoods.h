// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The neighbourhood of every point of a cloud, by radius or by count, for the
//! processing tools (internal to core).

#include "segmentation/Neighbourhoods.h"

#include <scandiff/core/Progress.h>
#include <scandiff/octree/Octree.h>

#include <algorithm>
#include <optional>

namespace scandiff::detail {

//! Counts a worker's steps and passes them on by the thousand: one atomic
//! update per point would cost more than a small neighbourhood's work. (The
//! last few hundred of each thread are not reported: the bar ends at 99.9 %.)
inline void stepSparingly(ProgressTicker& ticker)
{
    thread_local const ProgressTicker* owner = nullptr;
    thread_local std::uint64_t steps = 0;
    if (owner != &ticker) {
        owner = &ticker;
        steps = 0;
    }
    if (++steps >= 1024) {
        ticker.step(steps);
        steps = 0;
    }
}

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
    tree.withinRadiusBatch(tree.points(), tree.size(), static_cast<float>(*radius),
                           [&](std::uint32_t i, const octree::Neighbour* list, std::size_t count) {
                               visit(static_cast<std::size_t>(i), list, count);
                               stepSparingly(ticker);
                           });
}

//! The same with the moments of each point's neighbourhood within `radius`
//! (its offsets' sums and products, the point itself included) instead of a
//! list: what a plane fit needs, found faster.
template <typename Visit>
void forEachPointMoments(const octree::Octree& tree, double radius, ProgressTicker& ticker, Visit&& visit)
{
    tree.radiusMomentsBatch(tree.points(), tree.size(), static_cast<float>(radius),
                            [&](std::uint32_t i, const octree::NeighbourhoodMoments& moments) {
                                visit(static_cast<std::size_t>(i), moments);
                                stepSparingly(ticker);
                            });
}

} // namespace scandiff::detail
