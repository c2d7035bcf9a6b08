// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What the octree's batch queries (k nearest and radius) share: queries
//! grouped by cell, the lookup of a cell's 27-cell block, and the per-thread
//! scratch holding the block's candidates as coordinate arrays with the kernels
//! that scan them. Internal to octree/.

#include <scandiff/octree/Octree.h>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace scandiff::octree::detail {

// Float distances are compared against double geometric bounds; this relative
// slack makes the pruning and stopping tests conservative so that rounding can
// never drop a point that brute force would return.
constexpr double kSlack = 1e-5;

//! A code and its point index, packed to 12 bytes so the sort moves less memory.
#pragma pack(push, 4)
struct KeyedIndex
{
    MortonCode code;
    std::uint32_t index;
};
#pragma pack(pop)
static_assert(sizeof(KeyedIndex) == 12, "KeyedIndex must stay packed");

//! Queries in Morton order at one level, grouped by cell: group g is
//! order[start[g] .. start[g + 1]). A query outside the cube (or not finite)
//! has the code `outside` (one past the level's last cell) and a group of its own.
struct QueryGroups
{
    std::vector<KeyedIndex> order;
    std::vector<std::size_t> start;
    MortonCode outside = 0;
};

//! What every query of one nearest-neighbour batch shares (NearestBatch.cpp).
struct NearestBatchSetup
{
    std::size_t k = 1;
    int level = 1;
    bool bounded = false; //!< a finite maximum distance
    float maxDistance = std::numeric_limits<float>::infinity();
    float maxSquared = std::numeric_limits<float>::infinity();
    std::int64_t cellsPerAxis = 2;
    double cellSize = 1.0;
};

//! Finds the cells of the 3 x 3 x 3 block around one cell in a level's
//! directory of non-empty cells (codes in increasing order, and where each
//! cell's points start in sorted order, one more entry for the end). Morton
//! codes grow with each coordinate, so the block's cells lie between the codes
//! of its low and high corners: two searches over the directory find that short
//! stretch, and each cell is then searched within it.
class BlockLookup
{
public:
    BlockLookup(const std::vector<MortonCode>& codes, const std::vector<std::uint32_t>& starts, std::int64_t cx,
                std::int64_t cy, std::int64_t cz, std::int64_t cellsPerAxis)
        : codes_(codes), starts_(starts)
    {
        auto clampedCode = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
            auto clamp = [&](std::int64_t v) { return static_cast<std::uint32_t>(std::clamp<std::int64_t>(v, 0, cellsPerAxis - 1)); };
            return encodeCell(clamp(x), clamp(y), clamp(z));
        };
        const auto begin = codes.begin();
        const auto stretchBegin = std::lower_bound(begin, codes.end(), clampedCode(cx - 1, cy - 1, cz - 1));
        const auto stretchEnd = std::upper_bound(stretchBegin, codes.end(), clampedCode(cx + 1, cy + 1, cz + 1));
        from_ = static_cast<std::size_t>(stretchBegin - begin);
        to_ = static_cast<std::size_t>(stretchEnd - begin);
    }

    //! The sorted range [first, last) of the cell `code`; empty when it holds no point.
    std::pair<std::size_t, std::size_t> range(MortonCode code) const
    {
        const auto begin = codes_.begin();
        const auto it = std::lower_bound(begin + static_cast<std::ptrdiff_t>(from_), begin + static_cast<std::ptrdiff_t>(to_), code);
        if (it == begin + static_cast<std::ptrdiff_t>(to_) || *it != code)
            return {0, 0};
        const auto d = static_cast<std::size_t>(it - begin);
        return {starts_[d], starts_[d + 1]};
    }

private:
    const std::vector<MortonCode>& codes_;
    const std::vector<std::uint32_t>& starts_;
    std::size_t from_ = 0, to_ = 0;
};

//! Per-thread scratch of nearestBatch: the candidates of one query cell's
//! neighbourhood, copied contiguously so the inner loops stream through memory.
//! A neighbour cell is looked up and copied only when a query of the group
//! first needs it (its box is nearer than the query's best distance so far):
//! most groups never touch their corner cells.
struct BatchScratch
{
    enum : std::uint8_t { kUnknown, kEmpty, kGathered };

