// SPDX-License-Identifier: GPL-3.0-or-later
// Ground filtering by the Simple Morphological Filter (see GroundFilter.h).
// Written here rather than taken from PDAL or PCL: PDAL is not packaged with
// its filters' C++ API on Debian 12 for linking into a library, and PCL's
// progressive morphological filter is Zhang 2003's (no final terrain model,
// no slope-dependent threshold), whose defaults do worse on the ISPRS samples.
#include <scandiff/core/processing/GroundFilter.h>

#include <scandiff/core/Error.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <string>

namespace scandiff {

namespace {

constexpr double kEmpty = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kMaxCells = 200'000'000;

void checkParams(const GroundFilterParams& p)
{
    const auto positive = [](double v, const char* name) {
        if (!(v > 0) || !std::isfinite(v))
            throw Error(ErrorCode::InvalidArgument, std::string("ground: ") + name + " must be a positive number");
    };
    positive(p.cell, "the cell");
    positive(p.window, "the window");
    if (!(p.slope >= 0) || !std::isfinite(p.slope))
        throw Error(ErrorCode::InvalidArgument, "ground: the slope must be 0 or more");
    if (!(p.threshold >= 0) || !std::isfinite(p.threshold))
        throw Error(ErrorCode::InvalidArgument, "ground: the threshold must be 0 or more");
    if (!(p.scalar >= 0) || !std::isfinite(p.scalar))
        throw Error(ErrorCode::InvalidArgument, "ground: the scalar must be 0 or more");
}

//! A grid of heights, NaN where a cell has none.
struct HeightGrid
{
    std::size_t columns = 0, rows = 0;
    std::vector<double> z;
    std::size_t at(std::size_t column, std::size_t row) const { return row * columns + column; }
};

//! Every empty cell gets the mean of its filled 8-neighbours, ring after ring
//! outwards from the filled cells (a breadth-first pass: each cell is visited
//! a bounded number of times, whatever the holes' sizes), then `smoothing`
//! Jacobi steps on the cells filled so, which turn the rings' steps into a
//! smooth surface spanning the hole (a discrete harmonic fill, as the paper's
//! inpainting). Nothing happens when no cell is filled.
void fillEmptyCells(HeightGrid& g, int smoothing)
{
    const std::size_t n = g.z.size();
    std::vector<char> known(n, 0);
    std::vector<std::size_t> layer;
    for (std::size_t c = 0; c < n; ++c)
        if (!std::isnan(g.z[c]))
            known[c] = 1, layer.push_back(c);
    if (layer.empty() || layer.size() == n)
        return;
    std::vector<char> filledHere(n, 0);
    const auto forNeighbours = [&](std::size_t c, auto f) {
        const std::size_t col = c % g.columns, row = c / g.columns;
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                if ((dx || dy) && !(dx < 0 && col == 0) && !(dy < 0 && row == 0) && !(dx > 0 && col + 1 == g.columns)
                    && !(dy > 0 && row + 1 == g.rows))
                    f(g.at(col + dx, row + dy));
            }
    };
    std::vector<std::size_t> next;
    while (!layer.empty()) {
        next.clear();
        for (std::size_t c : layer)
            forNeighbours(c, [&](std::size_t m) {
                if (!known[m] && !filledHere[m])
                    filledHere[m] = 2, next.push_back(m); // 2: in this ring, not yet averaged
            });
        for (std::size_t m : next) {
            double sum = 0;
            int count = 0;
            forNeighbours(m, [&](std::size_t k) {
                if (known[k])
                    sum += g.z[k], ++count;
            });
            g.z[m] = sum / count;
        }
        for (std::size_t m : next)
            known[m] = 1, filledHere[m] = 1;
        layer.swap(next);
    }
    std::vector<double> previous;
    for (int step = 0; step < smoothing; ++step) {
        previous = g.z;
        for (std::size_t c = 0; c < n; ++c)
            if (filledHere[c]) {
                double sum = 0;
                int count = 0;
                forNeighbours(c, [&](std::size_t k) { sum += previous[k], ++count; });
                g.z[c] = sum / count;
            }
    }
}

//! The minimum (or maximum) over a window of 2r+1 along one line of the grid
//! (a monotonic queue: each value enters and leaves once).
void slidingExtreme(const double* in, double* out, std::size_t count, std::size_t stride, std::size_t r, bool minimum)
{
    std::deque<std::size_t> queue;
    const auto better = [&](double a, double b) { return minimum ? a <= b : a >= b; };
    std::size_t entered = 0;
    for (std::size_t i = 0; i < count; ++i) {
        const std::size_t last = std::min(count - 1, i + r);
        for (; entered <= last; ++entered) {
            while (!queue.empty() && better(in[entered * stride], in[queue.back() * stride]))
                queue.pop_back();
            queue.push_back(entered);
        }
        while (queue.front() + r < i)
            queue.pop_front();
        out[i * stride] = in[queue.front() * stride];
    }
}

//! Erosion (minimum) or dilation (maximum) by a square of radius r cells:
//! along the rows, then along the columns.
std::vector<double> squareExtreme(const HeightGrid& g, const std::vector<double>& in, std::size_t r, bool minimum)
{
    std::vector<double> rowsDone(in.size()), out(in.size());
    tbb::parallel_for(std::size_t(0), g.rows, [&](std::size_t row) {
        slidingExtreme(in.data() + row * g.columns, rowsDone.data() + row * g.columns, g.columns, 1, r, minimum);
    });
    tbb::parallel_for(std::size_t(0), g.columns, [&](std::size_t column) {
        slidingExtreme(rowsDone.data() + column, out.data() + column, g.rows, g.columns, r, minimum);
    });
    return out;
}

//! The progressive opening: 1 for the cells an opening lowered by more than
//! the slope allows over its radius.
std::vector<char> objectCells(const HeightGrid& lowest, const GroundFilterParams& p, ProgressObserver* progress)
{
    const auto radii = static_cast<std::size_t>(std::max(1.0, std::ceil(p.window / p.cell)));
    ProgressTicker ticker(progress, "Ground: opening", radii);
    std::vector<char> object(lowest.z.size(), 0);
    std::vector<double> surface = lowest.z;
    for (std::size_t r = 1; r <= radii; ++r) {
        std::vector<double> opened = squareExtreme(lowest, squareExtreme(lowest, surface, r, true), r, false);
        const double allowed = p.slope * static_cast<double>(r) * p.cell;
        for (std::size_t c = 0; c < surface.size(); ++c)
            if (surface[c] - opened[c] > allowed)
                object[c] = 1;
        surface.swap(opened);
        ticker.step();
    }
    return object;
}

void computeSlopes(TerrainGrid& t)
{
    t.slopes.assign(t.heights.size(), 0.0);
    const auto h = [&](std::size_t col, std::size_t row) { return t.heights[row * t.columns + col]; };
    for (std::size_t row = 0; row < t.rows; ++row)
        for (std::size_t col = 0; col < t.columns; ++col) {
            const std::size_t c0 = col ? col - 1 : col, c1 = col + 1 < t.columns ? col + 1 : col;
            const std::size_t r0 = row ? row - 1 : row, r1 = row + 1 < t.rows ? row + 1 : row;
            const double dx = c1 > c0 ? (h(c1, row) - h(c0, row)) / (static_cast<double>(c1 - c0) * t.cell) : 0.0;
            const double dy = r1 > r0 ? (h(col, r1) - h(col, r0)) / (static_cast<double>(r1 - r0) * t.cell) : 0.0;
            t.slopes[row * t.columns + col] = std::hypot(dx, dy);
        }
}

//! Bilinear interpolation of a per-cell array between the cells' centres.
double bilinear(const TerrainGrid& t, const std::vector<double>& values, double x, double y)
{
    const double fx = std::clamp((x - t.originX) / t.cell - 0.5, 0.0, static_cast<double>(t.columns - 1));
    const double fy = std::clamp((y - t.originY) / t.cell - 0.5, 0.0, static_cast<double>(t.rows - 1));
    const auto c0 = static_cast<std::size_t>(fx), r0 = static_cast<std::size_t>(fy);
    const std::size_t c1 = std::min(c0 + 1, t.columns - 1), r1 = std::min(r0 + 1, t.rows - 1);
    const double ax = fx - static_cast<double>(c0), ay = fy - static_cast<double>(r0);
    const auto v = [&](std::size_t c, std::size_t r) { return values[r * t.columns + c]; };
    return (1 - ay) * ((1 - ax) * v(c0, r0) + ax * v(c1, r0)) + ay * ((1 - ax) * v(c0, r1) + ax * v(c1, r1));
}

} // namespace

