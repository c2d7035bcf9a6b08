// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/distance/CloudToMesh.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/geometry/PointTriangleDistance.h>
#include <scandiff/octree/MortonCode.h>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace scandiff {

namespace {

using octree::CellCoordinates;
using octree::MortonCode;
using octree::decodeCell;
using octree::encodeCell;
using octree::kMaxLevel;

// Pruning and stopping tests compare computed distances (rounded) with
// geometric bounds (rounded too): they only discard a triangle or stop a search
// when the bound exceeds the best distance by this relative slack plus this
// absolute one (times the cube size), far above double rounding, so that the
// result always equals brute force.
constexpr double kRelativeSlack = 1e-9;
constexpr double kAbsoluteSlack = 1e-9;
//! The triangle/box test runs on cells enlarged by this fraction of their edge:
//! a triangle touching a cell is never lost to rounding (an extra reference is harmless).
constexpr double kCellEnlargement = 1e-6;
//! Rings 0..kMaxRing (a 5 x 5 x 5 block of cells) before the best-first descent.
constexpr int kMaxRing = 2;
//! A descent node holding at most this many references is scanned whole.
constexpr std::size_t kDescentLeafReferences = 16;
//! Automatic level: cell edge about this many mean triangle edges.
constexpr double kAutoCellEdgesPerTriangleEdge = 2.0;
//! Reference budget: max(kMinReferenceBudget, kReferencesPerTriangle x triangles).
constexpr double kMinReferenceBudget = 8388608.0; // 2^23
constexpr double kReferencesPerTriangle = 32.0;

constexpr std::uint32_t kNoTriangle = std::numeric_limits<std::uint32_t>::max();

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInfinity = std::numeric_limits<double>::infinity();

//! A triangle's float vertices (mesh frame) and their bounding box.
struct TriangleVertices
{
    Eigen::Vector3f v[3];
    Eigen::Vector3f lo, hi;
};

//! The grid: cells of `level` in the cube [min, min + size]^3 (mesh frame).
struct Grid
{
    Eigen::Vector3d min = Eigen::Vector3d::Zero();
    double size = 1.0;
    int level = 1;
    double cell = 1.0;     //!< edge of a cell at `level`
    std::int64_t n = 2;    //!< cells per axis at `level`
    double absoluteSlack = 0.0;

    double cellSize(int k) const { return size / static_cast<double>(std::int64_t(1) << k); }

    //! Cell of q at `level`, clamped into the grid (the far face belongs to the last cell).
    std::array<std::int64_t, 3> cellOf(const Eigen::Vector3d& q) const
    {
        std::array<std::int64_t, 3> c{};
        for (int a = 0; a < 3; ++a)
            c[static_cast<std::size_t>(a)] =
                std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor((q[a] - min[a]) / cell)), 0, n - 1);
        return c;
    }
};

//! Separating-axis triangle/box test (Akenine-Möller 2001): the box is centred
//! on `centre` with half-edge `h`. Degenerate triangles work too (their null
//! axes separate nothing), so a segment or a point is tested as such.
bool triangleBoxOverlap(const Eigen::Vector3d& centre, double h, const Eigen::Vector3d (&triangle)[3])
{
    const Eigen::Vector3d v0 = triangle[0] - centre, v1 = triangle[1] - centre, v2 = triangle[2] - centre;
    // The box's own axes: the bounding boxes must overlap.
    for (int a = 0; a < 3; ++a) {
        if (std::min({v0[a], v1[a], v2[a]}) > h || std::max({v0[a], v1[a], v2[a]}) < -h)
            return false;
    }
    // The triangle's plane.
    const Eigen::Vector3d e0 = v1 - v0, e1 = v2 - v1, e2 = v0 - v2;
    const Eigen::Vector3d normal = e0.cross(e1);
    if (std::abs(normal.dot(v0)) > h * normal.cwiseAbs().sum())
        return false;
    // Edge x box-axis cross products.
    const Eigen::Vector3d* edges[3] = {&e0, &e1, &e2};
    for (const Eigen::Vector3d* e : edges) {
        const Eigen::Vector3d axes[3] = {{0.0, (*e)[2], -(*e)[1]}, {-(*e)[2], 0.0, (*e)[0]}, {(*e)[1], -(*e)[0], 0.0}};
        for (const Eigen::Vector3d& axis : axes) {
            const double p0 = axis.dot(v0), p1 = axis.dot(v1), p2 = axis.dot(v2);
            const double r = h * axis.cwiseAbs().sum();
            if (std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r)
                return false;
        }
    }
    return true;
}

//! A (cell code, triangle) reference, packed to 12 bytes.
#pragma pack(push, 4)
struct Reference
{
    MortonCode code;
    std::uint32_t triangle;
};
#pragma pack(pop)
static_assert(sizeof(Reference) == 12, "Reference must stay packed");

bool operator<(const Reference& a, const Reference& b)
{
    return a.code < b.code || (a.code == b.code && a.triangle < b.triangle);
}

