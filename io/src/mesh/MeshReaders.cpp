// SPDX-License-Identifier: GPL-3.0-or-later
//! Readers of OBJ, STL and OFF meshes, written here rather than taken from
//! assimp (Debian's libassimp 5.2), for three reasons found in use:
//! - hostile files crash it: fuzzing found OFF files that abort on an internal
//!   assertion of its triangulation step or fault inside the library, and OBJ
//!   and STL files that leak; a reader of the workbench must give an error;
//! - it is built with float coordinates, so a georeferenced OBJ or OFF lost
//!   its sub-millimetre digits on reading (these text formats carry doubles);
//! - the three formats are simple enough that a complete reader is shorter
//!   than the code that walked assimp's scene graph.
//! Every size is checked against the file before anything is allocated, and
//! every loop is linear in the file.

#include "mesh/MeshReaders.h"

#include "internal/MappedFile.h"
#include "internal/TextUtil.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Progress.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

namespace scandiff::io::detail {

namespace fs = std::filesystem;

namespace {

constexpr std::uint64_t kMaxVertices = std::numeric_limits<std::uint32_t>::max();


//! Lines of a text file, with their numbers for error messages.
class TextLines
{
public:
    explicit TextLines(std::string_view text) : text_(text) {}
    bool next(std::string_view& line)
    {
        if (at_ >= text_.size())
            return false;
        const std::size_t end = text_.find('\n', at_);
        const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
        line = text_.substr(at_, stop - at_);
        if (!line.empty() && line.back() == '\r')
            line.remove_suffix(1);
        at_ = stop + 1;
        ++number_;
        return true;
    }
    std::size_t lineNumber() const { return number_; }
    std::size_t offset() const { return std::min(at_, text_.size()); }

private:
    std::string_view text_;
    std::size_t at_ = 0;
    std::size_t number_ = 0;
};

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

//! Next whitespace-separated word of `line` (consumed), empty at the end.
std::string_view nextWord(std::string_view& line)
{
    std::size_t i = 0;
    while (i < line.size() && isSpace(line[i]))
        ++i;
    std::size_t j = i;
    while (j < line.size() && !isSpace(line[j]))
        ++j;
    const std::string_view word = line.substr(i, j - i);
    line.remove_prefix(j);
    return word;
}

bool toDouble(std::string_view word, double& value)
{
    if (!word.empty() && word.front() == '+')
        word.remove_prefix(1);
    const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
    return error == std::errc() && end == word.data() + word.size();
}

bool toInteger(std::string_view word, long long& value)
{
    if (!word.empty() && word.front() == '+')
        word.remove_prefix(1);
    const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
    return error == std::errc() && end == word.data() + word.size();
}

class Reader
{
public:
    Reader(const fs::path& path, const ReadOptions& options)
        : path_(path), file_(path), ticker_(options.progress, "Reading " + path.filename().string(), file_.size() + 1)
    {
    }

    [[noreturn]] void fail(const std::string& message) const
    {
        throw Error(ErrorCode::InvalidData, path_.string() + ": " + message);
    }
    [[noreturn]] void failAt(std::size_t line, const std::string& message) const
    {
        fail("line " + std::to_string(line) + ": " + message);
    }
    //! Progress and Cancel, every 64 KiB of the file.
    void consumed(std::size_t offset)
    {
        if (offset >= reported_ + (1u << 16)) {
            ticker_.step(offset - reported_);
            reported_ = offset;
        }
    }
    void done() { ticker_.step(file_.size() + 1 - reported_); }

