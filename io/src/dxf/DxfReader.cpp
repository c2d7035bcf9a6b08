// SPDX-License-Identifier: GPL-3.0-or-later
//! The meshes of an ASCII DXF file, for comparing scans with CAD models:
//! 3DFACE entities, and POLYLINEs that are polyface meshes (flag 64: vertices,
//! then faces of up to four 1-based vertex indices) or polygon meshes (flag
//! 16: an M x N grid of vertices, possibly closed in either direction), in
//! the ENTITIES section. Layout facts from Autodesk's "DXF Reference"
//! (AutoCAD 2012), sections 3DFACE, POLYLINE and VERTEX. Written here: GDAL's
//! DXF driver reads these as 2.5D polygons through OGR and drops polyface
//! connectivity, and no other DXF library is packaged for Debian 12.
//!
//! Block definitions are not expanded (INSERT references are counted and
//! reported), nor are the newer MESH entity and binary DXF (refused clearly).

#include "dxf/DxfObjectAxes.h"
#include "internal/MappedFile.h"
#include "mesh/MeshReaders.h"
#include "internal/TextUtil.h"

#include <scandiff/io/DxfReader.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/Progress.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace scandiff::io::detail {

namespace fs = std::filesystem;

namespace {

constexpr std::uint64_t kMaxVertices = std::numeric_limits<std::uint32_t>::max();

//! One group: a code and its value, with the line of the code.
struct Group
{
    int code = 0;
    std::string_view value;
    std::size_t line = 0;
};

//! The groups of an ASCII DXF, two lines each.
class Groups
{
public:
    Groups(const fs::path& path, std::string_view text) : path_(path), text_(text) {}

    [[noreturn]] void fail(std::size_t line, const std::string& message) const
    {
        throw Error(ErrorCode::InvalidData, path_.string() + ": line " + std::to_string(line) + ": " + message);
    }

    bool next(Group& group)
    {
        std::string_view codeLine, valueLine;
        if (!line(codeLine))
            return false;
        group.line = number_;
        const std::string_view code = trim(codeLine);
        const auto [end, error] = std::from_chars(code.data(), code.data() + code.size(), group.code);
        if (error != std::errc() || end != code.data() + code.size())
            fail(number_, "a group code must be an integer, not " + quoted(code));
        if (!line(valueLine))
            fail(number_, "the file ends after group code " + std::to_string(group.code) + ", without its value");
        group.value = trim(valueLine);
        return true;
    }

    std::size_t offset() const { return at_; }

private:
    static std::string_view trim(std::string_view s)
    {
        while (!s.empty() && (s.front() == ' ' || s.front() == '\t'))
            s.remove_prefix(1);
        while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
            s.remove_suffix(1);
        return s;
    }
    bool line(std::string_view& out)
    {
        if (at_ >= text_.size())
            return false;
        const std::size_t end = text_.find('\n', at_);
        const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
        out = text_.substr(at_, stop - at_);
        at_ = stop + 1;
        ++number_;
        return true;
    }

    fs::path path_;
    std::string_view text_;
    std::size_t at_ = 0;
    std::size_t number_ = 0;
};

//! An entity: its type, the line it starts on, and its groups.
struct Entity
{
    std::string_view type;
    std::size_t line = 0;
    std::vector<Group> groups;

