// SPDX-License-Identifier: GPL-3.0-or-later
// A shape's surface as the grid cells of its unrolled coordinates that its
// inliers occupy. Written here rather than through CGAL's meshing: the shapes
// are known in closed form, so a grid on their own parameters gives vertices
// exactly on the surface, bounded by the points, in a few lines for all five types.
#include "ShapeSurfaces.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/segmentation/RegionReport.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <utility>

namespace scandiff::plugins {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::int64_t kMaxCells = 2048;

using Cell = std::pair<std::int64_t, std::int64_t>;

//! A shape's own coordinates (u, v) and the way back to the surface. u turns
//! around the axis on every curved shape (periodic); v runs along the axis,
//! over the colatitude of a sphere, around the tube of a torus (periodic).
class Unrolling
{
public:
    Unrolling(const Primitive& p) : p_(p)
    {
        axis_ = p.kind == PrimitiveKind::Sphere ? Eigen::Vector3d::UnitZ() : p.direction.normalized();
        e1_ = axis_.unitOrthogonal();
        e2_ = axis_.cross(e1_);
    }

    bool periodicU() const { return p_.kind != PrimitiveKind::Plane; }
    bool periodicV() const { return p_.kind == PrimitiveKind::Torus; }
    //! v lies in [0, pi] (a sphere's colatitude): its cells stop there.
    bool boundedV() const { return p_.kind == PrimitiveKind::Sphere; }

    Eigen::Vector2d coordinates(const Eigen::Vector3d& x) const
    {
        const Eigen::Vector3d w = x - p_.point;
        const double h = w.dot(axis_);
        const double u = std::atan2(w.dot(e2_), w.dot(e1_));
        switch (p_.kind) {
        case PrimitiveKind::Plane: return {w.dot(e1_), w.dot(e2_)};
        case PrimitiveKind::Sphere: return {u, std::acos(std::clamp(h / std::max(w.norm(), 1e-300), -1.0, 1.0))};
        case PrimitiveKind::Torus: return {u, std::atan2(h, (w - h * axis_).norm() - p_.radius)};
        default: return {u, h}; // cylinder, cone
        }
    }

    Eigen::Vector3d point(double u, double v) const
    {
        const Eigen::Vector3d around = std::cos(u) * e1_ + std::sin(u) * e2_;
        switch (p_.kind) {
        case PrimitiveKind::Plane: return p_.point + u * e1_ + v * e2_;
        case PrimitiveKind::Sphere: return p_.point + p_.radius * (std::sin(v) * around + std::cos(v) * axis_);
        case PrimitiveKind::Cylinder: return p_.point + v * axis_ + p_.radius * around;
        case PrimitiveKind::Cone: return p_.point + v * axis_ + v * std::tan(p_.halfAngle) * around;
        case PrimitiveKind::Torus:
            return p_.point + (p_.radius + p_.minorRadius * std::cos(v)) * around + p_.minorRadius * std::sin(v) * axis_;
        }
        return p_.point;
    }

    //! Metres on the surface per unit of u and of v, at the inliers' typical
    //! place (`typicalV`: a cone's height).
    Eigen::Vector2d metresPerUnit(double typicalV) const
    {
        switch (p_.kind) {
        case PrimitiveKind::Plane: return {1.0, 1.0};
        case PrimitiveKind::Sphere: return {p_.radius, p_.radius}; // along the equator
        case PrimitiveKind::Cylinder: return {p_.radius, 1.0};
        case PrimitiveKind::Cone:
            return {std::abs(typicalV) * std::tan(p_.halfAngle), 1.0 / std::cos(p_.halfAngle)};
        case PrimitiveKind::Torus: return {p_.radius + p_.minorRadius, p_.minorRadius};
        }
        return {1.0, 1.0};
    }

private:
    Primitive p_;
    Eigen::Vector3d axis_, e1_, e2_;
};

std::int64_t wrap(std::int64_t i, std::int64_t n)
{
    return ((i % n) + n) % n;
}

//! The cells of a grid with `countU` (`countV`) cells around a periodic axis.
struct Grid
{
    bool periodicU = false, periodicV = false, boundedV = false;
    std::int64_t countU = 0, countV = 0;

    //! The cell's neighbour (di, dj) away, folded onto the grid; false off a bounded edge.
    bool neighbour(const Cell& c, int di, int dj, Cell& out) const
    {
        std::int64_t i = c.first + di, j = c.second + dj;
        if (periodicU)
            i = wrap(i, countU);
        if (periodicV)
            j = wrap(j, countV);
        else if (boundedV && (j < 0 || j >= countV))
            return false;
        out = {i, j};
        return true;
    }

    //! Closing with a 3 x 3 square: the one-cell gaps of the sampling filled,
    //! the outer edge where it was (a missing neighbour off a bounded edge erodes nothing).
    std::set<Cell> close(const std::set<Cell>& occupied) const
    {
        std::set<Cell> dilated;
        Cell n;
        for (const Cell& c : occupied)
            for (int di = -1; di <= 1; ++di)
                for (int dj = -1; dj <= 1; ++dj)
                    if (neighbour(c, di, dj, n))
                        dilated.insert(n);
        std::set<Cell> closed;
        for (const Cell& c : dilated) {
            bool inside = true;
            for (int di = -1; di <= 1 && inside; ++di)
                for (int dj = -1; dj <= 1 && inside; ++dj)
                    inside = !neighbour(c, di, dj, n) || dilated.count(n) != 0;
            if (inside)
                closed.insert(c);
        }
        // The erosion never removes an occupied cell: closing only adds.
        closed.insert(occupied.begin(), occupied.end());
        return closed;
    }
};

} // namespace

