// SPDX-License-Identifier: GPL-3.0-or-later
//! DXF export (AutoCAD R12 / AC1009 ASCII): DxfDrawing, and the "dxf" format
//! handler that writes clouds as POINT entities and meshes as 3DFACEs (and
//! reads meshes back through DxfReader.cpp).
//!
//! R12 rather than a newer version: it needs no handles, owner references or
//! OBJECTS section, and it is the one version every CAD, GIS and survey program
//! imports. Its limits (symbol names of 31 characters from a small alphabet,
//! no true colour) do not matter for survey exports.

#include <scandiff/io/DxfWriter.h>

#include <map>

#include "dxf/DxfObjectAxes.h"
#include "internal/Formats.h"
#include "mesh/MeshReaders.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/Progress.h>
#include <scandiff/io/AtomicFile.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>
#include <string_view>

namespace scandiff::io {

namespace fs = std::filesystem;

struct DxfDrawing::Entity
{
    enum class Kind : unsigned char { Point, Polyline, ArcPolyline, Face, Text };
    Kind kind = Kind::Point;
    bool closed = false;
    bool planar = false;
    std::size_t layer = 0;       // index into layers_
    std::size_t firstVertex = 0; // range of vertices_
    std::size_t vertexCount = 0;
    double height = 0.0;
    std::string text;
    std::vector<double> bulges;                         // ArcPolyline: one per vertex
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ(); // ArcPolyline: its extrusion direction
};

namespace {

// R12 symbol names: letters, digits, '$', '-', '_' and at most 31 characters
// (AutoCAD R12 DXF reference, "Symbol table names"). Newer versions accept more,
// but these names are valid everywhere.
constexpr std::size_t kMaxSymbolName = 31;

std::string dxfSymbolName(const std::string& name, const char* fallback)
{
    std::string out;
    for (std::size_t i = 0; i < name.size() && out.size() < kMaxSymbolName; ++i) {
        const auto c = static_cast<unsigned char>(name[i]);
        if (c >= 0x80) {
            // One '_' per UTF-8 character, not per byte.
            while (i + 1 < name.size() && (static_cast<unsigned char>(name[i + 1]) & 0xC0) == 0x80)
                ++i;
            out += '_';
        } else if (std::isalnum(c) || c == '$' || c == '-' || c == '_') {
            out += static_cast<char>(c);
        } else {
            out += '_';
        }
    }
    return out.empty() ? std::string(fallback) : out;
}

bool sameSymbol(const std::string& a, const std::string& b)
{
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
               return std::toupper(static_cast<unsigned char>(x)) == std::toupper(static_cast<unsigned char>(y));
           });
}

// The Windows-1252 byte of a code point, or 0 when it has none: the drawing
// declares $DWGCODEPAGE ANSI_1252, the code page of most CAD installations.
unsigned char windows1252(unsigned codePoint)
{
    if (codePoint < 0x80 || (codePoint >= 0xA0 && codePoint <= 0xFF))
        return static_cast<unsigned char>(codePoint);
    // Bytes 0x80-0x9F of Windows-1252 (the rest of the range is undefined).
    static constexpr struct { unsigned short codePoint; unsigned char byte; } kHigh[] = {
        {0x20AC, 0x80}, {0x201A, 0x82}, {0x0192, 0x83}, {0x201E, 0x84}, {0x2026, 0x85}, {0x2020, 0x86},
        {0x2021, 0x87}, {0x02C6, 0x88}, {0x2030, 0x89}, {0x0160, 0x8A}, {0x2039, 0x8B}, {0x0152, 0x8C},
        {0x017D, 0x8E}, {0x2018, 0x91}, {0x2019, 0x92}, {0x201C, 0x93}, {0x201D, 0x94}, {0x2022, 0x95},
        {0x2013, 0x96}, {0x2014, 0x97}, {0x02DC, 0x98}, {0x2122, 0x99}, {0x0161, 0x9A}, {0x203A, 0x9B},
        {0x0153, 0x9C}, {0x017E, 0x9E}, {0x0178, 0x9F}};
    for (const auto& entry : kHigh)
        if (entry.codePoint == codePoint)
            return entry.byte;
    return 0;
}

