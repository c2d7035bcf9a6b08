// SPDX-License-Identifier: GPL-3.0-or-later
// PLY writing (see PlyWriter.h); the reader is PlyFormat.cpp.
#include "ply/PlyWriter.h"
#include "ply/PlyCommon.h"

#include "internal/Formats.h"
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
#include <charconv>
#include <memory>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace scandiff::io::detail::ply {

namespace {

namespace fs = std::filesystem;


enum class ColumnKind : std::uint8_t { Coordinate, Color, Normal, Field };

struct Column
{
    std::string name;
    PlyType type;
    ColumnKind kind;
    int index; //!< axis, channel or field index
};

std::string plyPropertyName(const std::string& fieldName)
{
    std::string name = fieldName.empty() ? std::string("field") : fieldName;
    for (char& c : name)
        if (static_cast<unsigned char>(c) <= 32 || static_cast<unsigned char>(c) >= 127)
            c = '_';
    // Names the reader would take for something else get the prefix it strips.
    static const char* reserved[] = {"x",     "y",           "z",             "red",          "green",
                                     "blue",  "diffuse_red", "diffuse_green", "diffuse_blue", "alpha",
                                     "diffuse_alpha", "nx",  "ny",            "nz",           "normal_x",
                                     "normal_y",      "normal_z"};
    const std::string key = lower(name);
    const bool clashes = key.rfind("scalar_", 0) == 0 ||
                         std::any_of(std::begin(reserved), std::end(reserved), [&](const char* r) { return key == r; });
    return clashes ? "scalar_" + name : name;
}

const char* plyTypeName(PlyType type)
{
    switch (type) {
    case PlyType::Int8: return "char";
    case PlyType::UInt8: return "uchar";
    case PlyType::Int16: return "short";
    case PlyType::UInt16: return "ushort";
    case PlyType::Int32: return "int";
    case PlyType::UInt32: return "uint";
    case PlyType::Float32: return "float";
    case PlyType::Float64: return "double";
    }
    return "float";
}

template <typename T, bool Swap>
inline char* store(char* out, T value)
{
    if constexpr (!Swap) {
        std::memcpy(out, &value, sizeof(T));
    } else {
        char bytes[sizeof(T)];
        std::memcpy(bytes, &value, sizeof(T));
        for (std::size_t i = 0; i < sizeof(T); ++i)
            out[i] = bytes[sizeof(T) - 1 - i];
    }
    return out + sizeof(T);
}

class PlyWriter
{
public:
    PlyWriter(const PointCloud& cloud, const std::vector<Triangle>* triangles, const fs::path& path,
              const WriteOptions& options)
        : cloud_(&cloud), triangles_(triangles), path_(path), options_(options)
    {
        switch (options.encoding) {
        case Encoding::Default:
        case Encoding::BinaryLittleEndian: encoding_ = PlyEncoding::BinaryLittleEndian; break;
        case Encoding::BinaryBigEndian: encoding_ = PlyEncoding::BinaryBigEndian; break;
        case Encoding::Ascii: encoding_ = PlyEncoding::Ascii; break;
        case Encoding::BinaryCompressed:
            throw Error(ErrorCode::InvalidArgument, path.string() + ": PLY has no compressed encoding");
        }
        layout_ = {cloud.hasColors(), cloud.hasNormals(), cloud.fields().size(), cloud.origin()};
        const bool globalDoubles = cloud.origin() != Eigen::Vector3d::Zero();
        for (int a = 0; a < 3; ++a)
            columns_.push_back({std::string(1, static_cast<char>('x' + a)),
                                globalDoubles ? PlyType::Float64 : PlyType::Float32, ColumnKind::Coordinate, a});
        if (cloud.hasColors())
            for (int c = 0; c < 3; ++c)
                columns_.push_back({c == 0 ? "red" : c == 1 ? "green" : "blue", PlyType::UInt8, ColumnKind::Color, c});
        if (cloud.hasNormals())
            for (int a = 0; a < 3; ++a)
                columns_.push_back({"n" + std::string(1, static_cast<char>('x' + a)), PlyType::Float32,
                                    ColumnKind::Normal, a});
        for (std::size_t f = 0; f < cloud.fields().size(); ++f) {
            const ScalarField& field = cloud.fields()[f];
            columns_.push_back({plyPropertyName(field.name()),
                                field.offset() != 0.0 || field.isDouble() ? PlyType::Float64 : PlyType::Float32,
                                ColumnKind::Field,
                                static_cast<int>(f)});
        }
    }