    //! Candidate coordinates as three arrays (structure of arrays), so that the
    //! distances of a cell's candidates are computed four at a time.
    std::vector<float> x, y, z;
    std::vector<std::uint32_t> indices;
    std::vector<float> distances; //!< one cell's squared distances (k > 1)
    std::vector<Neighbour> heap;
    std::vector<Neighbour> top; //!< k > 1: the k best so far of one query
    //! k > 1: the candidates within a guessed distance (selectWithin)
    std::vector<float> survivorDistances;
    std::vector<std::uint32_t> survivorIndices;
    std::vector<Neighbour> ordered;
    //! k > 1: the previous query's squared k-th distance (in this cell, or the worker's previous one)
    float guess = std::numeric_limits<float>::infinity();
    std::uint32_t used = 0; //!< candidates gathered for the current group
    //! Per neighbour offset (neighbourhoodOffsets() order): state and the
    //! candidates' range in the arrays once gathered.
    std::array<std::uint8_t, 27> cellState{};
    std::array<std::uint32_t, 27> cellBegin{}, cellEnd{};
    QueryStatistics statistics;

    //! Appends the points of sorted range [b, e) (their indices in
    //! sortedIndices) as the candidates of neighbour cell c.
    void gather(std::size_t c, std::size_t b, std::size_t e, const std::uint32_t* sortedIndices, const Eigen::Vector3f* points)
    {
        reserve(used + (e - b));
        float *px = x.data(), *py = y.data(), *pz = z.data();
        std::uint32_t* gatheredIndices = indices.data();
        std::uint32_t j = used;
        for (std::size_t i = b; i < e; ++i, ++j) {
            const std::uint32_t index = sortedIndices[i];
            const Eigen::Vector3f& p = points[index];
            gatheredIndices[j] = index;
            px[j] = p.x();
            py[j] = p.y();
            pz[j] = p.z();
        }
        cellBegin[c] = used;
        cellEnd[c] = j;
        used = j;
        cellState[c] = kGathered;
    }

    void reserve(std::size_t size)
    {
        if (x.size() >= size)
            return;
        const std::size_t grown = std::max(size, 2 * x.size());
        x.resize(grown);
        y.resize(grown);
        z.resize(grown);
        indices.resize(grown);
        distances.resize(grown);
        survivorDistances.resize(grown);
        survivorIndices.resize(grown);
    }

    //! The squared distance from q to candidate j, with the float operations
    //! of Eigen's squaredNorm(), x^2 + (y^2 + z^2), so that the results are
    //! bitwise those of nearest() and brute force; and the same for candidates
    //! j .. j + 3 (q given per coordinate, broadcast).
    float squaredDistance(const Eigen::Vector3f& q, std::uint32_t j) const
    {
        const float dx = x[j] - q.x(), dy = y[j] - q.y(), dz = z[j] - q.z();
        return dx * dx + (dy * dy + dz * dz);
    }
#ifdef __SSE2__
    __m128 squaredDistances4(__m128 qx, __m128 qy, __m128 qz, std::uint32_t j) const
    {
        const __m128 dx = _mm_sub_ps(_mm_loadu_ps(x.data() + j), qx);
        const __m128 dy = _mm_sub_ps(_mm_loadu_ps(y.data() + j), qy);
        const __m128 dz = _mm_sub_ps(_mm_loadu_ps(z.data() + j), qz);
        return _mm_add_ps(_mm_mul_ps(dx, dx), _mm_add_ps(_mm_mul_ps(dy, dy), _mm_mul_ps(dz, dz)));
    }
#endif

    //! Appends the candidates of [begin, end) within squared distance `limit`
    //! of q to the survivors, from position m; returns the new count. Most
    //! candidates fall outside, so four are tested at once where SSE2 is
    //! available and a group of four with none inside costs one branch.
    std::size_t keepWithin(const Eigen::Vector3f& q, std::uint32_t begin, std::uint32_t end, float limit, std::size_t m)
    {
        float* survivorDistance = survivorDistances.data();
        std::uint32_t* survivorIndex = survivorIndices.data();
        std::uint32_t j = begin;
#ifdef __SSE2__
        const __m128 qx = _mm_set1_ps(q.x()), qy = _mm_set1_ps(q.y()), qz = _mm_set1_ps(q.z()), bound = _mm_set1_ps(limit);
        for (; j + 4 <= end; j += 4) {
            const __m128 d = squaredDistances4(qx, qy, qz, j);
            int inside = _mm_movemask_ps(_mm_cmple_ps(d, bound));
            if (inside == 0)
                continue;
            alignas(16) float lanes[4];
            _mm_store_ps(lanes, d);
            for (; inside != 0; inside &= inside - 1) {
                const int lane = __builtin_ctz(static_cast<unsigned>(inside));
                survivorDistance[m] = lanes[lane];
                survivorIndex[m++] = indices[j + static_cast<std::uint32_t>(lane)];
            }
        }
#endif
        for (; j < end; ++j) {
            const float d = squaredDistance(q, j);
            survivorDistance[m] = d;
            survivorIndex[m] = indices[j];
            m += d <= limit;
        }
        return m;
    }

