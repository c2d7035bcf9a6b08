// SPDX-License-Identifier: GPL-3.0-or-later
// Batch radius queries: the neighbourhoods normals, local features, smoothing
// and subsampling need for every point of a cloud.
#include <scandiff/octree/Octree.h>

#include "BatchQueries.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace scandiff::octree {

namespace {

//! Queries per run: a few consecutive queries in Morton order lie close
//! together, so the candidates within reach of their common box are picked
//! once for all of them.
constexpr std::size_t kRun = 8;

//! The sums of the offsets p - q of the candidates [0, m) of `near` within
//! squared distance r2 of q, and of their products, into `moments`. The
//! distance is the one every query computes (float, x^2 + (y^2 + z^2)), so the
//! points counted are exactly those withinRadiusBatch() lists; the sums are in
//! double, four candidates at a time where SSE2 is available, those outside
//! masked to zero rather than branched over.
void accumulateMoments(const detail::BatchScratch& near, std::size_t m, const Eigen::Vector3f& q, float r2,
                       NeighbourhoodMoments& moments)
{
    moments = NeighbourhoodMoments{};
    std::size_t j = 0;
#ifdef __SSE2__
    const __m128 qx = _mm_set1_ps(q.x()), qy = _mm_set1_ps(q.y()), qz = _mm_set1_ps(q.z()), bound = _mm_set1_ps(r2);
    // Two lanes of double per sum: x, y, z, then xx xy xz yy yz zz.
    __m128d sums[9];
    for (__m128d& sum : sums)
        sum = _mm_setzero_pd();
    for (; j + 4 <= m; j += 4) {
        const __m128 dx = _mm_sub_ps(_mm_loadu_ps(near.x.data() + j), qx);
        const __m128 dy = _mm_sub_ps(_mm_loadu_ps(near.y.data() + j), qy);
        const __m128 dz = _mm_sub_ps(_mm_loadu_ps(near.z.data() + j), qz);
        const __m128 d2 = _mm_add_ps(_mm_mul_ps(dx, dx), _mm_add_ps(_mm_mul_ps(dy, dy), _mm_mul_ps(dz, dz)));
        const __m128 inside = _mm_cmple_ps(d2, bound);
        const int mask = _mm_movemask_ps(inside);
        if (mask == 0)
            continue;
        moments.count += static_cast<std::uint32_t>(__builtin_popcount(static_cast<unsigned>(mask)));
        const __m128 mx = _mm_and_ps(dx, inside), my = _mm_and_ps(dy, inside), mz = _mm_and_ps(dz, inside);
        for (int half = 0; half < 2; ++half) {
            const __m128d x = _mm_cvtps_pd(half ? _mm_movehl_ps(mx, mx) : mx);
            const __m128d y = _mm_cvtps_pd(half ? _mm_movehl_ps(my, my) : my);
            const __m128d z = _mm_cvtps_pd(half ? _mm_movehl_ps(mz, mz) : mz);
            const __m128d terms[9] = {x, y, z, _mm_mul_pd(x, x), _mm_mul_pd(x, y), _mm_mul_pd(x, z),
                                      _mm_mul_pd(y, y), _mm_mul_pd(y, z), _mm_mul_pd(z, z)};
            for (std::size_t t = 0; t < 9; ++t)
                sums[t] = _mm_add_pd(sums[t], terms[t]);
        }
    }
    alignas(16) double lanes[2];
    for (std::size_t t = 0; t < 9; ++t) {
        _mm_store_pd(lanes, sums[t]);
        const double total = lanes[0] + lanes[1];
        if (t < 3)
            moments.sum[static_cast<Eigen::Index>(t)] = total;
        else
            moments.products[t - 3] = total;
    }
#endif
    for (; j < m; ++j) {
        const float fx = near.x[j] - q.x(), fy = near.y[j] - q.y(), fz = near.z[j] - q.z();
        if (fx * fx + (fy * fy + fz * fz) <= r2)
            moments.add(Eigen::Vector3d(fx, fy, fz));
    }
}

} // namespace