//! Emits a reference in every cell of grid.level the triangle intersects, by a
//! recursive subdivision started at the deepest level where its bounding box
//! spans at most two cells per axis (work proportional to the references).
class Rasterizer
{
public:
    Rasterizer(const Grid& grid, std::vector<Reference>& out) : grid_(grid), out_(out) {}

    void run(const TriangleVertices& t, std::uint32_t index)
    {
        for (int i = 0; i < 3; ++i)
            triangle_[i] = t.v[i].cast<double>();
        index_ = index;
        const Eigen::Vector3d lo = t.lo.cast<double>(), hi = t.hi.cast<double>();
        int start = grid_.level;
        std::int64_t first[3] = {0, 0, 0}, last[3] = {0, 0, 0};
        for (; start >= 0; --start) {
            const double l = grid_.cellSize(start);
            const std::int64_t top = (std::int64_t(1) << start) - 1;
            bool small = true;
            for (int a = 0; a < 3; ++a) {
                first[a] = std::clamp<std::int64_t>(
                    static_cast<std::int64_t>(std::floor((lo[a] - grid_.min[a]) / l - kCellEnlargement)), 0, top);
                last[a] = std::clamp<std::int64_t>(
                    static_cast<std::int64_t>(std::floor((hi[a] - grid_.min[a]) / l + kCellEnlargement)), 0, top);
                small = small && last[a] - first[a] <= 1;
            }
            if (small)
                break;
        }
        for (std::int64_t x = first[0]; x <= last[0]; ++x)
            for (std::int64_t y = first[1]; y <= last[1]; ++y)
                for (std::int64_t z = first[2]; z <= last[2]; ++z)
                    visit(start, x, y, z);
    }

private:
    void visit(int k, std::int64_t x, std::int64_t y, std::int64_t z)
    {
        const double l = grid_.cellSize(k);
        const Eigen::Vector3d centre =
            grid_.min + (Eigen::Vector3d(static_cast<double>(x), static_cast<double>(y), static_cast<double>(z)).array() + 0.5)
                            .matrix() *
                            l;
        if (!triangleBoxOverlap(centre, l * (0.5 + kCellEnlargement), triangle_))
            return;
        if (k == grid_.level) {
            out_.push_back({encodeCell(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                                       static_cast<std::uint32_t>(z)),
                            index_});
            return;
        }
        // Children in Morton order (x bit highest).
        for (int c = 0; c < 8; ++c)
            visit(k + 1, 2 * x + ((c >> 2) & 1), 2 * y + ((c >> 1) & 1), 2 * z + (c & 1));
    }

    const Grid& grid_;
    std::vector<Reference>& out_;
    Eigen::Vector3d triangle_[3];
    std::uint32_t index_ = 0;
};

//! The triangles of each non-empty cell: cellCodes[i] (increasing) owns
//! triangles[cellFirst[i] .. cellFirst[i + 1]).
struct TriangleIndex
{
    std::vector<MortonCode> cellCodes;
    std::vector<std::size_t> cellFirst;
    std::vector<std::uint32_t> triangles;
    //! Per cell: its box clipped to the union of its triangles' boxes, which
    //! holds every point of those triangles inside the cell (a far tighter bound
    //! than the cell for a surface crossing it; empty boxes are harmless).
    std::vector<Eigen::Vector3d> tightLo, tightHi;

    //! [first, last) in `triangles` of the cell `code`; empty if the cell holds none.
    std::pair<std::size_t, std::size_t> find(MortonCode code) const
    {
        const auto it = std::lower_bound(cellCodes.begin(), cellCodes.end(), code);
        if (it == cellCodes.end() || *it != code)
            return {0, 0};
        const auto i = static_cast<std::size_t>(it - cellCodes.begin());
        return {cellFirst[i], cellFirst[i + 1]};
    }
};

//! A triangle gathered for the points of a cell, in double.
struct Candidate
{
    Eigen::Vector3d a, b, c;
    Eigen::Vector3d lo, hi;
    Eigen::Vector3d unitNormal; //!< (b - a) x (c - a) normalised; zero for a degenerate triangle
    double planeOffset;         //!< unitNormal . a
    std::uint32_t triangle;
};

Candidate makeCandidate(const std::vector<TriangleVertices>& triangles, std::uint32_t t)
{
    const TriangleVertices& v = triangles[t];
    Candidate c{v.v[0].cast<double>(), v.v[1].cast<double>(), v.v[2].cast<double>(), v.lo.cast<double>(),
                v.hi.cast<double>(), Eigen::Vector3d::Zero(), 0.0, t};
    if (!geometry::isDegenerateTriangle(c.a, c.b, c.c)) {
        const Eigen::Vector3d n = (c.b - c.a).cross(c.c - c.a);
        c.unitNormal = n / n.norm();
        c.planeOffset = c.unitNormal.dot(c.a);
    }
    return c;
}