// A TEXT value from UTF-8: one line, in Windows-1252, with the \U+XXXX escape
// (decoded by AutoCAD, GDAL and others) for characters outside that code page.
// "%%" starts a control code in AutoCAD text (%%d is a degree sign), so a
// literal "%%" is written as "%%%" (a percent sign) followed by "%".
std::string dxfText(const std::string& text)
{
    std::string out;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (c == '\n' || c == '\r' || c == '\t') {
            out += ' ';
            continue;
        }
        if (c < 0x20)
            continue;
        if (c == '%' && i + 1 < text.size() && text[i + 1] == '%') {
            out += "%%%";
            continue;
        }
        if (c < 0x80) {
            out += static_cast<char>(c);
            continue;
        }
        // Decode one UTF-8 sequence; a malformed one becomes '?'.
        const int extra = c >= 0xF8 ? -1 : c >= 0xF0 ? 3 : c >= 0xE0 ? 2 : c >= 0xC0 ? 1 : -1;
        if (extra < 0 || i + static_cast<std::size_t>(extra) >= text.size()) {
            out += '?';
            continue;
        }
        unsigned codePoint = c & (0x3Fu >> extra);
        bool wellFormed = true;
        for (int k = 1; k <= extra; ++k) {
            const auto next = static_cast<unsigned char>(text[i + static_cast<std::size_t>(k)]);
            wellFormed = wellFormed && (next & 0xC0) == 0x80;
            codePoint = (codePoint << 6) | (next & 0x3Fu);
        }
        if (!wellFormed) {
            out += '?';
            continue;
        }
        i += static_cast<std::size_t>(extra);
        if (const unsigned char byte = windows1252(codePoint)) {
            out += static_cast<char>(byte);
        } else {
            char escape[16];
            std::snprintf(escape, sizeof escape, "\\U+%04X", codePoint);
            out += escape;
        }
    }
    return out;
}

//! Group code / value pairs into a buffered stream.
class DxfOutput
{
public:
    explicit DxfOutput(std::ostream& stream) : stream_(stream) { buffer_.reserve(kFlushSize + 512); }

    void group(int code, std::string_view value)
    {
        writeCode(code);
        buffer_.append(value.data(), value.size());
        buffer_ += '\n';
        flushIfFull();
    }
    void group(int code, int value) { group(code, std::string_view(std::to_string(value))); }
    // Six decimals: micrometres, even at UTM (10^7 m) magnitudes where the
    // shortest round-trip form would switch to exponents.
    void real(int code, double value)
    {
        writeCode(code);
        // Room for the largest double in fixed notation (309 digits); "+ 0.0"
        // turns -0 into 0.
        char text[400];
        const auto result = std::to_chars(text, text + sizeof text, value + 0.0, std::chars_format::fixed, 6);
        buffer_.append(text, result.ptr);
        buffer_ += '\n';
        flushIfFull();
    }
    // The shortest text that reads back to the same double: for a bulge,
    // whose six decimals would move an arc's end by 1e-7 of its chord.
    void exact(int code, double value)
    {
        writeCode(code);
        char text[64];
        const auto result = std::to_chars(text, text + sizeof text, value + 0.0);
        buffer_.append(text, result.ptr);
        buffer_ += '\n';
        flushIfFull();
    }
    // A point as the groups base, base+10, base+20 (x, y, z).
    void point(int base, const Eigen::Vector3d& p)
    {
        real(base, p.x());
        real(base + 10, p.y());
        real(base + 20, p.z());
    }
    void flush()
    {
        stream_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
        buffer_.clear();
    }

private:
    static constexpr std::size_t kFlushSize = 1u << 20;

    // Group codes right-aligned on 3 characters, as AutoCAD writes them.
    void writeCode(int code)
    {
        char text[16];
        const int n = std::snprintf(text, sizeof text, "%3d\n", code);
        buffer_.append(text, static_cast<std::size_t>(n));
    }
    void flushIfFull()
    {
        if (buffer_.size() >= kFlushSize)
            flush();
    }

    std::ostream& stream_;
    std::string buffer_;
};

