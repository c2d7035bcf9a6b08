// SPDX-License-Identifier: GPL-3.0-or-later
//! The batched k-nearest search (Octree::nearestBatch), the distances' inner
//! loop: queries grouped by cell (thesis 000 §4.4, "same-cell optimisation"),
//! each cell's 27-cell block gathered once, each query answered from it when
//! the inscribed sphere settles it (eq. 4.1), by a full search otherwise.

#include <scandiff/octree/Octree.h>

#include "BatchQueries.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace scandiff::octree {

using detail::BatchScratch;
using detail::KeyedIndex;
using detail::kGuessFactor;
using detail::kSlack;
using detail::NearestBatchSetup;
using detail::neighbourhoodOffsets;

namespace {

constexpr std::uint32_t kNoIndex = std::numeric_limits<std::uint32_t>::max();

//! Writes a query's k slots: what was found, then `missing` entries.
void storeNeighbours(Neighbour* out, std::size_t k, std::uint32_t query, const std::vector<Neighbour>& found)
{
    const Neighbour missing{kNoIndex, std::numeric_limits<float>::infinity()};
    Neighbour* at = out + std::size_t(query) * k;
    std::copy(found.begin(), found.end(), at);
    std::fill(at + found.size(), at + k, missing);
}

//! The squared gaps from one query to the cells of its cell's 27-cell block:
//! per axis, to the near face of the neighbour at offset -1, 0 or +1 (a
//! cell's gap is their sum); and per group of offsets (faces, edges,
//! corners, in neighbourhoodOffsets() order) a lower bound on every gap of
//! the group, the sum of the 1, 2 or 3 smallest per-axis gaps.
class BlockGaps
{
public:
    BlockGaps(const Eigen::Vector3d& local, double cellSize) : offsets_(neighbourhoodOffsets())
    {
        for (int a = 0; a < 3; ++a) {
            const double below = 0.5 * cellSize + local[a], above = 0.5 * cellSize - local[a];
            faceGap2_[a][0] = below * below;
            faceGap2_[a][1] = 0.0;
            faceGap2_[a][2] = above * above;
        }
        std::array<double, 3> axisGap2;
        for (int a = 0; a < 3; ++a)
            axisGap2[static_cast<std::size_t>(a)] = std::min(faceGap2_[a][0], faceGap2_[a][2]);
        std::sort(axisGap2.begin(), axisGap2.end());
        groupGap2_[0] = axisGap2[0];
        groupGap2_[1] = axisGap2[0] + axisGap2[1];
        groupGap2_[2] = axisGap2[0] + axisGap2[1] + axisGap2[2];
    }

