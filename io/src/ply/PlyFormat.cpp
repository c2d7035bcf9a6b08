// SPDX-License-Identifier: GPL-3.0-or-later
//! PLY (Stanford polygon format): ascii, binary_little_endian and binary_big_endian.
//!
//! Reading maps the vertex element's properties to the cloud: x y z (any numeric
//! type), red green blue (or diffuse_*; integers 0-255, 16-bit integers scaled,
//! floats 0-1 scaled), nx ny nz (or normal_*), alpha ignored, list properties
//! skipped, and every other scalar property becomes a scalar field (a leading
//! "scalar_", as CloudCompare writes it, is removed). A "face" element with a
//! vertex_indices (or vertex_index) list gives triangles, polygons being fan
//! triangulated; the file is then a Mesh. Every other element is skipped.
//!
//! Writing (PlyWriter.cpp) uses float x y z when the origin is zero and double global
//! coordinates otherwise, uchar colours, float normals, and one float property
//! per scalar field (double when the field has an offset, so GPS times survive).

#include "internal/Formats.h"
#include "ply/PlyAscii.h"
#include "ply/PlyBinary.h"
#include "ply/PlyCommon.h"
#include "ply/PlyHeader.h"
#include "ply/PlyLayout.h"
#include "ply/PlyWriter.h"
#include "internal/FieldOffset.h"
#include "internal/MappedFile.h"
#include "internal/TextUtil.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/AtomicFile.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace scandiff::io::detail {

namespace {

using namespace ply;

namespace fs = std::filesystem;

// The reader's steps, in order: ply/PlyHeader (the header), ply/PlyLayout
// (where each property goes), ply/PlyBinary and ply/PlyAscii (the passes
// over the data); this file drives them for whole files and record ranges.

// ---------------------------------------------------------------- reading

bool isVertexElement(const PlyElement& e)
{
    return e.name == "vertex";
}

//! Index of the face element's vertex list, or -1 when the element gives no triangles.
int faceIndexProperty(const PlyElement& e)
{
    if (e.name != "face")
        return -1;
    for (std::size_t j = 0; j < e.properties.size(); ++j)
        if (e.properties[j].isList && (e.properties[j].name == "vertex_indices" || e.properties[j].name == "vertex_index"))
            return static_cast<int>(j);
    return -1;
}

class PlyReader
{
public:
    PlyReader(const fs::path& path, const ReadOptions& options, std::optional<RecordRange> range = std::nullopt)
        : path_(path), options_(options), range_(range), ctx_(path), file_(path), header_(parseHeader(file_, ctx_))
    {
    }

    //! The number of vertex records the header announces.
    std::uint64_t vertexRecordCount() const { return vertexCountFromHeader(); }

