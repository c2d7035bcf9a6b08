// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/distance/DemOfDifference.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/distance/M3C2.h>

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace scandiff {

CellStatistic parseCellStatistic(const std::string& name)
{
    if (name == "min")
        return CellStatistic::Min;
    if (name == "mean")
        return CellStatistic::Mean;
    if (name == "max")
        return CellStatistic::Max;
    if (name == "median")
        return CellStatistic::Median;
    throw Error(ErrorCode::InvalidArgument, "cell statistic '" + name + "': expected min, mean, max or median");
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kMaxCells = 268435456.0; // 2^28: 2 GB of doubles per layer

struct Grid
{
    double x0 = 0, y0 = 0, cell = 1;
    std::size_t cols = 0, rows = 0;
    std::size_t size() const { return cols * rows; }
};

//! One epoch's heights per cell; NaN where it has none.
struct EpochRaster
{
    std::vector<double> z, roughness;
    std::vector<std::uint32_t> count;
};

//! The grid of square cells covering [xmin, xmax] x [ymin, ymax], its corner
//! a whole number of cells from (0, 0) so that runs with one cell size share
//! their cells.
Grid alignedGrid(double cell, double xmin, double ymin, double xmax, double ymax, const char* what)
{
    Grid grid;
    grid.cell = cell;
    grid.x0 = std::floor(xmin / cell) * cell;
    grid.y0 = std::floor(ymin / cell) * cell;
    const double cols = std::floor((xmax - grid.x0) / cell) + 1, rows = std::floor((ymax - grid.y0) / cell) + 1;
    if (cols * rows > kMaxCells)
        throw Error(ErrorCode::InvalidArgument, std::string(what) + ": a " + std::to_string(cell) + " m cell makes " +
                                                    std::to_string(cols) + " x " + std::to_string(rows) + " cells (at most 2^28)");
    grid.cols = static_cast<std::size_t>(cols);
    grid.rows = static_cast<std::size_t>(rows);
    return grid;
}

std::uint32_t cellOf(const Grid& grid, const Eigen::Vector3d& p)
{
    const auto col = static_cast<std::size_t>(std::floor((p.x() - grid.x0) / grid.cell));
    const auto row = static_cast<std::size_t>(std::floor((p.y() - grid.y0) / grid.cell));
    return static_cast<std::uint32_t>(std::min(row, grid.rows - 1) * grid.cols + std::min(col, grid.cols - 1));
}

//! The statistic of a cell's n heights, given in increasing order (zAt(k):
//! the k-th), with their mean.
template <class HeightAt>
double cellHeight(CellStatistic statistic, std::size_t n, double mean, HeightAt zAt)
{
    switch (statistic) {
    case CellStatistic::Min: return zAt(0);
    case CellStatistic::Max: return zAt(n - 1);
    case CellStatistic::Mean: return mean;
    case CellStatistic::Median: return n % 2 ? zAt(n / 2) : 0.5 * (zAt(n / 2 - 1) + zAt(n / 2));
    }
    return mean;
}

//! The fields that place a grid's cells and count their points, rather than
//! measure something: not shown, not carried.
bool isGridBookkeeping(const std::string& name)
{
    return name == fields::kRasterCol || name == fields::kRasterRow || name == fields::kPointCount;
}

void addBounds(const PointCloud& cloud, double& xmin, double& ymin, double& xmax, double& ymax)
{
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d p = cloud.globalPosition(i);
        if (!p.allFinite())
            continue;
        xmin = std::min(xmin, p.x());
        ymin = std::min(ymin, p.y());
        xmax = std::max(xmax, p.x());
        ymax = std::max(ymax, p.y());
    }
}

EpochRaster rasterise(const PointCloud& cloud, const Grid& grid, CellStatistic statistic, ProgressTicker& ticker)
{
    // (cell, height) pairs sorted: each cell's heights in one increasing run,
    // which gives the median as directly as the mean.
    std::vector<std::pair<std::uint32_t, double>> keyed;
    keyed.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d p = cloud.globalPosition(i);
        if (!p.allFinite())
            continue;
        keyed.emplace_back(cellOf(grid, p), p.z());
    }
    ticker.step(cloud.size());
    tbb::parallel_sort(keyed.begin(), keyed.end());
    ticker.step(cloud.size());
    EpochRaster r;
    r.z.assign(grid.size(), kNaN);
    r.roughness.assign(grid.size(), kNaN);
    r.count.assign(grid.size(), 0);
    for (std::size_t begin = 0; begin < keyed.size();) {
        std::size_t end = begin;
        double sum = 0;
        while (end < keyed.size() && keyed[end].first == keyed[begin].first)
            sum += keyed[end++].second;
        const std::size_t n = end - begin;
        const double mean = sum / static_cast<double>(n);
        double squares = 0;
        for (std::size_t k = begin; k < end; ++k)
            squares += (keyed[k].second - mean) * (keyed[k].second - mean);
        const std::uint32_t cell = keyed[begin].first;
        r.count[cell] = static_cast<std::uint32_t>(n);
        r.roughness[cell] = std::sqrt(squares / static_cast<double>(n));
        r.z[cell] = cellHeight(statistic, n, mean, [&](std::size_t k) { return keyed[begin + k].second; });
        begin = end;
    }
    return r;
}