    const Group* find(int code) const
    {
        for (const Group& g : groups)
            if (g.code == code)
                return &g;
        return nullptr;
    }
};

double number(const Groups& groups, const Entity& e, int code, double fallback)
{
    const Group* g = e.find(code);
    if (!g)
        return fallback;
    double v = 0;
    std::string_view s = g->value;
    if (!s.empty() && s.front() == '+')
        s.remove_prefix(1);
    const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (error != std::errc() || end != s.data() + s.size() || !std::isfinite(v))
        groups.fail(g->line, "group " + std::to_string(code) + " of " + std::string(e.type) + " must be a finite number, not " +
                                 quoted(g->value));
    return v;
}

long long integer(const Groups& groups, const Entity& e, int code, long long fallback)
{
    const double v = number(groups, e, code, static_cast<double>(fallback));
    if (v != std::floor(v) || std::abs(v) > 2147483647.0)
        groups.fail(e.find(code)->line, "group " + std::to_string(code) + " of " + std::string(e.type) + " must be an integer");
    return static_cast<long long>(v);
}

Eigen::Vector3d point(const Groups& groups, const Entity& e, int xCode)
{
    return {number(groups, e, xCode, 0.0), number(groups, e, xCode + 10, 0.0), number(groups, e, xCode + 20, 0.0)};
}

class MeshBuilder
{
public:
    MeshBuilder(const Groups& groups) : groups_(groups) {}

    double number(const Entity& e, int code, double fallback) const { return detail::number(groups_, e, code, fallback); }
    long long integer(const Entity& e, int code, long long fallback) const { return detail::integer(groups_, e, code, fallback); }
    Eigen::Vector3d point(const Entity& e, int xCode) const { return detail::point(groups_, e, xCode); }

    std::uint32_t layerOf(const Entity& e)
    {
        const Group* g = e.find(8);
        const std::string name = g ? std::string(g->value) : "0";
        const auto [it, added] = layers_.emplace(name, static_cast<std::uint32_t>(layerNames_.size()));
        if (added)
            layerNames_.push_back(name);
        return it->second;
    }

    //! A corner shared by every face of the same layer that uses the same coordinates.
    std::uint32_t corner(const Eigen::Vector3d& p, std::uint32_t layer, std::size_t line)
    {
        const std::array<double, 4> key{p.x(), p.y(), p.z(), double(layer)};
        const auto it = corners_.find(key);
        if (it != corners_.end())
            return it->second;
        return addVertex(p, layer, line, &key);
    }
    std::uint32_t addVertex(const Eigen::Vector3d& p, std::uint32_t layer, std::size_t line,
                            const std::array<double, 4>* key = nullptr)
    {
        if (parts.vertices.size() >= kMaxVertices)
            groups_.fail(line, "more than 2^32 - 1 vertices");
        const auto index = static_cast<std::uint32_t>(parts.vertices.size());
        parts.vertices.push_back(p);
        vertexLayers_.push_back(static_cast<float>(layer));
        if (key)
            corners_.emplace(*key, index);
        return index;
    }

    //! A face of 3 or 4 corners (a repeated corner makes a quad a triangle).
    void face(std::array<std::uint32_t, 4> c, std::size_t count)
    {
        std::vector<std::uint32_t> ring;
        for (std::size_t k = 0; k < count; ++k)
            if (ring.empty() || (c[k] != ring.back() && !(k + 1 == count && c[k] == ring.front())))
                ring.push_back(c[k]);
        for (std::size_t k = 1; k + 1 < ring.size(); ++k)
            parts.triangles.push_back({ring[0], ring[k], ring[k + 1]});
    }

    MeshParts finish()
    {
        ScalarField field("dxf_layer", vertexLayers_.size());
        field.values() = std::move(vertexLayers_);
        parts.fields.push_back(std::move(field));
        return std::move(parts);
    }
    const std::vector<std::string>& layerNames() const { return layerNames_; }

