// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Reading and writing clouds and meshes, by file extension.
//!
//! A FormatRegistry maps extensions to format handlers. The built-in formats
//! (PLY, ASCII XYZ/TXT/CSV/PTS/ASC, LAS/LAZ, E57, OBJ/STL/OFF read and written here, DXF export) are
//! registered by registerBuiltinFormats(); plugins add more (PCD comes from the
//! PCL plugin). Every writer goes through AtomicFile: an existing output file is
//! never left half-written.

#include <scandiff/core/Entity.h>
#include <scandiff/core/Mesh.h>
#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace scandiff::io {

//! Column mapping of an ASCII point file. Names are case-insensitive:
//! x y z, r g b (0-255) or rf gf bf (0-1), nx ny nz, skip (ignored column), and
//! anything else becomes a scalar field of that name.
struct AsciiColumns
{
    std::vector<std::string> names;
};

struct ReadOptions
{
    ProgressObserver* progress = nullptr;
    //! Force this origin (global shift) instead of choosing one (suggestOrigin()).
    std::optional<Eigen::Vector3d> origin;
    //! ASCII only: overrides the detected column mapping.
    std::optional<AsciiColumns> asciiColumns;
    //! ASCII only: overrides the detected separator (' ', ',', ';' or '\t').
    std::optional<char> asciiSeparator;
    //! ASCII only: number of leading lines to skip (overrides header detection).
    std::optional<std::size_t> asciiSkipLines;
    //! The coordinate reference system (OGC WKT) of files that give none (PLY
    //! without scandiff's comment, text, PCD...). A file's own system wins,
    //! with a warning when it differs.
    std::string crsWkt;
    //! Positions and normals only: formats that can skip colours and scalar
    //! fields (PLY) do not decode them; others read everything.
    bool geometryOnly = false;
};

//! Records [first, first + count) of a file's points, in file order (the
//! count is cut at the file's end). Reading a file range by range holds one
//! range in memory at a time (scandiff-mpi streams its inputs so).
struct RecordRange
{
    std::uint64_t first = 0;
    std::uint64_t count = 0;
};

enum class Encoding
{
    Default,            //!< the format's usual choice (binary when it exists)
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
    BinaryCompressed    //!< PCD binary_compressed
};

struct WriteOptions
{
    ProgressObserver* progress = nullptr;
    Encoding encoding = Encoding::Default;
    //! Significant digits after the decimal point for ASCII coordinates (mm at 3).
    int asciiPrecision = 6;
};

using Entity = scandiff::Entity;

//! A cloud written chunk by chunk, for clouds larger than memory: the file is
//! laid out for the total announced when it was opened and renamed into place
//! by commit() once every point has come (until then the destination is untouched).
class PointChunkWriter
{
public:
    virtual ~PointChunkWriter() = default;
    //! The next points, with the colours, normals, fields and origin of the
    //! cloud the writer was opened with. Throws Error(InvalidArgument) otherwise.
    virtual void append(const PointCloud& chunk) = 0;
    //! Throws Error(InvalidArgument) unless exactly the announced points came.
    virtual void commit() = 0;
};

//! A cloud file several processes fill at once, each writing its own chunks
//! at their place (formats whose records have a fixed size: binary PLY). One
//! process creates it, the others join it by its temporary path; once every
//! writer is closed, the creator commits it (renamed into place; until then
//! the destination is untouched).
class PlacedChunkWriter
{
public:
    virtual ~PlacedChunkWriter() = default;
    //! Points [first, first + chunk.size()) of the file, with the attributes
    //! of the layout the writer was opened with. Throws Error(InvalidArgument) otherwise.
    virtual void write(std::uint64_t first, const PointCloud& chunk) = 0;
    //! Flushes this process's writes. Throws Error(Io) on a write error.
    virtual void close() = 0;
    //! The file being filled, for the others to join.
    virtual const std::filesystem::path& temporaryPath() const = 0;
    //! The creator's, once every writer is closed: `pointsWritten` is what
    //! all of them wrote, added up by the caller (a file system shared by
    //! several machines may show the file's size late). Throws
    //! Error(InvalidArgument) unless it is the total announced, Error(Io).
    virtual void commit(std::uint64_t pointsWritten) = 0;
};

