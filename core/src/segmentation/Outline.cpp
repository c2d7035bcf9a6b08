// SPDX-License-Identifier: GPL-3.0-or-later
//! The concave outline of 2D points (RegionReport.h): a grid trace whose edges
//! are then moved onto the outermost points.
#include "PlanarPolygons.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/segmentation/RegionReport.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <utility>

namespace scandiff {

namespace {

constexpr int kMaxGridCells = 4096;

//! Douglas-Peucker on the open chain ring[first..last] (indices modulo size):
//! marks the vertices to keep.
void simplifyChain(const Polygon2d& ring, std::size_t first, std::size_t last, double tolerance, std::vector<char>& keep)
{
    const std::size_t n = ring.size();
    if ((last + n - first) % n < 2)
        return;
    const Eigen::Vector2d a = ring[first % n], b = ring[last % n];
    const Eigen::Vector2d ab = b - a;
    const double length = ab.norm();
    double worst = -1.0;
    std::size_t worstIndex = first;
    for (std::size_t i = first + 1; i < last; ++i) {
        const Eigen::Vector2d ap = ring[i % n] - a;
        const double d = length > 0 ? std::abs(ab.x() * ap.y() - ab.y() * ap.x()) / length : ap.norm();
        if (d > worst) {
            worst = d;
            worstIndex = i;
        }
    }
    if (worst > tolerance) {
        keep[worstIndex % n] = 1;
        simplifyChain(ring, first, worstIndex, tolerance, keep);
        simplifyChain(ring, worstIndex, last, tolerance, keep);
    }
}

Polygon2d simplifyRing(const Polygon2d& ring, double tolerance)
{
    const std::size_t n = ring.size();
    if (n <= 4)
        return ring;
    // Split the ring at its first vertex and the vertex farthest from it, then
    // simplify the two chains.
    std::size_t far = 0;
    double best = -1.0;
    for (std::size_t i = 1; i < n; ++i) {
        const double d = (ring[i] - ring[0]).squaredNorm();
        if (d > best) {
            best = d;
            far = i;
        }
    }
    std::vector<char> keep(n, 0);
    keep[0] = keep[far] = 1;
    simplifyChain(ring, 0, far, tolerance, keep);
    simplifyChain(ring, far, n, tolerance, keep);
    Polygon2d out;
    for (std::size_t i = 0; i < n; ++i)
        if (keep[i])
            out.push_back(ring[i]);
    return out.size() >= 3 ? out : ring;
}

struct CellExtremes
{
    Eigen::Vector2d min = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector2d max = -min;
};

//! The traced boundary follows cell edges, up to a cell outside the points: an
//! 8 x 8 m square outlined on 0.75 m cells came out 80 m^2. Each boundary edge
//! is moved instead to the extreme point of its cell on that side (the lowest y
//! for a bottom edge...), and consecutive edges meet where their lines cross,
//! so the ring hugs the outermost points: a sampled rectangle gets its own
//! area. Cells filled by the closing hold no point and keep their edge.
//! `loop` holds the grid vertices; edge i runs from loop[i] to loop[i + 1] with
//! the occupied cell on its left.
Polygon2d snappedRing(const std::vector<Eigen::Vector2i>& loop, const std::unordered_map<std::int64_t, CellExtremes>& extremes,
                      const Eigen::Vector2d& lo, double cellSize, int pad, int nx)
{
    const std::size_t m = loop.size();
    auto gridToWorld = [&](int g, int axis) { return lo[axis] + cellSize * (g - pad); };
    // The line of edge i: the coordinate it sits at along the axis across it.
    auto edgeLine = [&](std::size_t i) {
        const Eigen::Vector2i a = loop[i], b = loop[(i + 1) % m];
        const Eigen::Vector2i d = b - a;
        int cx = 0, cy = 0, axis = 0;
        bool low = false; // the edge bounds its cell from below (on `axis`)
        if (d.x() == 1) {
            cx = a.x(), cy = a.y(), axis = 1, low = true;
        } else if (d.x() == -1) {
            cx = a.x() - 1, cy = a.y() - 1, axis = 1, low = false;
        } else if (d.y() == 1) {
            cx = a.x() - 1, cy = a.y(), axis = 0, low = false;
        } else {
            cx = a.x(), cy = a.y() - 1, axis = 0, low = true;
        }
        const int gridLine = axis == 1 ? a.y() : a.x();
        double at = gridToWorld(gridLine, axis);
        const auto it = extremes.find(static_cast<std::int64_t>(cy) * nx + cx);
        if (it != extremes.end())
            at = low ? it->second.min[axis] : it->second.max[axis];
        return std::pair<int, double>(axis, at);
    };
    Polygon2d ring;
    std::pair<int, double> previous = edgeLine(m - 1);
    for (std::size_t i = 0; i < m; ++i) {
        const std::pair<int, double> current = edgeLine(i);
        const Eigen::Vector2i& corner = loop[i]; // shared by edge i - 1 and edge i
        if (previous.first != current.first) {
            // A turn: the vertex where the two lines cross.
            Eigen::Vector2d v;
            v[previous.first] = previous.second;
            v[current.first] = current.second;
            ring.push_back(v);
        } else if (previous.second != current.second) {
            // A straight run whose cells reach out differently: a step at the shared grid vertex.
            const int along = 1 - current.first;
            Eigen::Vector2d a, b;
            a[along] = b[along] = gridToWorld(corner[along], along);
            a[current.first] = previous.second;
            b[current.first] = current.second;
            ring.push_back(a);
            ring.push_back(b);
        }
        previous = current;
    }
    // Drop repeated vertices (a cell whose extremes meet its neighbour's).
    Polygon2d out;
    for (const auto& v : ring)
        if (out.empty() || (v - out.back()).squaredNorm() > 0)
            out.push_back(v);
    while (out.size() > 1 && (out.front() - out.back()).squaredNorm() == 0)
        out.pop_back();
    return out;
}

} // namespace

Outline2d concaveOutline(const std::vector<Eigen::Vector2d>& points, double cellSize)
{
    if (!(cellSize > 0.0 && std::isfinite(cellSize)))
        throw Error(ErrorCode::InvalidArgument, "outline: the cell size must be > 0");
    Outline2d outline;
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const auto& p : points)
        if (p.allFinite()) {
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
    if (!(lo.x() <= hi.x()))
        return outline;
    const double extent = (hi - lo).maxCoeff();
    if (extent / cellSize > kMaxGridCells) {
        const double coarser = extent / kMaxGridCells;
        logWarning("outline: cell size " + std::to_string(cellSize) + " m gives a grid too large for an extent of " +
                   std::to_string(extent) + " m; using " + std::to_string(coarser) + " m");
        cellSize = coarser;
    }
    // Two empty cells of margin on every side, so dilation and erosion never clip.
    constexpr int pad = 2;
    const int nx = static_cast<int>(std::floor((hi.x() - lo.x()) / cellSize)) + 1 + 2 * pad;
    const int ny = static_cast<int>(std::floor((hi.y() - lo.y()) / cellSize)) + 1 + 2 * pad;
    std::vector<char> occupied(static_cast<std::size_t>(nx) * ny, 0);
    std::unordered_map<std::int64_t, CellExtremes> extremes; // of the points in each occupied cell
    auto at = [&](std::vector<char>& grid, int x, int y) -> char& { return grid[static_cast<std::size_t>(y) * nx + x]; };
    for (const auto& p : points) {
        if (!p.allFinite())
            continue;
        const int x = std::min(nx - 1 - pad, static_cast<int>((p.x() - lo.x()) / cellSize) + pad);
        const int y = std::min(ny - 1 - pad, static_cast<int>((p.y() - lo.y()) / cellSize) + pad);
        at(occupied, x, y) = 1;
        CellExtremes& e = extremes[static_cast<std::int64_t>(y) * nx + x];
        e.min = e.min.cwiseMin(p);
        e.max = e.max.cwiseMax(p);
    }
    // Closing with a 3x3 square: fills the one-cell holes that sampling leaves.
    auto morph = [&](const std::vector<char>& in, bool dilate) {
        std::vector<char> out(in.size(), 0);
        for (int y = 1; y + 1 < ny; ++y)
            for (int x = 1; x + 1 < nx; ++x) {
                bool any = false, all = true;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const bool v = in[static_cast<std::size_t>(y + dy) * nx + x + dx] != 0;
                        any = any || v;
                        all = all && v;
                    }
                out[static_cast<std::size_t>(y) * nx + x] = dilate ? any : all;
            }
        return out;
    };
    std::vector<char> closed = morph(morph(occupied, true), false);
    // Erosion may remove an isolated point's cell entirely; keep every occupied cell.
    for (std::size_t c = 0; c < closed.size(); ++c)
        closed[c] = closed[c] || occupied[c];

