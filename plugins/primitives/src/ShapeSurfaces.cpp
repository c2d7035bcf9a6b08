// SPDX-License-Identifier: GPL-3.0-or-later
// A shape's surface as the grid cells of its unrolled coordinates that its
// inliers occupy. Written here rather than through CGAL's meshing: the shapes
// are known in closed form, so a grid on their own parameters gives vertices
// exactly on the surface, bounded by the points, in a few lines for all five types.
#include "ShapeSurfaces.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/segmentation/RegionReport.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace scandiff::plugins {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::int64_t kMaxCells = 2048;

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

//! The cells of the unrolled surface, in a dense array: an axis that turns
//! (a periodic angle) has `count` cells and wraps; an open axis (a plane's, a
//! cylinder's height) has its cells plus one empty cell of margin on each
//! side, so that the closing never leaves the array; a sphere's colatitude
//! has its cells and ends at the poles.
class Grid
{
public:
    enum class Axis { Open, Periodic, Bounded };

    Grid(Axis u, std::int64_t countU, Axis v, std::int64_t countV) : axis_{u, v}
    {
        size_[0] = countU + (u == Axis::Open ? 2 : 0);
        size_[1] = countV + (v == Axis::Open ? 2 : 0);
        occupied_.assign(static_cast<std::size_t>(size_[0] * size_[1]), 0);
    }
    //! The margin before cell 0 along an axis.
    std::int64_t pad(int a) const { return axis_[a] == Axis::Open ? 1 : 0; }
    std::int64_t size(int a) const { return size_[a]; }
    bool periodic(int a) const { return axis_[a] == Axis::Periodic; }
    void occupy(std::int64_t i, std::int64_t j) { occupied_[index(i + pad(0), j + pad(1))] = 1; }

    //! Closing with a 3 x 3 square: the one-cell gaps of the sampling filled,
    //! the outer edge where it was (a missing neighbour past a pole erodes
    //! nothing). The closed cells in array order, as (i, j) with the margin.
    std::vector<std::pair<std::int64_t, std::int64_t>> closed() const
    {
        std::vector<std::uint8_t> dilated(occupied_.size(), 0);
        for (std::int64_t j = 0; j < size_[1]; ++j)
            for (std::int64_t i = 0; i < size_[0]; ++i)
                if (occupied_[index(i, j)])
                    for (int dj = -1; dj <= 1; ++dj)
                        for (int di = -1; di <= 1; ++di)
                            if (const auto n = neighbour(i + di, j + dj); n.inside)
                                dilated[index(n.i, n.j)] = 1;
        std::vector<std::pair<std::int64_t, std::int64_t>> cells;
        for (std::int64_t j = 0; j < size_[1]; ++j)
            for (std::int64_t i = 0; i < size_[0]; ++i) {
                if (!dilated[index(i, j)])
                    continue;
                bool inside = occupied_[index(i, j)] != 0; // closing only adds
                if (!inside) {
                    inside = true;
                    for (int dj = -1; dj <= 1 && inside; ++dj)
                        for (int di = -1; di <= 1 && inside; ++di) {
                            const auto n = neighbour(i + di, j + dj);
                            inside = n.inside ? dilated[index(n.i, n.j)] != 0 : n.pastPole;
                        }
                }
                if (inside)
                    cells.emplace_back(i, j);
            }
        return cells;
    }

    //! (i, j) folded around the periodic axes; `inside` false off the array.
    struct Place
    {
        std::int64_t i = 0, j = 0;
        bool inside = false, pastPole = false;
    };
    Place neighbour(std::int64_t i, std::int64_t j) const
    {
        Place p;
        std::int64_t at[2] = {i, j};
        for (int a = 0; a < 2; ++a) {
            if (periodic(a))
                at[a] = ((at[a] % size_[a]) + size_[a]) % size_[a];
            else if (at[a] < 0 || at[a] >= size_[a]) {
                p.pastPole = axis_[a] == Axis::Bounded;
                return p;
            }
        }
        p.i = at[0];
        p.j = at[1];
        p.inside = true;
        return p;
    }

private:
    std::size_t index(std::int64_t i, std::int64_t j) const { return static_cast<std::size_t>(j * size_[0] + i); }