void beginDocument(DxfOutput& out, const std::vector<DxfDrawing::Layer>& layers, const BoundingBox& extents)
{
    out.group(0, "SECTION");
    out.group(2, "HEADER");
    out.group(9, "$ACADVER");
    out.group(1, "AC1009");
    out.group(9, "$DWGCODEPAGE");
    out.group(3, "ANSI_1252");
    out.group(9, "$INSBASE");
    out.point(10, Eigen::Vector3d::Zero());
    // Extents let viewers "zoom to extents" straight away.
    const Eigen::Vector3d lo = extents.empty ? Eigen::Vector3d::Zero() : extents.min;
    const Eigen::Vector3d hi = extents.empty ? Eigen::Vector3d::Zero() : extents.max;
    out.group(9, "$EXTMIN");
    out.point(10, lo);
    out.group(9, "$EXTMAX");
    out.point(10, hi);
    out.group(0, "ENDSEC");

    out.group(0, "SECTION");
    out.group(2, "TABLES");
    out.group(0, "TABLE");
    out.group(2, "LTYPE");
    out.group(70, 1);
    out.group(0, "LTYPE");
    out.group(2, "CONTINUOUS");
    out.group(70, 0);
    out.group(3, "Solid line");
    out.group(72, 65);
    out.group(73, 0);
    out.real(40, 0.0);
    out.group(0, "ENDTAB");

    out.group(0, "TABLE");
    out.group(2, "LAYER");
    out.group(70, static_cast<int>(layers.size()));
    for (const auto& layer : layers) {
        out.group(0, "LAYER");
        out.group(2, layer.name);
        out.group(70, 0);
        out.group(62, layer.color);
        out.group(6, "CONTINUOUS");
    }
    out.group(0, "ENDTAB");

    out.group(0, "TABLE");
    out.group(2, "STYLE");
    out.group(70, 1);
    out.group(0, "STYLE");
    out.group(2, "STANDARD");
    out.group(70, 0);
    out.real(40, 0.0); // 0: the height comes from each TEXT
    out.real(41, 1.0);
    out.real(50, 0.0);
    out.group(71, 0);
    out.real(42, 2.5);
    out.group(3, "txt");
    out.group(4, "");
    out.group(0, "ENDTAB");
    out.group(0, "ENDSEC");

    out.group(0, "SECTION");
    out.group(2, "BLOCKS");
    out.group(0, "ENDSEC");

    out.group(0, "SECTION");
    out.group(2, "ENTITIES");
}

void endDocument(DxfOutput& out)
{
    out.group(0, "ENDSEC");
    out.group(0, "EOF");
    out.flush();
}

void writePoint(DxfOutput& out, const std::string& layer, const Eigen::Vector3d& p)
{
    out.group(0, "POINT");
    out.group(8, layer);
    out.point(10, p);
}

void writeFace(DxfOutput& out, const std::string& layer, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
               const Eigen::Vector3d& c)
{
    out.group(0, "3DFACE");
    out.group(8, layer);
    out.point(10, a);
    out.point(11, b);
    out.point(12, c);
    out.point(13, c); // a triangle repeats its third corner
}

// R12 POLYLINE (flag 1: closed, 8: 3D polyline) followed by VERTEX entities
// (flag 32: 3D polyline vertex) and SEQEND. A 2D polyline holds its elevation in
// the POLYLINE's z; its vertices repeat it.
void writePolyline(DxfOutput& out, const std::string& layer, const Eigen::Vector3d* vertices, std::size_t count,
                   bool closed, bool planar)
{
    const double elevation = planar ? vertices[0].z() : 0.0;
    out.group(0, "POLYLINE");
    out.group(8, layer);
    out.group(66, 1);
    out.point(10, Eigen::Vector3d(0.0, 0.0, elevation));
    out.group(70, (closed ? 1 : 0) | (planar ? 0 : 8));
    for (std::size_t i = 0; i < count; ++i) {
        out.group(0, "VERTEX");
        out.group(8, layer);
        out.point(10, vertices[i]);
        out.group(70, planar ? 0 : 32);
    }
    out.group(0, "SEQEND");
    out.group(8, layer);
}

// An R12 2D POLYLINE in its object coordinate system (extrusion 210/220/230,
// elevation in the POLYLINE's z), each VERTEX with its bulge (42): how DXF
// draws arcs. `vertices` are object coordinates at that elevation.
void writeArcPolyline(DxfOutput& out, const std::string& layer, const Eigen::Vector3d* vertices, std::size_t count,
                      const std::vector<double>& bulges, const Eigen::Vector3d& normal, bool closed)
{
    out.group(0, "POLYLINE");
    out.group(8, layer);
    out.group(66, 1);
    out.point(10, Eigen::Vector3d(0.0, 0.0, vertices[0].z()));
    out.group(70, closed ? 1 : 0);
    // In full: at UTM magnitudes a direction rounded to 6 decimals turns the
    // object axes enough to move the vertices by metres.
    out.exact(210, normal.x());
    out.exact(220, normal.y());
    out.exact(230, normal.z());
    for (std::size_t i = 0; i < count; ++i) {
        out.group(0, "VERTEX");
        out.group(8, layer);
        out.point(10, vertices[i]);
        if (bulges[i] != 0.0)
            out.exact(42, bulges[i]);
        out.group(70, 0);
    }
    out.group(0, "SEQEND");
    out.group(8, layer);
}

