// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/segmentation/RegionReport.h>
#include <scandiff/octree/Octree.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

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

double signedArea(const Polygon2d& ring)
{
    double twice = 0.0;
    for (std::size_t i = 0; i < ring.size(); ++i) {
        const Eigen::Vector2d& p = ring[i];
        const Eigen::Vector2d& q = ring[(i + 1) % ring.size()];
        twice += p.x() * q.y() - q.x() * p.y();
    }
    return 0.5 * twice;
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
    auto at = [&](std::vector<char>& grid, int x, int y) -> char& { return grid[static_cast<std::size_t>(y) * nx + x]; };
    for (const auto& p : points) {
        if (!p.allFinite())
            continue;
        const int x = std::min(nx - 1 - pad, static_cast<int>((p.x() - lo.x()) / cellSize) + pad);
        const int y = std::min(ny - 1 - pad, static_cast<int>((p.y() - lo.y()) / cellSize) + pad);
        at(occupied, x, y) = 1;
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
        // Drop the vertices in the middle of straight runs.
        Polygon2d ring;
        const std::size_t m = loop.size();
        for (std::size_t i = 0; i < m; ++i) {
            const Eigen::Vector2i d0 = loop[i] - loop[(i + m - 1) % m], d1 = loop[(i + 1) % m] - loop[i];
            if (d0.x() * d1.y() - d0.y() * d1.x() != 0)
                ring.push_back(lo + cellSize * (loop[i].cast<double>() - Eigen::Vector2d::Constant(pad)));
        }
        if (ring.size() < 3)
            continue;
        const double area = signedArea(ring);
        if (area <= 0)
            continue; // a hole
        outline.area += area;
        outline.rings.push_back(simplifyRing(ring, 0.5 * cellSize));
    }
    std::sort(outline.rings.begin(), outline.rings.end(),
              [](const Polygon2d& a, const Polygon2d& b) { return std::abs(signedArea(a)) > std::abs(signedArea(b)); });
    return outline;
}

