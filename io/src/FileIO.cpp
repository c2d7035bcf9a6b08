// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/io/FileIO.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/CoordinateSystem.h>

#include <algorithm>
#include <cctype>

namespace scandiff::io {

namespace fs = std::filesystem;

std::string lowerExtension(const fs::path& path)
{
    std::string ext = path.extension().string();
    if (!ext.empty() && ext.front() == '.')
        ext.erase(0, 1);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

void FormatRegistry::add(FormatHandler handler)
{
    handlers_.push_back(std::move(handler));
}

const FormatHandler& FormatRegistry::forPath(const fs::path& path) const
{
    const std::string ext = lowerExtension(path);
    for (auto it = handlers_.rbegin(); it != handlers_.rend(); ++it)
        if (std::find(it->extensions.begin(), it->extensions.end(), ext) != it->extensions.end())
            return *it;
    std::string known;
    for (const auto& h : handlers_)
        for (const auto& e : h.extensions)
            known += (known.empty() ? "" : ", ") + e;
    throw Error(ErrorCode::Unsupported, path.string() + ": unknown file extension '" + ext + "' (supported: " + known + ")");
}

namespace {

const FormatHandler& readerFor(const FormatRegistry& registry, const fs::path& path)
{
    const FormatHandler& handler = registry.forPath(path);
    if (!handler.read)
        throw Error(ErrorCode::Unsupported, path.string() + ": " + handler.name + " files can be written but not read");
    std::error_code ec;
    if (!fs::exists(path, ec))
        throw Error(ErrorCode::Io, path.string() + ": no such file");
    return handler;
}

//! What every reader's result gets: the coordinate system given by the user, and a name.
void finishEntity(Entity& entity, const fs::path& path, const ReadOptions& options)
{
    if (!options.crsWkt.empty()) {
        PointCloud& points = std::holds_alternative<Mesh>(entity) ? std::get<Mesh>(entity).vertices : std::get<PointCloud>(entity);
        if (points.crsWkt().empty())
            points.setCrsWkt(options.crsWkt);
        else if (points.crsWkt() != options.crsWkt)
            logWarning(path.string() + ": the file declares its own coordinate reference system (" + crsName(points.crsWkt()) +
                       "), which is kept rather than the one given (" + crsName(options.crsWkt) + ")");
    }
    const std::string stem = path.stem().string();
    std::visit([&](auto& e) {
        if (e.name.empty())
            e.name = stem;
    }, entity);
}

} // namespace

Entity readFile(const FormatRegistry& registry, const fs::path& path, const ReadOptions& options)
{
    const FormatHandler& handler = readerFor(registry, path);
    Entity entity = handler.read(path, options);
    finishEntity(entity, path, options);
    return entity;
}

std::vector<Entity> readEntities(const FormatRegistry& registry, const fs::path& path, const ReadOptions& options)
{
    const FormatHandler& handler = readerFor(registry, path);
    std::vector<Entity> entities;
    if (handler.readAll)
        entities = handler.readAll(path, options);
    else
        entities.push_back(handler.read(path, options));
    for (Entity& entity : entities)
        finishEntity(entity, path, options);
    return entities;
}

bool canReadRecordRanges(const FormatRegistry& registry, const fs::path& path)
{
    const FormatHandler& handler = registry.forPath(path);
    return handler.countRecords && handler.readRecords;
}

std::vector<std::string> fieldsLeftOutWhenZero(const FormatRegistry& registry, const fs::path& path)
{
    const FormatHandler& handler = readerFor(registry, path);
    return handler.fieldsLeftOutWhenZero ? handler.fieldsLeftOutWhenZero(path) : std::vector<std::string>();
}

std::uint64_t pointRecordCount(const FormatRegistry& registry, const fs::path& path)
{
    const FormatHandler& handler = readerFor(registry, path);
    if (!handler.countRecords)
        throw Error(ErrorCode::Unsupported, path.string() + ": " + handler.name + " files cannot be read by ranges of records");
    return handler.countRecords(path);
}

PointCloud readPointRecords(const FormatRegistry& registry, const fs::path& path, RecordRange range, const ReadOptions& options)
{
    const FormatHandler& handler = readerFor(registry, path);
    if (!handler.readRecords)
        throw Error(ErrorCode::Unsupported, path.string() + ": " + handler.name + " files cannot be read by ranges of records");
    Entity entity = handler.readRecords(path, range, options);
    finishEntity(entity, path, options);
    return std::move(std::get<PointCloud>(entity));
}

std::unique_ptr<PointChunkWriter> openPointChunkWriter(const FormatRegistry& registry, const fs::path& path,
                                                       const PointCloud& layout, std::uint64_t total,
                                                       const WriteOptions& options)
{
    const FormatHandler& handler = registry.forPath(path);
    if (!handler.openChunkWriter)
        throw Error(ErrorCode::Unsupported, path.string() + ": " + handler.name + " files cannot be written chunk by chunk");
    return handler.openChunkWriter(path, layout, total, options);
}

std::optional<BoundingBox> pointRecordBounds(const FormatRegistry& registry, const fs::path& path, RecordRange range)
{
    const FormatHandler& handler = readerFor(registry, path);
    if (!handler.recordBounds)
        return std::nullopt;
    return handler.recordBounds(path, range);
}

std::optional<std::vector<Eigen::Vector3d>> pointRecordPositions(const FormatRegistry& registry, const fs::path& path,
                                                                 RecordRange range)
{
    const FormatHandler& handler = readerFor(registry, path);
    if (!handler.recordPositions)
        return std::nullopt;
    return handler.recordPositions(path, range);
}

std::unique_ptr<PlacedChunkWriter> openPlacedChunkWriter(const FormatRegistry& registry, const fs::path& path,
                                                         const fs::path& join, const PointCloud& layout,
                                                         std::uint64_t total, const WriteOptions& options)
{
    const FormatHandler& handler = registry.forPath(path);
    if (!handler.openPlacedWriter)
        throw Error(ErrorCode::Unsupported, path.string() + ": " + handler.name +
                                                " files cannot be written by several processes at once");
    return handler.openPlacedWriter(path, join, layout, total, options);
}

PointCloud readPointCloud(const FormatRegistry& registry, const fs::path& path, const ReadOptions& options)
{
    Entity entity = readFile(registry, path, options);
    if (auto* mesh = std::get_if<Mesh>(&entity)) {
        PointCloud vertices = std::move(mesh->vertices);
        vertices.name = mesh->name;
        return vertices;
    }
    return std::move(std::get<PointCloud>(entity));
}

Mesh readMesh(const FormatRegistry& registry, const fs::path& path, const ReadOptions& options)
{
    Entity entity = readFile(registry, path, options);
    if (auto* mesh = std::get_if<Mesh>(&entity))
        return std::move(*mesh);
    throw Error(ErrorCode::InvalidData, path.string() + ": holds points but no triangles; a mesh was expected");
}

void writePointCloud(const FormatRegistry& registry, const PointCloud& cloud, const fs::path& path, const WriteOptions& options)
{
    const FormatHandler& handler = registry.forPath(path);
    if (!handler.writeCloud && !handler.writeMesh && handler.read)
        throw Error(ErrorCode::Unsupported, path.string() + ": " + handler.name + " files can be read but not written by this build");
    if (!handler.writeCloud)
        throw Error(ErrorCode::Unsupported, path.string() + ": " + handler.name + " cannot store point clouds");
    cloud.checkConsistency();
    handler.writeCloud(cloud, path, options);
}

void writePointClouds(const FormatRegistry& registry, const std::vector<const PointCloud*>& clouds, const fs::path& path,
                      const WriteOptions& options)
{
    if (clouds.size() == 1) {
        writePointCloud(registry, *clouds.front(), path, options);
        return;
    }
    const FormatHandler& handler = registry.forPath(path);
    if (!handler.writeClouds)
        throw Error(ErrorCode::Unsupported, path.string() + ": " + handler.name + " holds one cloud, not " + std::to_string(clouds.size()) +
                                                " (E57 holds several; or merge them first)");
    for (const PointCloud* cloud : clouds)
        cloud->checkConsistency();
    handler.writeClouds(clouds, path, options);
}

void writeMesh(const FormatRegistry& registry, const Mesh& mesh, const fs::path& path, const WriteOptions& options)
{
    const FormatHandler& handler = registry.forPath(path);
    if (!handler.writeMesh)
        throw Error(ErrorCode::Unsupported, path.string() + ": " + handler.name + " cannot store meshes");
    mesh.checkConsistency();
    handler.writeMesh(mesh, path, options);
}

void writeFile(const FormatRegistry& registry, const Entity& entity, const fs::path& path, const WriteOptions& options)
{
    if (const auto* mesh = std::get_if<Mesh>(&entity))
        writeMesh(registry, *mesh, path, options);
    else
        writePointCloud(registry, std::get<PointCloud>(entity), path, options);
}

} // namespace scandiff::io
