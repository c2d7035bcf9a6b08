// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The numeric-coded octree of thesis 000, chapter 4: one Morton code per point,
//! points ordered by code, so every cell of every level is a contiguous range
//! found by binary search. The octree never copies the points: it reads the
//! caller's contiguous float array (which must outlive it) and keeps 12 bytes per
//! point (a 64-bit code and a 32-bit point index).
//!
//! Queries run at one level chosen by the caller (or bestLevelFor()); the level
//! changes the speed, never the result: every query is exact, equal to brute
//! force with ties broken by the smaller point index.

#include <scandiff/octree/MortonCode.h>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

namespace scandiff::octree {

namespace detail {
struct QueryGroups;
struct BatchScratch;
struct KeyedIndex;
struct NearestBatchSetup;
} // namespace detail

//! What a plane fit needs of a neighbourhood, without listing it: how many
//! points, and the sums of their offsets d = p - q from the query and of the
//! offsets' products (xx xy xz yy yz zz), in double.
struct NeighbourhoodMoments
{
    std::uint32_t count = 0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::array<double, 6> products{};

    //! Counts one more point at offset d.
    void add(const Eigen::Vector3d& d)
    {
        ++count;
        sum += d;
        products[0] += d.x() * d.x();
        products[1] += d.x() * d.y();
        products[2] += d.x() * d.z();
        products[3] += d.y() * d.y();
        products[4] += d.y() * d.z();
        products[5] += d.z() * d.z();
    }
};

//! An axis-aligned cube: the root cell. Two octrees built on the same cube have
//! equal codes for homologous cells (needed for cloud/cloud work).
struct CubicBox
{
    Eigen::Vector3d min = Eigen::Vector3d::Zero();
    double size = 1.0;

    //! The smallest cube holding every point (a tiny margin keeps the maximum inside).
    static CubicBox enclosing(const Eigen::Vector3f* points, std::size_t count);
    //! The smallest cube holding both boxes' points.
    static CubicBox enclosingBoth(const CubicBox& a, const CubicBox& b);
};

struct LevelStatistics
{
    std::size_t nonEmptyCells = 0;
    double meanPointsPerCell = 0.0;
    std::size_t maxPointsPerCell = 0;
};

struct Neighbour
{
    std::uint32_t index = 0;     //!< point index in the caller's array
    float squaredDistance = 0.0f;
    friend bool operator<(const Neighbour& a, const Neighbour& b)
    {
        return a.squaredDistance < b.squaredDistance ||
               (a.squaredDistance == b.squaredDistance && a.index < b.index);
    }
};

//! Cell adjacency: faces (6), faces and edges (18), faces, edges and corners (26).
enum class Connectivity { Faces6 = 6, Edges18 = 18, Corners26 = 26 };

//! Work counters of batch queries, for the level heuristic's tests and benchmarks.
struct QueryStatistics
{
    std::uint64_t distances = 0;    //!< point distances computed
    std::uint64_t cellLookups = 0;  //!< binary searches for a cell
    std::uint64_t fullSearches = 0; //!< queries the cached neighbourhood did not settle
};

//! The indices 0..count-1 ordered by the Morton code of their point in `box`
//! (points outside the box are clamped to its faces; non-finite ones come
//! last). Processing queries in this order keeps neighbours together in cache
//! and lets batch queries share work between points of one cell.
std::vector<std::uint32_t> mortonOrder(const Eigen::Vector3f* points, std::size_t count, const CubicBox& box,
                                       const std::function<void()>& checkpoint = {});

class Octree
{
public:
    //! Throws std::invalid_argument for an empty array, more than 2^32-1 points,
    //! or a non-finite coordinate (naming the point index). `checkpoint`, when
    //! given, is called between the phases of the build (a few tens of
    //! milliseconds per million points each) so a caller can stop it by throwing.
    Octree(const Eigen::Vector3f* points, std::size_t count, std::optional<CubicBox> box = std::nullopt,
           const std::function<void()>& checkpoint = {});