std::vector<RegionStatistics> regionReport(const PointCloud& cloud, const RegionReportParams& params, ProgressObserver* progress)
{
    const ScalarField* regionField = cloud.field(params.regionField);
    if (!regionField)
        throw Error(ErrorCode::InvalidArgument, "region report: cloud '" + cloud.name + "' has no field '" + params.regionField + "'");
    const ScalarField* distance = nullptr;
    if (!params.distanceField.empty()) {
        distance = cloud.field(params.distanceField);
        if (!distance)
            throw Error(ErrorCode::InvalidArgument, "region report: cloud '" + cloud.name + "' has no field '" + params.distanceField + "'");
    }
    if (!(params.outlineCellSize >= 0.0 && std::isfinite(params.outlineCellSize)) ||
        !(params.volumeCellSize >= 0.0 && std::isfinite(params.volumeCellSize)))
        throw Error(ErrorCode::InvalidArgument, "region report: cell sizes must be finite and >= 0 (0: automatic)");

    std::map<int, std::vector<std::size_t>> members;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!regionField->hasValue(i) || !cloud.positions()[i].allFinite())
            continue;
        const double v = regionField->value(i);
        if (!(v >= 1.0 && v <= 2147483647.0 && v == std::floor(v)))
            throw Error(ErrorCode::InvalidData, "region report: field '" + params.regionField + "' holds " + std::to_string(v) +
                                                    " at point " + std::to_string(i) + ", not a positive integer id");
        members[static_cast<int>(v)].push_back(i);
    }

    std::vector<RegionStatistics> report;
    ProgressTicker ticker(progress, "Region report", members.size());
    for (const auto& [id, indices] : members) {
        ticker.step();
        RegionStatistics r;
        r.id = id;
        r.pointCount = indices.size();
        const double count = static_cast<double>(indices.size());
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        std::vector<Eigen::Vector3f> local;
        local.reserve(indices.size());
        for (std::size_t i : indices) {
            local.push_back(cloud.positions()[i]);
            mean += cloud.positions()[i].cast<double>();
        }
        mean /= count;
        Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
        r.bounds.min = r.bounds.max = cloud.globalPosition(indices.front());
        r.bounds.empty = false;
        for (std::size_t i : indices) {
            const Eigen::Vector3d d = cloud.positions()[i].cast<double>() - mean;
            covariance += d * d.transpose();
            const Eigen::Vector3d g = cloud.globalPosition(i);
            r.bounds.min = r.bounds.min.cwiseMin(g);
            r.bounds.max = r.bounds.max.cwiseMax(g);
        }
        r.centroid = cloud.origin() + mean;
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance / count);
        // Eigenvalues increase: the first vector is the plane's normal.
        r.planeNormal = eigen.eigenvectors().col(0).normalized();
        const Eigen::Vector3d u = eigen.eigenvectors().col(2).normalized();
        const Eigen::Vector3d v = r.planeNormal.cross(u);

        // Outline cell: from the spacing of the region's own points.
        double cell = params.outlineCellSize;
        if (cell == 0.0) {
            const octree::Octree tree(local.data(), local.size());
            const std::size_t k = std::min<std::size_t>(5, local.size());
            std::vector<octree::Neighbour> neighbours;
            int level = 1;
            for (int l = 1; l <= octree::kMaxLevel; ++l)
                if (tree.levelStatistics(l).meanPointsPerCell >= 8.0)
                    level = l;
            tree.nearestBatch(local.data(), local.size(), k, level, neighbours);
            std::vector<float> fourth;
            fourth.reserve(local.size());
            for (std::size_t i = 0; i < local.size(); ++i)
                fourth.push_back(std::sqrt(neighbours[i * k + k - 1].squaredDistance));
            std::nth_element(fourth.begin(), fourth.begin() + fourth.size() / 2, fourth.end());
            cell = 1.5 * fourth[fourth.size() / 2];
            if (!(cell > 0.0)) // a single point, or duplicates: some small square
                cell = std::max(1e-3, 1e-2 * (r.bounds.max - r.bounds.min).norm());
        }
        r.outlineCellSize = cell;
        std::vector<Eigen::Vector2d> planar;
        planar.reserve(indices.size());
        for (const auto& p : local) {
            const Eigen::Vector3d d = p.cast<double>() - mean;
            planar.emplace_back(d.dot(u), d.dot(v));
        }
        const Outline2d outline = concaveOutline(planar, cell);
        r.footprintArea = outline.area;
        for (const auto& ring : outline.rings) {
            std::vector<Eigen::Vector3d> lifted;
            for (const auto& q : ring)
                lifted.push_back(r.centroid + q.x() * u + q.y() * v);
            r.outlines.push_back(std::move(lifted));
        }

        if (distance) {
            double sum = 0.0, squares = 0.0, extreme = 0.0;
            for (std::size_t i : indices) {
                if (!distance->hasValue(i))
                    continue;
                const double d = distance->value(i);
                sum += d;
                squares += d * d;
                if (r.distanceCount == 0 || std::abs(d) > std::abs(extreme))
                    extreme = d;
                ++r.distanceCount;
            }
            if (r.distanceCount > 0) {
                const double n = static_cast<double>(r.distanceCount);
                r.meanDistance = sum / n;
                r.rmsDistance = std::sqrt(squares / n);
                r.maxDistance = extreme;
            }
        }

        if (params.reference) {
            // 2.5D columns on a horizontal grid anchored at the region's box.
            const double c = params.volumeCellSize > 0 ? params.volumeCellSize : cell;
            const Eigen::Vector2d anchor = r.bounds.min.head<2>();
            const double nxd = std::floor((r.bounds.max.x() - anchor.x()) / c) + 1;
            const double nyd = std::floor((r.bounds.max.y() - anchor.y()) / c) + 1;
            if (nxd * nyd > 1e8)
                throw Error(ErrorCode::InvalidArgument, "region report: the volume cell size " + std::to_string(c) +
                                                            " m is too small for region " + std::to_string(id));
            const auto nx = static_cast<std::int64_t>(nxd);
            auto column = [&](const Eigen::Vector3d& g) -> std::int64_t {
                const double fx = std::floor((g.x() - anchor.x()) / c), fy = std::floor((g.y() - anchor.y()) / c);
                if (fx < 0 || fy < 0 || fx >= nxd || fy >= nyd)
                    return -1;
                return static_cast<std::int64_t>(fy) * nx + static_cast<std::int64_t>(fx);
            };
            struct Column
            {
                double regionZ = 0, referenceZ = 0;
                std::size_t regionCount = 0, referenceCount = 0;
            };
            std::unordered_map<std::int64_t, Column> columns;
            for (std::size_t i : indices) {
                const Eigen::Vector3d g = cloud.globalPosition(i);
                Column& col = columns[column(g)];
                col.regionZ += g.z();
                ++col.regionCount;
            }
            const PointCloud& ref = *params.reference;
            for (std::size_t i = 0; i < ref.size(); ++i) {
                if (!ref.positions()[i].allFinite())
                    continue;
                const Eigen::Vector3d g = ref.globalPosition(i);
                const std::int64_t key = column(g);
                if (key < 0)
                    continue;
                const auto it = columns.find(key);
                if (it == columns.end())
                    continue;
                it->second.referenceZ += g.z();
                ++it->second.referenceCount;
            }
            double volume = 0.0;
            std::size_t covered = 0;
            for (const auto& [key, col] : columns) {
                if (col.referenceCount == 0)
                    continue;
                ++covered;
                volume += (col.regionZ / col.regionCount - col.referenceZ / col.referenceCount) * c * c;
            }
            r.volume = volume;
            r.volumeCoverage = columns.empty() ? 0.0 : static_cast<double>(covered) / static_cast<double>(columns.size());
        }
        report.push_back(std::move(r));
    }
    return report;
}

std::map<int, std::vector<std::size_t>> pointsByRegion(const ScalarField& regionIds)
{
    std::map<int, std::vector<std::size_t>> members;
    for (std::size_t i = 0; i < regionIds.size(); ++i)
        if (regionIds.hasValue(i))
            members[static_cast<int>(std::lround(regionIds.value(i)))].push_back(i);
    return members;
}

} // namespace scandiff