    Entity read()
    {
        const PlyElement* vertexElement = &findVertexElement();
        layout_ = makeVertexLayout(*vertexElement, ctx_);
        if (options_.geometryOnly)
            keepGeometryOnly(layout_);
        cloud_.setCrsWkt(header_.crsWkt);
        if (range_)
            return readRecordRange(*vertexElement);

        const bool binary = header_.encoding != PlyEncoding::Ascii;
        const bool needsRanges =
            binary && ((layout_.coordinatesAreDouble && !options_.origin) ||
                       std::find(layout_.fieldIsWide.begin(), layout_.fieldIsWide.end(), true) != layout_.fieldIsWide.end());
        std::uint64_t totalSteps = vertexElement->count * (needsRanges ? 2 : 1);
        for (const auto& e : header_.elements)
            if (faceIndexProperty(e) >= 0)
                totalSteps += e.count;
        ProgressTicker ticker(options_.progress, "Reading " + path_.filename().string(), totalSteps);

        const bool swap = binary && ((header_.encoding == PlyEncoding::BinaryBigEndian) == kHostLittleEndian);
        if (!binary)
            readAll(ticker, false);
        else if (swap)
            readAll<true>(ticker, needsRanges);
        else
            readAll<false>(ticker, needsRanges);
        return finish();
    }

private:
    template <bool Swap = false>
    void readAll(ProgressTicker& ticker, bool needsRanges)
    {
        const bool binary = header_.encoding != PlyEncoding::Ascii;
        const char* ptr = file_.data() + header_.dataOffset;
        const char* end = file_.data() + file_.size();
        AsciiLines lines(ptr, end, header_.lineCount + 1);
        bool vertexDone = false;
        bool facesDone = false;
        for (const auto& e : header_.elements) {
            const int indexProperty = faceIndexProperty(e);
            if (isVertexElement(e) && !vertexDone) {
                vertexDone = true;
                if (binary)
                    ptr = readBinaryVertexElement<Swap>(e, ptr, end, ticker, needsRanges);
                else
                    readAsciiVertexElement(e, lines, ticker);
            } else if (indexProperty >= 0 && !facesDone) {
                facesDone = true;
                const std::uint64_t vertexCount = vertexCountFromHeader();
                reserveTriangles(e, binary ? static_cast<std::size_t>(end - ptr) : lines.remainingBytes());
                FaceBuilder builder(e, vertexCount, ctx_, triangles_);
                if (binary)
                    ptr = readBinaryFaces<Swap>(e, static_cast<std::size_t>(indexProperty), builder, ptr, end, ctx_, ticker);
                else
                    readAsciiFaces(e, static_cast<std::size_t>(indexProperty), builder, lines, ctx_, ticker);
            } else {
                if (binary)
                    ptr = skipBinaryElement<Swap>(e, ptr, end, ctx_);
                else
                    skipAsciiElement(e, lines, ctx_);
            }
        }
    }

    //! Records [first, first + count) of the vertex element, through the
    //! parallel decoder of fixed-size records. The origin is the whole file's
    //! (a pass over every record's coordinates) unless the options give one.
    Entity readRecordRange(const PlyElement& vertexElement)
    {
        if (swapsBytes(vertexElement))
            readBinaryRange<true>(vertexElement);
        else
            readBinaryRange<false>(vertexElement);
        // Faces are not read: a range of vertices cannot keep their indices.
        return finish();
    }

    //! Throws Error(Unsupported) unless records can be read by ranges; then
    //! whether their bytes must be swapped.
    bool swapsBytes(const PlyElement& vertexElement) const
    {
        if (header_.encoding == PlyEncoding::Ascii || !vertexElement.fixedSize())
            throw Error(ErrorCode::Unsupported, path_.string() +
                                                    ": a range of records can only be read from a binary PLY whose vertex "
                                                    "records have a fixed size");
        return (header_.encoding == PlyEncoding::BinaryBigEndian) == kHostLittleEndian;
    }

    //! Where the vertex records start; throws when the file holds fewer than announced.
    template <bool Swap>
    const char* vertexRecords(const PlyElement& vertexElement, const char* end)
    {
        const char* ptr = file_.data() + header_.dataOffset;
        for (const auto& e : header_.elements) {
            if (&e == &vertexElement)
                break;
            ptr = skipBinaryElement<Swap>(e, ptr, end, ctx_);
        }
        const std::size_t recordSize = vertexElement.minRecordSize();
        if (recordSize == 0 || static_cast<std::uint64_t>(end - ptr) / recordSize < vertexElement.count)
            ctx_.truncated(vertexElement, recordSize == 0 ? 0 : static_cast<std::uint64_t>(end - ptr) / recordSize);
        return ptr;
    }

