// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The neighbourhood of every point of a cloud, by radius or by count, for the
//! processing tools (internal to core).

#include "segmentation/Neighbourhoods.h"

#include <scandiff/core/Progress.h>
#include <scandiff/octree/Octree.h>

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <atomic>
#include <optional>

namespace scandiff::detail {

//! Counts the workers' steps of one parallel pass and passes them on to the
//! ticker by the thousand (one atomic update per point would cost more than a
//! small neighbourhood's work); flush() passes on what each thread has left
//! once the pass is over. The ticker then hears exactly the pass's steps,
//! whatever the threads' share, and polls as often on every run (the last
//! poll included: tests press Cancel there).
class SparseSteps
{
public:
    explicit SparseSteps(ProgressTicker& ticker) : ticker_(ticker), id_(nextId()) {}
    void step()
    {
        // The thread's counter found once per pass, not per point (a lookup
        // in the thread-specific table costs more than the count); keyed by
        // the pass's id, as another pass may live at the same address later.
        thread_local std::uint64_t cachedId = 0;
        thread_local std::uint64_t* cached = nullptr;
        if (cachedId != id_) {
            cachedId = id_;
            cached = &pending_.local();
        }
        std::uint64_t& pending = *cached;
        if (++pending >= 1024) {
            ticker_.step(pending);
            pending = 0;
        }
    }
    void flush()
    {
        std::uint64_t rest = 0;
        for (std::uint64_t& pending : pending_) {
            rest += pending;
            pending = 0;
        }
        if (rest > 0)
            ticker_.step(rest);
    }

private:
    static std::uint64_t nextId()
    {
        static std::atomic<std::uint64_t> last{0};
        return ++last;
    }
    ProgressTicker& ticker_;
    std::uint64_t id_;
    tbb::enumerable_thread_specific<std::uint64_t> pending_{0};
};

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
    SparseSteps steps(ticker);
    tree.withinRadiusBatch(tree.points(), tree.size(), static_cast<float>(*radius),
                           [&](std::uint32_t i, const octree::Neighbour* list, std::size_t count) {
                               visit(static_cast<std::size_t>(i), list, count);
                               steps.step();
                           });
    steps.flush();
}

//! The same with the moments of each point's neighbourhood within `radius`
//! (its offsets' sums and products, the point itself included) instead of a
//! list: what a plane fit needs, found faster.
template <typename Visit>
void forEachPointMoments(const octree::Octree& tree, double radius, ProgressTicker& ticker, Visit&& visit)
{
    SparseSteps steps(ticker);
    tree.radiusMomentsBatch(tree.points(), tree.size(), static_cast<float>(radius),
                            [&](std::uint32_t i, const octree::NeighbourhoodMoments& moments) {
                                visit(static_cast<std::size_t>(i), moments);
                                steps.step();
                            });
    steps.flush();
}

} // namespace scandiff::detail
