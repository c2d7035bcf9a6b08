// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Helpers on sets of octree cells of one level (internal to core): neighbour
//! offsets for 6/18/26-connectivity, lookups in a sorted code list, and the
//! union-find that labels connected sets of cells.

#include <scandiff/octree/MortonCode.h>
#include <scandiff/octree/Octree.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <numeric>
#include <vector>

namespace scandiff::detail {

struct CellOffset
{
    int dx, dy, dz;
};

//! The offsets of the neighbours of a cell under `connectivity`; with
//! `forwardOnly`, only one of each pair {o, -o} (the half that comes first in
//! lexicographic order), enough to visit every adjacent pair once.
inline std::vector<CellOffset> neighbourOffsets(octree::Connectivity connectivity, bool forwardOnly)
{
    std::vector<CellOffset> offsets;
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
                const int nonZero = (dx != 0) + (dy != 0) + (dz != 0);
                if (nonZero == 0)
                    continue;
                if (connectivity == octree::Connectivity::Faces6 && nonZero > 1)
                    continue;
                if (connectivity == octree::Connectivity::Edges18 && nonZero > 2)
                    continue;
                const bool forward = dx > 0 || (dx == 0 && (dy > 0 || (dy == 0 && dz > 0)));
                if (forwardOnly && !forward)
                    continue;
                offsets.push_back({dx, dy, dz});
            }
    return offsets;
}

//! Index in `cells` (sorted, unique codes of one level) of the cell at
//! (x, y, z) + offset, or SIZE_MAX if it is outside the grid or not in the list.
inline std::size_t findNeighbour(const std::vector<octree::MortonCode>& cells, const octree::CellCoordinates& at,
                                 const CellOffset& o, int level)
{
    const std::int64_t side = std::int64_t(1) << level;
    const std::int64_t x = std::int64_t(at.x) + o.dx, y = std::int64_t(at.y) + o.dy, z = std::int64_t(at.z) + o.dz;
    if (x < 0 || y < 0 || z < 0 || x >= side || y >= side || z >= side)
        return SIZE_MAX;
    const octree::MortonCode code =
        octree::encodeCell(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y), static_cast<std::uint32_t>(z));
    const auto it = std::lower_bound(cells.begin(), cells.end(), code);
    return it != cells.end() && *it == code ? static_cast<std::size_t>(it - cells.begin()) : SIZE_MAX;
}

//! For sorted unique cell codes of one level: each cell's component, named by
//! the smallest index of its cells (so roots come in Morton order).
inline std::vector<std::size_t> cellComponents(const std::vector<octree::MortonCode>& cells, octree::Connectivity connectivity,
                                               int level)
{
    std::vector<std::size_t> parent(cells.size());
    std::iota(parent.begin(), parent.end(), std::size_t(0));
    auto find = [&](std::size_t c) {
        while (parent[c] != c) {
            parent[c] = parent[parent[c]];
            c = parent[c];
        }
        return c;
    };
    const std::vector<CellOffset> offsets = neighbourOffsets(connectivity, true);
    for (std::size_t c = 0; c < cells.size(); ++c) {
        const octree::CellCoordinates at = octree::decodeCell(cells[c]);
        for (const CellOffset& o : offsets) {
            const std::size_t m = findNeighbour(cells, at, o, level);
            if (m == SIZE_MAX)
                continue;
            const std::size_t a = find(c), b = find(m);
            if (a != b)
                parent[std::max(a, b)] = std::min(a, b);
        }
    }
    for (std::size_t c = 0; c < cells.size(); ++c)
        parent[c] = find(c);
    return parent;
}

} // namespace scandiff::detail