    void write()
    {
        AtomicFile file(path_);
        std::ofstream& out = file.stream();
        const std::string header = makeHeader(cloud_->size());
        out.write(header.data(), static_cast<std::streamsize>(header.size()));
        const std::uint64_t faceCount = triangles_ ? triangles_->size() : 0;
        ProgressTicker ticker(options_.progress, "Writing " + path_.filename().string(), cloud_->size() + faceCount);
        writeRecords(out, ticker);
        file.commit();
    }

    //! For writing chunk by chunk: the header for `vertexCount` vertices with
    //! the columns of the cloud given to the constructor...
    std::string makeHeader(std::uint64_t vertexCount) const
    {
        std::string h = "ply\nformat ";
        h += encoding_ == PlyEncoding::Ascii                ? "ascii"
             : encoding_ == PlyEncoding::BinaryLittleEndian ? "binary_little_endian"
                                                            : "binary_big_endian";
        h += " 1.0\ncomment Written by scandiff\n";
        if (!cloud_->crsWkt().empty()) {
            // WKT ignores whitespace between its tokens: one line holds it.
            std::string wkt = cloud_->crsWkt();
            std::replace_if(wkt.begin(), wkt.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
            h += std::string(kCrsComment) + wkt + "\n";
        }
        h += "element vertex " + std::to_string(vertexCount) + "\n";
        for (const Column& c : columns_)
            h += std::string("property ") + plyTypeName(c.type) + " " + c.name + "\n";
        if (triangles_) {
            h += "element face " + std::to_string(triangles_->size()) + "\n";
            h += "property list uchar int vertex_indices\n";
        }
        h += "end_header\n";
        return h;
    }

    //! The bytes of one vertex record (binary encodings).
    std::size_t vertexRecordSize() const
    {
        std::size_t size = 0;
        for (const Column& c : columns_)
            size += typeSize(c.type);
        return size;
    }

    bool isAscii() const { return encoding_ == PlyEncoding::Ascii; }

    //! ...then the records of each chunk, a cloud with the same attributes.
    void writeChunk(std::ostream& out, const PointCloud& chunk, ProgressTicker& ticker)
    {
        // Against the layout's attributes, kept as values: the cloud the
        // writer was made from, or the last chunk, may be gone by now.
        const bool sameAttributes = chunk.hasColors() == layout_.colours && chunk.hasNormals() == layout_.normals &&
                                    chunk.fields().size() == layout_.fields && chunk.origin() == layout_.origin;
        if (!sameAttributes)
            throw Error(ErrorCode::InvalidArgument,
                        path_.string() + ": a chunk's colours, normals, fields or origin differ from the first chunk's");
        for (const Column& c : columns_)
            if (c.kind == ColumnKind::Field && c.type == PlyType::Float32) {
                const ScalarField& field = chunk.fields()[static_cast<std::size_t>(c.index)];
                if (field.isDouble() || field.offset() != 0.0)
                    throw Error(ErrorCode::InvalidArgument, path_.string() + ": field '" + field.name() +
                                                                "' needs doubles in a later chunk than the first");
            }
        cloud_ = &chunk;
        writeRecords(out, ticker);
    }

private:
    void writeRecords(std::ostream& out, ProgressTicker& ticker)
    {
        if (encoding_ == PlyEncoding::Ascii)
            writeAscii(out, ticker);
        else if ((encoding_ == PlyEncoding::BinaryBigEndian) == kHostLittleEndian)
            writeBinary<true>(out, ticker);
        else
            writeBinary<false>(out, ticker);
    }

    double value(const Column& c, std::size_t i) const
    {
        switch (c.kind) {
        case ColumnKind::Coordinate:
            // Doubles with what a float misses of a file's exact coordinates (PointCloud::positionResiduals).
            return c.type == PlyType::Float64 ? cloud_->exactGlobalPosition(i)[c.index]
                                              : static_cast<double>(cloud_->positions()[i][c.index]);
        case ColumnKind::Color: {
            const Rgb8& rgb = cloud_->colors()[i];
            return c.index == 0 ? rgb.r : c.index == 1 ? rgb.g : rgb.b;
        }
        case ColumnKind::Normal: return cloud_->normals()[i][c.index];
        case ColumnKind::Field: return cloud_->fields()[static_cast<std::size_t>(c.index)].value(i);
        }
        return 0.0;
    }

    template <bool Swap>
    void writeBinary(std::ostream& out, ProgressTicker& ticker)
    {
        const std::size_t recordSize = vertexRecordSize();
        const std::size_t n = cloud_->size();
        std::vector<char> buffer(static_cast<std::size_t>(kChunk) * std::max<std::size_t>(recordSize, 13));
        for (std::size_t start = 0; start < n; start += kChunk) {
            const std::size_t stop = std::min<std::size_t>(n, start + kChunk);
            char* o = buffer.data();
            for (std::size_t i = start; i < stop; ++i)
                for (const Column& c : columns_) {
                    const double v = value(c, i);
                    switch (c.type) {
                    case PlyType::UInt8: o = store<std::uint8_t, Swap>(o, static_cast<std::uint8_t>(v)); break;
                    case PlyType::Float64: o = store<double, Swap>(o, v); break;
                    default: o = store<float, Swap>(o, static_cast<float>(v)); break;
                    }
                }
            out.write(buffer.data(), o - buffer.data());
            ticker.step(stop - start);
        }
        if (!triangles_)
            return;
        const std::size_t m = triangles_->size();
        for (std::size_t start = 0; start < m; start += kChunk) {
            const std::size_t stop = std::min<std::size_t>(m, start + kChunk);
            char* o = buffer.data();
            for (std::size_t t = start; t < stop; ++t) {
                *o++ = 3;
                for (std::uint32_t v : (*triangles_)[t])
                    o = store<std::int32_t, Swap>(o, static_cast<std::int32_t>(v));
            }
            out.write(buffer.data(), o - buffer.data());
            ticker.step(stop - start);
        }
    }

    void writeAscii(std::ostream& out, ProgressTicker& ticker)
    {
        std::string text;
        char number[64];
        auto append = [&](auto v) {
            const auto result = std::to_chars(number, number + sizeof(number), v);
            // Keep "nan" unsigned: some readers reject "-nan".
            if (number[0] == '-' && result.ptr - number == 4 && number[1] == 'n')
                text.append(number + 1, 3);
            else
                text.append(number, result.ptr);
        };
        auto flushIfLarge = [&]() {
            if (text.size() > (1u << 20)) {
                out.write(text.data(), static_cast<std::streamsize>(text.size()));
                text.clear();
            }
        };
        const std::size_t n = cloud_->size();
        for (std::size_t i = 0; i < n; ++i) {
            for (std::size_t k = 0; k < columns_.size(); ++k) {
                const Column& c = columns_[k];
                if (k > 0)
                    text += ' ';
                const double v = value(c, i);
                if (c.type == PlyType::UInt8)
                    append(static_cast<int>(v));
                else if (c.type == PlyType::Float64)
                    append(v);
                else
                    append(static_cast<float>(v));
            }
            text += '\n';
            flushIfLarge();
            if ((i + 1) % kChunk == 0)
                ticker.step(kChunk);
        }
        ticker.step(n % kChunk);
        if (triangles_) {
            for (std::size_t t = 0; t < triangles_->size(); ++t) {
                const Triangle& tri = (*triangles_)[t];
                text += '3';
                for (std::uint32_t v : tri) {
                    text += ' ';
                    append(v);
                }
                text += '\n';
                flushIfLarge();
                if ((t + 1) % kChunk == 0)
                    ticker.step(kChunk);
            }
            ticker.step(triangles_->size() % kChunk);
        }
        out.write(text.data(), static_cast<std::streamsize>(text.size()));
    }

    //! The attributes every chunk must have (writeChunk).
    struct Layout
    {
        bool colours = false, normals = false;
        std::size_t fields = 0;
        Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    };
    Layout layout_;
    const PointCloud* cloud_; //!< what writeRecords writes: the cloud, or the chunk being written
    const std::vector<Triangle>* triangles_;
    fs::path path_;
    const WriteOptions& options_;
    PlyEncoding encoding_ = PlyEncoding::BinaryLittleEndian;
    std::vector<Column> columns_;
};

//! A PLY written chunk by chunk: the header announces the total, each chunk's
//! records follow, and the file is renamed into place once all have come.
class PlyChunkWriter final : public PointChunkWriter
{
public:
    PlyChunkWriter(const fs::path& path, const PointCloud& layout, std::uint64_t total, const WriteOptions& options)
        : options_(options), file_(path), writer_(layout, nullptr, path, options_), total_(total),
          ticker_(options_.progress, "Writing " + path.filename().string(), total)
    {
        const std::string header = writer_.makeHeader(total);
        file_.stream().write(header.data(), static_cast<std::streamsize>(header.size()));
    }

