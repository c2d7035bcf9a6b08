// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! DEM of difference and 2.5D volumes: each epoch rasterised on one grid of
//! square cells in the horizontal plane, the heights subtracted cell by cell.
//!
//! - A cell's height is the minimum, mean, maximum or median of the heights of
//!   the epoch's points in it (nodata when it holds none, or filled from its
//!   neighbours on request); its roughness δz is their population standard
//!   deviation, or a given height error.
//! - dz = z(compared) − z(reference) where both cells have a height. Its
//!   level of detection is a given minimum (`lod`), or the propagated error
//!   1.96 √(δz₁² + δz₂²) (`propagated`); a cell is significant when |dz|
//!   exceeds it.
//! - Volumes count the significant cells: deposition Σ dz·a where dz > 0,
//!   erosion Σ |dz|·a where dz < 0 (a = cell area), each ± √Σ (a·σ_dz)², the
//!   errors of the cells taken as independent (σ_dz = √(δz₁² + δz₂²)).
//! - The 2.5D volume report of CloudCompare ("Compute 2.5D volume"): added and
//!   removed volume over every cell with both heights, no threshold, their
//!   surface and the share of cells where both epochs have a height.
//!
//! The result is a cloud of cell centres (the grid as points: fields
//! raster_col, raster_row, so a GeoTIFF writer can rebuild the grid) and the
//! report. Coordinates are global; the grid's origin is a whole number of cells
//! from the point (0, 0) so that two runs with one cell size share their cells.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/Table.h>

#include <optional>
#include <string>
#include <vector>

namespace scandiff {

enum class CellStatistic { Min, Mean, Max, Median };

//! "min", "mean", "max", "median"; throws Error(InvalidArgument) otherwise.
CellStatistic parseCellStatistic(const std::string& name);

namespace fields {
inline constexpr const char* kRasterCol = "raster_col";
inline constexpr const char* kRasterRow = "raster_row";
inline constexpr const char* kZReference = "z_reference";
inline constexpr const char* kZCompared = "z_compared";
inline constexpr const char* kDodDifference = "dod_difference";
inline constexpr const char* kDodLod = "dod_lod";
inline constexpr const char* kDodSignificant = "dod_significant";
inline constexpr const char* kPointCount = "point_count";
inline constexpr const char* kCellHeight = "height";
} // namespace fields

struct DemOfDifferenceParams
{
    double cell = 1.0; //!< m, > 0
    CellStatistic statistic = CellStatistic::Mean;
    //! Passes of filling empty cells from their filled neighbours (mean of
    //! the up to 8 around); 0 leaves them nodata.
    int fillPasses = 0;
    //! Threshold: this minimum level of detection (m, >= 0) ...
    std::optional<double> lod;
    //! ... or the propagated error 1.96 √(δz₁² + δz₂²) of each cell.
    bool propagated = false;
    //! δz of every cell (m, >= 0) instead of its roughness.
    std::optional<double> heightError;
    //! Without a reference cloud: the reference is this constant height (m).
    std::optional<double> referenceHeight;
};

struct DemOfDifferenceResult
{
    //! One point per cell holding a height in either epoch, at the cell's
    //! centre and the compared (else reference) height, with the fields above.
    PointCloud cells;
    double cellArea = 0.0;
    std::size_t columns = 0, rows = 0;
    std::size_t matchingCells = 0;    //!< both epochs have a height
    std::size_t significantCells = 0;
    double deposition = 0.0, depositionError = 0.0; //!< m³, significant cells
    double erosion = 0.0, erosionError = 0.0;       //!< m³, as a positive number
    double added = 0.0, removed = 0.0;              //!< m³, every matching cell (2.5D volume)
    //! The report: one row per quantity (name, value, unit).
    Table report() const;
};

//! `reference` may be null with params.referenceHeight. Throws
//! Error(InvalidArgument) for a bad cell size, a grid over 2^28 cells, both
//! or neither threshold kinds given twice; Error(InvalidData) for an empty
//! cloud; Error(Cancelled).
DemOfDifferenceResult demOfDifference(const PointCloud* reference, const PointCloud& compared,
                                      const DemOfDifferenceParams& params, ProgressObserver* progress = nullptr);

//! The cell size of a gridded cloud (the points of demOfDifference() or
//! rasteriseCloud(): whole raster_col and raster_row fields) from its two
//! points farthest apart in column, else in row; empty for a cloud without
//! those fields, or with a single cell.
std::optional<double> gridCellSize(const PointCloud& cloud);

//! The field a gridded cloud is best shown by: the first present of
//! dod_difference, m3c2_distance and height, else the first field that is not
//! raster_col, raster_row or point_count; null for a cloud that is not a grid
//! or has no such field.
const ScalarField* mainGridField(const PointCloud& cloud);

struct RasteriseParams
{
    double cell = 1.0; //!< m, > 0
    CellStatistic statistic = CellStatistic::Mean; //!< of the heights in a cell
    //! The scalar fields to carry (each cell: the mean of the finite values of
    //! its points, so a 0/1 flag gives the share of 1s); empty: every field.
    std::vector<std::string> fields;
};

//! One cloud on a grid of square cells (the grid of demOfDifference() for the
//! same cell size): one point per cell holding a point, at the cell's centre
//! and the statistic of its heights, with raster_col, raster_row, point_count,
//! height (that statistic again, as a field) and the fields. A GeoTIFF of it
//! has one band per field. Throws
//! Error(InvalidArgument) for a bad cell, an unknown field or a grid over
//! 2^28 cells; Error(InvalidData) without a finite point; Error(Cancelled).
PointCloud rasteriseCloud(const PointCloud& cloud, const RasteriseParams& params, ProgressObserver* progress = nullptr);

} // namespace scandiff