    const fs::path& path() const { return path_; }
    const MappedFile& file() const { return file_; }

private:
    fs::path path_;
    MappedFile file_;
    ProgressTicker ticker_;
    std::size_t reported_ = 0;
};

//! A polygon of `count` corners as a fan of triangles, as every reader of
//! these formats does (the faces are planar and convex in practice).
void addFan(const std::vector<std::uint32_t>& corners, std::vector<Triangle>& triangles)
{
    for (std::size_t k = 1; k + 1 < corners.size(); ++k)
        triangles.push_back({corners[0], corners[k], corners[k + 1]});
}

// ------------------------------------------------------------------- OBJ

//! OBJ: `v x y z [w]` or `v x y z r g b` (colours in 0..1, a common
//! extension), `vn`, and `f` with 1-based or negative (relative) indices in
//! the forms v, v/t, v//n, v/t/n. Normals belong to face corners in OBJ; a
//! vertex takes the normal of its corners (they agree in files that carry
//! one normal per vertex, as ours). Other statements (vt, g, o, s, usemtl,
//! mtllib, l, p) are read past.
MeshParts readObj(Reader& reader)
{
    MeshParts parts;
    std::vector<Eigen::Vector3f> fileNormals;
    std::vector<std::int64_t> normalOfVertex; // index into fileNormals, -1 none
    std::vector<std::uint32_t> corners;
    bool allVerticesColoured = true;
    bool everyCornerHasNormal = true;
    TextLines lines(reader.file().view());
    std::string_view line;
    const auto resolve = [&](long long index, std::size_t count, const char* what) -> std::uint64_t {
        // 1-based, or negative: relative to the end of the list so far.
        const long long resolved = index > 0 ? index - 1 : static_cast<long long>(count) + index;
        if (index == 0 || resolved < 0 || static_cast<std::uint64_t>(resolved) >= count)
            reader.failAt(lines.lineNumber(), std::string(what) + " index " + std::to_string(index) + " out of range (" +
                                                  std::to_string(count) + " so far)");
        return static_cast<std::uint64_t>(resolved);
    };
    while (lines.next(line)) {
        reader.consumed(lines.offset());
        // A comment may follow the values on the line, as many writers put it.
        std::string_view rest = line.substr(0, line.find('#'));
        const std::string_view keyword = nextWord(rest);
        if (keyword == "v") {
            double values[7];
            int count = 0;
            for (std::string_view word = nextWord(rest); !word.empty(); word = nextWord(rest)) {
                if (count == 7)
                    reader.failAt(lines.lineNumber(), "a vertex has more than 7 numbers");
                if (!toDouble(word, values[count]))
                    reader.failAt(lines.lineNumber(), "not a number: " + quoted(word));
                ++count;
            }
            if (count < 3)
                reader.failAt(lines.lineNumber(), "a vertex needs 3 coordinates");
            if (parts.vertices.size() == kMaxVertices)
                reader.failAt(lines.lineNumber(), "more than 4,294,967,295 vertices");
            parts.vertices.emplace_back(values[0], values[1], values[2]);
            normalOfVertex.push_back(-1);
            if (count == 6) {
                const auto byte = [](double v) {
                    return static_cast<std::uint8_t>(std::lround(std::clamp(std::isfinite(v) ? v : 0.0, 0.0, 1.0) * 255.0));
                };
                parts.colors.push_back({byte(values[3]), byte(values[4]), byte(values[5])});
            } else {
                allVerticesColoured = false;
            }
        } else if (keyword == "vn") {
            double n[3];
            for (double& value : n)
                if (!toDouble(nextWord(rest), value))
                    reader.failAt(lines.lineNumber(), "a normal needs 3 numbers");
            fileNormals.emplace_back(static_cast<float>(n[0]), static_cast<float>(n[1]), static_cast<float>(n[2]));
        } else if (keyword == "f") {
            corners.clear();
            for (std::string_view word = nextWord(rest); !word.empty(); word = nextWord(rest)) {
                const std::size_t slash = word.find('/');
                long long index;
                if (!toInteger(word.substr(0, slash), index))
                    reader.failAt(lines.lineNumber(), "not a vertex index: " + quoted(word));
                const std::uint64_t vertex = resolve(index, parts.vertices.size(), "vertex");
                corners.push_back(static_cast<std::uint32_t>(vertex));
                const std::size_t second = slash == std::string_view::npos ? slash : word.find('/', slash + 1);
                if (second == std::string_view::npos) {
                    everyCornerHasNormal = false;
                    continue;
                }
                long long normalIndex;
                if (!toInteger(word.substr(second + 1), normalIndex))
                    reader.failAt(lines.lineNumber(), "not a normal index: " + quoted(word));
                normalOfVertex[vertex] = static_cast<std::int64_t>(resolve(normalIndex, fileNormals.size(), "normal"));
            }
            if (corners.size() < 3)
                reader.failAt(lines.lineNumber(), "a face needs at least 3 vertices");
            addFan(corners, parts.triangles);
        }
    }
    if (allVerticesColoured && !parts.vertices.empty())
        parts.colors.resize(parts.vertices.size());
    else
        parts.colors.clear();
    if (everyCornerHasNormal && !parts.triangles.empty()) {
        parts.normals.assign(parts.vertices.size(), Eigen::Vector3f::Zero());
        for (std::size_t v = 0; v < parts.vertices.size(); ++v)
            if (normalOfVertex[v] >= 0)
                parts.normals[v] = fileNormals[static_cast<std::size_t>(normalOfVertex[v])];
    }
    return parts;
}

// ------------------------------------------------------------------- OFF

//! OFF and its variants (Princeton's and Geomview's): a first line OFF,
//! COFF, NOFF, CNOFF (optionally with the counts on it), then
//! `vertices faces edges`, the vertices (x y z, then nx ny nz with N, then a
//! colour with C), then the faces (`k i1 ... ik`, then an optional colour).
//! Comments start with '#'. The binary variant is refused with a message.
MeshParts readOff(Reader& reader)
{
    TextLines lines(reader.file().view());
    std::string_view line;
    // The next non-empty, non-comment line, comments cut off.
    const auto nextContent = [&](std::string_view& content) {
        while (lines.next(line)) {
            const std::size_t hash = line.find('#');
            content = line.substr(0, hash);
            std::size_t i = 0;
            while (i < content.size() && isSpace(content[i]))
                ++i;
            if (i < content.size())
                return true;
        }
        return false;
    };
    std::string_view content;
    if (!nextContent(content))
        reader.fail("empty file");
    const std::string_view keyword = nextWord(content);
    if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF")
        reader.fail("not an OFF file: it starts with " + quoted(keyword));
    const std::string_view prefix = keyword.substr(0, keyword.size() - 3);
    const bool hasColours = prefix.find('C') != std::string_view::npos;
    const bool hasNormals = prefix.find('N') != std::string_view::npos;
    if (prefix.find_first_not_of("CN") != std::string_view::npos)
        reader.fail("the OFF variant " + quoted(keyword) + " is not read (texture coordinates, 4D or n-dimensional)");
    std::string_view counts = content;
    if (nextWord(counts) == "BINARY")
        reader.fail("binary OFF is not read; save it as text OFF, PLY or OBJ");
    counts = content;
    std::string_view probe = counts;
    if (nextWord(probe).empty() && !nextContent(counts))
        reader.fail("no vertex and face counts after " + quoted(keyword));
    long long vertexCount, faceCount;
    if (!toInteger(nextWord(counts), vertexCount) || !toInteger(nextWord(counts), faceCount) || vertexCount < 0 || faceCount < 0)
        reader.failAt(lines.lineNumber(), "the counts of vertices and faces must be two non-negative integers");
    // The shortest vertex line is "0 0 0\n" (6 bytes), the shortest face "3 0 0 0\n" (8).
    const std::uint64_t remaining = reader.file().size() - lines.offset();
    if (static_cast<std::uint64_t>(vertexCount) > remaining / 6 ||
        static_cast<std::uint64_t>(faceCount) > (remaining - 6 * static_cast<std::uint64_t>(vertexCount)) / 8)
        reader.fail("the header announces " + std::to_string(vertexCount) + " vertices and " + std::to_string(faceCount) +
                    " faces, more than the " + std::to_string(remaining) + " bytes left can hold");
    if (static_cast<std::uint64_t>(vertexCount) > kMaxVertices)
        reader.fail("more than 4,294,967,295 vertices");

    MeshParts parts;
    parts.vertices.reserve(static_cast<std::size_t>(vertexCount));
    if (hasNormals)
        parts.normals.reserve(static_cast<std::size_t>(vertexCount));
    std::vector<Rgb8> colours;
    bool allColoured = hasColours;
    for (long long v = 0; v < vertexCount; ++v) {
        if (!nextContent(content))
            reader.fail("truncated: " + std::to_string(v) + " of " + std::to_string(vertexCount) + " vertices");
        reader.consumed(lines.offset());
        double x[10];
        int count = 0;
        for (std::string_view word = nextWord(content); !word.empty() && count < 10; word = nextWord(content)) {
            if (!toDouble(word, x[count]))
                reader.failAt(lines.lineNumber(), "not a number: " + quoted(word));
            ++count;
        }
        const int needed = 3 + (hasNormals ? 3 : 0);
        if (count < needed)
            reader.failAt(lines.lineNumber(), "a vertex needs " + std::to_string(needed) + " numbers");
        parts.vertices.emplace_back(x[0], x[1], x[2]);
        if (hasNormals)
            parts.normals.emplace_back(static_cast<float>(x[3]), static_cast<float>(x[4]), static_cast<float>(x[5]));
        if (allColoured) {
            // A colour as 3 or 4 numbers, integers in 0..255 or reals in 0..1.
            const int first = needed, channels = count - needed;
            if (channels < 3) {
                allColoured = false;
                continue;
            }
            // Integers when any channel, alpha included (ours writes 255), exceeds 1.
            const bool integers = x[first] > 1 || x[first + 1] > 1 || x[first + 2] > 1 || (channels > 3 && x[first + 3] > 1);
            Rgb8 c;
            std::uint8_t* out[3] = {&c.r, &c.g, &c.b};
            for (int k = 0; k < 3; ++k) {
                const double value = std::isfinite(x[first + k]) ? x[first + k] : 0.0;
                *out[k] = static_cast<std::uint8_t>(std::lround(std::clamp(integers ? value : value * 255.0, 0.0, 255.0)));
            }
            colours.push_back(c);
        }
    }
    if (allColoured && colours.size() == parts.vertices.size())
        parts.colors = std::move(colours);

    std::vector<std::uint32_t> corners;
    for (long long f = 0; f < faceCount; ++f) {
        if (!nextContent(content))
            reader.fail("truncated: " + std::to_string(f) + " of " + std::to_string(faceCount) + " faces");
        reader.consumed(lines.offset());
        long long k;
        if (!toInteger(nextWord(content), k) || k < 0)
            reader.failAt(lines.lineNumber(), "a face starts with its number of vertices");
        // Each index needs at least two characters of the line: a count beyond
        // that is a lie, refused before anything is allocated.
        if (static_cast<std::uint64_t>(k) > content.size() / 2 + 1)
            reader.failAt(lines.lineNumber(), "a face announces " + std::to_string(k) + " vertices but the line is shorter");
        corners.clear();
        for (long long c = 0; c < k; ++c) {
            long long index;
            if (!toInteger(nextWord(content), index))
                reader.failAt(lines.lineNumber(), "a face announces " + std::to_string(k) + " vertices but lists fewer");
            if (index < 0 || index >= vertexCount)
                reader.failAt(lines.lineNumber(), "vertex index " + std::to_string(index) + " out of range (" +
                                                      std::to_string(vertexCount) + " vertices)");
            corners.push_back(static_cast<std::uint32_t>(index));
        }
        // Points and edges listed as faces (k < 3) carry no surface: read past.
        addFan(corners, parts.triangles);
    }
    return parts;
}

// ------------------------------------------------------------------- STL

//! Shared corners merged: STL repeats the three corners of every facet, and a
//! surface needs them shared. Corners are merged when bit-identical (what
//! every STL writer gives for a shared vertex); facet normals are dropped
//! (one per facet, they would keep shared vertices apart).
class CornerMerger
{
public:
    explicit CornerMerger(MeshParts& parts) : parts_(parts) {}
    std::uint32_t add(const Eigen::Vector3d& p)
    {
        Key key{p.x(), p.y(), p.z()};
        const auto [it, inserted] = index_.try_emplace(key, static_cast<std::uint32_t>(parts_.vertices.size()));
        if (inserted)
            parts_.vertices.push_back(p);
        return it->second;
    }

private:
    struct Key
    {
        double x, y, z;
        bool operator==(const Key& o) const
        {
            return std::memcmp(this, &o, sizeof(Key)) == 0; // bit-identical (0.0 and -0.0 kept apart)
        }
    };
    struct Hash
    {
        std::size_t operator()(const Key& k) const
        {
            std::uint64_t h = 0xcbf29ce484222325ull, bits;
            for (double v : {k.x, k.y, k.z}) {
                std::memcpy(&bits, &v, sizeof bits);
                h = (h ^ bits) * 0x100000001b3ull;
                h ^= h >> 29;
            }
            return static_cast<std::size_t>(h);
        }
    };
    MeshParts& parts_;
    std::unordered_map<Key, std::uint32_t, Hash> index_;
};

MeshParts readBinaryStl(Reader& reader)
{
    const char* data = reader.file().data();
    std::uint32_t count;
    std::memcpy(&count, data + 80, 4);
    MeshParts parts;
    parts.triangles.reserve(count);
    CornerMerger merger(parts);
    for (std::uint32_t t = 0; t < count; ++t) {
        const char* record = data + 84 + 50 * static_cast<std::size_t>(t);
        float values[12];
        std::memcpy(values, record, sizeof values);
        Triangle triangle;
        for (int c = 0; c < 3; ++c)
            triangle[static_cast<std::size_t>(c)] = merger.add(Eigen::Vector3d(values[3 + 3 * c], values[4 + 3 * c], values[5 + 3 * c]));
        parts.triangles.push_back(triangle);
        reader.consumed(84 + 50 * static_cast<std::size_t>(t));
    }
    return parts;
}

MeshParts readAsciiStl(Reader& reader)
{
    MeshParts parts;
    CornerMerger merger(parts);
    TextLines lines(reader.file().view());
    std::string_view line;
    std::uint32_t corners[3];
    int cornerCount = 0;
    while (lines.next(line)) {
        reader.consumed(lines.offset());
        std::string_view rest = line;
        const std::string_view keyword = nextWord(rest);
        if (keyword == "vertex") {
            double p[3];
            for (double& value : p)
                if (!toDouble(nextWord(rest), value))
                    reader.failAt(lines.lineNumber(), "a vertex needs 3 numbers");
            if (cornerCount == 3)
                reader.failAt(lines.lineNumber(), "a facet with more than 3 vertices");
            corners[cornerCount++] = merger.add(Eigen::Vector3d(p[0], p[1], p[2]));
        } else if (keyword == "endloop" || keyword == "endfacet") {
            if (cornerCount == 3)
                parts.triangles.push_back({corners[0], corners[1], corners[2]});
            else if (cornerCount != 0)
                reader.failAt(lines.lineNumber(), "a facet with " + std::to_string(cornerCount) + " vertices");
            cornerCount = 0;
        }
    }
    if (cornerCount != 0)
        reader.fail("truncated inside a facet");
    return parts;
}

//! Binary when the size is exactly that of the count in its header (an ASCII
//! file may start with "solid" too, and binary ones often do); ASCII when it
//! starts with "solid" and says "facet"; otherwise an error.
MeshParts readStl(Reader& reader)
{
    const std::size_t size = reader.file().size();
    if (size >= 84) {
        std::uint32_t count;
        std::memcpy(&count, reader.file().data() + 80, 4);
        if (84 + 50 * static_cast<std::uint64_t>(count) == size)
            return readBinaryStl(reader);
    }
    const std::string_view text = reader.file().view();
    std::size_t i = 0;
    while (i < text.size() && (isSpace(text[i]) || text[i] == '\n'))
        ++i;
    if (text.substr(i, 5) == "solid" && text.find("facet", i) != std::string_view::npos)
        return readAsciiStl(reader);
    if (size >= 84) {
        std::uint32_t count;
        std::memcpy(&count, reader.file().data() + 80, 4);
        reader.fail("not an STL file: a binary STL of " + std::to_string(count) + " triangles is " +
                    std::to_string(84 + 50 * static_cast<std::uint64_t>(count)) + " bytes, this one is " + std::to_string(size));
    }
    reader.fail("not an STL file (too short for binary, no 'solid ... facet' for ASCII)");
}

} // namespace

Mesh meshFromParts(MeshParts parts, const fs::path& path, const ReadOptions& options)
{
    auto fail = [&](const std::string& message) { throw Error(ErrorCode::InvalidData, path.string() + ": " + message); };
    if (parts.triangles.empty())
        fail("the file holds no triangle");
    BoundingBox box;
    for (const auto& v : parts.vertices) {
        if (!v.allFinite())
            fail("a vertex has a non-finite coordinate");
        box.min = box.empty ? v : box.min.cwiseMin(v);
        box.max = box.empty ? v : box.max.cwiseMax(v);
        box.empty = false;
    }
    Mesh mesh;
    const Eigen::Vector3d origin = options.origin ? *options.origin : suggestOrigin(box);
    mesh.vertices.setOrigin(origin);
    mesh.vertices.resize(parts.vertices.size());
    auto& positions = mesh.vertices.positions();
    for (std::size_t i = 0; i < parts.vertices.size(); ++i)
        positions[i] = (parts.vertices[i] - origin).cast<float>();
    if (!parts.normals.empty())
        mesh.vertices.enableNormals() = std::move(parts.normals);
    if (!parts.colors.empty())
        mesh.vertices.enableColors() = std::move(parts.colors);
    for (ScalarField& field : parts.fields)
        mesh.vertices.addField(std::move(field));
    mesh.triangles = std::move(parts.triangles);
    mesh.checkConsistency();
    return mesh;
}

Mesh readMeshFile(const fs::path& path, const ReadOptions& options)
{
    Reader reader(path, options);
    const std::string ext = lowerExtension(path);
    MeshParts parts = ext == "obj" ? readObj(reader) : ext == "off" ? readOff(reader) : readStl(reader);
    Mesh mesh = meshFromParts(std::move(parts), path, options);
    reader.done();
    return mesh;
}

} // namespace scandiff::io::detail