    MeshParts parts;

private:
    struct KeyHash
    {
        std::size_t operator()(const std::array<double, 4>& k) const
        {
            std::size_t h = 0;
            for (double v : k)
                h = h * 1000003u ^ std::hash<double>()(v);
            return h;
        }
    };
    const Groups& groups_;
    std::map<std::string, std::uint32_t> layers_;
    std::vector<std::string> layerNames_;
    std::vector<float> vertexLayers_;
    std::unordered_map<std::array<double, 4>, std::uint32_t, KeyHash> corners_;
};

//! A POLYLINE's vertices and faces (its VERTEX entities) into the mesh.
void addPolyline(MeshBuilder& mesh, const Groups& groups, const Entity& polyline, const std::vector<Entity>& vertices)
{
    const long long flags = mesh.integer(polyline, 70, 0);
    const std::uint32_t layer = mesh.layerOf(polyline);
    if (flags & 64) {
        // Polyface: vertices (flags 64 | 128) then faces (flag 128 alone),
        // whose groups 71-74 are 1-based vertex numbers, negative for an invisible edge.
        std::vector<std::uint32_t> index;
        for (const Entity& v : vertices) {
            const long long vflags = mesh.integer(v, 70, 0);
            if ((vflags & 128) && !(vflags & 64)) {
                std::array<std::uint32_t, 4> c{};
                std::size_t count = 0;
                for (int code = 71; code <= 74; ++code) {
                    const long long k = std::llabs(mesh.integer(v, code, 0));
                    if (k == 0)
                        continue;
                    if (static_cast<std::size_t>(k) > index.size())
                        groups.fail(v.line, "a polyface face uses vertex " + std::to_string(k) + " of " +
                                                std::to_string(index.size()));
                    c[count++] = index[static_cast<std::size_t>(k - 1)];
                }
                if (count >= 3)
                    mesh.face(c, count);
            } else {
                index.push_back(mesh.addVertex(mesh.point(v, 10), layer, v.line));
            }
        }
        return;
    }
    if (flags & 16) {
        // Polygon mesh: M x N vertices row by row, closed in M (flag 1) or N (flag 32).
        const long long m = mesh.integer(polyline, 71, 0), n = mesh.integer(polyline, 72, 0);
        if (m < 2 || n < 2 || static_cast<unsigned long long>(m) * static_cast<unsigned long long>(n) != vertices.size())
            groups.fail(polyline.line, "a polygon mesh of " + std::to_string(m) + " x " + std::to_string(n) + " vertices has " +
                                           std::to_string(vertices.size()));
        std::vector<std::uint32_t> index;
        for (const Entity& v : vertices)
            index.push_back(mesh.addVertex(mesh.point(v, 10), layer, v.line));
        const bool closedM = flags & 1, closedN = flags & 32;
        auto at = [&](long long i, long long j) { return index[static_cast<std::size_t>((i % m) * n + (j % n))]; };
        for (long long i = 0; i < (closedM ? m : m - 1); ++i)
            for (long long j = 0; j < (closedN ? n : n - 1); ++j)
                mesh.face({at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)}, 4);
    }
    // Other polylines are lines, not surfaces.
}


//! The ENTITIES section of an ASCII DXF, entity by entity: onEntity(e) for
//! each one outside a POLYLINE, onPolyline(polyline, vertices) for each
//! POLYLINE with the VERTEX entities after it, up to its SEQEND.
template <class OnEntity, class OnPolyline>
void walkEntities(Groups& groups, ProgressTicker& ticker, std::size_t fileSize, OnEntity&& onEntity, OnPolyline&& onPolyline)
{
    std::size_t reported = 0;
    bool inEntities = false;
    std::string_view section;
    Entity current, polyline;
    std::vector<Entity> polylineVertices;
    bool inPolyline = false;
    auto finishEntity = [&](const Entity& e) {
        if (e.type.empty() || !inEntities)
            return;
        if (inPolyline) {
            if (e.type == "VERTEX") {
                polylineVertices.push_back(e);
                return;
            }
            onPolyline(polyline, polylineVertices);
            inPolyline = false;
            polylineVertices.clear();
            if (e.type == "SEQEND")
                return;
        }
        if (e.type == "POLYLINE") {
            polyline = e;
            inPolyline = true;
        } else {
            onEntity(e);
        }
    };
    Group g;
    while (groups.next(g)) {
        if (groups.offset() >= reported + (1u << 16)) {
            ticker.step(groups.offset() - reported);
            reported = groups.offset();
        }
        if (g.code != 0) {
            if (current.type == "SECTION" && g.code == 2)
                section = g.value;
            current.groups.push_back(g);
            continue;
        }
        finishEntity(current);
        current = Entity{g.value, g.line, {}};
        if (g.value == "SECTION") {
            inEntities = false;
        } else if (g.value == "ENDSEC") {
            inEntities = false;
            section = {};
        } else if (g.value == "EOF") {
            break;
        }
        if (current.type != "SECTION" && section == "ENTITIES")
            inEntities = true;
    }
    finishEntity(current);
    if (inPolyline)
        onPolyline(polyline, polylineVertices);
    ticker.step(fileSize + 1 - reported);
}

