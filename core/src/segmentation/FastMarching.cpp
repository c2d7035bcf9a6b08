// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/RobustStatistics.h>
#include <scandiff/core/segmentation/Classification.h>
#include <scandiff/core/segmentation/FastMarching.h>

#include "GridCells.h"
#include "Neighbourhoods.h"

#include <Eigen/Eigenvalues>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>
#include <string>

namespace scandiff {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

//! The occupied cells of one level and the cell of every point.
struct CellGrid
{
    int level = 0;
    double h = 0.0;                          //!< cell size
    Eigen::Vector3d cubeMin;                 //!< local coordinates
    std::vector<octree::MortonCode> cells;   //!< sorted, unique
    std::vector<std::uint32_t> cellOfPoint;  //!< per point
    std::vector<std::size_t> firstSorted;    //!< one more than cells: range in the octree's sorted order

    Eigen::Vector3d centre(std::size_t c) const
    {
        const octree::CellCoordinates at = octree::decodeCell(cells[c]);
        return cubeMin + h * Eigen::Vector3d(at.x + 0.5, at.y + 0.5, at.z + 0.5);
    }
};

CellGrid makeGrid(const octree::Octree& tree, int level)
{
    CellGrid grid;
    grid.level = level;
    grid.h = tree.cellSize(level);
    grid.cubeMin = tree.box().min;
    grid.cellOfPoint.resize(tree.size());
    const auto& indices = tree.sortedIndices();
    tree.forEachCell(level, [&](octree::MortonCode code, std::size_t first, std::size_t last) {
        const auto c = static_cast<std::uint32_t>(grid.cells.size());
        grid.cells.push_back(code);
        grid.firstSorted.push_back(first);
        for (std::size_t s = first; s < last; ++s)
            grid.cellOfPoint[indices[s]] = c;
    });
    grid.firstSorted.push_back(tree.size());
    return grid;
}

enum CellState : std::uint8_t { Far = 0, Trial = 1, Accepted = 2, Closed = 3 };

//! Fast marching on the occupied cells (Sethian's algorithm, thesis Fig. 3.15).
//! `times` and `state` are per cell; cells already Accepted (with their time)
//! act as sources, Closed cells are never entered. speed(i, j) > 0 is the speed
//! from accepted cell i into cell j; 0 means the front does not cross there.
//! Face neighbours get the upwind quadratic update of the Eikonal equation
//! |grad T| F = 1 (eq. 3.7); edge and corner neighbours also get a straight step
//! T_i + |offset| h / F, which keeps fronts going where a thin or slanted
//! surface leaves only diagonal contacts between occupied cells.
//! `sources` lists the Accepted cells the front starts from. Returns the cells
//! accepted, sources first; `touched` receives every cell made Trial.
template <typename Speed>
std::vector<std::size_t> march(const CellGrid& grid, const std::vector<std::size_t>& sources, std::vector<double>& times,
                               std::vector<std::uint8_t>& state, Speed&& speed, ProgressTicker* ticker,
                               std::vector<std::size_t>* touched = nullptr)
{
    using Item = std::pair<double, std::size_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
    static const std::vector<detail::CellOffset> offsets = detail::neighbourOffsets(octree::Connectivity::Corners26, false);
    std::vector<std::size_t> order;

    auto relax = [&](std::size_t i) {
        const octree::CellCoordinates at = octree::decodeCell(grid.cells[i]);
        for (const detail::CellOffset& o : offsets) {
            const std::size_t j = detail::findNeighbour(grid.cells, at, o, grid.level);
            if (j == SIZE_MAX || state[j] == Accepted || state[j] == Closed)
                continue;
            const double f = speed(i, j);
            if (!(f > 0.0))
                continue;
            const double step = grid.h / f;
            const int nonZero = (o.dx != 0) + (o.dy != 0) + (o.dz != 0);
            double t = times[i] + std::sqrt(static_cast<double>(nonZero)) * step;
            if (nonZero == 1) {
                // Per axis, the upwind side (the smaller accepted neighbour) gives
                // a term w (T - c)^2 of the discrete |grad T|^2: first order
                // w = 1, c = T1; second order when the next cell on that side is
                // accepted and not later, w = 9/4, c = (4 T1 - T2) / 3 (Sethian's
                // FMM2, whose error on smooth fronts is far below one cell).
                const octree::CellCoordinates aj = octree::decodeCell(grid.cells[j]);
                std::array<std::pair<double, double>, 3> terms; // (c, w)
                for (int a = 0; a < 3; ++a) {
                    terms[a] = {kInf, 1.0};
                    for (int sign : {-1, 1}) {
                        const detail::CellOffset d1{a == 0 ? sign : 0, a == 1 ? sign : 0, a == 2 ? sign : 0};
                        const std::size_t m1 = detail::findNeighbour(grid.cells, aj, d1, grid.level);
                        if (m1 == SIZE_MAX || state[m1] != Accepted || !(times[m1] < terms[a].first))
                            continue;
                        terms[a] = {times[m1], 1.0};
                        const detail::CellOffset d2{2 * d1.dx, 2 * d1.dy, 2 * d1.dz};
                        const std::size_t m2 = detail::findNeighbour(grid.cells, aj, d2, grid.level);
                        if (m2 != SIZE_MAX && state[m2] == Accepted && times[m2] <= times[m1])
                            terms[a] = {(4.0 * times[m1] - times[m2]) / 3.0, 2.25};
                    }
                }
                std::sort(terms.begin(), terms.end());
                // Solve sum w (T - c)^2 = step^2 over the axes whose c lies below
                // the solution, adding axes in increasing c.
                double solution = kInf, sw = 0.0, swc = 0.0, swcc = 0.0;
                for (int used = 0; used < 3; ++used) {
                    const auto [c, w] = terms[used];
                    if (!(c < solution))
                        break;
                    sw += w;
                    swc += w * c;
                    swcc += w * c * c;
                    const double disc = swc * swc - sw * (swcc - step * step);
                    if (disc < 0)
                        break;
                    solution = (swc + std::sqrt(disc)) / sw;
                }
                t = std::min(t, solution);
            }
            if (t < times[j]) {
                times[j] = t;
                if (touched && state[j] != Trial)
                    touched->push_back(j);
                state[j] = Trial;
                heap.push({t, j});
            }
        }
    };

    order = sources;
    for (std::size_t c : sources)
        relax(c);
    while (!heap.empty()) {
        const auto [t, i] = heap.top();
        heap.pop();
        if (state[i] == Accepted || t > times[i])
            continue; // a stale entry: the cell was reached sooner
        state[i] = Accepted;
        order.push_back(i);
        if (ticker)
            ticker->step();
        relax(i);
    }
    return order;
}

void checkCloud(const PointCloud& cloud, const char* what)
{
    if (cloud.empty())
        throw Error(ErrorCode::InvalidData, std::string(what) + ": cloud '" + cloud.name + "' is empty");
}

const ScalarField& requireField(const PointCloud& cloud, const std::string& name, const char* what)
{
    const ScalarField* field = cloud.field(name);
    if (!field)
        throw Error(ErrorCode::InvalidArgument, std::string(what) + ": cloud '" + cloud.name + "' has no field '" + name + "'");
    return *field;
}

} // namespace