    //! Where the range's records lie: the vertex element's records, the
    //! range's first one, the file's end, and the range (cut at the
    //! element's end) as an element of its own.
    struct RangeRecords
    {
        const char* all = nullptr;
        const char* first = nullptr;
        const char* end = nullptr;
        PlyElement part;
    };
    template <bool Swap>
    RangeRecords rangeRecords(const PlyElement& vertexElement)
    {
        RangeRecords r;
        r.end = file_.data() + file_.size();
        r.all = vertexRecords<Swap>(vertexElement, r.end);
        const std::uint64_t first = std::min(range_->first, vertexElement.count);
        r.first = r.all + first * vertexElement.minRecordSize();
        r.part = vertexElement;
        r.part.count = std::min(range_->count, vertexElement.count - first);
        return r;
    }

    //! The box of the coordinates of `part`'s records, which start at `ptr`
    //! (non-finite values left out, axis by axis, as a whole read does).
    template <bool Swap>
    BoundingBox coordinateBox(const PlyElement& part, const char* ptr, const char* end, ProgressTicker& ticker)
    {
        return coordinateRanges<Swap>(part, ptr, end, ticker).box();
    }

    //! Each axis's range of finite values (+inf/-inf where it has none).
    template <bool Swap>
    RangeAccumulator coordinateRanges(const PlyElement& part, const char* ptr, const char* end, ProgressTicker& ticker)
    {
        std::vector<RangeAccumulator> perChunk(static_cast<std::size_t>(part.count / kChunk + 1), RangeAccumulator(0));
        if (const std::optional<PlainCoordinates> plain = plainCoordinates<Swap>(layout_, part)) {
            const auto add = [&perChunk](std::uint64_t i, double x, double y, double z) {
                RangeAccumulator& r = perChunk[static_cast<std::size_t>(i / kChunk)];
                r.addCoordinate(0, x);
                r.addCoordinate(1, y);
                r.addCoordinate(2, z);
            };
            visitPlainCoordinates(part, *plain, ptr, end, ctx_, ticker, add);
        } else {
            visitCoordinates<Swap>(part, ptr, end, ticker, perChunk);
        }
        RangeAccumulator whole(0);
        for (const RangeAccumulator& chunk : perChunk)
            whole.merge(chunk);
        return whole;
    }

    template <bool Swap>
    void visitCoordinates(const PlyElement& part, const char* ptr, const char* end, ProgressTicker& ticker,
                          std::vector<RangeAccumulator>& perChunk)
    {
        visitBinaryVertices<Swap>(part, coordinatesOnly(layout_), ptr, end, ctx_, ticker,
                                  [&perChunk](std::uint64_t i, const Slot& s, double v) {
                                      perChunk[static_cast<std::size_t>(i / kChunk)].add(s, v);
                                  });
    }

    template <bool Swap>
    void readBinaryRange(const PlyElement& vertexElement)
    {
        const RangeRecords r = rangeRecords<Swap>(vertexElement);
        std::optional<Eigen::Vector3d> origin = options_.origin;
        ProgressTicker ticker(options_.progress, "Reading " + path_.filename().string(),
                              r.part.count + (!origin && layout_.coordinatesAreDouble ? vertexElement.count : 0));
        if (!origin && layout_.coordinatesAreDouble)
            origin = suggestOrigin(coordinateBox<Swap>(vertexElement, r.all, r.end, ticker));
        const bool wideFields =
            std::find(layout_.fieldIsWide.begin(), layout_.fieldIsWide.end(), true) != layout_.fieldIsWide.end();
        readBinaryVertexElement<Swap>(r.part, r.first, r.end, ticker, wideFields,
                                      origin ? origin : std::optional<Eigen::Vector3d>(Eigen::Vector3d::Zero()));
    }

public:
    //! See FormatHandler::recordBounds: the box of the range's coordinates
    //! when they are doubles (the origin then comes from every point's box),
    //! else none (the origin is zero, whatever the points).
    std::optional<BoundingBox> recordBounds()
    {
        const PlyElement& vertexElement = findVertexElement();
        layout_ = makeVertexLayout(vertexElement, ctx_);
        const bool swap = swapsBytes(vertexElement);
        if (!layout_.coordinatesAreDouble)
            return std::nullopt;
        return swap ? rangeBox<true>(vertexElement) : rangeBox<false>(vertexElement);
    }

