// SPDX-License-Identifier: GPL-3.0-or-later
// Batch radius queries: the neighbourhoods normals, local features, smoothing
// and subsampling need for every point of a cloud.
#include <scandiff/octree/Octree.h>

#include "BatchQueries.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
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
            // The gathered cells once, for every query of the group.
            std::array<std::uint8_t, 27> cells;
            std::size_t cellCount = 0;
            for (std::size_t o = 0; o < offsets.size(); ++o)
                if (s.cellState[o] == detail::BatchScratch::kGathered)
                    cells[cellCount++] = static_cast<std::uint8_t>(o);
            s.reserve(s.used);
            const double reach2 = static_cast<double>(r2) * (1 + detail::kSlack);
            for (std::size_t i = first; i < last; ++i) {
                const std::uint32_t qi = groups.order[i].index;
                const Eigen::Vector3f& q = queries[qi];
                const Eigen::Vector3d local3 = q.cast<double>() - centre;
                // Squared gap from q to the faces of the cells at offset -1 / 0 / +1 per axis.
                double faceGap2[3][3];
                for (int a = 0; a < 3; ++a) {
                    const double below = 0.5 * l + local3[a], above = 0.5 * l - local3[a];
                    faceGap2[a][0] = below * below;
                    faceGap2[a][1] = 0.0;
                    faceGap2[a][2] = above * above;
                }
                std::size_t m = 0;
                for (std::size_t k = 0; k < cellCount; ++k) {
                    const auto& o = offsets[cells[k]];
                    // A neighbour cell farther than the radius holds nothing within it.
                    if (faceGap2[0][o[0] + 1] + faceGap2[1][o[1] + 1] + faceGap2[2][o[2] + 1] > reach2)
                        continue;
                    m = s.keepWithin(q, s.cellBegin[cells[k]], s.cellEnd[cells[k]], r2, m);
                }
                local.found.resize(m);
                for (std::size_t j = 0; j < m; ++j)
                    local.found[j] = Neighbour{s.survivorIndices[j], s.survivorDistances[j]};
                visit(qi, local.found.data(), m);
            }
        }
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
