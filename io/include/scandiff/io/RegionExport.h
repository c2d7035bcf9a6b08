// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Export of segmented change regions: point clouds (PLY or any format the
//! registry writes), a DXF drawing for CAD, and a CSV report.
//!
//! Every file is written atomically (AtomicFile / writePointCloud): a failure
//! or a cancellation never leaves a half-written file.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/segmentation/RegionReport.h>
#include <scandiff/io/FileIO.h>

#include <filesystem>
#include <string>
#include <vector>

namespace scandiff::io {

struct RegionDxfOptions
{
    //! Also draw each region's points (POINT entities) on its layer.
    bool includePoints = false;
    //! Height of the labels (m), > 0; 0 = automatic: 3 % of the region's box
    //! diagonal, at least 5 cm.
    double textHeight = 0.0;
};

//! The layer of a region in the DXF: "REGION_0001".
std::string regionLayerName(int id);

//! One line of text for a region's label: id, points, distances, area, volume.
std::string regionLabel(const RegionStatistics& region);

//! A DXF with one layer per region, holding its outline(s) as closed 3D
//! polylines and its label as a text at the top of its box; with includePoints,
//! its points too (read from `cloud`'s `regionField`). Throws Error(Io),
//! Error(InvalidArgument) for a region without an outline.
void writeRegionsDxf(const PointCloud& cloud, const std::vector<RegionStatistics>& regions, const std::filesystem::path& path,
                     const RegionDxfOptions& options = {}, const std::string& regionField = "region_id");

//! The per-region report as CSV (comma-separated, one header line, '.' as the
//! decimal mark, empty cells for missing values; coordinates global).
//! Throws Error(Io).
void writeRegionsCsv(const std::vector<RegionStatistics>& regions, const std::filesystem::path& path);

struct RegionExportOptions
{
    RegionDxfOptions dxf;
    WriteOptions write;
    std::string regionField = "region_id";
    //! Extension of the point-cloud files (without dot); the registry must write it.
    std::string cloudExtension = "ply";
};

struct RegionExportFiles
{
    std::filesystem::path allRegions;                //!< DIR/regions.ply
    std::vector<std::filesystem::path> regionClouds; //!< DIR/region_0001.ply, ... in report order
    std::filesystem::path dxf;                       //!< DIR/regions.dxf
    std::filesystem::path csv;                       //!< DIR/regions.csv
};

//! Writes into `dir` (created if missing): regions.ply (every point that has a
//! region, all its fields), region_NNNN.ply per region, regions.dxf and
//! regions.csv. Throws Error(InvalidArgument) if the cloud lacks the region
//! field, Error(Io), Error(Unsupported) for an extension nobody writes.
RegionExportFiles exportRegions(const FormatRegistry& registry, const PointCloud& cloud,
                                const std::vector<RegionStatistics>& regions, const std::filesystem::path& dir,
                                const RegionExportOptions& options = {});

} // namespace scandiff::io