GradientResult gradientNorm(const PointCloud& cloud, const std::string& fieldName, const GradientParams& params,
                            ProgressObserver* progress)
{
    const ScalarField& field = requireField(cloud, fieldName, "gradient");
    if (!(params.radius >= 0.0 && std::isfinite(params.radius)))
        throw Error(ErrorCode::InvalidArgument, "gradient: the radius must be > 0 (0: automatic)");
    if (params.smoothingSigma && !(*params.smoothingSigma > 0.0 && std::isfinite(*params.smoothingSigma)))
        throw Error(ErrorCode::InvalidArgument, "gradient: the smoothing sigma must be > 0");
    checkCloud(cloud, "gradient");
    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    GradientResult result;
    result.radius = params.radius > 0 ? params.radius : tree.cellSize(tree.levelNearestMeanPopulation(16.0));
    const std::size_t n = cloud.size();
    const auto& positions = cloud.positions();
    // The level whose cells are about as wide as the search sphere.
    auto levelFor = [&](double radius) {
        const double l = std::round(std::log2(tree.box().size / radius));
        return static_cast<int>(std::clamp(l, 1.0, static_cast<double>(octree::kMaxLevel)));
    };

    std::vector<float> norms(n, std::numeric_limits<float>::quiet_NaN());
    tbb::enumerable_thread_specific<std::vector<octree::Neighbour>> scratch;
    {
        const int level = levelFor(result.radius);
        const auto radius = static_cast<float>(result.radius);
        ProgressTicker ticker(progress, "Gradient of the scalar field", n);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
            auto& neighbours = scratch.local();
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                if (!field.hasValue(i))
                    continue;
                tree.withinRadius(positions[i], radius, level, neighbours);
                Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
                Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
                int used = 0;
                const double fi = field.value(i);
                for (const auto& nb : neighbours) {
                    if (nb.index == i || !field.hasValue(nb.index))
                        continue;
                    const Eigen::Vector3d d = (positions[nb.index] - positions[i]).cast<double>();
                    normal += d * d.transpose();
                    rhs += d * (field.value(nb.index) - fi);
                    ++used;
                }
                if (used < 3)
                    continue;
                // Pseudo-inverse: directions with little spread (the surface
                // normal, or the axis of a thin strip) are left out of the gradient.
                const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(normal);
                const Eigen::Vector3d values = eigen.eigenvalues();
                Eigen::Vector3d g = Eigen::Vector3d::Zero();
                for (int a = 0; a < 3; ++a)
                    if (values[a] > 1e-2 * values[2] && values[a] > 0) {
                        const Eigen::Vector3d v = eigen.eigenvectors().col(a);
                        g += v * (v.dot(rhs) / values[a]);
                    }
                double norm = g.norm();
                if (params.clampToOne)
                    norm = std::min(norm, 1.0);
                norms[i] = static_cast<float>(norm);
            }
            ticker.step(range.size());
        });
    }
    result.norm = ScalarField(fields::kGradient, n);
    if (!params.smoothingSigma) {
        result.norm.values() = std::move(norms);
        return result;
    }
    // Gaussian-weighted mean of the norms (eq. 3.10); the constant factor of
    // the Gaussian cancels in a weighted mean.
    const double sigma = *params.smoothingSigma;
    const int level = levelFor(3.0 * sigma);
    ProgressTicker ticker(progress, "Smoothing the gradient", n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
        auto& neighbours = scratch.local();
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (std::isnan(norms[i]))
                continue;
            tree.withinRadius(positions[i], static_cast<float>(3.0 * sigma), level, neighbours);
            double sum = 0.0, weights = 0.0;
            for (const auto& nb : neighbours) {
                if (std::isnan(norms[nb.index]))
                    continue;
                const double w = std::exp(-0.5 * nb.squaredDistance / (sigma * sigma));
                sum += w * norms[nb.index];
                weights += w;
            }
            result.norm.values()[i] = static_cast<float>(sum / weights);
        }
        ticker.step(range.size());
    });
    return result;
}

