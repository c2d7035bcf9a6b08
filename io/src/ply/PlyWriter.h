// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Writing PLY: float x y z when the origin is zero and double global
//! coordinates otherwise, uchar colours, float normals, one property per
//! scalar field (double when it has an offset or is kept in double); whole,
//! chunk by chunk, or by several processes at fixed places.

#include <scandiff/io/FileIO.h>

#include <filesystem>
#include <memory>

namespace scandiff::io::detail::ply {

void writeCloud(const PointCloud& cloud, const std::filesystem::path& path, const WriteOptions& options);
void writeMesh(const Mesh& mesh, const std::filesystem::path& path, const WriteOptions& options);
std::unique_ptr<PointChunkWriter> openChunkWriter(const std::filesystem::path& path, const PointCloud& layout, std::uint64_t total,
                                                  const WriteOptions& options);
std::unique_ptr<PlacedChunkWriter> openPlacedWriter(const std::filesystem::path& destination, const std::filesystem::path& join,
                                                    const PointCloud& layout, std::uint64_t total, const WriteOptions& options);

} // namespace scandiff::io::detail::ply