struct FormatHandler
{
    std::string name;                    //!< "PLY", "LAS"...
    std::vector<std::string> extensions; //!< lower case, without dot
    //! Reads a file as a cloud or a mesh. Null if the format cannot be read.
    std::function<Entity(const std::filesystem::path&, const ReadOptions&)> read;
    std::function<void(const PointCloud&, const std::filesystem::path&, const WriteOptions&)> writeCloud;
    std::function<void(const Mesh&, const std::filesystem::path&, const WriteOptions&)> writeMesh;
    //! Formats that hold several clouds (the scans of an E57 file): every one,
    //! in file order. Null for formats of one entity.
    std::function<std::vector<Entity>(const std::filesystem::path&, const ReadOptions&)> readAll;
    //! Writes several clouds as the parts of one file (E57 scans). Null when the format holds one.
    std::function<void(const std::vector<const PointCloud*>&, const std::filesystem::path&, const WriteOptions&)> writeClouds;
    //! The number of point records the file's header announces. Null when the
    //! format cannot tell without reading (text) or cannot read ranges.
    std::function<std::uint64_t(const std::filesystem::path&)> countRecords;
    //! A range of the file's point records (see RecordRange), with the origin
    //! the whole file gets unless ReadOptions::origin is set. May throw
    //! Error(Unsupported) for a variant of the format that cannot seek (PLY text).
    std::function<PointCloud(const std::filesystem::path&, RecordRange, const ReadOptions&)> readRecords;
    //! A writer for `total` points laid out like `layout` (its attributes).
    std::function<std::unique_ptr<PointChunkWriter>(const std::filesystem::path&, const PointCloud& layout,
                                                    std::uint64_t total, const WriteOptions&)>
        openChunkWriter;
    //! The coordinates' box of a range of records, where the origin a whole
    //! read chooses is suggestOrigin() of every point's box; std::nullopt
    //! where the header alone fixes the origin. Null when the header always
    //! fixes it. `min` and `max` hold each axis's range of finite values
    //! (+inf and -inf on an axis with none) even when `empty` (an axis has
    //! none): the box of a file read by parts is then the parts' joined axis
    //! by axis, empty when an axis has no value in any part.
    std::function<std::optional<BoundingBox>(const std::filesystem::path&, RecordRange)> recordBounds;
    //! The global coordinates of a range of records, in double, exactly as
    //! the file holds them, where recordBounds gives a box: a caller that
    //! chooses the origin from every part's box reads each record once
    //! instead of a box pass, then a read. std::nullopt where recordBounds
    //! gives none. Null where the format has no such reader.
    std::function<std::optional<std::vector<Eigen::Vector3d>>(const std::filesystem::path&, RecordRange)> recordPositions;
    //! The fields a whole read leaves out when every value in the file is 0
    //! (LAS's standard attributes, which most files leave at 0); a range of
    //! records keeps them all, so that every range has the same fields. Null
    //! where a whole read keeps every field.
    std::function<std::vector<std::string>(const std::filesystem::path&)> fieldsLeftOutWhenZero;
    //! A placed writer (see PlacedChunkWriter) for `total` points laid out like
    //! `layout`: created when `join` is empty, else joining the file at `join`.
    //! May throw Error(Unsupported) for an encoding whose records vary in size.
    std::function<std::unique_ptr<PlacedChunkWriter>(const std::filesystem::path& destination,
                                                     const std::filesystem::path& join, const PointCloud& layout,
                                                     std::uint64_t total, const WriteOptions&)>
        openPlacedWriter;
};

