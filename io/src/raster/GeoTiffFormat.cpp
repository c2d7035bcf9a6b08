// SPDX-License-Identifier: GPL-3.0-or-later
//! GeoTIFF export of a gridded cloud (a DEM of difference, a rasterised
//! result): a cloud whose points are cell centres with the integer fields
//! raster_col and raster_row. Every other scalar field becomes a band, named
//! after it; cells without a point or a value are nodata (NaN). Written
//! through GDAL's GTiff driver, to a temporary file renamed at the end.
//!
//! The grid is rebuilt from the points: the cell size from two points of
//! different columns (or rows), the origin from any point. North up: the
//! first row of the image is the northernmost. The cloud's coordinate
//! reference system, when it has one, is the GeoTIFF's.

#include "internal/Formats.h"
#include "raster/GdalDataset.h"
#include "raster/GriddedCloud.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/distance/DemOfDifference.h>
#include <scandiff/io/AtomicFile.h>


#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace scandiff::io::detail {

namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what)
{
    throw Error(ErrorCode::InvalidArgument, path.string() + ": " + what);
}

void writeGeoTiff(const PointCloud& cloud, const std::filesystem::path& path, const WriteOptions& options)
{
    const ScalarField* col = cloud.field(fields::kRasterCol);
    const ScalarField* row = cloud.field(fields::kRasterRow);
    if (!col || !row)
        fail(path, "only a gridded cloud (fields raster_col and raster_row: a DEM of difference) can be written as GeoTIFF");
    if (cloud.empty())
        fail(path, "the grid has no cell");
    const GridOfCloud g = gridOf(cloud, *col, *row, path);
    std::vector<const ScalarField*> bands;
    for (const ScalarField& f : cloud.fields())
        if (&f != col && &f != row)
            bands.push_back(&f);
    if (bands.empty())
        fail(path, "the grid has no field to write as a band");

    GDALDriverH driver = gdalDriver("GTiff", path);
    AtomicFile file(path);
    const std::string temp = file.tempPath().string();
    char compress[] = "COMPRESS=DEFLATE";
    char* creation[] = {compress, nullptr};
    GdalDataset owned(gdal().GDALCreate(driver, temp.c_str(), static_cast<int>(g.cols), static_cast<int>(g.rows), static_cast<int>(bands.size()),
                                 GDT_Float64, creation));
    GDALDatasetH dataset = owned.get();
    if (!dataset)
        throw Error(ErrorCode::Io, path.string() + ": GDAL cannot create the file: " + gdal().CPLGetLastErrorMsg());
    // North up: row 0 of the image is the top (the largest y).
    double transform[6] = {g.x0, g.cell, 0.0, g.y0 + static_cast<double>(g.rows) * g.cell, 0.0, -g.cell};
    gdal().GDALSetGeoTransform(dataset, transform);
    if (!cloud.crsWkt().empty() && gdal().GDALSetProjection(dataset, cloud.crsWkt().c_str()) != CE_None)
        logWarning(path.string() + ": GDAL did not take the cloud's coordinate reference system; the GeoTIFF has none");
    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), bands.size());
    std::vector<double> image(g.cols * g.rows);
    CPLErr status = CE_None;
    for (std::size_t b = 0; b < bands.size() && status == CE_None; ++b) {
        std::fill(image.begin(), image.end(), std::numeric_limits<double>::quiet_NaN());
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            const auto c = static_cast<std::size_t>(col->value(i));
            const auto r = static_cast<std::size_t>(row->value(i));
            image[(g.rows - 1 - r) * g.cols + c] = bands[b]->value(i);
        }
        GDALRasterBandH band = gdal().GDALGetRasterBand(dataset, static_cast<int>(b) + 1);
        gdal().GDALSetRasterNoDataValue(band, std::numeric_limits<double>::quiet_NaN());
        gdal().GDALSetDescription(band, bands[b]->name().c_str());
        status = gdal().GDALRasterIO(band, GF_Write, 0, 0, static_cast<int>(g.cols), static_cast<int>(g.rows), image.data(),
                              static_cast<int>(g.cols), static_cast<int>(g.rows), GDT_Float64, 0, 0);
        ticker.step();
    }
    owned.close();
    if (status != CE_None)
        throw Error(ErrorCode::Io, path.string() + ": GDAL failed to write: " + gdal().CPLGetLastErrorMsg());
    file.commit();
}

} // namespace

GridOfCloud gridOf(const PointCloud& cloud, const ScalarField& col, const ScalarField& row, const std::filesystem::path& path)
{
    GridOfCloud g;
    double maxCol = 0, maxRow = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!col.hasValue(i) || !row.hasValue(i) || col.value(i) < 0 || row.value(i) < 0 || col.value(i) != std::floor(col.value(i)) ||
            row.value(i) != std::floor(row.value(i)))
            fail(path, "point " + std::to_string(i) + " has no whole raster_col / raster_row");
        maxCol = std::max(maxCol, col.value(i));
        maxRow = std::max(maxRow, row.value(i));
    }
    g.cols = static_cast<std::size_t>(maxCol) + 1;
    g.rows = static_cast<std::size_t>(maxRow) + 1;
    if (static_cast<double>(g.cols) * static_cast<double>(g.rows) > 268435456.0)
        fail(path, "the grid has more than 2^28 cells");
    // The cell size from the two points farthest apart in column (or row).
    g.cell = gridCellSize(cloud).value_or(0.0);
    if (!(g.cell > 0))
        fail(path, "a raster needs at least two cells in a row or a column to know the cell size");
    const Eigen::Vector3d p = cloud.globalPosition(0);
    g.x0 = p.x() - (col.value(0) + 0.5) * g.cell;
    g.y0 = p.y() - (row.value(0) + 0.5) * g.cell;
    return g;
}

FormatHandler geoTiffFormat()
{
    FormatHandler h;
    h.name = "GeoTIFF (gridded clouds: DEM of difference, rasters)";
    h.extensions = {"tif", "tiff"};
    h.writeCloud = writeGeoTiff;
    return h;
}

} // namespace scandiff::io::detail