    Axis axis_[2];
    std::int64_t size_[2];
    std::vector<std::uint8_t> occupied_;
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
    // Each inlier's coordinates on the shape (both cores; a plane's ground holds most of a scan).
    std::vector<Eigen::Vector2d> all(inliers.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, inliers.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k != r.end(); ++k)
            all[k] = unrolling.coordinates(cloud.globalPosition(inliers[k]));
    });
    std::vector<Eigen::Vector2d> uv;
    uv.reserve(all.size());
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    std::vector<double> heights;
    heights.reserve(all.size());
    for (const Eigen::Vector2d& c : all) {
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
    const Grid::Axis axisU = unrolling.periodicU() ? Grid::Axis::Periodic : Grid::Axis::Open;
    const Grid::Axis axisV = unrolling.periodicV() ? Grid::Axis::Periodic : unrolling.boundedV() ? Grid::Axis::Bounded : Grid::Axis::Open;
    auto steps = [&](double span, double metresPerUnit, Grid::Axis axis, std::int64_t& count) {
        const double cells = std::clamp(span * std::max(metresPerUnit, 1e-12) / cellSize, 1.0, double(kMaxCells));
        if (axis != Grid::Axis::Open) {
            count = std::max<std::int64_t>(3, static_cast<std::int64_t>(std::ceil(cells)));
            return span / static_cast<double>(count);
        }
        const double step = std::max(span / cells, cellSize / metresPerUnit);
        count = static_cast<std::int64_t>(std::floor(span / step)) + 1;
        return step;
    };
    std::int64_t countU = 0, countV = 0;
    const double du = steps(axisU == Grid::Axis::Periodic ? 2 * kPi : hi.x() - lo.x(), metres.x(), axisU, countU);
    const double dv = steps(axisV == Grid::Axis::Periodic ? 2 * kPi : axisV == Grid::Axis::Bounded ? kPi : hi.y() - lo.y(), metres.y(),
                            axisV, countV);
    // Where cell (0, 0) starts: -pi on an angle, the inliers' low corner otherwise.
    const double u0 = axisU == Grid::Axis::Periodic ? -kPi : lo.x();
    const double v0 = axisV == Grid::Axis::Periodic ? -kPi : axisV == Grid::Axis::Bounded ? 0.0 : lo.y();

    Grid grid(axisU, countU, axisV, countV);
    for (const Eigen::Vector2d& c : uv) {
        std::int64_t i = static_cast<std::int64_t>(std::floor((c.x() - u0) / du));
        std::int64_t j = static_cast<std::int64_t>(std::floor((c.y() - v0) / dv));
        // Rounding may put the last point one cell out; an angle wraps.
        i = axisU == Grid::Axis::Periodic ? ((i % countU) + countU) % countU : std::clamp<std::int64_t>(i, 0, countU - 1);
        j = axisV == Grid::Axis::Periodic ? ((j % countV) + countV) % countV : std::clamp<std::int64_t>(j, 0, countV - 1);
        grid.occupy(i, j);
    }
    const auto cells = grid.closed();

    // Corners shared between cells (folded around periodic axes), each made
    // once: a dense index over the grid's corners.
    const std::int64_t cornersU = grid.size(0) + 1, cornersV = grid.size(1) + 1;
    std::vector<std::uint32_t> cornerIndex(static_cast<std::size_t>(cornersU * cornersV), std::numeric_limits<std::uint32_t>::max());
    std::vector<Eigen::Vector3f> positions;
    auto corner = [&](std::int64_t i, std::int64_t j) {
        if (grid.periodic(0))
            i %= grid.size(0);
        if (grid.periodic(1))
            j %= grid.size(1);
        std::uint32_t& slot = cornerIndex[static_cast<std::size_t>(j * cornersU + i)];
        if (slot == std::numeric_limits<std::uint32_t>::max()) {
            slot = static_cast<std::uint32_t>(positions.size());
            const Eigen::Vector3d p = unrolling.point(u0 + static_cast<double>(i - grid.pad(0)) * du,
                                                      v0 + static_cast<double>(j - grid.pad(1)) * dv);
            positions.push_back((p - cloud.origin()).cast<float>());
        }
        return slot;
    };
    for (const auto& [i, j] : cells) {
        const std::uint32_t a = corner(i, j), b = corner(i + 1, j), d = corner(i + 1, j + 1), e = corner(i, j + 1);
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