template <typename PerQuery>
void Octree::forEachRadiusRun(const Eigen::Vector3f* queries, std::size_t count, float radius, PerQuery&& perQuery) const
{
    if (!(radius >= 0) || !std::isfinite(radius))
        throw std::invalid_argument("the search radius must be finite and >= 0");
    if (count == 0)
        return;
    // The deepest level whose cells are at least as wide as the radius: the
    // 27 cells around a query's cell then hold its whole sphere.
    // (With a relative margin: a cell exactly the radius wide could let float
    // rounding accept a point two cells away, which the block does not hold.)
    int level = 1;
    while (level < kMaxLevel && cellSize(level + 1) >= static_cast<double>(radius) * (1 + 1e-5))
        ++level;
    const std::int64_t n = std::int64_t(1) << level;
    const CellDirectory& directory = cellDirectory(level);
    // The octree's own points need no sorting: they are in Morton order
    // already, and the level's cells are their groups.
    detail::QueryGroups groups;
    if (queries == points_ && count == size()) {
        groups.outside = MortonCode(1) << (3 * level); // no own point is outside
        groups.order.resize(count);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i)
                groups.order[i] = {cellCodeAtLevel(codes_[i], level), indices_[i]};
        });
        groups.start.assign(directory.starts.begin(), directory.starts.end());
    } else {
        groups = groupQueriesByCell(queries, count, level);
    }
    const auto& offsets = detail::neighbourhoodOffsets();
    // A run's box is widened by the radius plus more than the rounding of any
    // float coordinate of the cube, so that the box test never drops a
    // candidate the exact distance keeps.
    const float reach = radius + static_cast<float>(8 * std::numeric_limits<float>::epsilon() *
                                                    (box_.min.cwiseAbs().maxCoeff() + box_.size) + 1e-6 * radius);
    struct Scratch
    {
        detail::BatchScratch block; //!< a group's 27-cell candidates
        detail::BatchScratch near;  //!< those within reach of a run of queries
        std::vector<Neighbour> outside; //!< a query outside the cube: its full search
    };
    tbb::enumerable_thread_specific<Scratch> scratch;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups.start.size() - 1, 16), [&](const tbb::blocked_range<std::size_t>& range) {
        Scratch& local = scratch.local();
        detail::BatchScratch& s = local.block;
        detail::BatchScratch& near = local.near;
        for (std::size_t g = range.begin(); g != range.end(); ++g) {
            const std::size_t first = groups.start[g], last = groups.start[g + 1];
            const MortonCode cell = groups.order[first].code;
            if (cell == groups.outside) {
                // Its candidates are the full search's points, the ones within the radius.
                for (std::size_t i = first; i < last; ++i) {
                    const std::uint32_t qi = groups.order[i].index;
                    local.outside.clear();
                    if (queries[qi].allFinite())
                        withinRadius(queries[qi], radius, level, local.outside);
                    near.reserve(local.outside.size());
                    for (std::size_t j = 0; j < local.outside.size(); ++j) {
                        const Eigen::Vector3f& p = points_[local.outside[j].index];
                        near.x[j] = p.x();
                        near.y[j] = p.y();
                        near.z[j] = p.z();
                        near.indices[j] = local.outside[j].index;
                    }
                    perQuery(qi, near, local.outside.size());
                }
                continue;
            }
            const CellCoordinates c = decodeCell(cell);
            const std::int64_t cx = c.x, cy = c.y, cz = c.z;
            const detail::BlockLookup block(directory.codes, directory.starts, cx, cy, cz, n);
            s.used = 0;
            for (std::size_t o = 0; o < offsets.size(); ++o) {
                const std::int64_t x = cx + offsets[o][0], y = cy + offsets[o][1], z = cz + offsets[o][2];
                s.cellState[o] = detail::BatchScratch::kEmpty;
                if (x < 0 || y < 0 || z < 0 || x >= n || y >= n || z >= n)
                    continue;
                const auto [b, e] = block.range(encodeCell(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                                                           static_cast<std::uint32_t>(z)));
                if (b != e)
                    s.gather(o, b, e, indices_.data(), points_);
            }
            near.reserve(s.used);
            for (std::size_t run = first; run < last; run += kRun) {
                const std::size_t runEnd = std::min(last, run + kRun);
                Eigen::Array3f low = queries[groups.order[run].index].array(), high = low;
                for (std::size_t i = run + 1; i < runEnd; ++i) {
                    low = low.min(queries[groups.order[i].index].array());
                    high = high.max(queries[groups.order[i].index].array());
                }
                low -= reach;
                high += reach;
                // The block's candidates within the run's widened box, copied
                // without a branch (a candidate outside is overwritten by the next).
                std::uint32_t m = 0;
                for (std::uint32_t j = 0; j < s.used; ++j) {
                    const float x = s.x[j], y = s.y[j], z = s.z[j];
                    const bool inside = x >= low.x() && x <= high.x() && y >= low.y() && y <= high.y() && z >= low.z() && z <= high.z();
                    near.x[m] = x;
                    near.y[m] = y;
                    near.z[m] = z;
                    near.indices[m] = s.indices[j];
                    m += inside;
                }
                for (std::size_t i = run; i < runEnd; ++i)
                    perQuery(groups.order[i].index, near, m);
            }
        }
    });
}