class FormatRegistry
{
public:
    //! Adds a handler; a later handler for the same extension takes precedence.
    void add(FormatHandler handler);
    //! Throws Error(Unsupported) naming the extension when nothing handles it.
    const FormatHandler& forPath(const std::filesystem::path& path) const;
    const std::vector<FormatHandler>& handlers() const { return handlers_; }

private:
    std::vector<FormatHandler> handlers_;
};

//! Registers PLY, ASCII, LAS/LAZ, E57, PCD, OBJ/STL/OFF, DXF and GeoTIFF (gridded clouds).
void registerBuiltinFormats(FormatRegistry& registry);

//! Reads any supported file. Throws Error naming the file on failure.
Entity readFile(const FormatRegistry& registry, const std::filesystem::path& path, const ReadOptions& options = {});
//! Every entity of a file: one per scan of a multi-scan format (E57), else
//! the one readFile() gives. Each is named after its part ("scan 2") or the file.
std::vector<Entity> readEntities(const FormatRegistry& registry, const std::filesystem::path& path, const ReadOptions& options = {});
//! Reads a point cloud; a mesh file yields its vertices.
PointCloud readPointCloud(const FormatRegistry& registry, const std::filesystem::path& path, const ReadOptions& options = {});
//! Reads a mesh; throws Error(InvalidData) if the file holds no triangles.
Mesh readMesh(const FormatRegistry& registry, const std::filesystem::path& path, const ReadOptions& options = {});
void writePointCloud(const FormatRegistry& registry, const PointCloud& cloud, const std::filesystem::path& path, const WriteOptions& options = {});
//! Writes several clouds into one file when the format holds several
//! (E57), else throws Error(Unsupported) for more than one.
void writePointClouds(const FormatRegistry& registry, const std::vector<const PointCloud*>& clouds, const std::filesystem::path& path,
                      const WriteOptions& options = {});
void writeMesh(const FormatRegistry& registry, const Mesh& mesh, const std::filesystem::path& path, const WriteOptions& options = {});
void writeFile(const FormatRegistry& registry, const Entity& entity, const std::filesystem::path& path, const WriteOptions& options = {});

//! Reading and writing by ranges of records (see RecordRange): whether the
//! file's format can, the number of records, one range, a chunk writer.
//! Each throws Error(Unsupported) naming the file where the format cannot.
bool canReadRecordRanges(const FormatRegistry& registry, const std::filesystem::path& path);
std::uint64_t pointRecordCount(const FormatRegistry& registry, const std::filesystem::path& path);
PointCloud readPointRecords(const FormatRegistry& registry, const std::filesystem::path& path, RecordRange range,
                            const ReadOptions& options = {});
std::unique_ptr<PointChunkWriter> openPointChunkWriter(const FormatRegistry& registry, const std::filesystem::path& path,
                                                       const PointCloud& layout, std::uint64_t total,
                                                       const WriteOptions& options = {});
//! See FormatHandler::recordBounds (std::nullopt when the format has none).
std::optional<BoundingBox> pointRecordBounds(const FormatRegistry& registry, const std::filesystem::path& path,
                                             RecordRange range);
//! See FormatHandler::recordPositions (std::nullopt when the format has none).
std::optional<std::vector<Eigen::Vector3d>> pointRecordPositions(const FormatRegistry& registry,
                                                                 const std::filesystem::path& path, RecordRange range);
//! See FormatHandler::fieldsLeftOutWhenZero (empty when the format has none).
std::vector<std::string> fieldsLeftOutWhenZero(const FormatRegistry& registry, const std::filesystem::path& path);
//! See PlacedChunkWriter: creates the file when `join` is empty, else joins it.
//! Throws Error(Unsupported) where the format or the encoding cannot.
std::unique_ptr<PlacedChunkWriter> openPlacedChunkWriter(const FormatRegistry& registry, const std::filesystem::path& path,
                                                         const std::filesystem::path& join, const PointCloud& layout,
                                                         std::uint64_t total, const WriteOptions& options = {});

//! Lower-case extension without the dot ("PLY" -> "ply").
std::string lowerExtension(const std::filesystem::path& path);

} // namespace scandiff::io