FastMarchingResult fastMarching(const PointCloud& cloud, const std::vector<std::size_t>& seeds, const FastMarchingParams& params,
                                ProgressObserver* progress)
{
    if (seeds.empty())
        throw Error(ErrorCode::InvalidArgument, "fast marching: no seed point");
    for (std::size_t s : seeds)
        if (s >= cloud.size())
            throw Error(ErrorCode::InvalidArgument, "fast marching: seed index " + std::to_string(s) + " is beyond the " +
                                                        std::to_string(cloud.size()) + " points");
    if (params.level < 0 || params.level > octree::kMaxLevel)
        throw Error(ErrorCode::InvalidArgument, "fast marching: the level must be in [1, 21] (0: automatic)");
    checkCloud(cloud, "fast marching");
    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    FastMarchingResult result;
    result.level = params.level > 0 ? params.level : tree.levelNearestMeanPopulation(4.0);
    const CellGrid grid = makeGrid(tree, result.level);
    result.cellSize = grid.h;
    result.cellCount = grid.cells.size();
    const auto& positions = cloud.positions();

    std::vector<double> times(grid.cells.size(), kInf);
    std::vector<std::uint8_t> state(grid.cells.size(), Far);
    std::vector<std::size_t> sources;
    // Near a seed the front is far from planar and the difference scheme least
    // accurate; the cells within two cells of a seed get their exact distance instead.
    std::vector<detail::CellOffset> block;
    for (int dx = -2; dx <= 2; ++dx)
        for (int dy = -2; dy <= 2; ++dy)
            for (int dz = -2; dz <= 2; ++dz)
                if (dx || dy || dz)
                    block.push_back({dx, dy, dz});
    for (std::size_t s : seeds) {
        const Eigen::Vector3d p = positions[s].cast<double>();
        const std::size_t c = grid.cellOfPoint[s];
        const octree::CellCoordinates at = octree::decodeCell(grid.cells[c]);
        for (const auto& o : block) {
            const std::size_t m = detail::findNeighbour(grid.cells, at, o, grid.level);
            if (m != SIZE_MAX) {
                times[m] = std::min(times[m], (grid.centre(m) - p).norm());
                if (state[m] != Accepted)
                    sources.push_back(m);
                state[m] = Accepted;
            }
        }
        times[c] = std::min(times[c], (grid.centre(c) - p).norm());
        if (state[c] != Accepted)
            sources.push_back(c);
        state[c] = Accepted;
    }
    ProgressTicker ticker(progress, "Fast marching", grid.cells.size());
    march(grid, sources, times, state, [](std::size_t, std::size_t) { return 1.0; }, &ticker);

    // A point's time: the best of "reach the centre of a nearby cell, then go
    // straight to the point" over its cell and the 26 around it, which removes
    // most of the error of giving every point of a cell the same time.
    result.arrivalTime = ScalarField(fields::kArrivalTime, cloud.size());
    static const std::vector<detail::CellOffset> offsets = detail::neighbourOffsets(octree::Connectivity::Corners26, false);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.size(), 4096), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const std::size_t c = grid.cellOfPoint[i];
            const Eigen::Vector3d p = positions[i].cast<double>();
            double best = times[c] + (grid.centre(c) - p).norm();
            const octree::CellCoordinates at = octree::decodeCell(grid.cells[c]);
            for (const auto& o : offsets) {
                const std::size_t m = detail::findNeighbour(grid.cells, at, o, grid.level);
                if (m != SIZE_MAX && std::isfinite(times[m]))
                    best = std::min(best, times[m] + (grid.centre(m) - p).norm());
            }
            if (std::isfinite(best))
                result.arrivalTime.values()[i] = static_cast<float>(best);
        }
    });
    for (std::size_t s : seeds)
        result.arrivalTime.values()[s] = 0.0f;
    return result;
}