    double gapTo(std::size_t c) const
    {
        return faceGap2_[0][offsets_[c][0] + 1] + faceGap2_[1][offsets_[c][1] + 1] + faceGap2_[2][offsets_[c][2] + 1];
    }
    //! True when c starts a group (faces at 1, edges at 7, corners at 19)
    //! whose every cell lies beyond `limit`: the rest is skipped unseen.
    bool groupBeyond(std::size_t c, double limit) const
    {
        const int group = c == 1 ? 0 : c == 7 ? 1 : c == 19 ? 2 : -1;
        return group >= 0 && groupGap2_[group] > limit;
    }

private:
    const std::array<std::array<int, 3>, 27>& offsets_;
    double faceGap2_[3][3];
    double groupGap2_[3];
};

//! k = 1, the common case (cloud/cloud distance): a running minimum in one
//! pass per cell, the own cell first, then faces, edges and corners; a cell
//! whose box is already farther than the best distance is skipped (ties are
//! still scanned). Bounded: a candidate at most at the bound is kept (the
//! tie rule prefers any index to the missing one).
template <class Gathered>
void nearestOneInBlock(const Eigen::Vector3f& q, const BlockGaps& gaps, float maxSquared, BatchScratch& s, Gathered&& gathered)
{
    float bestDistance = maxSquared;
    std::uint32_t bestIndex = kNoIndex;
    std::size_t scanned = 0;
    for (std::size_t c = 0; c < 27; ++c) {
        if (gaps.groupBeyond(c, static_cast<double>(bestDistance) * (1 + kSlack)))
            break;
        if (s.cellState[c] == BatchScratch::kEmpty || gaps.gapTo(c) > static_cast<double>(bestDistance) * (1 + kSlack) ||
            !gathered(c))
            continue;
        s.foldNearest(q, s.cellBegin[c], s.cellEnd[c], bestDistance, bestIndex);
        scanned += s.cellEnd[c] - s.cellBegin[c];
    }
    if (bestIndex != kNoIndex)
        s.heap.push_back(Neighbour{bestIndex, bestDistance});
    s.statistics.distances += scanned;
}

//! k > 1: first every candidate within a radius guessed from the previous
//! query of the cell (kGuessFactor times its squared k-th distance),
//! selected without ordering them one by one. Exact whenever at least k
//! candidates fall within the guess: every point left out is farther than
//! the guess, hence than the k-th. Else the cells in order of their gap.
template <class Gathered>
void nearestManyInBlock(const Eigen::Vector3f& q, std::size_t k, const BlockGaps& gaps, BatchScratch& s, Gathered&& gathered)
{
    std::size_t scanned = 0;
    const auto gapTo = [&gaps](std::size_t c) { return gaps.gapTo(c); };
    bool selected = false;
    if (s.guess < std::numeric_limits<float>::infinity())
        selected = s.selectWithin(q, kGuessFactor * s.guess, k, [&gaps](std::size_t c, double limit) { return gaps.groupBeyond(c, limit); },
                                  gapTo, gathered, 27, scanned);
    if (!selected)
        s.selectInGapOrder(q, k, gapTo, gathered, 27, scanned);
    s.guess = s.heap.size() == k ? s.heap.back().squaredDistance : std::numeric_limits<float>::infinity();
    s.statistics.distances += scanned;
}

//! Whether the block's answer is final: the k-th distance inside the sphere
//! inscribed in the 27 cells around q (eq. 4.1 with j = 1) or, bounded, the
//! bound itself inside it. Bounded answers first lose their entries beyond
//! the bound. s.heap holds the answer sorted (k = 1: its single entry).
bool blockSettles(BatchScratch& s, const Eigen::Vector3d& local, const NearestBatchSetup& setup)
{
    const double inner = 0.5 * setup.cellSize - local.cwiseAbs().maxCoeff();
    const double inscribed = setup.cellSize + inner;
    while (setup.bounded && !s.heap.empty() && s.heap.back().squaredDistance > setup.maxSquared)
        s.heap.pop_back();
    return (s.heap.size() >= setup.k && static_cast<double>(s.heap.back().squaredDistance) * (1 + kSlack) < inscribed * inscribed) ||
           (setup.bounded && static_cast<double>(setup.maxDistance) * (1 + kSlack) < inscribed);
}

} // namespace

void Octree::nearestAlone(const Eigen::Vector3f& q, const NearestBatchSetup& setup, std::vector<Neighbour>& heap) const
{
    if (setup.bounded) {
        // The bounded full search: best-first descent pruned at the distance.
        heap.clear();
        descendNearest(q, setup.k, setup.level, heap, setup.maxSquared);
        std::sort_heap(heap.begin(), heap.end());
    } else {
        nearest(q, setup.k, setup.level, heap);
    }
}