    void append(const PointCloud& chunk) override
    {
        if (written_ + chunk.size() > total_)
            throw Error(ErrorCode::InvalidArgument, file_.destination().string() + ": more points than the " +
                                                        std::to_string(total_) + " announced");
        writer_.writeChunk(file_.stream(), chunk, ticker_);
        written_ += chunk.size();
    }

    void commit() override
    {
        if (written_ != total_)
            throw Error(ErrorCode::InvalidArgument, file_.destination().string() + ": " + std::to_string(written_) +
                                                        " points written of the " + std::to_string(total_) + " announced");
        file_.commit();
    }

private:
    WriteOptions options_;
    AtomicFile file_;
    PlyWriter writer_;
    std::uint64_t total_ = 0, written_ = 0;
    ProgressTicker ticker_;
};

//! A binary PLY filled by several processes: its records have a fixed size,
//! so each chunk has its place after the header whichever process writes it.
class PlyPlacedWriter final : public PlacedChunkWriter
{
public:
    PlyPlacedWriter(const fs::path& destination, const fs::path& join, const PointCloud& layout, std::uint64_t total,
                    const WriteOptions& options)
        : options_(options), writer_(layout, nullptr, destination, options_), total_(total),
          header_(writer_.makeHeader(total)), recordSize_(writer_.vertexRecordSize()),
          ticker_(options_.progress, "Writing " + destination.filename().string(), total)
    {
        if (writer_.isAscii())
            throw Error(ErrorCode::Unsupported,
                        destination.string() + ": ASCII PLY records vary in size, so they cannot be written at their place");
        if (join.empty()) {
            file_.emplace(destination);
            file_->stream().flush(); // the temporary exists, empty
            path_ = file_->tempPath();
            // The header written and the file closed before anyone joins: a
            // network file system shows other machines what was closed.
            std::ofstream header(path_, std::ios::in | std::ios::out | std::ios::binary);
            header.write(header_.data(), static_cast<std::streamsize>(header_.size()));
            header.close();
            if (!header)
                throw Error(ErrorCode::Io, path_.string() + ": cannot write the header");
        } else {
            path_ = join;
        }
        // Opened for update, so nothing another process wrote is truncated.
        stream_.open(path_, std::ios::in | std::ios::out | std::ios::binary);
        if (!stream_)
            throw Error(ErrorCode::Io, path_.string() + ": cannot open for writing");
        if (!join.empty()) {
            std::string found(header_.size(), '\0');
            stream_.read(found.data(), static_cast<std::streamsize>(found.size()));
            if (!stream_ || found != header_)
                throw Error(ErrorCode::InvalidArgument,
                            path_.string() + ": its header is not the one this cloud's attributes give");
        }
    }