    //! The k nearest among the candidates within squared distance `limit` of q,
    //! into heap (sorted), if there are at least k; false (heap untouched) if
    //! not. Cells are skipped by their gap (gapTo) or their group (beyond);
    //! gathered(c) brings a cell in. The survivors are ranked by counting
    //! (branch-free, for the usual few dozen) or partially sorted.
    template <typename Beyond, typename Gap, typename Gather>
    bool selectWithin(const Eigen::Vector3f& q, float limit, std::size_t k, Beyond&& beyond, Gap&& gapTo, Gather&& gathered,
                      std::size_t cells, std::size_t& scanned)
    {
        const double reach = static_cast<double>(limit) * (1 + kSlack);
        std::size_t m = 0;
        for (std::size_t c = 0; c < cells; ++c) {
            if (beyond(c, reach))
                break;
            if (cellState[c] == kEmpty || gapTo(c) > reach || !gathered(c))
                continue;
            const std::uint32_t begin = cellBegin[c], end = cellEnd[c];
            m = keepWithin(q, begin, end, limit, m);
            scanned += end - begin;
        }
        if (m < k)
            return false;
        heap.resize(k);
        const float* d = survivorDistances.data();
        const std::uint32_t* id = survivorIndices.data();
        if (m <= 64) {
            // Rank of each survivor among them, (distance, index) order: the
            // inner loop has no branch and vectorises.
            for (std::size_t i = 0; i < m; ++i) {
                const float di = d[i];
                const std::uint32_t ii = id[i];
                std::uint32_t rank = 0;
                for (std::size_t j = 0; j < m; ++j)
                    rank += static_cast<std::uint32_t>((d[j] < di) | ((d[j] == di) & (id[j] < ii)));
                if (rank < k)
                    heap[rank] = Neighbour{ii, di};
            }
        } else {
            ordered.resize(m);
            for (std::size_t i = 0; i < m; ++i)
                ordered[i] = Neighbour{id[i], d[i]};
            std::partial_sort(ordered.begin(), ordered.begin() + static_cast<std::ptrdiff_t>(k), ordered.end());
            std::copy(ordered.begin(), ordered.begin() + static_cast<std::ptrdiff_t>(k), heap.begin());
        }
        return true;
    }

    //! The k nearest of q into heap (sorted; fewer if the neighbourhood holds
    //! fewer), when no guess settled it: the own cell first, then the other
    //! cells by increasing gap to q, into a sorted list of the k best so far.
    //! Once the list is full, a cell whose box lies farther than its last
    //! entry cannot contribute, and neither can any later cell; cells already
    //! beyond the own cell's k-th distance are not even sorted.
    template <typename Gap, typename Gather>
    void selectInGapOrder(const Eigen::Vector3f& q, std::size_t k, Gap&& gapTo, Gather&& gathered, std::size_t cells,
                          std::size_t& scanned)
    {
        // The list in a plain array, its size and k-th distance in locals
        // (registers), not in a vector's fields.
        if (top.size() < k)
            top.resize(k);
        Neighbour* best = top.data();
        std::size_t size = 0;
        float worst = std::numeric_limits<float>::infinity(); // k-th distance once full
        auto scan = [&](std::size_t c) {
            const std::uint32_t begin = cellBegin[c];
            const std::size_t count = cellEnd[c] - begin;
            float* d2 = distances.data();
            squaredDistances(q, begin, count, d2);
            for (std::size_t j = 0; j < count; ++j) {
                if (d2[j] > worst)
                    continue;
                const Neighbour candidate{indices[begin + j], d2[j]};
                std::size_t at;
                if (size == k) {
                    if (!(candidate < best[k - 1]))
                        continue; // a tie at the k-th distance with a larger index
                    at = k - 1;
                } else {
                    at = size++;
                }
                // Insertion from the back: for a dozen entries, cheaper than a
                // binary search's unpredictable branches.
                for (; at > 0 && candidate < best[at - 1]; --at)
                    best[at] = best[at - 1];
                best[at] = candidate;
                if (size == k)
                    worst = best[k - 1].squaredDistance;
            }
            scanned += count;
        };
        if (cellState[0] != kEmpty && gathered(0))
            scan(0);
        const double bound = static_cast<double>(worst) * (1 + kSlack); // +inf until k are found
        std::array<std::pair<double, std::size_t>, 26> byGap;
        std::size_t candidates = 0;
        for (std::size_t c = 1; c < cells; ++c) {
            if (cellState[c] == kEmpty)
                continue;
            const double gap2 = gapTo(c);
            if (gap2 > bound)
                continue;
            std::size_t j = candidates++;
            for (; j > 0 && byGap[j - 1].first > gap2; --j)
                byGap[j] = byGap[j - 1];
            byGap[j] = {gap2, c};
        }
        for (std::size_t r = 0; r < candidates; ++r) {
            const auto [gap2, c] = byGap[r];
            if (gap2 > static_cast<double>(worst) * (1 + kSlack))
                break;
            if (gathered(c))
                scan(c);
        }
        heap.assign(best, best + size);
    }

