// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/processing/Subsampling.h>

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <unordered_set>

namespace scandiff {

std::vector<std::size_t> randomSubsample(const PointCloud& cloud, std::size_t count, std::uint64_t seed)
{
    const std::size_t n = cloud.size();
    std::vector<std::size_t> kept;
    if (count >= n) {
        kept.resize(n);
        for (std::size_t i = 0; i < n; ++i)
            kept[i] = i;
        return kept;
    }
    // Floyd's algorithm: `count` distinct indices in `count` draws, whatever n.
    std::mt19937_64 rng(seed);
    std::unordered_set<std::size_t> chosen;
    chosen.reserve(count * 2);
    for (std::size_t j = n - count; j < n; ++j) {
        const std::size_t t = std::uniform_int_distribution<std::size_t>(0, j)(rng);
        if (!chosen.insert(t).second)
            chosen.insert(j);
    }
    kept.assign(chosen.begin(), chosen.end());
    std::sort(kept.begin(), kept.end());
    return kept;
}

std::vector<std::size_t> spatialSubsample(const PointCloud& cloud, double minDistance, ProgressObserver* progress)
{
    if (!(minDistance > 0) || !std::isfinite(minDistance))
        throw Error(ErrorCode::InvalidArgument, "spatial subsampling: the minimum distance must be > 0");
    if (cloud.empty())
        return {};
    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    const std::size_t n = cloud.size();
    const auto& order = tree.sortedIndices();
    const auto& positions = cloud.positions();
    const auto d2 = static_cast<float>(minDistance * minDistance);
    // Cells at least minDistance wide, so a point's 27-cell block holds every
    // point within reach, and of about 16 points, so a block's candidates are
    // gathered once for a dozen points.
    // (With a relative margin: a cell exactly minDistance wide could let float
    // rounding find a point two cells away within it.)
    int level = 1;
    while (level < octree::kMaxLevel && tree.cellSize(level + 1) >= minDistance * (1 + 1e-5))
        ++level;
    level = std::max(1, std::min(level, tree.levelNearestMeanPopulation(16.0)));

    // The greedy rule: a point is kept when no point kept before it lies
    // within minDistance. "Before" is the order of the cells' eight parity
    // classes (x, y and z of the cell even or odd), then Morton order within a
    // cell. Two cells of one class are at least a cell apart, so at least
    // minDistance: the cells of a class are decided independently, on both
    // cores, and the result never depends on the number of threads.
    const double size = tree.cellSize(level);
    const Eigen::Vector3d boxMin = tree.box().min;
    // Cell boxes are widened before they are rounded to float, by more than
    // the rounding of any coordinate of the cube, so that skipping a box the
    // point is farther from than minDistance can never skip a point within it.
    const double margin = 1e-4 * size + 8 * std::numeric_limits<float>::epsilon() *
                                            (boxMin.cwiseAbs().maxCoeff() + tree.box().size);
    std::vector<char> keptAt(n, 0);    // by position in Morton order
    std::vector<char> keptPoint(n, 0); // by point index
    std::array<std::vector<octree::Octree::CellSpan>, 8> classes;
    tree.forEachCell(level, [&](octree::MortonCode code, std::size_t first, std::size_t last) {
        const octree::CellCoordinates c = octree::decodeCell(code);
        classes[(c.x & 1) << 2 | (c.y & 1) << 1 | (c.z & 1)].push_back({code, first, last});
    });
    struct Segment
    {
        std::size_t begin, end;
        Eigen::Vector3f low, high; //!< the cell's box (local coordinates)
    };
    struct Scratch
    {
        std::vector<float> x, y, z;
        std::vector<Segment> segments;
        std::vector<octree::Octree::CellSpan> block;
    };
    tbb::enumerable_thread_specific<Scratch> scratch;
    const auto decide = [&](const octree::Octree::CellSpan& cell, Scratch& k) {
        k.x.clear();
        k.y.clear();
        k.z.clear();
        k.segments.clear();
        // The points kept so far in the block: cells of earlier classes only.
        tree.blockAround(cell.code, level, k.block);
        for (const auto& other : k.block) {
            if (other.code == cell.code)
                continue;
            Segment segment{k.x.size(), 0, {}, {}};
            for (std::size_t j = other.first; j < other.last; ++j)
                if (keptAt[j]) {
                    const Eigen::Vector3f& p = positions[order[j]];
                    k.x.push_back(p.x());
                    k.y.push_back(p.y());
                    k.z.push_back(p.z());
                }
            segment.end = k.x.size();
            if (segment.end == segment.begin)
                continue;
            const octree::CellCoordinates c = octree::decodeCell(other.code);
            const Eigen::Vector3d low = boxMin + Eigen::Vector3d(c.x, c.y, c.z) * size;
            segment.low = (low - Eigen::Vector3d::Constant(margin)).cast<float>();
            segment.high = (low + Eigen::Vector3d::Constant(size + margin)).cast<float>();
            k.segments.push_back(segment);
        }
        const std::size_t ownBegin = k.x.size();
        for (std::size_t j = cell.first; j < cell.last; ++j) {
            const Eigen::Vector3f& p = positions[order[j]];
            bool free = true;
            const auto scan = [&](std::size_t from, std::size_t to) {
                // No early exit: the loop vectorises.
                for (std::size_t q = from; q < to; ++q) {
                    const float ex = k.x[q] - p.x(), ey = k.y[q] - p.y(), ez = k.z[q] - p.z();
                    free &= ex * ex + (ey * ey + ez * ez) > d2;
                }
            };
            for (const Segment& segment : k.segments) {
                const Eigen::Vector3f gap = (segment.low - p).cwiseMax(p - segment.high).cwiseMax(0.0f);
                if (gap.squaredNorm() <= d2) // else the point is farther than minDistance from the whole cell
                    scan(segment.begin, segment.end);
            }
            scan(ownBegin, k.x.size());
            if (free) {
                keptAt[j] = 1;
                keptPoint[order[j]] = 1;
                k.x.push_back(p.x());
                k.y.push_back(p.y());
                k.z.push_back(p.z());
            }
        }
    };
    ProgressTicker ticker(progress, "Spatial subsampling", n);
    for (const auto& cells : classes)
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
            Scratch& k = scratch.local();
            std::size_t points = 0;
            for (std::size_t c = r.begin(); c != r.end(); ++c) {
                decide(cells[c], k);
                points += cells[c].last - cells[c].first;
            }
            ticker.step(points);
        });
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < n; ++i)
        if (keptPoint[i])
            out.push_back(i);
    return out;
}