void Octree::nearestInCellGroup(const Eigen::Vector3f* queries, const KeyedIndex* first, const KeyedIndex* last,
                                const NearestBatchSetup& setup, const CellDirectory& directory, BatchScratch& s, Neighbour* out) const
{
    const std::int64_t n = setup.cellsPerAxis;
    const double l = setup.cellSize;
    const CellCoordinates cellCoordinates = decodeCell(first->code);
    // Signed copies: the neighbourhood of a cell on the cube's low faces starts at -1.
    const std::int64_t cx = cellCoordinates.x, cy = cellCoordinates.y, cz = cellCoordinates.z;
    const auto& offsets = neighbourhoodOffsets();
    s.used = 0;
    // s.guess carries over from the previous cell of this worker, a near one
    // in Morton order with about the same density: the group's first query
    // then tries it too instead of the slower search in gap order (it falls
    // back to that if the guess holds fewer than k candidates).
    const detail::BlockLookup block(directory.codes, directory.starts, cx, cy, cz, n);
    for (std::size_t c = 0; c < offsets.size(); ++c) {
        const std::int64_t x = cx + offsets[c][0], y = cy + offsets[c][1], z = cz + offsets[c][2];
        const bool inCube = x >= 0 && y >= 0 && z >= 0 && x < n && y < n && z < n;
        s.cellState[c] = inCube ? BatchScratch::kUnknown : BatchScratch::kEmpty;
    }
    // Looks up and copies neighbour cell c on first use; false if it is empty.
    auto gathered = [&](std::size_t c) {
        if (s.cellState[c] == BatchScratch::kUnknown) {
            const auto [b, e] = block.range(encodeCell(static_cast<std::uint32_t>(cx + offsets[c][0]),
                                                       static_cast<std::uint32_t>(cy + offsets[c][1]),
                                                       static_cast<std::uint32_t>(cz + offsets[c][2])));
            ++s.statistics.cellLookups;
            if (b == e)
                s.cellState[c] = BatchScratch::kEmpty;
            else
                s.gather(c, b, e, indices_.data(), points_);
        }
        return s.cellState[c] == BatchScratch::kGathered;
    };
    const Eigen::Vector3d centre = box_.min + (Eigen::Vector3d(double(cx), double(cy), double(cz)).array() + 0.5).matrix() * l;
    for (const KeyedIndex* query = first; query != last; ++query) {
        const Eigen::Vector3f& q = queries[query->index];
        s.heap.clear();
        const Eigen::Vector3d local = q.cast<double>() - centre;
        const BlockGaps gaps(local, l);
        if (setup.k == 1)
            nearestOneInBlock(q, gaps, setup.maxSquared, s, gathered);
        else
            nearestManyInBlock(q, setup.k, gaps, s, gathered);
        if (!blockSettles(s, local, setup)) {
            nearestAlone(q, setup, s.heap);
            ++s.statistics.fullSearches;
        }
        storeNeighbours(out, setup.k, query->index, s.heap);
    }
}

void Octree::nearestBatch(const Eigen::Vector3f* queries, std::size_t count, std::size_t k, int level,
                          std::vector<Neighbour>& out, QueryStatistics* statistics, float maxDistance) const
{
    if (level < 1 || level > kMaxLevel)
        throw std::invalid_argument("octree level must be in 1.." + std::to_string(kMaxLevel));
    if (std::isnan(maxDistance) || maxDistance < 0)
        throw std::invalid_argument("the maximum distance must be >= 0");
    NearestBatchSetup setup;
    setup.k = k;
    setup.level = level;
    setup.bounded = maxDistance < std::numeric_limits<float>::infinity();
    setup.maxDistance = maxDistance;
    setup.maxSquared = setup.bounded ? maxDistance * maxDistance : std::numeric_limits<float>::infinity();
    setup.cellsPerAxis = std::int64_t(1) << level;
    setup.cellSize = cellSize(level);
    // Every slot is written by the worker that answers its query (padded with
    // missing entries), so a caller's buffer of the right size is reused as
    // it is, without a serial pass over it.
    if (out.size() != count * k)
        out.resize(count * k);
    if (count == 0 || k == 0)
        return;

    const detail::QueryGroups groups = groupQueriesByCell(queries, count, level);
    const std::vector<KeyedIndex>& order = groups.order;
    const std::vector<std::size_t>& groupStart = groups.start;
    // The level's directory of non-empty cells: one binary search over the cells
    // (small enough to stay in cache) instead of two over every code.
    const CellDirectory& directory = cellDirectory(level);
    tbb::enumerable_thread_specific<BatchScratch> scratch;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groupStart.size() - 1, 16), [&](const tbb::blocked_range<std::size_t>& range) {
        BatchScratch& s = scratch.local();
        for (std::size_t g = range.begin(); g != range.end(); ++g) {
            const KeyedIndex* first = order.data() + groupStart[g];
            const KeyedIndex* last = order.data() + groupStart[g + 1];
            if (first->code != groups.outside) {
                nearestInCellGroup(queries, first, last, setup, directory, s, out.data());
                continue;
            }
            // Outside the cube: each query searched alone (none for a NaN).
            for (const KeyedIndex* query = first; query != last; ++query) {
                s.heap.clear();
                if (queries[query->index].allFinite()) {
                    nearestAlone(queries[query->index], setup, s.heap);
                    ++s.statistics.fullSearches;
                }
                storeNeighbours(out.data(), k, query->index, s.heap);
            }
        }
    });
    if (statistics) {
        *statistics = QueryStatistics{};
        for (const BatchScratch& s : scratch) {
            statistics->distances += s.statistics.distances;
            statistics->cellLookups += s.statistics.cellLookups;
            statistics->fullSearches += s.statistics.fullSearches;
        }
    }
}

} // namespace scandiff::octree