    std::size_t size() const { return codes_.size(); }
    const CubicBox& box() const { return box_; }
    const Eigen::Vector3f* points() const { return points_; }

    //! Full-depth codes in increasing order, and the point index of each.
    const std::vector<MortonCode>& sortedCodes() const { return codes_; }
    const std::vector<std::uint32_t>& sortedIndices() const { return indices_; }

    //! Statistics of levels 1..kMaxLevel (index 0 is the root: one cell).
    const LevelStatistics& levelStatistics(int level) const { return stats_.at(static_cast<std::size_t>(level)); }
    double cellSize(int level) const { return box_.size / static_cast<double>(1u << level); }

    //! Range [first, last) in sorted order of the cell `cellCode` (3*level bits); empty if no point.
    std::pair<std::size_t, std::size_t> cellRange(MortonCode cellCode, int level) const;

    //! The k nearest points to q, closest first. Fewer than k if the octree is smaller.
    void nearest(const Eigen::Vector3f& q, std::size_t k, int level, std::vector<Neighbour>& out) const;
    //! Every point within `radius` of q (distance <= radius), closest first.
    void withinRadius(const Eigen::Vector3f& q, float radius, int level, std::vector<Neighbour>& out) const;

    //! Calls visit(cellCode, first, last) for every non-empty cell of `level`,
    //! in Morton order; [first, last) is the cell's range in sorted order.
    template <typename Visit>
    void forEachCell(int level, Visit&& visit) const
    {
        const int shift = 3 * (kMaxLevel - level);
        std::size_t first = 0;
        while (first < codes_.size()) {
            const MortonCode cell = codes_[first] >> shift;
            std::size_t last = first + 1;
            while (last < codes_.size() && (codes_[last] >> shift) == cell)
                ++last;
            visit(cell, first, last);
            first = last;
        }
    }

    //! The non-empty cells of the 3 x 3 x 3 block centred on `cellCode` at
    //! `level` (the cell itself included), in increasing code order, each with
    //! its range [first, last) in sorted order. Found in the level's directory
    //! of non-empty cells, within the stretch between the block's corner codes:
    //! much cheaper than 27 calls of cellRange() when done for every cell.
    struct CellSpan
    {
        MortonCode code;
        std::size_t first, last;
    };
    void blockAround(MortonCode cellCode, int level, std::vector<CellSpan>& out) const;

    //! Codes of the non-empty cells adjacent to `cellCode` at `level` (the cell
    //! itself excluded), in increasing order. Cells outside the root cube do not exist.
    std::vector<MortonCode> neighbourCells(MortonCode cellCode, int level, Connectivity connectivity) const;

    //! The k nearest points of every query, in parallel (TBB) with per-thread
    //! scratch and no lock. out[i * k + r] is the r-th neighbour of query i;
    //! missing ones (a cloud smaller than k) are {UINT32_MAX, +inf}. Queries are
    //! visited in Morton order and grouped by cell: the candidates of a cell's
    //! 27-neighbourhood are gathered once for all its queries (thesis 000 §4.4,
    //! "same-cell optimisation"), and a query they do not settle by the
    //! inscribed-sphere rule gets a full search. Exact at every level.
    //! With a finite `maxDistance`, only neighbours within it (squared distance,
    //! in float, at most maxDistance²) are sought and reported, the others
    //! missing: a query far from the cloud then costs a few cells instead of a
    //! full search (what ICP needs with a maximum correspondence distance).
    void nearestBatch(const Eigen::Vector3f* queries, std::size_t count, std::size_t k, int level,
                      std::vector<Neighbour>& out, QueryStatistics* statistics = nullptr,
                      float maxDistance = std::numeric_limits<float>::infinity()) const;

    //! Receives one query's neighbours in withinRadiusBatch(): the query's
    //! index and every point within the radius, in no particular order (the
    //! same order for the same inputs, whatever the number of threads).
    using RadiusVisitor = std::function<void(std::uint32_t query, const Neighbour* neighbours, std::size_t count)>;