    //! See FormatHandler::recordPositions: the range's coordinates as the
    //! file holds them, when they are doubles; else none.
    std::optional<std::vector<Eigen::Vector3d>> recordPositions()
    {
        const PlyElement& vertexElement = findVertexElement();
        layout_ = makeVertexLayout(vertexElement, ctx_);
        const bool swap = swapsBytes(vertexElement);
        if (!layout_.coordinatesAreDouble)
            return std::nullopt;
        return swap ? rangePositions<true>(vertexElement) : rangePositions<false>(vertexElement);
    }

private:
    template <bool Swap>
    std::vector<Eigen::Vector3d> rangePositions(const PlyElement& vertexElement)
    {
        // rangeRecords has checked that the file holds every record.
        const RangeRecords r = rangeRecords<Swap>(vertexElement);
        std::vector<Eigen::Vector3d> positions(static_cast<std::size_t>(r.part.count));
        ProgressTicker ticker(nullptr, "", r.part.count);
        if (const std::optional<PlainCoordinates> plain = plainCoordinates<Swap>(layout_, r.part)) {
            const auto store = [&positions](std::uint64_t i, double x, double y, double z) { positions[i] = {x, y, z}; };
            visitPlainCoordinates(r.part, *plain, r.first, r.end, ctx_, ticker, store);
            return positions;
        }
        visitBinaryVertices<Swap>(r.part, coordinatesOnly(layout_), r.first, r.end, ctx_, ticker,
                                  [&positions](std::uint64_t i, const Slot& s, double v) {
                                      positions[i][static_cast<int>(s.role) - static_cast<int>(Role::X)] = v;
                                  });
        return positions;
    }

    template <bool Swap>
    BoundingBox rangeBox(const PlyElement& vertexElement)
    {
        const RangeRecords r = rangeRecords<Swap>(vertexElement);
        ProgressTicker ticker(nullptr, "", r.part.count);
        const RangeAccumulator ranges = coordinateRanges<Swap>(r.part, r.first, r.end, ticker);
        // Every axis's range, even where another has none: the parts of a
        // file join axis by axis, as a whole read's ranges do.
        BoundingBox box = ranges.box();
        box.min = Eigen::Vector3d(ranges.lo[0], ranges.lo[1], ranges.lo[2]);
        box.max = Eigen::Vector3d(ranges.hi[0], ranges.hi[1], ranges.hi[2]);
        return box;
    }

    const PlyElement& findVertexElement() const
    {
        for (const auto& e : header_.elements)
            if (isVertexElement(e))
                return e;
        ctx_.fail("no vertex element in the PLY header");
    }

    std::uint64_t vertexCountFromHeader() const
    {
        for (const auto& e : header_.elements)
            if (isVertexElement(e))
                return e.count;
        return 0;
    }

    void reserveTriangles(const PlyElement& e, std::size_t remainingBytes)
    {
        // Most faces are triangles; the bound keeps a lying count from allocating wildly.
        const std::size_t bound = remainingBytes / std::max<std::size_t>(e.minRecordSize(), 2);
        triangles_.reserve(static_cast<std::size_t>(std::min<std::uint64_t>(e.count, bound)));
    }

    //! Allocates the cloud and points the sink at its arrays.
    VertexSink prepareCloud(std::uint64_t count)
    {
        const auto n = static_cast<std::size_t>(count);
        cloud_.resize(n);
        VertexSink sink;
        sink.positions = cloud_.positions().data();
        sink.colors = layout_.hasColors ? cloud_.enableColors().data() : nullptr;
        sink.normals = layout_.hasNormals ? cloud_.enableNormals().data() : nullptr;
        for (const auto& name : layout_.fieldNames)
            cloud_.addField(name);
        // Pointers are taken once every field exists: addField may reallocate the field vector.
        for (const auto& name : layout_.fieldNames)
            sink.fieldValues.push_back(cloud_.field(name)->values().data());
        sink.fieldResiduals.assign(layout_.fieldNames.size(), nullptr);
        sink.fieldResidualsFailed.assign(layout_.fieldNames.size(), nullptr);
        sink.fieldOffsets.assign(layout_.fieldNames.size(), 0.0);
        sink.stagedFields.assign(layout_.fieldNames.size(), nullptr);
        return sink;
    }