double TerrainGrid::heightAt(double x, double y) const { return bilinear(*this, heights, x, y); }
double TerrainGrid::slopeAt(double x, double y) const { return bilinear(*this, slopes, x, y); }

GroundFilterResult filterGround(const PointCloud& cloud, const GroundFilterParams& params, ProgressObserver* progress)
{
    checkParams(params);
    const auto& positions = cloud.positions();
    double minX = kEmpty, minY = kEmpty, maxX = kEmpty, maxY = kEmpty;
    std::size_t finite = 0;
    for (const auto& q : positions)
        if (q.allFinite()) {
            minX = finite ? std::min<double>(minX, q.x()) : q.x(), maxX = finite ? std::max<double>(maxX, q.x()) : q.x();
            minY = finite ? std::min<double>(minY, q.y()) : q.y(), maxY = finite ? std::max<double>(maxY, q.y()) : q.y();
            ++finite;
        }
    if (!finite)
        throw Error(ErrorCode::InvalidData, "ground: the cloud '" + cloud.name + "' has no finite point");
    const double columnsWide = std::floor((maxX - minX) / params.cell) + 1, rowsWide = std::floor((maxY - minY) / params.cell) + 1;
    if (columnsWide * rowsWide > static_cast<double>(kMaxCells))
        throw Error(ErrorCode::InvalidData, "ground: a " + std::to_string(params.cell) + " m grid over the cloud would hold "
                                                + std::to_string(static_cast<long long>(columnsWide * rowsWide))
                                                + " cells (at most 200 million): give a larger cell");

    HeightGrid lowest;
    lowest.columns = static_cast<std::size_t>(columnsWide);
    lowest.rows = static_cast<std::size_t>(rowsWide);
    lowest.z.assign(lowest.columns * lowest.rows, kEmpty);
    {
        ProgressTicker ticker(progress, "Ground: lowest points", positions.size());
        for (std::size_t i = 0; i < positions.size(); ++i) {
            const auto& q = positions[i];
            if (!q.allFinite())
                continue;
            const auto col = std::min(lowest.columns - 1, static_cast<std::size_t>((q.x() - minX) / params.cell));
            const auto row = std::min(lowest.rows - 1, static_cast<std::size_t>((q.y() - minY) / params.cell));
            const std::size_t c = lowest.at(col, row);
            if (std::isnan(lowest.z[c]) || q.z() < lowest.z[c])
                lowest.z[c] = q.z();
            ticker.step();
        }
    }
    const std::vector<char> hadPoints = [&] {
        std::vector<char> had(lowest.z.size());
        for (std::size_t c = 0; c < had.size(); ++c)
            had[c] = !std::isnan(lowest.z[c]);
        return had;
    }();
    HeightGrid filled = lowest;
    fillEmptyCells(filled, 0);
    const std::vector<char> object = objectCells(filled, params, progress);

    GroundFilterResult result;
    HeightGrid terrain = lowest;
    for (std::size_t c = 0; c < terrain.z.size(); ++c) {
        if (object[c] || !hadPoints[c])
            terrain.z[c] = kEmpty;
        result.objectCells += object[c] && hadPoints[c];
    }
    if (std::all_of(terrain.z.begin(), terrain.z.end(), [](double z) { return std::isnan(z); }))
        terrain.z = lowest.z; // every cell an object (a lone roof): the lowest points are all the terrain there is
    fillEmptyCells(terrain, 20);

    result.terrain.originX = minX;
    result.terrain.originY = minY;
    result.terrain.cell = params.cell;
    result.terrain.columns = terrain.columns;
    result.terrain.rows = terrain.rows;
    result.terrain.heights = std::move(terrain.z);
    computeSlopes(result.terrain);

    result.ground.assign(positions.size(), 0);
    ProgressTicker ticker(progress, "Ground: points", positions.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, positions.size(), 1 << 14), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            const auto& q = positions[i];
            if (!q.allFinite())
                continue;
            const double allowed = params.threshold + params.scalar * result.terrain.slopeAt(q.x(), q.y());
            result.ground[i] = std::abs(q.z() - result.terrain.heightAt(q.x(), q.y())) <= allowed;
        }
        ticker.step(range.size());
    });
    result.groundCount = static_cast<std::size_t>(std::count(result.ground.begin(), result.ground.end(), 1));
    return result;
}

} // namespace scandiff