    //! Squared distances from q to candidates [begin, begin + count) into d2,
    //! with the float operations of Eigen's squaredNorm(), x^2 + (y^2 + z^2),
    //! so that the results are bitwise those of nearest() and brute force.
    void squaredDistances(const Eigen::Vector3f& q, std::size_t begin, std::size_t count, float* d2) const
    {
        using Column = Eigen::Map<const Eigen::ArrayXf>;
        const Eigen::Index n = static_cast<Eigen::Index>(count);
        Eigen::Map<Eigen::ArrayXf>(d2, n) = (Column(x.data() + begin, n) - q.x()).square() +
                                            ((Column(y.data() + begin, n) - q.y()).square() +
                                             (Column(z.data() + begin, n) - q.z()).square());
    }

    //! Folds candidates [begin, end) into (bestDistance, bestIndex): the
    //! smallest squared distance, ties to the smallest point index, exactly as
    //! brute force decides. One pass, four candidates per step where SSE2 is
    //! available (every x86-64).
    void foldNearest(const Eigen::Vector3f& q, std::uint32_t begin, std::uint32_t end, float& bestDistance,
                     std::uint32_t& bestIndex) const
    {
        std::uint32_t j = begin;
        auto better = [](float d, std::uint32_t i, float bd, std::uint32_t bi) { return d < bd || (d == bd && i < bi); };
#ifdef __SSE2__
        if (end - begin >= 8) {
            const __m128 qx = _mm_set1_ps(q.x()), qy = _mm_set1_ps(q.y()), qz = _mm_set1_ps(q.z());
            // Indices compared as signed integers after flipping the sign bit,
            // which orders them as unsigned (SSE2 has no unsigned compare).
            const __m128i bias = _mm_set1_epi32(static_cast<int>(0x80000000u));
            __m128 laneDistance = _mm_set1_ps(bestDistance);
            __m128i laneIndex = _mm_xor_si128(_mm_set1_epi32(static_cast<int>(bestIndex)), bias);
            for (; j + 4 <= end; j += 4) {
                const __m128 d = squaredDistances4(qx, qy, qz, j);
                const __m128i i = _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(indices.data() + j)), bias);
                const __m128 take = _mm_or_ps(_mm_cmplt_ps(d, laneDistance),
                                              _mm_and_ps(_mm_cmpeq_ps(d, laneDistance), _mm_castsi128_ps(_mm_cmplt_epi32(i, laneIndex))));
                laneDistance = _mm_or_ps(_mm_and_ps(take, d), _mm_andnot_ps(take, laneDistance));
                const __m128i takeIndex = _mm_castps_si128(take);
                laneIndex = _mm_or_si128(_mm_and_si128(takeIndex, i), _mm_andnot_si128(takeIndex, laneIndex));
            }
            alignas(16) float lanes[4];
            alignas(16) std::uint32_t laneIndices[4];
            _mm_store_ps(lanes, laneDistance);
            _mm_store_si128(reinterpret_cast<__m128i*>(laneIndices), _mm_xor_si128(laneIndex, bias));
            for (int lane = 0; lane < 4; ++lane)
                if (better(lanes[lane], laneIndices[lane], bestDistance, bestIndex)) {
                    bestDistance = lanes[lane];
                    bestIndex = laneIndices[lane];
                }
        }
#endif
        for (; j < end; ++j) {
            const float d = squaredDistance(q, j);
            if (better(d, indices[j], bestDistance, bestIndex)) {
                bestDistance = d;
                bestIndex = indices[j];
            }
        }
    }
};

//! k > 1: the squared radius a query first tries, relative to the previous
//! query's squared k-th distance in the same cell (1.5: measured best of 1.2,
//! 1.5, 2 and 3 on the benchmark's surface, no difference between 1.25, 1.5
//! and 2 on the c2c data; a guess that holds fewer than k candidates costs
//! one ordinary search more).
constexpr float kGuessFactor = 1.5f;

//! The 27 cell offsets, the own cell first, then faces, edges and corners, so
//! that the closest candidates come first and the later cells are often pruned.
inline const std::array<std::array<int, 3>, 27>& neighbourhoodOffsets()
{
    static const std::array<std::array<int, 3>, 27> offsets = [] {
        std::array<std::array<int, 3>, 27> o{};
        int i = 0;
        for (int nonZero = 0; nonZero <= 3; ++nonZero)
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz)
                        if ((dx != 0) + (dy != 0) + (dz != 0) == nonZero)
                            o[static_cast<std::size_t>(i++)] = {dx, dy, dz};
        return o;
    }();
    return offsets;
}

} // namespace scandiff::octree::detail