    //! Every point within `radius` (distance <= radius, the set withinRadius()
    //! returns) of each query, in parallel (TBB): queries are grouped by cell
    //! at the deepest level whose cells are at least `radius` wide, so the 3 x 3
    //! x 3 block around a cell holds every sphere centred in it; the block's
    //! points are gathered once for all the cell's queries and each query keeps
    //! those within reach. `visit` is called exactly once per query, from the
    //! worker threads, concurrently; an exception it throws (a cancellation)
    //! stops the batch and reaches the caller. A query that is not finite gets
    //! no neighbour. Throws std::invalid_argument for a negative or non-finite radius.
    void withinRadiusBatch(const Eigen::Vector3f* queries, std::size_t count, float radius, const RadiusVisitor& visit) const;

    //! The moments of the same neighbourhoods as withinRadiusBatch() (the same
    //! points: the same float distances and test), without listing them: the
    //! sums are taken as the distances are, four candidates at a time. For the
    //! plane fits of normals and features, a third faster than the lists.
    using MomentsVisitor = std::function<void(std::uint32_t query, const NeighbourhoodMoments& moments)>;
    void radiusMomentsBatch(const Eigen::Vector3f* queries, std::size_t count, float radius, const MomentsVisitor& visit) const;

    //! A finite cylinder in the octree's frame (the points' coordinates), in
    //! double: the points p with t = (p - centre)·axis in [-halfLength,
    //! halfLength] and |p - centre|² - t² <= radius². `axis` must be of unit length.
    struct CylinderQuery
    {
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
        double radius = 0.0;
        double halfLength = 0.0;
    };
    //! Receives one cylinder's points in withinCylinderBatch(): their indices
    //! and their positions t along the axis, in no particular order (the same
    //! order for the same inputs, whatever the number of threads).
    using CylinderVisitor =
        std::function<void(std::uint32_t query, const std::uint32_t* indices, const double* positions, std::size_t count)>;

    //! Every point inside each cylinder, by the exact test above in double on
    //! the float points, in parallel (TBB). Only the cells the cylinder can
    //! touch are read (those whose centre lies within the radius plus their
    //! half-diagonal of the axis segment), at the deepest level whose cells are
    //! at least the radius wide; a cylinder so long that its bounding box holds
    //! too many such cells is searched by descent from the root instead. What
    //! M3C2 needs, a cylinder per core point: a sphere around it would read
    //! several times the cylinder's points on a surface. `visit` is called
    //! exactly once per query, from the worker threads, concurrently; an
    //! exception it throws (a cancellation) stops the batch and reaches the
    //! caller. A query that is not finite, has a zero axis or a negative size
    //! gets no point.
    void withinCylinderBatch(const CylinderQuery* queries, std::size_t count, const CylinderVisitor& visit) const;

    //! The level of thesis 000 §4.5 (eq. 4.2) for k-nearest queries of the
    //! points of `queries`, an octree built on the same cube: the level that
    //! minimises the estimated cost of distances (candidates per query) plus
    //! cell searches, the cells with no homologue counting as full searches.
    int bestLevelFor(const Octree& queries, std::size_t k) const;

    //! The ISPRS 2005 rule (thesis 000 §4.5): the shallowest level whose mean
    //! number of points per non-empty cell is at most `maxMeanPointsPerCell`.
    int levelForMeanPopulation(double maxMeanPointsPerCell) const;

