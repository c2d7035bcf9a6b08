// SPDX-License-Identifier: GPL-3.0-or-later
// Batch radius queries: the neighbourhoods normals, local features, smoothing
// and subsampling need for every point of a cloud.
#include <scandiff/octree/Octree.h>

#include "BatchQueries.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace scandiff::octree {

void Octree::withinRadiusBatch(const Eigen::Vector3f* queries, std::size_t count, float radius, const RadiusVisitor& visit) const
{
    if (!(radius >= 0) || !std::isfinite(radius))
        throw std::invalid_argument("the search radius must be finite and >= 0");
    if (count == 0)
        return;
    // The deepest level whose cells are at least as wide as the radius: the
    // 27 cells around a query's cell then hold its whole sphere.
    int level = 1;
    while (level < kMaxLevel && cellSize(level + 1) >= static_cast<double>(radius))
        ++level;
    const std::int64_t n = std::int64_t(1) << level;
    const double l = cellSize(level);
    const float r2 = radius * radius;
    const detail::QueryGroups groups = groupQueriesByCell(queries, count, level);
    const CellDirectory& directory = cellDirectory(level);
    const auto& offsets = detail::neighbourhoodOffsets();

    struct Scratch
    {
        detail::BatchScratch block;
        std::vector<Neighbour> found;
    };
    tbb::enumerable_thread_specific<Scratch> scratch;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups.start.size() - 1, 16), [&](const tbb::blocked_range<std::size_t>& range) {
        Scratch& local = scratch.local();
        detail::BatchScratch& s = local.block;
        for (std::size_t g = range.begin(); g != range.end(); ++g) {
            const std::size_t first = groups.start[g], last = groups.start[g + 1];
            const MortonCode cell = groups.order[first].code;
            if (cell == groups.outside) {
                for (std::size_t i = first; i < last; ++i) {
                    const std::uint32_t qi = groups.order[i].index;
                    local.found.clear();
                    if (queries[qi].allFinite())
                        withinRadius(queries[qi], radius, level, local.found);
                    visit(qi, local.found.data(), local.found.size());
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
            const Eigen::Vector3d centre = box_.min + (Eigen::Vector3d(double(cx), double(cy), double(cz)).array() + 0.5).matrix() * l;
            for (std::size_t i = first; i < last; ++i) {
                const std::uint32_t qi = groups.order[i].index;
                const Eigen::Vector3f& q = queries[qi];
                const Eigen::Vector3d local3 = q.cast<double>() - centre;
                std::size_t m = 0;
                for (std::size_t o = 0; o < offsets.size(); ++o) {
                    if (s.cellState[o] != detail::BatchScratch::kGathered)
                        continue;
                    // A neighbour cell farther than the radius holds nothing within it.
                    double gap2 = 0;
                    for (int a = 0; a < 3; ++a) {
                        const int d = offsets[o][static_cast<std::size_t>(a)];
                        const double gap = d < 0 ? 0.5 * l + local3[a] : d > 0 ? 0.5 * l - local3[a] : 0.0;
                        gap2 += gap * gap;
                    }
                    if (gap2 > static_cast<double>(r2) * (1 + detail::kSlack))
                        continue;
                    s.reserve(m + (s.cellEnd[o] - s.cellBegin[o]));
                    m = s.keepWithin(q, s.cellBegin[o], s.cellEnd[o], r2, m);
                }
                local.found.resize(m);
                for (std::size_t j = 0; j < m; ++j)
                    local.found[j] = Neighbour{s.survivorIndices[j], s.survivorDistances[j]};
                visit(qi, local.found.data(), m);
            }
        }
    });
}

} // namespace scandiff::octree