namespace {

//! Which regions are the field's noise rather than a change (see
//! PropagationResult::backgroundRegions); `ceiling` receives median + 3 sigma.
std::vector<bool> backgroundRegions(const ScalarField& field, const CellGrid& grid, const std::vector<std::uint32_t>& indices,
                                    const std::vector<std::size_t>& regionOfCell, const std::vector<std::size_t>& regionPoints,
                                    const PropagationParams& params, double& ceiling)
{
    std::vector<double> all;
    all.reserve(field.size());
    for (std::size_t i = 0; i < field.size(); ++i)
        if (field.hasValue(i))
            all.push_back(field.value(i));
    if (all.empty() || regionPoints.size() <= 1) {
        ceiling = std::numeric_limits<double>::quiet_NaN();
        return std::vector<bool>(regionPoints.size(), false);
    }
    const double median = medianInPlace(all);
    for (double& v : all) // the deviations in place: a field holds millions of values
        v = std::abs(v - median);
    const double sigma = kMadToSigma * medianInPlace(all);
    ceiling = median + 3.0 * sigma;

    std::vector<std::vector<double>> values(regionPoints.size());
    for (std::size_t c = 0; c < regionOfCell.size(); ++c) {
        const std::size_t r = regionOfCell[c];
        if (r == 0 || regionPoints[r] < params.minPoints)
            continue;
        for (std::size_t s = grid.firstSorted[c]; s < grid.firstSorted[c + 1]; ++s)
            if (field.hasValue(indices[s]))
                values[r].push_back(field.value(indices[s]));
    }
    std::vector<bool> background(regionPoints.size(), false);
    for (std::size_t r = 1; r < values.size(); ++r) {
        if (values[r].empty())
            continue;
        const double regionMedian = medianInPlace(values[r]);
        background[r] = regionMedian < params.minSeedValue && regionMedian <= ceiling;
    }
    return background;
}

} // namespace