//! Search state of one compared point.
struct PointState
{
    Eigen::Vector3d q;        //!< mesh frame, double
    double inner = 0.0;       //!< distance from q to its cell's faces (eq. 4.1)
    double best2 = kInfinity; //!< best squared distance so far
    double bound2 = kInfinity; //!< triangles farther than this cannot matter
    double alignment = 0.0;   //!< |(q - closest) . unit normal| of the best triangle (signed ties)
    double side = 1.0;        //!< +1 or -1: the side of the best triangle's plane
    std::uint32_t triangle = kNoTriangle;
    std::uint32_t index = 0;  //!< point index in the compared cloud
    bool searching = true;
};

struct SearchSettings
{
    bool signedDistances = false;
    double maxBound2 = kInfinity; //!< squared search limit from maxDistance (with slack)
    double absoluteSlack = 0.0;
};

//! Offers a triangle to a point: exact distance unless its bounding box is
//! already too far; the best is the smallest (squared distance, then the
//! largest alignment, then the smallest index when signed), a total order, so
//! the result does not depend on the order triangles are offered.
inline void consider(PointState& s, const Candidate& c, const SearchSettings& settings)
{
    double gap2 = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double d = std::max({c.lo[a] - s.q[a], s.q[a] - c.hi[a], 0.0});
        gap2 += d * d;
    }
    if (gap2 > s.bound2)
        return;
    // The distance to the triangle's plane is a lower bound too (0 if degenerate).
    const double planeGap = c.unitNormal.dot(s.q) - c.planeOffset;
    if (planeGap * planeGap > s.bound2)
        return;
    const geometry::PointTriangleResult r = geometry::pointTriangleDistance(s.q, c.a, c.b, c.c);
    if (r.squaredDistance > s.best2)
        return;
    double alignment = -1.0, side = 1.0;
    if (settings.signedDistances) {
        if (!r.degenerate) {
            const double dot = (s.q - r.closestPoint).dot(c.unitNormal);
            alignment = std::abs(dot);
            side = dot >= 0.0 ? 1.0 : -1.0;
        }
        if (r.squaredDistance == s.best2 &&
            (alignment < s.alignment || (alignment == s.alignment && c.triangle > s.triangle)))
            return;
    } else if (r.squaredDistance == s.best2) {
        return;
    }
    s.best2 = r.squaredDistance;
    s.alignment = alignment;
    s.side = side;
    s.triangle = c.triangle;
    const double bound = std::sqrt(s.best2) * (1.0 + kRelativeSlack) + settings.absoluteSlack;
    s.bound2 = std::min(settings.maxBound2, bound * bound);
}

//! Per-thread scratch of the distance stage.
struct Scratch
{
    std::vector<std::uint32_t> stamp; //!< stamp[t] == epoch: triangle t already offered
    std::uint32_t epoch = 0;
    std::vector<Candidate> candidates;
    std::vector<PointState> points;
    std::vector<std::size_t> active;  //!< points of the cell in the descent

    struct Node
    {
        double gap2;
        int level;
        MortonCode prefix;
        std::size_t first, last; //!< range of cells (in TriangleIndex::cellCodes)
    };
    std::vector<Node> queue;

    std::uint32_t nextEpoch(std::size_t triangleCount)
    {
        if (stamp.size() != triangleCount)
            stamp.assign(triangleCount, 0);
        if (++epoch == 0) {
            std::fill(stamp.begin(), stamp.end(), 0);
            epoch = 1;
        }
        return epoch;
    }
};

//! Squared distance from q to the box [lo, hi] (0 inside).
inline double squaredGapToBox(const Eigen::Vector3d& q, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi)
{
    double gap2 = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double d = std::max({lo[a] - q[a], q[a] - hi[a], 0.0});
        gap2 += d * d;
    }
    return gap2;
}

//! Squared distance between the boxes [alo, ahi] and [blo, bhi].
inline double squaredGapBetweenBoxes(const Eigen::Vector3d& alo, const Eigen::Vector3d& ahi, const Eigen::Vector3d& blo,
                                     const Eigen::Vector3d& bhi)
{
    double gap2 = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double d = std::max({blo[a] - ahi[a], alo[a] - bhi[a], 0.0});
        gap2 += d * d;
    }
    return gap2;
}

