// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The grid of a gridded cloud (DEM of difference, rasterised cloud): points
//! at cell centres with whole raster_col and raster_row fields. Shared by the
//! GeoTIFF writer and the PNG preview.

#include <scandiff/core/PointCloud.h>

#include <filesystem>

namespace scandiff::io::detail {

struct GridOfCloud
{
    double x0 = 0, y0 = 0, cell = 0; //!< lower-left corner of cell (0, 0), cell size
    std::size_t cols = 0, rows = 0;
};

//! Rebuilds the grid from the points: the cell size from the two points
//! farthest apart in column (else row), the corner from the first point.
//! Throws Error(InvalidArgument) naming `path` for a point without whole
//! indices, a single row and column, or more than 2^28 cells.
GridOfCloud gridOf(const PointCloud& cloud, const ScalarField& col, const ScalarField& row, const std::filesystem::path& path);

} // namespace scandiff::io::detail