std::string_view checkedText(const MappedFile& file, const fs::path& path)
{
    const std::string_view text = file.view();
    constexpr std::string_view kBinary = "AutoCAD Binary DXF";
    if (text.substr(0, kBinary.size()) == kBinary)
        throw Error(ErrorCode::Unsupported, path.string() + ": binary DXF cannot be read; save it as ASCII DXF");
    return text;
}

//! The world axes of an entity's object coordinate system, from its
//! extrusion direction (DXF Reference, "Arbitrary Axis Algorithm").
Eigen::Matrix3d objectAxes(const Groups& groups, const Entity& e)
{
    Eigen::Vector3d n(number(groups, e, 210, 0.0), number(groups, e, 220, 0.0), number(groups, e, 230, 1.0));
    if (!(n.norm() > 0))
        groups.fail(e.line, std::string(e.type) + " has a zero extrusion direction");
    return dxfObjectAxes(n.normalized());
}

} // namespace

Mesh readDxfMesh(const fs::path& path, const ReadOptions& options)
{
    MappedFile file(path);
    ProgressTicker ticker(options.progress, "Reading " + path.filename().string(), file.size() + 1);
    Groups groups(path, checkedText(file, path));
    MeshBuilder mesh(groups);
    std::size_t inserts = 0, meshEntities = 0;
    walkEntities(
        groups, ticker, file.size(),
        [&](const Entity& e) {
            if (e.type == "3DFACE") {
                const std::uint32_t layer = mesh.layerOf(e);
                std::array<std::uint32_t, 4> c{};
                for (int k = 0; k < 4; ++k) {
                    // A missing fourth corner repeats the third.
                    const int code = e.find(13) || k < 3 ? 10 + k : 12;
                    c[static_cast<std::size_t>(k)] = mesh.corner(mesh.point(e, code), layer, e.line);
                }
                mesh.face(c, 4);
            } else if (e.type == "INSERT") {
                ++inserts;
            } else if (e.type == "MESH") {
                ++meshEntities;
            }
        },
        [&](const Entity& polyline, const std::vector<Entity>& vertices) { addPolyline(mesh, groups, polyline, vertices); });
    if (inserts > 0)
        logWarning(path.string() + ": " + std::to_string(inserts) +
                   " block references (INSERT) were not expanded; explode them in the CAD program to read their faces");
    if (meshEntities > 0)
        logWarning(path.string() + ": " + std::to_string(meshEntities) +
                   " MESH entities were skipped (3DFACE and polyface or polygon-mesh POLYLINEs are read)");
    const std::vector<std::string> layers = mesh.layerNames();
    MeshParts parts = mesh.finish();
    if (parts.triangles.empty())
        throw Error(ErrorCode::InvalidData, path.string() +
                                                ": no surface in the ENTITIES section (3DFACE, or a polyface or polygon-mesh POLYLINE)");
    Mesh result = meshFromParts(std::move(parts), path, options);
    std::string names;
    for (std::size_t i = 0; i < layers.size(); ++i)
        names += (i ? ", " : "") + std::to_string(i) + " = " + layers[i];
    logInfo(path.string() + ": field dxf_layer: " + names);
    return result;
}

} // namespace scandiff::io::detail