PropagationResult propagationSegmentation(const PointCloud& cloud, const std::string& fieldName, const PropagationParams& params,
                                          ProgressObserver* progress)
{
    const ScalarField& field = requireField(cloud, fieldName, "propagation");
    if (!(params.alpha >= 0.0 && std::isfinite(params.alpha)))
        throw Error(ErrorCode::InvalidArgument, "propagation: alpha must be a finite value >= 0");
    if (!std::isfinite(params.minSeedValue))
        throw Error(ErrorCode::InvalidArgument, "propagation: a finite minimum seed value is required");
    if (!(params.stopSpeed > 0.0 && params.stopSpeed <= 1.0))
        throw Error(ErrorCode::InvalidArgument, "propagation: the stop speed must be in (0, 1]");
    if (params.level < 0 || params.level > octree::kMaxLevel)
        throw Error(ErrorCode::InvalidArgument, "propagation: the level must be in [1, 21] (0: automatic)");
    if (params.minPoints < 1)
        throw Error(ErrorCode::InvalidArgument, "propagation: the minimum region size must be at least 1 point");
    checkCloud(cloud, "propagation");

    PropagationResult result;
    result.gradient = gradientNorm(cloud, fieldName, params.gradient, progress).norm;
    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    result.level = params.level > 0 ? params.level : tree.levelNearestMeanPopulation(8.0);
    const CellGrid grid = makeGrid(tree, result.level);
    result.cellSize = grid.h;
    const std::size_t cellCount = grid.cells.size();
    const auto& indices = tree.sortedIndices();

    // Per cell: the largest value (seeds are chosen on it) and the mean gradient
    // norm (the speed uses it). Cells without any value are not nodes.
    std::vector<double> cellValue(cellCount, -kInf), cellGradient(cellCount, 0.0);
    std::vector<std::uint8_t> state(cellCount, Closed);
    for (std::size_t c = 0; c < cellCount; ++c) {
        double sum = 0.0;
        std::size_t count = 0;
        for (std::size_t s = grid.firstSorted[c]; s < grid.firstSorted[c + 1]; ++s) {
            const std::uint32_t i = indices[s];
            if (!field.hasValue(i))
                continue;
            cellValue[c] = std::max(cellValue[c], field.value(i));
            if (result.gradient.hasValue(i)) {
                sum += result.gradient.value(i);
                ++count;
            }
        }
        if (cellValue[c] > -kInf) {
            state[c] = Far;
            cellGradient[c] = count ? sum / static_cast<double>(count) : 0.0;
        }
    }
    std::vector<std::size_t> bySeedValue;
    for (std::size_t c = 0; c < cellCount; ++c)
        if (state[c] == Far && cellValue[c] >= params.minSeedValue)
            bySeedValue.push_back(c);
    std::stable_sort(bySeedValue.begin(), bySeedValue.end(), [&](std::size_t a, std::size_t b) { return cellValue[a] > cellValue[b]; });

    std::vector<double> times(cellCount, kInf);
    std::vector<std::size_t> regionOfCell(cellCount, 0);
    std::vector<std::size_t> regionPoints{0}; // index 0: no region
    const double alpha = params.alpha, stopSpeed = params.stopSpeed;
    const bool enterSure = params.enterAboveSeedValue;
    const double minSeed = params.minSeedValue;
    auto speed = [&](std::size_t i, std::size_t j) {
        const double f = std::exp(alpha * (cellGradient[j] - cellGradient[i]));
        if (f >= stopSpeed)
            return f;
        // A cell that could be a seed itself is changed for sure: crossing into
        // it is allowed (at the slowest speed) so a plateau does not split.
        return enterSure && cellValue[j] >= minSeed ? stopSpeed : 0.0;
    };
    ProgressTicker ticker(progress, "Front propagation", cellCount);
    for (std::size_t seed : bySeedValue) {
        if (state[seed] != Far)
            continue; // already in a region
        times[seed] = 0.0;
        state[seed] = Accepted;
        const std::size_t region = regionPoints.size();
        std::size_t points = 0;
        std::vector<std::size_t> touched;
        const std::vector<std::size_t> reached = march(grid, {seed}, times, state, speed, &ticker, &touched);
        for (std::size_t c : reached) {
            regionOfCell[c] = region;
            points += grid.firstSorted[c + 1] - grid.firstSorted[c];
            state[c] = Closed; // removed from the cloud before the next seed
        }
        // Cells reached as candidates but never accepted go back to the pool.
        for (std::size_t c : touched)
            if (state[c] == Trial) {
                state[c] = Far;
                times[c] = kInf;
            }
        regionPoints.push_back(points);
    }

    // Ids by decreasing size; small regions dropped, background left out.
    const std::vector<bool> background =
        backgroundRegions(field, grid, indices, regionOfCell, regionPoints, params, result.noiseCeiling);
    std::vector<std::size_t> regions;
    for (std::size_t r = 1; r < regionPoints.size(); ++r) {
        if (regionPoints[r] < params.minPoints) {
            ++result.droppedRegions;
        } else if (background[r]) {
            ++result.backgroundRegions;
            result.backgroundPoints += regionPoints[r];
            if (params.keepBackground)
                regions.push_back(r);
        } else {
            regions.push_back(r);
        }
    }
    std::stable_sort(regions.begin(), regions.end(), [&](std::size_t a, std::size_t b) { return regionPoints[a] > regionPoints[b]; });
    std::vector<std::size_t> idOf(regionPoints.size(), 0);
    for (std::size_t r = 0; r < regions.size(); ++r) {
        idOf[regions[r]] = r + 1;
        result.regionSizes.push_back(regionPoints[regions[r]]);
    }
    result.regionCount = regions.size();
    result.regionId = ScalarField(fields::kRegionId, cloud.size());
    result.arrivalTime = ScalarField(fields::kArrivalTime, cloud.size());
    for (std::size_t c = 0; c < cellCount; ++c) {
        const std::size_t id = idOf[regionOfCell[c]];
        if (id == 0)
            continue;
        for (std::size_t s = grid.firstSorted[c]; s < grid.firstSorted[c + 1]; ++s) {
            result.regionId.values()[indices[s]] = static_cast<float>(id);
            result.arrivalTime.values()[indices[s]] = static_cast<float>(times[c]);
        }
    }
    return result;
}

} // namespace scandiff