//! Best-first traversal of the cell hierarchy for the points of one cell the
//! rings did not settle, shared by all of them: nodes come out by increasing
//! distance to the box of those points, and the traversal ends when the next
//! node is farther than every point's bound. A leaf (a cell of the grid's
//! level, or a node with few references) is offered to each point unless the
//! leaf's box is farther than that point's own bound; grid cells use their
//! tight box. The cost grows with log(cells) and is paid once per cell.
void descend(std::vector<PointState>& points, Scratch& scratch, const TriangleIndex& index, const Grid& grid,
             const std::vector<TriangleVertices>& triangles, const SearchSettings& settings)
{
    auto& active = scratch.active;
    active.clear();
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInfinity), hi = -lo;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (points[i].searching) {
            active.push_back(i);
            lo = lo.cwiseMin(points[i].q);
            hi = hi.cwiseMax(points[i].q);
        }
    if (active.empty())
        return;
    const auto largestBound = [&] {
        double bound2 = 0.0;
        for (const std::size_t i : active)
            bound2 = std::max(bound2, points[i].bound2);
        return bound2;
    };
    double limit = largestBound();
    const auto nodeBox = [&](int level, MortonCode prefix, std::size_t firstCell, Eigen::Vector3d& boxLo, Eigen::Vector3d& boxHi) {
        if (level == grid.level) {
            boxLo = index.tightLo[firstCell];
            boxHi = index.tightHi[firstCell];
        } else {
            const CellCoordinates c = decodeCell(prefix);
            const double l = grid.cellSize(level);
            boxLo = grid.min + Eigen::Vector3d(static_cast<double>(c.x), static_cast<double>(c.y), static_cast<double>(c.z)) * l;
            boxHi = (boxLo.array() + l).matrix();
        }
    };

    auto& queue = scratch.queue;
    const auto farther = [](const Scratch::Node& a, const Scratch::Node& b) { return a.gap2 > b.gap2; };
    queue.clear();
    queue.push_back({0.0, 0, 0, 0, index.cellCodes.size()});
    Eigen::Vector3d boxLo, boxHi;
    while (!queue.empty()) {
        std::pop_heap(queue.begin(), queue.end(), farther);
        const Scratch::Node node = queue.back();
        queue.pop_back();
        if (node.gap2 > limit)
            break;
        const std::size_t refFirst = index.cellFirst[node.first], refLast = index.cellFirst[node.last];
        if (node.level == grid.level || refLast - refFirst <= kDescentLeafReferences) {
            // A node of several cells may list a triangle more than once.
            const std::uint32_t epoch = scratch.nextEpoch(triangles.size());
            auto& candidates = scratch.candidates;
            candidates.clear();
            for (std::size_t r = refFirst; r < refLast; ++r) {
                const std::uint32_t t = index.triangles[r];
                if (scratch.stamp[t] != epoch) {
                    scratch.stamp[t] = epoch;
                    candidates.push_back(makeCandidate(triangles, t));
                }
            }
            nodeBox(node.level, node.prefix, node.first, boxLo, boxHi);
            for (const std::size_t i : active) {
                PointState& s = points[i];
                if (squaredGapToBox(s.q, boxLo, boxHi) > s.bound2)
                    continue;
                for (const Candidate& c : candidates)
                    consider(s, c, settings);
            }
            limit = largestBound();
            continue;
        }
        const int childLevel = node.level + 1;
        const int shift = 3 * (grid.level - childLevel);
        std::size_t begin = node.first;
        for (MortonCode c = 0; c < 8 && begin < node.last; ++c) {
            const MortonCode child = (node.prefix << 3) | c;
            const auto end = static_cast<std::size_t>(
                std::lower_bound(index.cellCodes.begin() + static_cast<std::ptrdiff_t>(begin),
                                 index.cellCodes.begin() + static_cast<std::ptrdiff_t>(node.last), (child + 1) << shift) -
                index.cellCodes.begin());
            if (end > begin) {
                nodeBox(childLevel, child, begin, boxLo, boxHi);
                const double gap2 = squaredGapBetweenBoxes(lo, hi, boxLo, boxHi);
                if (!(gap2 > limit)) {
                    queue.push_back({gap2, childLevel, child, begin, end});
                    std::push_heap(queue.begin(), queue.end(), farther);
                }
            }
            begin = end;
        }
    }
    for (const std::size_t i : active)
        points[i].searching = false;
}

//! Estimated references at a level: each triangle covers about 2 area / l^2
//! + 2 perimeter / l + 1 cells.
double estimatedReferences(double totalArea, double totalPerimeter, std::size_t triangleCount, double cell)
{
    return 2.0 * totalArea / (cell * cell) + 2.0 * totalPerimeter / cell + static_cast<double>(triangleCount);
}

//! Orders compared points by cell, packed to 12 bytes.
#pragma pack(push, 4)
struct KeyedPoint
{
    MortonCode code;
    std::uint32_t index;
};
#pragma pack(pop)


void checkInputs(const PointCloud& compared, const Mesh& reference, const CloudToMeshParams& params)
{
    if (params.octreeLevel < 0 || params.octreeLevel > kMaxLevel)
        throw Error(ErrorCode::InvalidArgument, "cloud-to-mesh: octreeLevel must be 0 (automatic) or 1.." +
                                                    std::to_string(kMaxLevel) + ", got " +
                                                    std::to_string(params.octreeLevel));
    if (params.maxDistance && !(std::isfinite(*params.maxDistance) && *params.maxDistance > 0.0))
        throw Error(ErrorCode::InvalidArgument, "cloud-to-mesh: maxDistance must be a finite distance > 0, got " +
                                                    std::to_string(*params.maxDistance));
    if (params.clampBeyondMax && !params.maxDistance)
        throw Error(ErrorCode::InvalidArgument, "cloud-to-mesh: clampBeyondMax needs a maxDistance");
    compared.checkConsistency();
    if (compared.empty())
        throw Error(ErrorCode::InvalidData, "cloud-to-mesh: the compared cloud '" + compared.name + "' is empty");
    if (compared.size() > std::numeric_limits<std::uint32_t>::max())
        throw Error(ErrorCode::Unsupported, "cloud-to-mesh: the compared cloud '" + compared.name +
                                                "' has more than 4,294,967,295 points");
    reference.checkConsistency();
    if (reference.triangles.empty())
        throw Error(ErrorCode::InvalidData, "cloud-to-mesh: the reference mesh '" + reference.name + "' has no triangle");
    if (reference.triangles.size() > std::numeric_limits<std::uint32_t>::max())
        throw Error(ErrorCode::Unsupported, "cloud-to-mesh: the reference mesh '" + reference.name +
                                                "' has more than 4,294,967,295 triangles");
}

