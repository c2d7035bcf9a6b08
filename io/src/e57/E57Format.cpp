// SPDX-License-Identifier: GPL-3.0-or-later
// E57 in the format registry: one cloud per scan for readEntities(), the
// scans merged (with a scan_index field) for readers that want one cloud.
#include <scandiff/io/E57.h>

#include "internal/Formats.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/processing/CloudEditing.h>

namespace scandiff::io::detail {

namespace fs = std::filesystem;

namespace {

std::string holdsNoScan(const fs::path& path)
{
    const E57Summary summary = inspectE57(path);
    return path.string() + ": the E57 file holds no 3D scan" +
           (summary.images.empty() ? std::string() : " (only " + std::to_string(summary.images.size()) + " images; list them with 'scandiff-cli info')");
}

Entity readMerged(const fs::path& path, const ReadOptions& options)
{
    std::vector<PointCloud> scans = readE57Scans(path, options);
    if (scans.empty())
        throw Error(ErrorCode::InvalidData, holdsNoScan(path));
    if (scans.size() == 1)
        return std::move(scans.front());
    std::vector<const PointCloud*> parts;
    for (const PointCloud& scan : scans)
        parts.push_back(&scan);
    PointCloud merged = mergeClouds(parts, options.progress);
    // The scan each point came from; a file that already has such a field keeps it, and the index keeps merge's name.
    if (ScalarField* index = merged.field(fields::kSourceIndex); index && !merged.field("scan_index"))
        index->rename("scan_index");
    merged.name = path.stem().string();
    return merged;
}

} // namespace

FormatHandler e57Format()
{
    FormatHandler handler;
    handler.name = "E57";
    handler.extensions = {"e57"};
    handler.read = readMerged;
    handler.readAll = [](const fs::path& path, const ReadOptions& options) {
        std::vector<PointCloud> scans = readE57Scans(path, options);
        if (scans.empty())
            throw Error(ErrorCode::InvalidData, holdsNoScan(path));
        std::vector<Entity> entities;
        for (PointCloud& scan : scans)
            entities.emplace_back(std::move(scan));
        return entities;
    };
    handler.writeCloud = [](const PointCloud& cloud, const fs::path& path, const WriteOptions& options) {
        writeE57({&cloud}, path, options);
    };
    handler.writeClouds = [](const std::vector<const PointCloud*>& clouds, const fs::path& path, const WriteOptions& options) {
        writeE57(clouds, path, options);
    };
    return handler;
}

} // namespace scandiff::io::detail