    void write(std::uint64_t first, const PointCloud& chunk) override
    {
        if (first > total_ || chunk.size() > total_ - first)
            throw Error(ErrorCode::InvalidArgument, destination() + ": points " + std::to_string(first) + " to " +
                                                        std::to_string(first + chunk.size()) + " beyond the " +
                                                        std::to_string(total_) + " announced");
        stream_.seekp(static_cast<std::streamoff>(header_.size() + first * recordSize_));
        writer_.writeChunk(stream_, chunk, ticker_);
        if (!stream_)
            throw Error(ErrorCode::Io, path_.string() + ": write failed");
    }

    void close() override
    {
        stream_.close();
        if (stream_.fail())
            throw Error(ErrorCode::Io, path_.string() + ": write failed");
    }

    const fs::path& temporaryPath() const override { return path_; }

    void commit(std::uint64_t pointsWritten) override
    {
        if (!file_)
            throw Error(ErrorCode::Internal, path_.string() + ": only the process that created it commits it");
        if (stream_.is_open())
            close();
        if (pointsWritten != total_)
            throw Error(ErrorCode::InvalidArgument, destination() + ": " + std::to_string(pointsWritten) +
                                                        " points written of the " + std::to_string(total_) + " announced");
        file_->commit();
    }

private:
    std::string destination() const { return file_ ? file_->destination().string() : path_.string(); }

    WriteOptions options_;
    PlyWriter writer_;
    std::uint64_t total_ = 0;
    std::string header_;
    std::size_t recordSize_ = 0;
    ProgressTicker ticker_;
    std::optional<AtomicFile> file_; //!< the creator's
    fs::path path_;
    std::fstream stream_;
};

} // namespace

void writeCloud(const PointCloud& cloud, const fs::path& path, const WriteOptions& options)
{
    PlyWriter(cloud, nullptr, path, options).write();
}

void writeMesh(const Mesh& mesh, const fs::path& path, const WriteOptions& options)
{
    PlyWriter(mesh.vertices, &mesh.triangles, path, options).write();
}

std::unique_ptr<PointChunkWriter> openChunkWriter(const fs::path& path, const PointCloud& layout, std::uint64_t total,
                                                  const WriteOptions& options)
{
    return std::make_unique<PlyChunkWriter>(path, layout, total, options);
}

std::unique_ptr<PlacedChunkWriter> openPlacedWriter(const fs::path& destination, const fs::path& join, const PointCloud& layout,
                                                    std::uint64_t total, const WriteOptions& options)
{
    return std::make_unique<PlyPlacedWriter>(destination, join, layout, total, options);
}

} // namespace scandiff::io::detail::ply