//! What the level choice needs of the triangles: their total area and
//! perimeters, how many are degenerate, and the box they span.
struct TriangleTotals
{
    double area = 0.0, perimeter = 0.0, nonDegeneratePerimeter = 0.0;
    std::size_t degenerate = 0;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInfinity), hi = Eigen::Vector3d::Constant(-kInfinity);
};

//! Each triangle's vertices and box, and their totals. A vertex with a
//! non-finite coordinate is an error naming the first such triangle.
std::vector<TriangleVertices> triangleTable(const Mesh& reference, TriangleTotals& totals, ProgressTicker& ticker)
{
    const std::size_t triangleCount = reference.triangles.size();
    const auto& vertices = reference.vertices.positions();
    std::vector<TriangleVertices> triangles(triangleCount);
    std::atomic<std::size_t> firstBadTriangle{std::numeric_limits<std::size_t>::max()};
    tbb::enumerable_thread_specific<TriangleTotals> triangleTotals;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangleCount, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
        TriangleTotals& local = triangleTotals.local();
        for (std::size_t t = r.begin(); t != r.end(); ++t) {
            TriangleVertices& tv = triangles[t];
            bool finite = true;
            for (int i = 0; i < 3; ++i) {
                tv.v[i] = vertices[reference.triangles[t][static_cast<std::size_t>(i)]];
                finite = finite && tv.v[i].allFinite();
            }
            if (!finite) {
                std::size_t expected = firstBadTriangle.load();
                while (t < expected && !firstBadTriangle.compare_exchange_weak(expected, t)) {
                }
                continue;
            }
            tv.lo = tv.v[0].cwiseMin(tv.v[1]).cwiseMin(tv.v[2]);
            tv.hi = tv.v[0].cwiseMax(tv.v[1]).cwiseMax(tv.v[2]);
            const Eigen::Vector3d a = tv.v[0].cast<double>(), b = tv.v[1].cast<double>(), c = tv.v[2].cast<double>();
            const double perimeter = (b - a).norm() + (c - b).norm() + (a - c).norm();
            local.perimeter += perimeter;
            local.area += 0.5 * (b - a).cross(c - a).norm();
            if (geometry::isDegenerateTriangle(a, b, c))
                ++local.degenerate;
            else
                local.nonDegeneratePerimeter += perimeter;
            local.lo = local.lo.cwiseMin(tv.lo.cast<double>());
            local.hi = local.hi.cwiseMax(tv.hi.cast<double>());
        }
        ticker.step(r.size());
    });
    if (firstBadTriangle.load() != std::numeric_limits<std::size_t>::max())
        throw Error(ErrorCode::InvalidData, "cloud-to-mesh: triangle " + std::to_string(firstBadTriangle.load()) +
                                                " of the reference mesh '" + reference.name +
                                                "' has a vertex with a non-finite coordinate");
    for (const TriangleTotals& t : triangleTotals) {
        totals.area += t.area;
        totals.perimeter += t.perimeter;
        totals.nonDegeneratePerimeter += t.nonDegeneratePerimeter;
        totals.degenerate += t.degenerate;
        totals.lo = totals.lo.cwiseMin(t.lo);
        totals.hi = totals.hi.cwiseMax(t.hi);
    }
    return triangles;
}

//! The compared points in the mesh's local frame, in double (their origins
//! may differ).
struct InMeshFrame
{
    const std::vector<Eigen::Vector3f>& positions;
    Eigen::Vector3d offset;
    Eigen::Vector3d operator()(std::size_t i) const { return offset + positions[i].cast<double>(); }
};