//! Each pass gives every empty cell with a filled neighbour the mean height
//! (and roughness) of its filled neighbours among the 8 around it.
void fill(EpochRaster& r, const Grid& grid, int passes)
{
    for (int pass = 0; pass < passes; ++pass) {
        std::vector<double> z = r.z, roughness = r.roughness;
        bool changed = false;
        for (std::size_t row = 0; row < grid.rows; ++row)
            for (std::size_t col = 0; col < grid.cols; ++col) {
                const std::size_t c = row * grid.cols + col;
                if (!std::isnan(r.z[c]))
                    continue;
                double sum = 0, rough = 0;
                int n = 0;
                for (int dr = -1; dr <= 1; ++dr)
                    for (int dc = -1; dc <= 1; ++dc) {
                        const auto nr = static_cast<std::ptrdiff_t>(row) + dr, nc = static_cast<std::ptrdiff_t>(col) + dc;
                        if ((dr == 0 && dc == 0) || nr < 0 || nc < 0 || nr >= static_cast<std::ptrdiff_t>(grid.rows) ||
                            nc >= static_cast<std::ptrdiff_t>(grid.cols))
                            continue;
                        const std::size_t k = static_cast<std::size_t>(nr) * grid.cols + static_cast<std::size_t>(nc);
                        if (std::isnan(r.z[k]))
                            continue;
                        sum += r.z[k];
                        rough += std::isnan(r.roughness[k]) ? 0.0 : r.roughness[k];
                        ++n;
                    }
                if (n > 0) {
                    z[c] = sum / n;
                    roughness[c] = rough / n;
                    changed = true;
                }
            }
        r.z = std::move(z);
        r.roughness = std::move(roughness);
        if (!changed)
            break;
    }
}

} // namespace

Table DemOfDifferenceResult::report() const
{
    Table t;
    t.columns = {"quantity", "value", "unit"};
    auto row = [&](const char* name, double value, const char* unit) { t.rows.push_back({std::string(name), value, std::string(unit)}); };
    row("cell_size", std::sqrt(cellArea), "m");
    row("columns", static_cast<double>(columns), "cells");
    row("rows", static_cast<double>(rows), "cells");
    row("matching_cells", static_cast<double>(matchingCells), "cells");
    row("matching_surface", static_cast<double>(matchingCells) * cellArea, "m2");
    row("significant_cells", static_cast<double>(significantCells), "cells");
    row("deposition", deposition, "m3");
    row("deposition_uncertainty", depositionError, "m3");
    row("erosion", erosion, "m3");
    row("erosion_uncertainty", erosionError, "m3");
    row("net_change", deposition - erosion, "m3");
    row("added_volume_2_5d", added, "m3");
    row("removed_volume_2_5d", removed, "m3");
    return t;
}