    template <bool Swap>
    const char* readBinaryVertexElement(const PlyElement& e, const char* ptr, const char* end, ProgressTicker& ticker,
                                        bool needsRanges, const std::optional<Eigen::Vector3d>& wholeFileOrigin = std::nullopt)
    {
        // Check the size before allocating: a corrupt count must not allocate gigabytes.
        const std::size_t minSize = std::max<std::size_t>(e.minRecordSize(), 1);
        if (static_cast<std::uint64_t>(end - ptr) / minSize < e.count) {
            if (e.fixedSize())
                ctx_.truncated(e, static_cast<std::uint64_t>(end - ptr) / minSize);
            ctx_.fail("truncated: the header announces " + std::to_string(e.count) + " vertices but only " +
                      std::to_string(end - ptr) + " bytes of data remain");
        }
        RangeAccumulator ranges(layout_.fieldNames.size());
        if (needsRanges && layout_.fieldNames.empty()) {
            ranges = coordinateRanges<Swap>(e, ptr, end, ticker);
        } else if (needsRanges) {
            // One accumulator per chunk (the decoding is parallel by chunk), merged after.
            std::vector<RangeAccumulator> perChunk(static_cast<std::size_t>(e.count / kChunk + 1), ranges);
            visitBinaryVertices<Swap>(e, layout_, ptr, end, ctx_, ticker, [&perChunk](std::uint64_t i, const Slot& s, double v) {
                perChunk[static_cast<std::size_t>(i / kChunk)].add(s, v);
            });
            for (const RangeAccumulator& chunk : perChunk)
                ranges.merge(chunk);
        }
        VertexSink sink = prepareCloud(e.count);
        if (options_.origin)
            sink.origin = *options_.origin;
        else if (wholeFileOrigin)
            sink.origin = *wholeFileOrigin;
        else if (layout_.coordinatesAreDouble)
            sink.origin = suggestOrigin(ranges.box());
        cloud_.setOrigin(sink.origin);
        // Wide values keep an exact form: float residuals as they are decoded
        // (4 bytes a value), doubles for a field they fail on (a second pass).
        const auto failed = std::make_unique<std::atomic<bool>[]>(layout_.fieldNames.size());
        for (std::size_t f = 0; f < layout_.fieldNames.size(); ++f) {
            failed[f].store(false);
            if (layout_.fieldIsWide[f]) {
                sink.fieldOffsets[f] = chooseFieldOffset(ranges.fieldLo[f], ranges.fieldHi[f]);
                ScalarField& field = *cloud_.field(layout_.fieldNames[f]);
                field.keepResiduals();
                sink.fieldResiduals[f] = field.residuals().data();
                sink.fieldResidualsFailed[f] = &failed[f];
            }
        }
        applyFieldOffsets(sink);
        sink.compile(layout_);
        const char* next = nullptr;
        const std::optional<PlainCoordinates> plain = plainCoordinates<Swap>(layout_, e);
        if (plain && layout_.slots.size() == 3 && e.count > 0) {
            // Coordinates only (a geometry-only read): each one as put() would store it.
            Eigen::Vector3f* positions = sink.positions;
            const Eigen::Vector3d origin = sink.origin;
            const auto store = [positions, origin](std::uint64_t i, double x, double y, double z) {
                positions[i] = Eigen::Vector3f(static_cast<float>(x - origin.x()), static_cast<float>(y - origin.y()),
                                               static_cast<float>(z - origin.z()));
            };
            next = visitPlainCoordinates(e, *plain, ptr, end, ctx_, ticker, store);
        } else {
            next = visitBinaryVertices<Swap>(
                e, layout_, ptr, end, ctx_, ticker, [&sink](std::uint64_t i, const Slot& s, double v) { sink.put(i, s, v); });
        }
        for (std::size_t f = 0; f < layout_.fieldNames.size(); ++f) {
            if (!failed[f].load())
                continue;
            ScalarField& field = *cloud_.field(layout_.fieldNames[f]);
            field.keepDoubles();
            double* doubles = field.doubles().data();
            visitBinaryVertices<Swap>(e, layout_, ptr, end, ctx_, ticker, [doubles, f](std::uint64_t i, const Slot& s, double v) {
                if (s.role == Role::Field && s.field == f)
                    doubles[i] = v;
            });
        }
        keepWideFieldsExact();
        return next;
    }

