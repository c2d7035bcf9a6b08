// SPDX-License-Identifier: GPL-3.0-or-later
// Cylinder queries: the points inside a finite cylinder, for M3C2's
// projection cylinders. A sphere around a cylinder of radius r and half-length
// H holds a ball of radius sqrt(r² + H²); on a surface crossed by the axis it
// reads several times the cylinder's points, and its 27-cell block more. Here
// only the cells within reach of the axis segment are read.
#include <scandiff/octree/Octree.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <vector>

namespace scandiff::octree {

namespace {

//! Beyond this many cells in a cylinder's bounding box (a long cylinder
//! oblique to the axes), the cells are found by descent from the root.
constexpr double kMaxBoxCells = 1024;
//! The descent scans a node's points once it holds no more than this.
constexpr std::size_t kLeafPoints = 32;

bool usable(const Octree::CylinderQuery& q)
{
    return q.centre.allFinite() && q.axis.allFinite() && !q.axis.isZero() && std::isfinite(q.radius) &&
           std::isfinite(q.halfLength) && q.radius >= 0 && q.halfLength >= 0;
}

//! Squared distance from x to the cylinder's axis segment.
double squaredDistanceToAxis(const Eigen::Vector3d& x, const Octree::CylinderQuery& q)
{
    const Eigen::Vector3d v = x - q.centre;
    const double t = std::clamp(v.dot(q.axis), -q.halfLength, q.halfLength);
    return (v - t * q.axis).squaredNorm();
}

//! One worker's lists and descent stack, kept between queries.
struct CylinderScratch
{
    std::vector<std::uint32_t> indices;
    std::vector<double> positions;
    struct Node
    {
        MortonCode cell;
        int level;
        std::size_t first, last;
    };
    std::vector<Node> stack;
};

} // namespace

void Octree::withinCylinderBatch(const CylinderQuery* queries, std::size_t count, const CylinderVisitor& visit) const
{
    if (count == 0)
        return;
    // Cells are assigned from float coordinates: a point may sit this far
    // outside its cell's exact box. Widening every bound by it keeps the cell
    // tests conservative; the point test itself is exact.
    const double slack = 8 * FLT_EPSILON * (box_.min.cwiseAbs().maxCoeff() + box_.size);
    // The deepest level whose cells are at least the radius wide, per query;
    // the directories of the levels in use are fetched once, before the
    // workers start (the cache takes a lock).
    auto levelFor = [&](double radius) {
        int level = 1;
        while (level < kMaxLevel && cellSize(level + 1) >= radius)
            ++level;
        return level;
    };
    std::array<const CellDirectory*, kMaxLevel + 1> directories{};
    std::vector<Eigen::Vector3f> centres(count);
    for (std::size_t i = 0; i < count; ++i) {
        centres[i] = Eigen::Vector3f::Constant(NAN);
        if (usable(queries[i])) {
            centres[i] = queries[i].centre.cast<float>();
            const int level = levelFor(queries[i].radius);
            if (!directories[static_cast<std::size_t>(level)])
                directories[static_cast<std::size_t>(level)] = &cellDirectory(level);
        }
    }
    // Neighbouring cylinders one after the other: their cells stay in cache.
    const std::vector<std::uint32_t> order = mortonOrder(centres.data(), count, box_);

    // Appends the points of sorted range [first, last) inside the cylinder.
    auto scan = [&](const CylinderQuery& q, std::size_t first, std::size_t last, CylinderScratch& s) {
        const double r2 = q.radius * q.radius;
        for (std::size_t i = first; i < last; ++i) {
            const std::uint32_t index = indices_[i];
            const Eigen::Vector3d v = points_[index].cast<double>() - q.centre;
            const double t = v.dot(q.axis);
            if (t >= -q.halfLength && t <= q.halfLength && v.squaredNorm() - t * t <= r2) {
                s.indices.push_back(index);
                s.positions.push_back(t);
            }
        }
    };
    // Whether the cell (x, y, z) of `level` may hold a point of the cylinder:
    // its centre within the radius plus its half-diagonal of the axis segment.
    auto cellMayHold = [&](const CylinderQuery& q, const CellCoordinates& c, int level) {
        const double l = cellSize(level);
        const Eigen::Vector3d centre = box_.min + l * Eigen::Vector3d(c.x + 0.5, c.y + 0.5, c.z + 0.5);
        const double reach = q.radius + l * std::sqrt(3.0) / 2 + slack;
        return squaredDistanceToAxis(centre, q) <= reach * reach;
    };
    auto descendFromRoot = [&](const CylinderQuery& q, int leafLevel, CylinderScratch& s) {
        s.stack.clear();
        s.stack.push_back({0, 0, 0, codes_.size()});
        while (!s.stack.empty()) {
            const CylinderScratch::Node node = s.stack.back();
            s.stack.pop_back();
            if (!cellMayHold(q, decodeCell(node.cell), node.level))
                continue;
            if (node.level >= leafLevel || node.last - node.first <= kLeafPoints) {
                scan(q, node.first, node.last, s);
                continue;
            }
            forEachChild(node.cell, node.level, node.first, node.last, [&](MortonCode child, std::size_t begin, std::size_t end) {
                s.stack.push_back({child, node.level + 1, begin, end});
            });
        }
    };
    auto collect = [&](const CylinderQuery& q, CylinderScratch& s) {
        const int level = levelFor(q.radius);
        const double l = cellSize(level);
        const std::int64_t n = std::int64_t(1) << level;
        std::int64_t lo[3], hi[3];
        double boxCells = 1;
        for (int a = 0; a < 3; ++a) {
            // The exact extent of a cylinder along axis a, widened by the slack.
            const double along = std::abs(q.axis[a]);
            const double extent = q.halfLength * along + q.radius * std::sqrt(std::max(0.0, 1 - along * along)) + slack;
            const double low = q.centre[a] - extent - box_.min[a], high = q.centre[a] + extent - box_.min[a];
            if (high < 0 || low > box_.size)
                return; // the cylinder misses the cube
            lo[a] = static_cast<std::int64_t>(std::clamp(std::floor(low / l), 0.0, double(n - 1)));
            hi[a] = static_cast<std::int64_t>(std::clamp(std::floor(high / l), 0.0, double(n - 1)));
            boxCells *= double(hi[a] - lo[a] + 1);
        }
        if (boxCells > kMaxBoxCells) {
            descendFromRoot(q, level, s);
            return;
        }
        // Morton codes grow with each coordinate: the box's cells lie in the
        // directory between the codes of its low and high corners.
        const CellDirectory& directory = *directories[static_cast<std::size_t>(level)];
        const auto codesBegin = directory.codes.begin();
        const auto from = std::lower_bound(codesBegin, directory.codes.end(),
                                           encodeCell(std::uint32_t(lo[0]), std::uint32_t(lo[1]), std::uint32_t(lo[2])));
        const auto to = std::upper_bound(from, directory.codes.end(),
                                         encodeCell(std::uint32_t(hi[0]), std::uint32_t(hi[1]), std::uint32_t(hi[2])));
        auto scanCell = [&](std::size_t d) { scan(q, directory.starts[d], directory.starts[d + 1], s); };
        if (double(to - from) <= 4 * boxCells) {
            // A short stretch: walk it, keeping the cells inside the box.
            for (auto it = from; it != to; ++it) {
                const CellCoordinates c = decodeCell(*it);
                if (c.x < lo[0] || c.x > hi[0] || c.y < lo[1] || c.y > hi[1] || c.z < lo[2] || c.z > hi[2])
                    continue;
                if (cellMayHold(q, c, level))
                    scanCell(static_cast<std::size_t>(it - codesBegin));
            }
            return;
        }
        for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
            for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
                for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
                    const CellCoordinates c{std::uint32_t(x), std::uint32_t(y), std::uint32_t(z)};
                    if (!cellMayHold(q, c, level))
                        continue;
                    const MortonCode code = encodeCell(c.x, c.y, c.z);
                    const auto it = std::lower_bound(from, to, code);
                    if (it != to && *it == code)
                        scanCell(static_cast<std::size_t>(it - codesBegin));
                }
    };

    tbb::enumerable_thread_specific<CylinderScratch> scratch;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16), [&](const tbb::blocked_range<std::size_t>& range) {
        CylinderScratch& s = scratch.local();
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
            const std::uint32_t qi = order[k];
            s.indices.clear();
            s.positions.clear();
            if (usable(queries[qi]))
                collect(queries[qi], s);
            visit(qi, s.indices.data(), s.positions.data(), s.indices.size());
        }
    });
}

} // namespace scandiff::octree