DemOfDifferenceResult demOfDifference(const PointCloud* reference, const PointCloud& compared, const DemOfDifferenceParams& params,
                                      ProgressObserver* progress)
{
    if (!std::isfinite(params.cell) || params.cell <= 0)
        throw Error(ErrorCode::InvalidArgument, "DEM of difference: the cell size must be positive (m)");
    if (params.lod && params.propagated)
        throw Error(ErrorCode::InvalidArgument, "DEM of difference: give a level of detection or the propagated error, not both");
    if (params.lod && !(*params.lod >= 0))
        throw Error(ErrorCode::InvalidArgument, "DEM of difference: the level of detection must be zero or positive (m)");
    if (params.heightError && !(*params.heightError >= 0))
        throw Error(ErrorCode::InvalidArgument, "DEM of difference: the height error must be zero or positive (m)");
    if (!reference && !params.referenceHeight)
        throw Error(ErrorCode::InvalidArgument, "DEM of difference: give a reference cloud or a reference height");
    if (reference && params.referenceHeight)
        throw Error(ErrorCode::InvalidArgument, "DEM of difference: give a reference cloud or a reference height, not both");
    if (compared.empty() || (reference && reference->empty()))
        throw Error(ErrorCode::InvalidData, "DEM of difference: an epoch has no point");

    double xmin = std::numeric_limits<double>::infinity(), ymin = xmin, xmax = -xmin, ymax = -xmin;
    addBounds(compared, xmin, ymin, xmax, ymax);
    if (reference)
        addBounds(*reference, xmin, ymin, xmax, ymax);
    if (!(xmin <= xmax))
        throw Error(ErrorCode::InvalidData, "DEM of difference: no finite point");
    const Grid grid = alignedGrid(params.cell, xmin, ymin, xmax, ymax, "DEM of difference");

    ProgressTicker ticker(progress, "DEM of difference", 2 * (compared.size() + (reference ? reference->size() : 0)) + 1);
    EpochRaster second = rasterise(compared, grid, params.statistic, ticker);
    EpochRaster first;
    if (reference) {
        first = rasterise(*reference, grid, params.statistic, ticker);
    } else {
        first.z.assign(grid.size(), *params.referenceHeight);
        first.roughness.assign(grid.size(), 0.0);
        first.count.assign(grid.size(), 0);
    }
    fill(first, grid, params.fillPasses);
    fill(second, grid, params.fillPasses);
    ticker.checkCancel();

    DemOfDifferenceResult result;
    result.cellArea = params.cell * params.cell;
    result.columns = grid.cols;
    result.rows = grid.rows;
    std::vector<std::size_t> kept;
    for (std::size_t c = 0; c < grid.size(); ++c)
        if (!std::isnan(second.z[c]) || (reference && !std::isnan(first.z[c])))
            kept.push_back(c);
    PointCloud& cells = result.cells;
    cells.name = compared.name + "_dod";
    // The grid is in the epochs' system (a GeoTIFF of it is georeferenced with it).
    cells.setCrsWkt(!compared.crsWkt().empty() ? compared.crsWkt() : reference ? reference->crsWkt() : std::string());
    if (reference && !reference->crsWkt().empty() && !compared.crsWkt().empty() && reference->crsWkt() != compared.crsWkt())
        logWarning("DEM of difference: the epochs declare different coordinate reference systems; the grid takes the compared one's");
    cells.setOrigin(Eigen::Vector3d(std::round(grid.x0), std::round(grid.y0), 0.0));
    cells.resize(kept.size());
    const char* names[] = {fields::kRasterCol,    fields::kRasterRow, fields::kZReference,     fields::kZCompared,
                           fields::kDodDifference, fields::kDodLod,   fields::kDodSignificant};
    // The difference is the first field after the cell's place, so that it is
    // a GeoTIFF's band 1: the band QGIS and gdaldem show unless told otherwise.
    for (int k : {0, 1, 4, 5, 6, 2, 3})
        cells.addField(ScalarField(names[k], kept.size()));
    ScalarField* f[7];
    for (int k = 0; k < 7; ++k)
        f[k] = cells.field(names[k]);
    // Heights far from zero keep their millimetres around an offset.
    for (int k : {2, 3}) {
        for (std::size_t c : kept) {
            const double z = k == 2 ? first.z[c] : second.z[c];
            if (!std::isnan(z)) {
                f[k]->setOffset(std::floor(z));
                break;
            }
        }
    }
    double depositionVariance = 0, erosionVariance = 0;
    const double area = result.cellArea;
    for (std::size_t k = 0; k < kept.size(); ++k) {
        const std::size_t c = kept[k];
        const std::size_t col = c % grid.cols, row = c / grid.cols;
        const double z1 = first.z[c], z2 = second.z[c];
        const double shown = std::isnan(z2) ? z1 : z2;
        cells.positions()[k] = (Eigen::Vector3d(grid.x0 + (static_cast<double>(col) + 0.5) * grid.cell,
                                                grid.y0 + (static_cast<double>(row) + 0.5) * grid.cell, shown) -
                                cells.origin())
                                   .cast<float>();
        f[0]->setValue(k, static_cast<double>(col));
        f[1]->setValue(k, static_cast<double>(row));
        f[2]->setValue(k, z1);
        f[3]->setValue(k, z2);
        if (std::isnan(z1) || std::isnan(z2))
            continue;
        ++result.matchingCells;
        const double dz = z2 - z1;
        (dz > 0 ? result.added : result.removed) += std::abs(dz) * area;
        const double e1 = params.heightError ? *params.heightError : first.roughness[c];
        const double e2 = params.heightError ? *params.heightError : second.roughness[c];
        const double sigma = std::sqrt(e1 * e1 + e2 * e2);
        const double lod = params.lod ? *params.lod : params.propagated ? 1.96 * sigma : 0.0;
        f[4]->setValue(k, dz);
        f[5]->setValue(k, lod);
        const bool significant = std::abs(dz) > lod;
        f[6]->setValue(k, significant ? 1.0 : 0.0);
        if (!significant)
            continue;
        ++result.significantCells;
        if (dz > 0) {
            result.deposition += dz * area;
            depositionVariance += (area * sigma) * (area * sigma);
        } else {
            result.erosion -= dz * area;
            erosionVariance += (area * sigma) * (area * sigma);
        }
    }
    result.depositionError = std::sqrt(depositionVariance);
    result.erosionError = std::sqrt(erosionVariance);
    ticker.step();
    return result;
}