    //! A double property stays exact, to the bit, and a double when written
    //! back. A 32-bit integer one keeps an exact form only when the float around
    //! the field's offset cannot hold every value (a range wider than 2^24).
    void keepWideFieldsExact()
    {
        for (const Slot& s : layout_.slots) {
            if (s.role != Role::Field || !layout_.fieldIsWide[s.field])
                continue;
            ScalarField& field = *cloud_.field(layout_.fieldNames[s.field]);
            // Residuals that held need no second look for a double property.
            // A range of records keeps every wide field exact, whatever its
            // values: the ranges of one file then all have the same types.
            if (s.type != PlyType::Float64 || !field.doubles().empty() || range_)
                field.compact(s.type == PlyType::Float64 || range_.has_value());
        }
    }

    void readAsciiVertexElement(const PlyElement& e, AsciiLines& lines, ProgressTicker& ticker)
    {
        // The text gives every coordinate in full: keep them in double until the
        // bounding box, hence the origin, is known.
        AsciiRecordReader reader(lines, e, ctx_);
        // Allocating for the records the data can hold: the count may lie, and
        // parsing then stops with a precise message before the arrays end.
        const auto n = static_cast<std::size_t>(reader.capacity());
        VertexSink sink = prepareCloud(n);
        std::vector<double> stagedXyz;
        if (options_.origin) {
            sink.origin = *options_.origin;
        } else {
            stagedXyz.resize(3 * n);
            sink.stagedXyz = stagedXyz.data();
        }
        std::vector<std::vector<double>> stagedFields(layout_.fieldNames.size());
        for (std::size_t f = 0; f < layout_.fieldNames.size(); ++f)
            if (layout_.fieldIsWide[f]) {
                stagedFields[f].assign(n, std::numeric_limits<double>::quiet_NaN());
                sink.stagedFields[f] = stagedFields[f].data();
            }
        sink.compile(layout_);
        readAsciiVertices(e, layout_, reader, sink, ticker);

        if (!options_.origin) {
            RangeAccumulator ranges(0);
            Slot axis[3];
            for (int a = 0; a < 3; ++a)
                axis[a].role = static_cast<Role>(static_cast<int>(Role::X) + a);
            for (std::size_t i = 0; i < n; ++i)
                for (int a = 0; a < 3; ++a)
                    ranges.add(axis[a], stagedXyz[3 * i + static_cast<std::size_t>(a)]);
            const Eigen::Vector3d origin = suggestOrigin(ranges.box());
            auto& positions = cloud_.positions();
            for (std::size_t i = 0; i < n; ++i)
                for (int a = 0; a < 3; ++a)
                    positions[i][a] = static_cast<float>(stagedXyz[3 * i + static_cast<std::size_t>(a)] - origin[a]);
            sink.origin = origin;
        }
        cloud_.setOrigin(sink.origin);
        for (std::size_t f = 0; f < layout_.fieldNames.size(); ++f) {
            if (!layout_.fieldIsWide[f])
                continue;
            const auto& staged = stagedFields[f];
            double lo = std::numeric_limits<double>::infinity();
            double hi = -lo;
            for (double v : staged)
                if (std::isfinite(v)) {
                    lo = std::min(lo, v);
                    hi = std::max(hi, v);
                }
            sink.fieldOffsets[f] = chooseFieldOffset(lo, hi);
            float* values = sink.fieldValues[f];
            for (std::size_t i = 0; i < n; ++i)
                values[i] = static_cast<float>(staged[i] - sink.fieldOffsets[f]);
            ScalarField& field = *cloud_.field(layout_.fieldNames[f]);
            field.keepDoubles();
            field.doubles().swap(stagedFields[f]);
        }
        applyFieldOffsets(sink);
        keepWideFieldsExact();
    }