//! The grid's cube: the mesh's box and the finite compared points'. Counts
//! the points without a finite coordinate (warned about: they get NaN).
Grid enclosingGrid(const PointCloud& compared, const Mesh& reference, const InMeshFrame& meshFrame, const TriangleTotals& totals,
                   std::size_t& nonFinite)
{
    struct PointBox
    {
        Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInfinity), hi = Eigen::Vector3d::Constant(-kInfinity);
        std::size_t nonFinite = 0;
    };
    const auto& positions = compared.positions();
    tbb::enumerable_thread_specific<PointBox> pointBoxes;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, compared.size(), 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
        PointBox& box = pointBoxes.local();
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            if (!positions[i].allFinite()) {
                ++box.nonFinite;
                continue;
            }
            const Eigen::Vector3d q = meshFrame(i);
            box.lo = box.lo.cwiseMin(q);
            box.hi = box.hi.cwiseMax(q);
        }
    });
    Eigen::Vector3d lo = totals.lo, hi = totals.hi;
    nonFinite = 0;
    for (const PointBox& b : pointBoxes) {
        lo = lo.cwiseMin(b.lo);
        hi = hi.cwiseMax(b.hi);
        nonFinite += b.nonFinite;
    }
    if (nonFinite > 0)
        logWarning("cloud-to-mesh: " + std::to_string(nonFinite) + " point(s) of '" + compared.name +
                   "' with a non-finite coordinate get no distance (NaN)");
    Grid grid;
    grid.min = lo;
    const double extent = (hi - lo).maxCoeff();
    grid.size = extent > 0.0 ? extent * (1.0 + 1e-6) : 1.0;
    if (!std::isfinite(grid.size))
        throw Error(ErrorCode::InvalidData, "cloud-to-mesh: the cloud '" + compared.name + "' and the mesh '" +
                                                reference.name + "' span too large a volume");
    grid.absoluteSlack = kAbsoluteSlack * grid.size;
    return grid;
}

//! The level of the triangle index (thesis §2.2.2): cells about twice the
//! mean edge of the usable triangles, or the one asked for; lowered while the
//! triangles would be indexed in too many cells (a warning when the asked
//! level was lowered).
void chooseLevel(Grid& grid, const CloudToMeshParams& params, const TriangleTotals& totals, std::size_t triangleCount)
{
    int level = params.octreeLevel;
    if (level == 0) {
        const std::size_t usable = triangleCount - totals.degenerate;
        const double meanEdge = usable > 0 ? totals.nonDegeneratePerimeter / (3.0 * static_cast<double>(usable)) : 0.0;
        level = 1;
        if (meanEdge > 0.0) {
            const double ideal = std::log2(grid.size / (kAutoCellEdgesPerTriangleEdge * meanEdge));
            level = static_cast<int>(std::clamp(std::lround(ideal), 1L, static_cast<long>(kMaxLevel)));
        }
    }
    const double budget = std::max(kMinReferenceBudget, kReferencesPerTriangle * static_cast<double>(triangleCount));
    const int requestedLevel = level;
    while (level > 1 && estimatedReferences(totals.area, totals.perimeter, triangleCount, grid.cellSize(level)) > budget)
        --level;
    if (params.octreeLevel != 0 && level != requestedLevel)
        logWarning("cloud-to-mesh: octree level " + std::to_string(requestedLevel) + " would index about " +
                   std::to_string(static_cast<long long>(estimatedReferences(
                       totals.area, totals.perimeter, triangleCount, grid.cellSize(requestedLevel)))) +
                   " triangle references; using level " + std::to_string(level) + " instead");
    grid.level = level;
    grid.cell = grid.cellSize(level);
    grid.n = std::int64_t(1) << level;
}

//! Every triangle referenced in each cell it crosses (exact triangle-box
//! overlap), the references sorted by (cell, triangle), each cell's box
//! tightened to its triangles'.
TriangleIndex indexTriangles(const std::vector<TriangleVertices>& triangles, const Grid& grid, ProgressTicker& ticker)
{
    TriangleIndex index;
    tbb::enumerable_thread_specific<std::vector<Reference>> localReferences;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangles.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<Reference>& out = localReferences.local();
        Rasterizer rasterizer(grid, out);
        for (std::size_t t = r.begin(); t != r.end(); ++t)
            rasterizer.run(triangles[t], static_cast<std::uint32_t>(t));
        ticker.step(r.size());
    });
    std::size_t total = 0;
    for (const auto& v : localReferences)
        total += v.size();
    std::vector<Reference> references;
    references.reserve(total);
    for (auto& v : localReferences) {
        references.insert(references.end(), v.begin(), v.end());
        std::vector<Reference>().swap(v);
    }
    tbb::parallel_sort(references.begin(), references.end());
    index.triangles.resize(references.size());
    for (std::size_t i = 0; i < references.size(); ++i) {
        // By value: push_back takes a reference, and a reference to a
        // member of the packed struct would be misaligned.
        const MortonCode code = references[i].code;
        if (i == 0 || code != references[i - 1].code) {
            index.cellCodes.push_back(code);
            index.cellFirst.push_back(i);
        }
        index.triangles[i] = references[i].triangle;
    }
    index.cellFirst.push_back(references.size());
    const std::size_t cellCount = index.cellCodes.size();
    index.tightLo.resize(cellCount);
    index.tightHi.resize(cellCount);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cellCount, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity()), hi = -lo;
            for (std::size_t k = index.cellFirst[i]; k < index.cellFirst[i + 1]; ++k) {
                lo = lo.cwiseMin(triangles[index.triangles[k]].lo);
                hi = hi.cwiseMax(triangles[index.triangles[k]].hi);
            }
            const CellCoordinates c = decodeCell(index.cellCodes[i]);
            const Eigen::Vector3d cellLo =
                grid.min + Eigen::Vector3d(static_cast<double>(c.x), static_cast<double>(c.y), static_cast<double>(c.z)) * grid.cell;
            index.tightLo[i] = cellLo.cwiseMax(lo.cast<double>());
            index.tightHi[i] = (cellLo.array() + grid.cell).matrix().cwiseMin(hi.cast<double>());
        }
    });
    return index;
}