const ScalarField* mainGridField(const PointCloud& cloud)
{
    if (!cloud.field(fields::kRasterCol) || !cloud.field(fields::kRasterRow))
        return nullptr;
    for (const char* name : {fields::kDodDifference, fields::kM3c2Distance, fields::kCellHeight})
        if (const ScalarField* f = cloud.field(name))
            return f;
    for (const ScalarField& f : cloud.fields())
        if (!isGridBookkeeping(f.name()))
            return &f;
    return nullptr;
}

std::optional<double> gridCellSize(const PointCloud& cloud)
{
    const ScalarField* col = cloud.field(fields::kRasterCol);
    const ScalarField* row = cloud.field(fields::kRasterRow);
    if (!col || !row || cloud.empty())
        return std::nullopt;
    for (const auto& [index, axis] : {std::pair{col, 0}, std::pair{row, 1}}) {
        std::size_t lo = 0, hi = 0;
        for (std::size_t i = 1; i < cloud.size(); ++i) {
            if (index->value(i) < index->value(lo))
                lo = i;
            if (index->value(i) > index->value(hi))
                hi = i;
        }
        const double steps = index->value(hi) - index->value(lo);
        if (steps > 0) {
            const double cell = (cloud.globalPosition(hi)[axis] - cloud.globalPosition(lo)[axis]) / steps;
            if (std::isfinite(cell) && cell > 0)
                return cell;
            return std::nullopt;
        }
    }
    return std::nullopt;
}