std::vector<std::size_t> octreeSubsample(const PointCloud& cloud, int level, ProgressObserver* progress)
{
    if (level < 1 || level > octree::kMaxLevel)
        throw Error(ErrorCode::InvalidArgument, "octree subsampling: the level must be in [1, 21]");
    if (cloud.empty())
        return {};
    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    const auto& order = tree.sortedIndices();
    const auto& positions = cloud.positions();
    const double size = tree.cellSize(level);
    const Eigen::Vector3d boxMin = tree.box().min;
    std::vector<std::size_t> kept;
    kept.reserve(tree.levelStatistics(level).nonEmptyCells);
    ProgressTicker ticker(progress, "Octree subsampling", cloud.size());
    tree.forEachCell(level, [&](octree::MortonCode code, std::size_t first, std::size_t last) {
        const octree::CellCoordinates c = octree::decodeCell(code);
        const Eigen::Vector3d centre = boxMin + (Eigen::Vector3d(c.x, c.y, c.z).array() + 0.5).matrix() * size;
        std::size_t best = order[first];
        double bestDistance = std::numeric_limits<double>::infinity();
        for (std::size_t j = first; j < last; ++j) {
            const std::size_t i = order[j];
            const double d = (positions[i].cast<double>() - centre).squaredNorm();
            if (d < bestDistance || (d == bestDistance && i < best)) {
                bestDistance = d;
                best = i;
            }
        }
        kept.push_back(best);
        ticker.step(last - first);
    });
    std::sort(kept.begin(), kept.end());
    return kept;
}

} // namespace scandiff