//! The finite compared points grouped by cell, in Morton order: `order`, and
//! where each cell's group starts in it (one past the end last).
struct CellGroups
{
    std::vector<KeyedPoint> order;
    std::vector<std::size_t> start;
};

CellGroups groupPointsByCell(const PointCloud& compared, const InMeshFrame& meshFrame, const Grid& grid, std::size_t nonFinite)
{
    CellGroups groups;
    groups.order.reserve(compared.size() - nonFinite);
    for (std::size_t i = 0; i < compared.size(); ++i) {
        if (!compared.positions()[i].allFinite())
            continue;
        const auto c = grid.cellOf(meshFrame(i));
        groups.order.push_back({encodeCell(static_cast<std::uint32_t>(c[0]), static_cast<std::uint32_t>(c[1]),
                                           static_cast<std::uint32_t>(c[2])),
                                static_cast<std::uint32_t>(i)});
    }
    tbb::parallel_sort(groups.order.begin(), groups.order.end(), [](const KeyedPoint& a, const KeyedPoint& b) {
        return a.code < b.code || (a.code == b.code && a.index < b.index);
    });
    for (std::size_t i = 0; i < groups.order.size(); ++i)
        if (i == 0 || groups.order[i].code != groups.order[i - 1].code)
            groups.start.push_back(i);
    groups.start.push_back(groups.order.size());
    return groups;
}

//! The search for the points of one cell (thesis §2.2.2): the triangles of
//! the rings j = 0, 1, 2 of cells around it, gathered once and offered to
//! every point still searching, until the stopping rule (eq. 4.1) settles
//! it; the points left then share one descent of the index.
class CellSearch
{
public:
    CellSearch(const Grid& grid, const TriangleIndex& index, const std::vector<TriangleVertices>& triangles, const SearchSettings& settings,
               const InMeshFrame& meshFrame)
        : grid_(grid), index_(index), triangles_(triangles), settings_(settings), meshFrame_(meshFrame)
    {
    }

    //! The points order[first, last), all in one cell, searched; their states in scratch.points.
    void run(const std::vector<KeyedPoint>& order, std::size_t first, std::size_t last, Scratch& scratch) const
    {
        const CellCoordinates cell = decodeCell(order[first].code);
        const Eigen::Vector3d cellLo =
            grid_.min + Eigen::Vector3d(static_cast<double>(cell.x), static_cast<double>(cell.y), static_cast<double>(cell.z)) * grid_.cell;
        auto& points = scratch.points;
        points.clear();
        for (std::size_t i = first; i < last; ++i) {
            PointState s;
            s.index = order[i].index;
            s.q = meshFrame_(s.index);
            s.inner = kInfinity;
            for (int a = 0; a < 3; ++a)
                s.inner = std::min({s.inner, s.q[a] - cellLo[a], cellLo[a] + grid_.cell - s.q[a]});
            s.bound2 = settings_.maxBound2;
            points.push_back(s);
        }
        const std::uint32_t epoch = scratch.nextEpoch(triangles_.size());
        std::size_t searching = points.size();
        for (int j = 0; j <= kMaxRing && searching > 0; ++j) {
            gatherRing(cell, j, epoch, scratch);
            const std::int64_t cx = cell.x, cy = cell.y, cz = cell.z; // signed: the ring may pass the grid's edges
            const bool coversGrid = cx - j <= 0 && cy - j <= 0 && cz - j <= 0 && cx + j >= grid_.n - 1 && cy + j >= grid_.n - 1 &&
                                    cz + j >= grid_.n - 1;
            const double ringRadius = static_cast<double>(j) * grid_.cell;
            for (PointState& s : points) {
                if (!s.searching)
                    continue;
                for (const Candidate& c : scratch.candidates)
                    consider(s, c, settings_);
                // Stopping rule (eq. 4.1): every triangle not yet offered lies
                // outside the rings 0..j, farther than their inscribed sphere.
                const double inscribed = ringRadius + s.inner;
                if (coversGrid || (inscribed > 0.0 && s.bound2 < inscribed * inscribed)) {
                    s.searching = false;
                    --searching;
                }
            }
        }
        // Points the rings did not settle: one shared descent.
        descend(points, scratch, index_, grid_, triangles_, settings_);
    }

private:
    //! The triangles of the cells at Chebyshev distance j of `cell` (its shell),
    //! each once per cell searched (stamped with the cell's epoch), into scratch.candidates.
    void gatherRing(const CellCoordinates& cell, int j, std::uint32_t epoch, Scratch& scratch) const
    {
        auto& candidates = scratch.candidates;
        candidates.clear();
        const auto gather = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
            const auto [b, e] =
                index_.find(encodeCell(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y), static_cast<std::uint32_t>(z)));
            for (std::size_t r = b; r < e; ++r) {
                const std::uint32_t t = index_.triangles[r];
                if (scratch.stamp[t] != epoch) {
                    scratch.stamp[t] = epoch;
                    candidates.push_back(makeCandidate(triangles_, t));
                }
            }
        };
        const std::int64_t cx = cell.x, cy = cell.y, cz = cell.z;
        const std::int64_t x0 = std::max<std::int64_t>(cx - j, 0), x1 = std::min<std::int64_t>(cx + j, grid_.n - 1);
        const std::int64_t y0 = std::max<std::int64_t>(cy - j, 0), y1 = std::min<std::int64_t>(cy + j, grid_.n - 1);
        const std::int64_t z0 = std::max<std::int64_t>(cz - j, 0), z1 = std::min<std::int64_t>(cz + j, grid_.n - 1);
        for (std::int64_t x = x0; x <= x1; ++x)
            for (std::int64_t y = y0; y <= y1; ++y) {
                if (std::abs(x - cx) == j || std::abs(y - cy) == j) {
                    for (std::int64_t z = z0; z <= z1; ++z)
                        gather(x, y, z);
                } else {
                    if (cz - j >= 0)
                        gather(x, y, cz - j);
                    if (j > 0 && cz + j < grid_.n)
                        gather(x, y, cz + j);
                }
            }
    }

    const Grid& grid_;
    const TriangleIndex& index_;
    const std::vector<TriangleVertices>& triangles_;
    const SearchSettings& settings_;
    const InMeshFrame& meshFrame_;
};

} // namespace