    void applyFieldOffsets(const VertexSink& sink)
    {
        for (std::size_t f = 0; f < layout_.fieldNames.size(); ++f)
            cloud_.field(layout_.fieldNames[f])->setOffset(sink.fieldOffsets[f]);
    }

    Entity finish()
    {
        if (!triangles_.empty()) {
            const auto& positions = cloud_.positions();
            for (std::size_t i = 0; i < positions.size(); ++i)
                if (!positions[i].allFinite())
                    ctx_.fail("vertex " + std::to_string(i + 1) + " of " + std::to_string(positions.size()) +
                              " has a non-finite coordinate; a mesh cannot have one");
            Mesh mesh;
            mesh.vertices = std::move(cloud_);
            mesh.triangles = std::move(triangles_);
            return mesh;
        }
        if (const std::size_t dropped = cloud_.removeNonFinitePoints(); dropped > 0)
            logWarning(ctx_.fileName() + ": " + std::to_string(dropped) +
                       " points with non-finite coordinates were skipped");
        return std::move(cloud_);
    }

    fs::path path_;
    const ReadOptions& options_;
    std::optional<RecordRange> range_;
    Context ctx_;
    MappedFile file_;
    PlyHeader header_;
    VertexLayout layout_;
    PointCloud cloud_;
    std::vector<Triangle> triangles_;
};

} // namespace

FormatHandler plyFormat()
{
    FormatHandler handler;
    handler.name = "PLY";
    handler.extensions = {"ply"};
    handler.read = [](const fs::path& path, const ReadOptions& options) -> Entity {
        return PlyReader(path, options).read();
    };
    handler.countRecords = [](const fs::path& path) { return PlyReader(path, ReadOptions{}).vertexRecordCount(); };
    handler.readRecords = [](const fs::path& path, RecordRange range, const ReadOptions& options) -> PointCloud {
        Entity entity = PlyReader(path, options, range).read();
        return std::move(std::get<PointCloud>(entity));
    };
    handler.writeCloud = [](const PointCloud& cloud, const fs::path& path, const WriteOptions& options) {
        ply::writeCloud(cloud, path, options);
    };
    handler.writeMesh = [](const Mesh& mesh, const fs::path& path, const WriteOptions& options) {
        ply::writeMesh(mesh, path, options);
    };
    handler.openChunkWriter = [](const fs::path& path, const PointCloud& layout, std::uint64_t total,
                                 const WriteOptions& options) -> std::unique_ptr<PointChunkWriter> {
        return ply::openChunkWriter(path, layout, total, options);
    };
    handler.recordBounds = [](const fs::path& path, RecordRange range) {
        return PlyReader(path, ReadOptions{}, range).recordBounds();
    };
    handler.recordPositions = [](const fs::path& path, RecordRange range) {
        return PlyReader(path, ReadOptions{}, range).recordPositions();
    };
    handler.openPlacedWriter = [](const fs::path& destination, const fs::path& join, const PointCloud& layout,
                                  std::uint64_t total, const WriteOptions& options) -> std::unique_ptr<PlacedChunkWriter> {
        return ply::openPlacedWriter(destination, join, layout, total, options);
    };
    return handler;
}

} // namespace scandiff::io::detail