void writeText(DxfOutput& out, const std::string& layer, const Eigen::Vector3d& position, double height,
               const std::string& text)
{
    out.group(0, "TEXT");
    out.group(8, layer);
    out.point(10, position);
    out.real(40, height);
    out.group(1, text);
    out.group(7, "STANDARD");
}

// The layer table of a cloud or mesh export: "0", which every drawing has, and
// the entity's own layer.
std::vector<DxfDrawing::Layer> exportLayers(const std::string& layer)
{
    std::vector<DxfDrawing::Layer> layers{{"0", 7}};
    if (!sameSymbol(layer, "0"))
        layers.push_back({layer, 7});
    return layers;
}

[[noreturn]] void invalidArgument(const std::string& what)
{
    throw Error(ErrorCode::InvalidArgument, "DXF drawing: " + what);
}

void requireFinite(const Eigen::Vector3d& p, const char* entity)
{
    if (!p.allFinite())
        invalidArgument(std::string(entity) + " with a non-finite coordinate");
}

} // namespace

DxfDrawing::DxfDrawing() = default;
DxfDrawing::~DxfDrawing() = default;
DxfDrawing::DxfDrawing(DxfDrawing&&) noexcept = default;
DxfDrawing& DxfDrawing::operator=(DxfDrawing&&) noexcept = default;

std::size_t DxfDrawing::layerIndex(const std::string& name, int colorIndex)
{
    const std::string symbol = dxfSymbolName(name, "0");
    for (std::size_t i = 0; i < layers_.size(); ++i)
        if (sameSymbol(layers_[i].name, symbol))
            return i;
    layers_.push_back(Layer{symbol, colorIndex});
    return layers_.size() - 1;
}

std::size_t DxfDrawing::addVertices(const Eigen::Vector3d* first, std::size_t count)
{
    const std::size_t start = vertices_.size();
    vertices_.insert(vertices_.end(), first, first + count);
    return start;
}

void DxfDrawing::addLayer(const std::string& name, int colorIndex)
{
    // ACI 0 (BYBLOCK) and 256 (BYLAYER) are not layer colours.
    if (colorIndex < 1 || colorIndex > 255)
        invalidArgument("layer '" + name + "': colour index " + std::to_string(colorIndex) + " is outside 1..255");
    layerIndex(name, colorIndex);
}

void DxfDrawing::addPoint(const std::string& layer, const Eigen::Vector3d& p)
{
    requireFinite(p, "point");
    Entity e;
    e.kind = Entity::Kind::Point;
    e.layer = layerIndex(layer);
    e.firstVertex = addVertices(&p, 1);
    e.vertexCount = 1;
    entities_.push_back(std::move(e));
}

void DxfDrawing::addPolyline(const std::string& layer, const std::vector<Eigen::Vector3d>& vertices, bool closed,
                             bool planar)
{
    if (vertices.size() < 2)
        invalidArgument("a polyline needs at least 2 vertices, got " + std::to_string(vertices.size()));
    for (const auto& v : vertices) {
        requireFinite(v, "polyline vertex");
        if (planar && v.z() != vertices.front().z())
            invalidArgument("planar polyline with vertices at different elevations (" +
                            std::to_string(vertices.front().z()) + " and " + std::to_string(v.z()) + ")");
    }
    Entity e;
    e.kind = Entity::Kind::Polyline;
    e.closed = closed;
    e.planar = planar;
    e.layer = layerIndex(layer);
    e.firstVertex = addVertices(vertices.data(), vertices.size());
    e.vertexCount = vertices.size();
    entities_.push_back(std::move(e));
}