void Octree::withinRadiusBatch(const Eigen::Vector3f* queries, std::size_t count, float radius, const RadiusVisitor& visit) const
{
    const float r2 = radius * radius;
    tbb::enumerable_thread_specific<std::vector<Neighbour>> lists;
    forEachRadiusRun(queries, count, radius, [&](std::uint32_t qi, detail::BatchScratch& near, std::size_t m) {
        const std::size_t kept = near.keepWithin(queries[qi], 0, static_cast<std::uint32_t>(m), r2, 0);
        std::vector<Neighbour>& found = lists.local();
        found.resize(kept);
        for (std::size_t j = 0; j < kept; ++j)
            found[j] = Neighbour{near.survivorIndices[j], near.survivorDistances[j]};
        visit(qi, found.data(), kept);
    });
}

void Octree::radiusMomentsBatch(const Eigen::Vector3f* queries, std::size_t count, float radius, const MomentsVisitor& visit) const
{
    const float r2 = radius * radius;
    forEachRadiusRun(queries, count, radius, [&](std::uint32_t qi, detail::BatchScratch& near, std::size_t m) {
        NeighbourhoodMoments moments;
        accumulateMoments(near, m, queries[qi], r2, moments);
        visit(qi, moments);
    });
}

void Octree::blockAround(MortonCode cellCode, int level, std::vector<CellSpan>& out) const
{
    if (level < 1 || level > kMaxLevel)
        throw std::invalid_argument("octree level must be in 1.." + std::to_string(kMaxLevel));
    out.clear();
    const CellDirectory& directory = cellDirectory(level);
    const std::int64_t n = std::int64_t(1) << level;
    const CellCoordinates c = decodeCell(cellCode);
    const detail::BlockLookup block(directory.codes, directory.starts, c.x, c.y, c.z, n);
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
                const std::int64_t x = std::int64_t(c.x) + dx, y = std::int64_t(c.y) + dy, z = std::int64_t(c.z) + dz;
                if (x < 0 || y < 0 || z < 0 || x >= n || y >= n || z >= n)
                    continue;
                const MortonCode code = encodeCell(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y), static_cast<std::uint32_t>(z));
                const auto [first, last] = block.range(code);
                if (first != last)
                    out.push_back(CellSpan{code, first, last});
            }
    std::sort(out.begin(), out.end(), [](const CellSpan& a, const CellSpan& b) { return a.code < b.code; });
}

} // namespace scandiff::octree