    // Boundary edges, each oriented with the occupied cell on its left, so outer
    // boundaries run counter-clockwise and hole boundaries clockwise.
    struct Edge
    {
        int x0, y0, x1, y1;
        bool used = false;
    };
    std::vector<Edge> edges;
    std::unordered_map<std::int64_t, std::vector<std::size_t>> outgoing;
    auto key = [&](int x, int y) { return static_cast<std::int64_t>(y) * (nx + 1) + x; };
    auto addEdge = [&](int x0, int y0, int x1, int y1) {
        outgoing[key(x0, y0)].push_back(edges.size());
        edges.push_back({x0, y0, x1, y1});
    };
    for (int y = 1; y + 1 < ny; ++y)
        for (int x = 1; x + 1 < nx; ++x) {
            if (!at(closed, x, y))
                continue;
            if (!at(closed, x, y - 1))
                addEdge(x, y, x + 1, y);
            if (!at(closed, x + 1, y))
                addEdge(x + 1, y, x + 1, y + 1);
            if (!at(closed, x, y + 1))
                addEdge(x + 1, y + 1, x, y + 1);
            if (!at(closed, x - 1, y))
                addEdge(x, y + 1, x, y);
        }
    for (std::size_t start = 0; start < edges.size(); ++start) {
        if (edges[start].used)
            continue;
        std::vector<Eigen::Vector2i> loop;
        std::size_t e = start;
        while (!edges[e].used) {
            edges[e].used = true;
            loop.emplace_back(edges[e].x0, edges[e].y0);
            const int dx = edges[e].x1 - edges[e].x0, dy = edges[e].y1 - edges[e].y0;
            // Where two pieces touch at a corner, two edges leave the vertex:
            // turning left keeps to the current piece, so 4-connected pieces
            // get separate outlines.
            std::size_t next = SIZE_MAX;
            int bestRank = 3;
            for (std::size_t candidate : outgoing[key(edges[e].x1, edges[e].y1)]) {
                if (edges[candidate].used && candidate != start)
                    continue;
                const int cx = edges[candidate].x1 - edges[candidate].x0, cy = edges[candidate].y1 - edges[candidate].y0;
                const int cross = dx * cy - dy * cx;
                const int rank = cross > 0 ? 0 : (cross == 0 ? 1 : 2);
                if (rank < bestRank) {
                    bestRank = rank;
                    next = candidate;
                }
            }
            if (next == SIZE_MAX || next == start)
                break;
            e = next;
        }
        // Holes run clockwise: the sign of the cell-edge ring tells them apart.
        long twiceArea = 0;
        for (std::size_t i = 0; i < loop.size(); ++i) {
            const Eigen::Vector2i& p = loop[i];
            const Eigen::Vector2i& q = loop[(i + 1) % loop.size()];
            twiceArea += static_cast<long>(p.x()) * q.y() - static_cast<long>(q.x()) * p.y();
        }
        if (twiceArea <= 0)
            continue; // a hole
        Polygon2d ring = snappedRing(loop, extremes, lo, cellSize, pad, nx);
        if (ring.size() < 3) {
            // A lone point (or a pile of duplicates) has no area; it keeps its
            // cell's square so that it still gets drawn.
            ring.clear();
            for (const Eigen::Vector2i& corner : loop)
                ring.push_back(lo + cellSize * (corner.cast<double>() - Eigen::Vector2d::Constant(pad)));
        } else {
            outline.area += std::max(0.0, signedArea(ring));
        }
        outline.rings.push_back(simplifyRing(ring, 0.5 * cellSize));
    }
    std::sort(outline.rings.begin(), outline.rings.end(),
              [](const Polygon2d& a, const Polygon2d& b) { return std::abs(signedArea(a)) > std::abs(signedArea(b)); });
    return outline;
}

} // namespace scandiff