CloudToMeshResult cloudToMesh(const PointCloud& compared, const Mesh& reference, const CloudToMeshParams& params,
                              ProgressObserver* progress)
{
    checkInputs(compared, reference, params);
    const std::size_t triangleCount = reference.triangles.size();
    // Everything happens in the mesh's local frame, in double.
    const InMeshFrame meshFrame{compared.positions(), compared.origin() - reference.vertices.origin()};

    // The index of the triangles: a grid over the cube of the mesh and the
    // points, its level from the triangles' size, each triangle in the cells
    // it crosses.
    ProgressTicker indexTicker(progress, "Indexing the mesh triangles", 2 * triangleCount);
    TriangleTotals totals;
    const std::vector<TriangleVertices> triangles = triangleTable(reference, totals, indexTicker);
    std::size_t nonFinite = 0;
    Grid grid = enclosingGrid(compared, reference, meshFrame, totals, nonFinite);
    chooseLevel(grid, params, totals, triangleCount);
    const TriangleIndex index = indexTriangles(triangles, grid, indexTicker);

    // The points cell by cell, each cell's searched together.
    const CellGroups groups = groupPointsByCell(compared, meshFrame, grid, nonFinite);
    CloudToMeshResult result;
    result.distance = ScalarField("c2m_distance", compared.size());
    result.level = grid.level;
    result.degenerateTriangles = totals.degenerate;
    if (params.closestTriangles)
        result.closestTriangle.assign(compared.size(), kNoClosestTriangle);
    SearchSettings settings;
    settings.signedDistances = params.signedDistances;
    settings.absoluteSlack = grid.absoluteSlack;
    if (params.maxDistance) {
        const double bound = *params.maxDistance * (1.0 + kRelativeSlack) + grid.absoluteSlack;
        settings.maxBound2 = bound * bound;
    }
    const double beyond = params.clampBeyondMax ? *params.maxDistance : kNaN;
    const CellSearch search(grid, index, triangles, settings, meshFrame);
    std::vector<float>& values = result.distance.values();
    ProgressTicker distanceTicker(progress, "Computing cloud-to-mesh distances", groups.order.size());
    tbb::enumerable_thread_specific<Scratch> scratches;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups.start.size() - 1, 4), [&](const tbb::blocked_range<std::size_t>& range) {
        Scratch& scratch = scratches.local();
        for (std::size_t g = range.begin(); g != range.end(); ++g) {
            search.run(groups.order, groups.start[g], groups.start[g + 1], scratch);
            for (const PointState& s : scratch.points) {
                const double d = std::sqrt(s.best2);
                const bool outside = !(s.best2 < kInfinity) || (params.maxDistance && d > *params.maxDistance);
                values[s.index] = static_cast<float>(outside ? beyond : s.side * d);
                if (params.closestTriangles && !outside)
                    result.closestTriangle[s.index] = s.triangle;
            }
            distanceTicker.step(groups.start[g + 1] - groups.start[g]);
        }
    });
    result.statistics = computeStatistics(result.distance);
    return result;
}

} // namespace scandiff