void DxfDrawing::addArcPolyline(const std::string& layer, const std::vector<Eigen::Vector3d>& vertices, const std::vector<double>& bulges,
                                const Eigen::Vector3d& normal, bool closed)
{
    if (vertices.size() < 2 || bulges.size() != vertices.size())
        invalidArgument("an arc polyline needs at least 2 vertices and one bulge per vertex");
    if (!(normal.norm() > 0) || !normal.allFinite())
        invalidArgument("an arc polyline needs the normal of its plane");
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        requireFinite(vertices[i], "polyline vertex");
        if (!std::isfinite(bulges[i]))
            invalidArgument("a bulge is not finite");
    }
    const Eigen::Vector3d n = normal.normalized();
    const Eigen::Matrix3d axes = detail::dxfObjectAxes(n);
    std::vector<Eigen::Vector3d> local;
    local.reserve(vertices.size());
    for (const Eigen::Vector3d& v : vertices)
        local.emplace_back(v.dot(axes.col(0)), v.dot(axes.col(1)), v.dot(n));
    const double elevation = local.front().z();
    for (const Eigen::Vector3d& q : local)
        if (std::abs(q.z() - elevation) > 1e-6 + 1e-12 * std::abs(elevation))
            invalidArgument("an arc polyline's vertices are not in one plane normal to its extrusion direction");
    for (Eigen::Vector3d& q : local)
        q.z() = elevation;
    Entity e;
    e.kind = Entity::Kind::ArcPolyline;
    e.closed = closed;
    e.layer = layerIndex(layer);
    e.firstVertex = addVertices(local.data(), local.size());
    e.vertexCount = local.size();
    e.bulges = bulges;
    e.normal = n;
    entities_.push_back(std::move(e));
}

void DxfDrawing::add3dFace(const std::string& layer, const std::array<Eigen::Vector3d, 3>& corners)
{
    for (const auto& c : corners)
        requireFinite(c, "3DFACE corner");
    Entity e;
    e.kind = Entity::Kind::Face;
    e.layer = layerIndex(layer);
    e.firstVertex = addVertices(corners.data(), 3);
    e.vertexCount = 3;
    entities_.push_back(std::move(e));
}

void DxfDrawing::addText(const std::string& layer, const Eigen::Vector3d& position, double height,
                         const std::string& text)
{
    requireFinite(position, "text");
    if (!(height > 0.0) || !std::isfinite(height))
        invalidArgument("text height " + std::to_string(height) + " must be a positive number");
    Entity e;
    e.kind = Entity::Kind::Text;
    e.layer = layerIndex(layer);
    e.firstVertex = addVertices(&position, 1);
    e.vertexCount = 1;
    e.height = height;
    e.text = dxfText(text);
    entities_.push_back(std::move(e));
}

void DxfDrawing::write(const fs::path& path) const
{
    // Layer "0" always exists in a DXF drawing; readers expect it in the table.
    std::vector<Layer> layers = layers_;
    if (std::none_of(layers.begin(), layers.end(), [](const Layer& l) { return l.name == "0"; }))
        layers.insert(layers.begin(), Layer{"0", 7});

    BoundingBox extents;
    if (!vertices_.empty()) {
        extents.min = extents.max = vertices_.front();
        extents.empty = false;
        for (const auto& v : vertices_) {
            extents.min = extents.min.cwiseMin(v);
            extents.max = extents.max.cwiseMax(v);
        }
    }

    AtomicFile file(path);
    DxfOutput out(file.stream());
    beginDocument(out, layers, extents);
    for (const Entity& e : entities_) {
        const std::string& layer = layers_[e.layer].name;
        const Eigen::Vector3d* v = vertices_.data() + e.firstVertex;
        switch (e.kind) {
        case Entity::Kind::Point: writePoint(out, layer, v[0]); break;
        case Entity::Kind::Polyline: writePolyline(out, layer, v, e.vertexCount, e.closed, e.planar); break;
        case Entity::Kind::ArcPolyline: writeArcPolyline(out, layer, v, e.vertexCount, e.bulges, e.normal, e.closed); break;
        case Entity::Kind::Face: writeFace(out, layer, v[0], v[1], v[2]); break;
        case Entity::Kind::Text: writeText(out, layer, v[0], e.height, e.text); break;
        }
    }
    endDocument(out);
    file.commit();
}

