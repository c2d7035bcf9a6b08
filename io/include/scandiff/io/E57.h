// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! E57 (ASTM E2807), the exchange format of terrestrial scanners, read and
//! written from the standard (Debian has no libE57Format). A file holds
//! several scans (`data3D`), each with its pose, and images (`images2D`).
//!
//! Reading: every scan becomes one cloud in world coordinates (the pose
//! applied in double), its pose kept as the cloud's sensor pose, with
//! intensity, colour (scaled to 0-255 by its limits), normals (the
//! `nor:` extension), return index/count, row/column index and time stamp as
//! fields; points whose coordinates are flagged invalid are skipped, invalid
//! intensities and times are NaN. Through the format registry a multi-scan
//! file reads as one cloud with a `scan_index` field (readFile) or as one
//! cloud per scan (readEntities).
//!
//! Writing: one scan per cloud, coordinates as doubles, intensity and every
//! other field as floats or doubles (doubles for fields kept exactly),
//! colour as 8-bit integers, normals in the `nor:` extension; a cloud with a
//! sensor pose is written in its scanner's frame with that pose.

#include <scandiff/core/PointCloud.h>
#include <scandiff/io/FileIO.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace scandiff::io {

struct E57Pose
{
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity(); //!< scan frame -> file frame
    Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

struct E57ScanSummary
{
    std::string name, guid, description;
    std::uint64_t recordCount = 0;
    std::optional<E57Pose> pose;
    bool spherical = false;            //!< coordinates stored as range/azimuth/elevation
    std::vector<std::string> fields;   //!< the record's fields, as named in the file
    std::optional<std::pair<double, double>> intensityLimits;
};

struct E57ImageSummary
{
    std::string name, guid;
    std::string representation;  //!< "pinhole", "spherical", "cylindrical" or "visualReference"
    std::string format;          //!< "jpeg" or "png"
    std::int64_t width = 0, height = 0;
    std::uint64_t byteLength = 0;
    std::optional<E57Pose> pose;
};

struct E57Summary
{
    std::string guid, libraryVersion, coordinateMetadata;
    std::vector<E57ScanSummary> scans;
    std::vector<E57ImageSummary> images;
};

//! What the file holds, from its XML section (no point is decoded).
E57Summary inspectE57(const std::filesystem::path& path);
//! Every scan as one cloud, all with the same origin (options.origin, or one chosen for all scans together).
std::vector<PointCloud> readE57Scans(const std::filesystem::path& path, const ReadOptions& options = {});
//! Writes each image of the file into `folder` (name.jpg or name.png); returns the files written.
std::vector<std::filesystem::path> extractE57Images(const std::filesystem::path& path, const std::filesystem::path& folder);
//! Writes the clouds as the scans of one E57 file (through a temporary file renamed at the end).
void writeE57(const std::vector<const PointCloud*>& clouds, const std::filesystem::path& path, const WriteOptions& options = {});

} // namespace scandiff::io