PointCloud rasteriseCloud(const PointCloud& cloud, const RasteriseParams& params, ProgressObserver* progress)
{
    if (!std::isfinite(params.cell) || params.cell <= 0)
        throw Error(ErrorCode::InvalidArgument, "rasterise: the cell size must be positive (m)");
    std::vector<const ScalarField*> carried;
    if (params.fields.empty()) {
        for (const ScalarField& f : cloud.fields())
            if (!isGridBookkeeping(f.name()) && f.name() != fields::kCellHeight)
                carried.push_back(&f);
    } else {
        for (const std::string& name : params.fields) {
            if (isGridBookkeeping(name))
                throw Error(ErrorCode::InvalidArgument, "rasterise: '" + name + "' is a field of the grid itself; it cannot be carried");
            const ScalarField* f = cloud.field(name);
            if (!f)
                throw Error(ErrorCode::InvalidArgument, "rasterise: the cloud has no scalar field '" + name + "'");
            carried.push_back(f);
        }
    }
    double xmin = std::numeric_limits<double>::infinity(), ymin = xmin, xmax = -xmin, ymax = -xmin;
    addBounds(cloud, xmin, ymin, xmax, ymax);
    if (!(xmin <= xmax))
        throw Error(ErrorCode::InvalidData, "rasterise: no finite point");
    const Grid grid = alignedGrid(params.cell, xmin, ymin, xmax, ymax, "rasterise");

    ProgressTicker ticker(progress, "Rasterising " + cloud.name, 3 * cloud.size() + 1);
    // (cell, height, point) sorted: each cell's points in one run, by height.
    struct Keyed
    {
        std::uint32_t cell;
        double z;
        std::size_t point;
        bool operator<(const Keyed& o) const { return cell != o.cell ? cell < o.cell : z != o.z ? z < o.z : point < o.point; }
    };
    std::vector<Keyed> keyed;
    keyed.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d p = cloud.globalPosition(i);
        if (p.allFinite())
            keyed.push_back({cellOf(grid, p), p.z(), i});
    }
    ticker.step(cloud.size());
    tbb::parallel_sort(keyed.begin(), keyed.end());
    ticker.step(cloud.size());

    std::vector<std::pair<std::size_t, std::size_t>> runs; // [begin, end) of each occupied cell
    for (std::size_t begin = 0; begin < keyed.size();) {
        std::size_t end = begin;
        while (end < keyed.size() && keyed[end].cell == keyed[begin].cell)
            ++end;
        runs.emplace_back(begin, end);
        begin = end;
    }
    PointCloud out;
    out.name = cloud.name + "_raster";
    out.setCrsWkt(cloud.crsWkt());
    out.setOrigin(Eigen::Vector3d(std::round(grid.x0), std::round(grid.y0), std::floor(keyed.front().z)));
    out.resize(runs.size());
    out.addField(ScalarField(fields::kRasterCol, runs.size()));
    out.addField(ScalarField(fields::kRasterRow, runs.size()));
    out.addField(ScalarField(fields::kPointCount, runs.size()));
    // The height as a band too (a GeoTIFF holds fields only), unless a carried field has the name.
    const bool heightTaken =
        std::any_of(carried.begin(), carried.end(), [](const ScalarField* f) { return f->name() == fields::kCellHeight; });
    if (!heightTaken) {
        ScalarField heights(fields::kCellHeight, runs.size());
        heights.setOffset(std::floor(keyed.front().z));
        out.addField(std::move(heights));
    }
    for (const ScalarField* f : carried) {
        ScalarField means(f->name(), runs.size());
        means.setOffset(f->offset()); // large values (GPS times) keep their digits
        out.addField(std::move(means));
    }
    // Looked up after every addField: it may move the fields.
    ScalarField* col = out.field(fields::kRasterCol);
    ScalarField* row = out.field(fields::kRasterRow);
    ScalarField* count = out.field(fields::kPointCount);
    ScalarField* heightField = heightTaken ? nullptr : out.field(fields::kCellHeight);
    std::vector<ScalarField*> targets;
    for (const ScalarField* f : carried)
        targets.push_back(out.field(f->name()));
    for (std::size_t r = 0; r < runs.size(); ++r) {
        const auto [begin, end] = runs[r];
        const std::size_t n = end - begin;
        double sum = 0;
        for (std::size_t k = begin; k < end; ++k)
            sum += keyed[k].z;
        const double height =
            cellHeight(params.statistic, n, sum / static_cast<double>(n), [&, begin = begin](std::size_t k) { return keyed[begin + k].z; });
        const std::size_t cell = keyed[begin].cell;
        const std::size_t c = cell % grid.cols, rr = cell / grid.cols;
        out.positions()[r] = (Eigen::Vector3d(grid.x0 + (static_cast<double>(c) + 0.5) * grid.cell,
                                              grid.y0 + (static_cast<double>(rr) + 0.5) * grid.cell, height) -
                              out.origin())
                                 .cast<float>();
        col->setValue(r, static_cast<double>(c));
        row->setValue(r, static_cast<double>(rr));
        count->setValue(r, static_cast<double>(n));
        if (heightField)
            heightField->setValue(r, height);
        for (std::size_t f = 0; f < carried.size(); ++f) {
            double sum = 0;
            std::size_t valid = 0;
            for (std::size_t k = begin; k < end; ++k) {
                const double v = carried[f]->value(keyed[k].point);
                if (std::isfinite(v)) {
                    sum += v;
                    ++valid;
                }
            }
            targets[f]->setValue(r, valid ? sum / static_cast<double>(valid) : kNaN);
        }
        if (r % 4096 == 0)
            ticker.checkCancel();
    }
    ticker.step(cloud.size() + 1);
    return out;
}

} // namespace scandiff