namespace detail {

namespace {

void writeCloudDxf(const PointCloud& cloud, const fs::path& path, const WriteOptions& options)
{
    const std::string layer = dxfSymbolName(cloud.name, "points");
    const std::size_t n = cloud.size();
    std::size_t skipped = 0;
    AtomicFile file(path);
    DxfOutput out(file.stream());
    beginDocument(out, exportLayers(layer), cloud.bounds());
    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), n);
    constexpr std::size_t kChunk = 1u << 14;
    for (std::size_t begin = 0; begin < n; begin += kChunk) {
        const std::size_t end = std::min(n, begin + kChunk);
        for (std::size_t i = begin; i < end; ++i) {
            if (!cloud.positions()[i].allFinite()) {
                ++skipped;
                continue;
            }
            writePoint(out, layer, cloud.globalPosition(i));
        }
        ticker.step(end - begin);
    }
    endDocument(out);
    file.commit();
    if (skipped > 0)
        logWarning(path.string() + ": " + std::to_string(skipped) +
                   " points with non-finite coordinates were not written");
}

void writeMeshDxf(const Mesh& mesh, const fs::path& path, const WriteOptions& options)
{
    const std::string layer = dxfSymbolName(mesh.name, "mesh");
    const PointCloud& vertices = mesh.vertices;
    std::size_t skipped = 0;
    AtomicFile file(path);
    DxfOutput out(file.stream());
    beginDocument(out, exportLayers(layer), vertices.bounds());
    const std::size_t n = mesh.triangles.size();
    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), n);
    constexpr std::size_t kChunk = 1u << 14;
    for (std::size_t begin = 0; begin < n; begin += kChunk) {
        const std::size_t end = std::min(n, begin + kChunk);
        for (std::size_t t = begin; t < end; ++t) {
            const Triangle& tri = mesh.triangles[t];
            if (!vertices.positions()[tri[0]].allFinite() || !vertices.positions()[tri[1]].allFinite() ||
                !vertices.positions()[tri[2]].allFinite()) {
                ++skipped;
                continue;
            }
            writeFace(out, layer, vertices.globalPosition(tri[0]), vertices.globalPosition(tri[1]),
                      vertices.globalPosition(tri[2]));
        }
        ticker.step(end - begin);
    }
    endDocument(out);
    file.commit();
    if (skipped > 0)
        logWarning(path.string() + ": " + std::to_string(skipped) +
                   " triangles with a non-finite vertex were not written");
}

} // namespace

FormatHandler dxfFormat()
{
    FormatHandler handler;
    handler.name = "DXF";
    handler.extensions = {"dxf"};
    // Reading takes the meshes (DxfReader.cpp): CAD models to compare scans with.
    handler.read = [](const fs::path& path, const ReadOptions& options) -> Entity { return readDxfMesh(path, options); };
    handler.writeCloud = [](const PointCloud& cloud, const fs::path& path, const WriteOptions& options) {
        writeCloudDxf(cloud, path, options);
    };
    handler.writeMesh = [](const Mesh& mesh, const fs::path& path, const WriteOptions& options) {
        writeMeshDxf(mesh, path, options);
    };
    return handler;
}

} // namespace detail

void writeDrawingDxf(const Drawing& drawing, const std::filesystem::path& path)
{
    DxfDrawing dxf;
    std::map<std::string, int> colours;
    auto declare = [&](const std::string& layer) {
        if (colours.count(layer))
            return;
        // Six plain AutoCAD colours (red, yellow, green, cyan, blue, magenta) in turn.
        const int colour = 1 + static_cast<int>(colours.size() % 6);
        colours[layer] = colour;
        dxf.addLayer(layer, colour);
    };
    for (const DrawingPolyline& line : drawing.polylines) {
        if (line.points.size() < 2)
            continue;
        declare(line.layer);
        const bool arcs = line.bulges.size() == line.points.size() &&
                          std::any_of(line.bulges.begin(), line.bulges.end(), [](double b) { return b != 0.0; });
        if (arcs) {
            try {
                dxf.addArcPolyline(line.layer, line.points, line.bulges, line.normal, line.closed);
                continue;
            } catch (const Error&) {
                // Not planar: its arcs as points along them, in 3D.
            }
            if (!(line.normal.norm() > 0))
                logWarning("DXF: a polyline on layer " + line.layer + " has arcs but no plane: written with straight segments");
            dxf.addPolyline(line.layer, polylineVertices(line), line.closed);
            continue;
        }
        dxf.addPolyline(line.layer, line.points, line.closed);
    }
    for (const DrawingText& text : drawing.texts) {
        declare(text.layer);
        dxf.addText(text.layer, text.position, text.height, text.text);
    }
    dxf.write(path);
}

} // namespace scandiff::io