    //! The level whose mean number of points per non-empty cell is nearest
    //! `targetPointsPerCell` on a log scale (the shallowest on a tie): what the
    //! batch queries use so that a cell's 27-neighbourhood settles most queries.
    int levelNearestMeanPopulation(double targetPointsPerCell) const;

private:
    std::array<std::int64_t, 3> cellOf(const Eigen::Vector3f& q, int level) const;
    double squaredGap(MortonCode cell, int level, const Eigen::Vector3f& q) const;
    //! Best-first traversal of the cells down to `leafLevel`; `visitRange` scans
    //! sorted ranges, `prune(gap2)` ends the search once nothing closer remains.
    template <typename Visit, typename Prune>
    void descend(const Eigen::Vector3f& q, int leafLevel, Visit&& visitRange, Prune&& prune) const;
    //! Calls visit(childCode, first, last) for each non-empty child of the
    //! cell `cell` of `level` whose points are the sorted range [first, last).
    template <typename Visit>
    void forEachChild(MortonCode cell, int level, std::size_t first, std::size_t last, Visit&& visit) const
    {
        const int shift = 3 * (kMaxLevel - (level + 1));
        std::size_t begin = first;
        for (MortonCode c = 0; c < 8 && begin < last; ++c) {
            const MortonCode child = (cell << 3) | c;
            const auto end = static_cast<std::size_t>(std::lower_bound(codes_.begin() + static_cast<std::ptrdiff_t>(begin),
                                                                       codes_.begin() + static_cast<std::ptrdiff_t>(last),
                                                                       (child + 1) << shift) -
                                                      codes_.begin());
            if (end > begin)
                visit(child, begin, end);
            begin = end;
        }
    }
    //! The k nearest within sqrt(maxSquared) by best-first descent, as a max-heap.
    void descendNearest(const Eigen::Vector3f& q, std::size_t k, int leafLevel, std::vector<Neighbour>& heap,
                        float maxSquared = std::numeric_limits<float>::infinity()) const;
    void scanCell(std::int64_t x, std::int64_t y, std::int64_t z, int level, const Eigen::Vector3f& q, std::size_t k,
                  std::vector<Neighbour>& heap) const;

    //! The traversal both radius batches share (RadiusBatch.cpp): per query,
    //! perQuery(query, candidates, count) with candidates [0, count) of a
    //! scratch holding every point within the radius (and a few more).
    template <typename PerQuery>
    void forEachRadiusRun(const Eigen::Vector3f* queries, std::size_t count, float radius, PerQuery&& perQuery) const;

    //! The queries in Morton order at `level`, grouped by cell (BatchQueries.h).
    detail::QueryGroups groupQueriesByCell(const Eigen::Vector3f* queries, std::size_t count, int level) const;

    //! The non-empty cells of one level with where their points start: batch
    //! queries search this (small, cache-resident) list instead of every code.
    struct CellDirectory
    {
        std::vector<MortonCode> codes;
        std::vector<std::uint32_t> starts; //!< one more than codes: the end
    };
    //! Built on first use for a level and kept (thread-safe): callers that query
    //! in chunks must not rebuild it for every chunk.
    const CellDirectory& cellDirectory(int level) const;

    //! nearestBatch's steps (NearestBatch.cpp): one query searched alone
    //! (outside the cube, or not settled by its cell's block), and the
    //! queries [first, last) of one cell answered from its 27-cell block.
    void nearestAlone(const Eigen::Vector3f& q, const detail::NearestBatchSetup& setup, std::vector<Neighbour>& heap) const;
    void nearestInCellGroup(const Eigen::Vector3f* queries, const detail::KeyedIndex* first, const detail::KeyedIndex* last,
                            const detail::NearestBatchSetup& setup, const CellDirectory& directory, detail::BatchScratch& s,
                            Neighbour* out) const;
    struct DirectoryCache
    {
        std::mutex mutex;
        std::array<std::unique_ptr<CellDirectory>, kMaxLevel + 1> levels;
    };

    const Eigen::Vector3f* points_;
    CubicBox box_;
    std::shared_ptr<DirectoryCache> directories_ = std::make_shared<DirectoryCache>();
    std::vector<MortonCode> codes_;
    std::vector<std::uint32_t> indices_;
    std::vector<LevelStatistics> stats_;
};

} // namespace scandiff::octree