double shapeCellSize(const PointCloud& cloud, const std::vector<std::uint32_t>& inliers)
{
    if (inliers.empty())
        return 1.0;
    const Eigen::Vector3d centre = cloud.globalPosition(inliers.front());
    std::vector<Eigen::Vector3f> local;
    local.reserve(inliers.size());
    BoundingBox box;
    box.empty = false;
    box.min = box.max = Eigen::Vector3d::Zero();
    for (const std::uint32_t i : inliers) {
        const Eigen::Vector3d v = cloud.globalPosition(i) - centre;
        local.push_back(v.cast<float>());
        box.min = box.min.cwiseMin(v);
        box.max = box.max.cwiseMax(v);
    }
    return outlineCellFor(local, box);
}

Mesh shapeSurface(const Primitive& primitive, const PointCloud& cloud, const std::vector<std::uint32_t>& inliers, double cellSize)
{
    if (!(cellSize > 0.0) || !std::isfinite(cellSize))
        throw Error(ErrorCode::InvalidArgument, "shape surface: the cell size must be > 0");
    const Unrolling unrolling(primitive);
    std::vector<Eigen::Vector2d> uv;
    uv.reserve(inliers.size());
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    std::vector<double> heights;
    for (const std::uint32_t i : inliers) {
        const Eigen::Vector2d c = unrolling.coordinates(cloud.globalPosition(i));
        if (!c.allFinite())
            continue;
        uv.push_back(c);
        lo = lo.cwiseMin(c);
        hi = hi.cwiseMax(c);
        heights.push_back(c.y());
    }
    Mesh mesh;
    mesh.vertices.setOrigin(cloud.origin());
    if (uv.empty())
        return mesh;
    std::nth_element(heights.begin(), heights.begin() + static_cast<std::ptrdiff_t>(heights.size() / 2), heights.end());
    const Eigen::Vector2d metres = unrolling.metresPerUnit(heights[heights.size() / 2]);

    // Steps in u and v: a whole number of cells around a periodic axis; a
    // coarser cell where the grid would pass kMaxCells a side.
    Grid grid;
    grid.periodicU = unrolling.periodicU();
    grid.periodicV = unrolling.periodicV();
    grid.boundedV = unrolling.boundedV();
    auto steps = [&](double periodOrExtent, double metresPerUnit, bool periodic, std::int64_t& count) {
        const double cells = std::clamp(periodOrExtent * std::max(metresPerUnit, 1e-12) / cellSize, 1.0, double(kMaxCells));
        count = std::max<std::int64_t>(periodic ? 3 : 1, static_cast<std::int64_t>(std::ceil(cells)));
        return periodic ? periodOrExtent / static_cast<double>(count) : std::max(periodOrExtent / cells, cellSize / metresPerUnit);
    };
    const double du = steps(grid.periodicU ? 2 * kPi : hi.x() - lo.x(), metres.x(), grid.periodicU, grid.countU);
    const double dv = steps(grid.periodicV ? 2 * kPi : grid.boundedV ? kPi : hi.y() - lo.y(), metres.y(),
                            grid.periodicV || grid.boundedV, grid.countV);
    // Where cell (0, 0) starts: -pi on an angle, the inliers' low corner otherwise.
    const double u0 = grid.periodicU ? -kPi : lo.x();
    const double v0 = grid.periodicV ? -kPi : grid.boundedV ? 0.0 : lo.y();

    std::set<Cell> occupied;
    for (const Eigen::Vector2d& c : uv) {
        std::int64_t i = static_cast<std::int64_t>(std::floor((c.x() - u0) / du));
        std::int64_t j = static_cast<std::int64_t>(std::floor((c.y() - v0) / dv));
        if (grid.periodicU)
            i = wrap(i, grid.countU);
        if (grid.periodicV)
            j = wrap(j, grid.countV);
        else if (grid.boundedV)
            j = std::clamp<std::int64_t>(j, 0, grid.countV - 1);
        occupied.insert({i, j});
    }
    const std::set<Cell> cells = grid.close(occupied);

    // Corners shared between cells (folded around periodic axes), each made once.
    std::map<Cell, std::uint32_t> cornerIndex;
    std::vector<Eigen::Vector3f> positions;
    auto corner = [&](std::int64_t i, std::int64_t j) {
        if (grid.periodicU)
            i = wrap(i, grid.countU);
        if (grid.periodicV)
            j = wrap(j, grid.countV);
        const auto [at, added] = cornerIndex.emplace(Cell{i, j}, static_cast<std::uint32_t>(positions.size()));
        if (added) {
            const Eigen::Vector3d p = unrolling.point(u0 + static_cast<double>(i) * du, v0 + static_cast<double>(j) * dv);
            positions.push_back((p - cloud.origin()).cast<float>());
        }
        return at->second;
    };
    for (const Cell& c : cells) {
        const std::uint32_t a = corner(c.first, c.second), b = corner(c.first + 1, c.second),
                            d = corner(c.first + 1, c.second + 1), e = corner(c.first, c.second + 1);
        for (const Triangle& t : {Triangle{a, b, d}, Triangle{a, d, e}}) {
            // A sphere's cells at a pole have two corners on it: that triangle has no area.
            const Eigen::Vector3f ab = positions[t[1]] - positions[t[0]], ac = positions[t[2]] - positions[t[0]];
            if (ab.cross(ac).squaredNorm() > 1e-12f * ab.squaredNorm() * ac.squaredNorm())
                mesh.triangles.push_back(t);
        }
    }
    mesh.vertices.resize(positions.size());
    mesh.vertices.positions() = std::move(positions);
    return mesh;
}

} // namespace scandiff::plugins