namespace scandiff::io {

Drawing readDrawingDxf(const std::filesystem::path& path, ProgressObserver* progress)
{
    using namespace detail;
    MappedFile file(path);
    ProgressTicker ticker(progress, "Reading " + path.filename().string(), file.size() + 1);
    Groups groups(path, checkedText(file, path));
    Drawing drawing;
    std::size_t arcs = 0;
    // A polyline keeps its bulges, and its plane, only when it has an arc.
    auto keepArcs = [&arcs](DrawingPolyline& polyline, std::vector<double> bulge, const Eigen::Matrix3d& axes) {
        if (std::none_of(bulge.begin(), bulge.end(), [](double b) { return b != 0.0; }))
            return;
        polyline.bulges = std::move(bulge);
        polyline.normal = axes.col(2);
        ++arcs;
    };
    auto layerOf = [](const detail::Entity& e) {
        const Group* g = e.find(8);
        return g ? std::string(g->value) : std::string("0");
    };
    walkEntities(
        groups, ticker, file.size(),
        [&](const detail::Entity& e) {
            if (e.type == "LWPOLYLINE") {
                // Vertices are repeated 10/20 pairs in the object system, at elevation 38.
                const Eigen::Matrix3d axes = objectAxes(groups, e);
                const double elevation = number(groups, e, 38, 0.0);
                DrawingPolyline polyline{layerOf(e), {}, (integer(groups, e, 70, 0) & 1) != 0};
                std::vector<Eigen::Vector2d> xy;
                std::vector<double> bulge; // one per vertex: its 42 follows its 10/20
                for (const Group& g : e.groups) {
                    if (g.code == 10 || g.code == 20 || g.code == 42) {
                        detail::Entity one{e.type, g.line, {g}};
                        const double v = number(groups, one, g.code, 0.0);
                        if (g.code == 10) {
                            xy.emplace_back(v, 0.0);
                            bulge.push_back(0.0);
                        } else if (!xy.empty()) {
                            (g.code == 20 ? xy.back().y() : bulge.back()) = v;
                        }
                    }
                }
                for (const Eigen::Vector2d& q : xy)
                    polyline.points.push_back(axes * Eigen::Vector3d(q.x(), q.y(), elevation));
                keepArcs(polyline, std::move(bulge), axes);
                if (polyline.points.size() >= 2)
                    drawing.polylines.push_back(std::move(polyline));
            } else if (e.type == "LINE") {
                drawing.polylines.push_back({layerOf(e), {point(groups, e, 10), point(groups, e, 11)}, false});
            } else if (e.type == "TEXT") {
                const Group* text = e.find(1);
                drawing.texts.push_back({layerOf(e), point(groups, e, 10), number(groups, e, 40, 1.0), text ? std::string(text->value) : ""});
            }
        },
        [&](const detail::Entity& polyline, const std::vector<detail::Entity>& vertices) {
            const long long flags = integer(groups, polyline, 70, 0);
            if (flags & (16 | 64))
                return; // a polygon or polyface mesh: a surface, not a line
            const bool is3d = (flags & 8) != 0;
            const Eigen::Matrix3d axes = is3d ? Eigen::Matrix3d::Identity() : objectAxes(groups, polyline);
            const double elevation = number(groups, polyline, 30, 0.0);
            DrawingPolyline out{layerOf(polyline), {}, (flags & 1) != 0};
            std::vector<double> bulge;
            for (const detail::Entity& v : vertices) {
                Eigen::Vector3d p = point(groups, v, 10);
                if (!is3d)
                    p = axes * Eigen::Vector3d(p.x(), p.y(), elevation);
                bulge.push_back(is3d ? 0.0 : number(groups, v, 42, 0.0)); // a 3D polyline has no arcs
                out.points.push_back(p);
            }
            keepArcs(out, std::move(bulge), axes);
            if (out.points.size() >= 2)
                drawing.polylines.push_back(std::move(out));
        });
    if (arcs > 0)
        logInfo(path.string() + ": " + std::to_string(arcs) + " polylines with arcs (bulges)");
    return drawing;
}

} // namespace scandiff::io
