// SPDX-License-Identifier: GPL-3.0-or-later
//! OBJ, STL and OFF meshes: read by MeshReaders.cpp, written here. The
//! writers are ours too: these text formats carry the full double precision of
//! georeferenced coordinates, and each is a few lines.

#include "internal/Formats.h"
#include "mesh/MeshReaders.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/AtomicFile.h>

#include <charconv>
#include <cstring>

namespace scandiff::io::detail {

namespace fs = std::filesystem;

namespace {

//! Shortest text that reads back to the same double.
void appendNumber(std::string& out, double v)
{
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
    out.append(buffer, result.ptr);
}

//! "X Y Z" of vertex i in global coordinates, every digit, then its colour
//! when the mesh has colours: " R G B" in 0..1 (OBJ's common extension) or
//! " R G B 255" in 0..255 (COFF).
void appendVertex(std::string& line, const Mesh& mesh, std::size_t i, bool unitColours)
{
    const Eigen::Vector3d p = mesh.vertices.globalPosition(i);
    appendNumber(line, p.x());
    line += ' ';
    appendNumber(line, p.y());
    line += ' ';
    appendNumber(line, p.z());
    if (mesh.vertices.hasColors()) {
        const Rgb8 c = mesh.vertices.colors()[i];
        for (const std::uint8_t channel : {c.r, c.g, c.b}) {
            line += ' ';
            if (unitColours)
                appendNumber(line, channel / 255.0);
            else
                line += std::to_string(channel);
        }
        if (!unitColours)
            line += " 255";
    }
    line += '\n';
}

void writeObj(const Mesh& mesh, const fs::path& path, const WriteOptions& options)
{
    AtomicFile file(path);
    auto& out = file.stream();
    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), mesh.vertices.size() + mesh.triangles.size());
    std::string line;
    out << "# written by scandiff\n";
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        line = "v ";
        appendVertex(line, mesh, i, true);
        out << line;
        ticker.step();
    }
    if (mesh.vertices.hasNormals())
        for (const auto& n : mesh.vertices.normals())
            out << "vn " << n.x() << ' ' << n.y() << ' ' << n.z() << '\n';
    const bool normals = mesh.vertices.hasNormals();
    for (const auto& t : mesh.triangles) {
        out << 'f';
        for (std::uint32_t v : t) {
            out << ' ' << v + 1;
            if (normals)
                out << "//" << v + 1;
        }
        out << '\n';
        ticker.step();
    }
    file.commit();
}

void writeOff(const Mesh& mesh, const fs::path& path, const WriteOptions& options)
{
    AtomicFile file(path);
    auto& out = file.stream();
    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), mesh.vertices.size() + mesh.triangles.size());
    out << (mesh.vertices.hasColors() ? "COFF\n" : "OFF\n") << mesh.vertices.size() << ' ' << mesh.triangles.size() << " 0\n";
    std::string line;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        line.clear();
        appendVertex(line, mesh, i, false);
        out << line;
        ticker.step();
    }
    for (const auto& t : mesh.triangles) {
        out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
        ticker.step();
    }
    file.commit();
}

//! A triangle as STL stores it: its unit normal, then its three corners (global).
struct Facet
{
    Eigen::Vector3d corners[4];
};

Facet facetOf(const Mesh& mesh, const Triangle& t)
{
    Facet f;
    for (int k = 0; k < 3; ++k)
        f.corners[k + 1] = mesh.vertices.globalPosition(t[static_cast<std::size_t>(k)]);
    Eigen::Vector3d n = (f.corners[2] - f.corners[1]).cross(f.corners[3] - f.corners[1]);
    if (n.norm() > 0)
        n.normalize();
    f.corners[0] = n;
    return f;
}

//! "X Y Z" as float32 (STL's precision, even in ASCII), each written as the
//! float's exact value (512345.6875, not the float-shortest 512345.7 that a
//! double reader takes 1 cm away): the stream's default six digits lost half a
//! metre at UTM magnitudes.
void appendFloats(std::string& line, const Eigen::Vector3d& v)
{
    for (int axis = 0; axis < 3; ++axis) {
        if (axis)
            line += ' ';
        char buffer[32];
        const auto result = std::to_chars(buffer, buffer + sizeof buffer, static_cast<double>(static_cast<float>(v[axis])));
        line.append(buffer, result.ptr);
    }
}

//! STL, binary (the compact, universal variant) unless ASCII is asked for: float32 by definition.
void writeStl(const Mesh& mesh, const fs::path& path, const WriteOptions& options)
{
    AtomicFile file(path);
    auto& out = file.stream();
    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), mesh.triangles.size());
    if (options.encoding == Encoding::Ascii) {
        out << "solid scandiff\n";
        std::string line;
        for (const auto& t : mesh.triangles) {
            const Facet f = facetOf(mesh, t);
            line = " facet normal ";
            appendFloats(line, f.corners[0]);
            line += "\n  outer loop\n";
            for (int k = 1; k < 4; ++k) {
                line += "   vertex ";
                appendFloats(line, f.corners[k]);
                line += '\n';
            }
            line += "  endloop\n endfacet\n";
            out << line;
            ticker.step();
        }
        out << "endsolid scandiff\n";
    } else {
        char header[80] = {};
        std::strncpy(header, "binary STL written by scandiff", sizeof header - 1);
        out.write(header, sizeof header);
        const auto count = static_cast<std::uint32_t>(mesh.triangles.size());
        out.write(reinterpret_cast<const char*>(&count), 4);
        for (const auto& t : mesh.triangles) {
            const Facet f = facetOf(mesh, t);
            float record[12];
            for (int v = 0; v < 4; ++v)
                for (int axis = 0; axis < 3; ++axis)
                    record[v * 3 + axis] = static_cast<float>(f.corners[v][axis]);
            out.write(reinterpret_cast<const char*>(record), sizeof record);
            const std::uint16_t attributes = 0;
            out.write(reinterpret_cast<const char*>(&attributes), 2);
            ticker.step();
        }
    }
    file.commit();
}

} // namespace

FormatHandler meshFormat()
{
    FormatHandler handler;
    handler.name = "Mesh (OBJ/STL/OFF)";
    handler.extensions = {"obj", "stl", "off"};
    handler.read = [](const fs::path& path, const ReadOptions& options) -> Entity { return readMeshFile(path, options); };
    handler.writeMesh = [](const Mesh& mesh, const fs::path& path, const WriteOptions& options) {
        const std::string ext = lowerExtension(path);
        if (ext == "obj")
            writeObj(mesh, path, options);
        else if (ext == "off")
            writeOff(mesh, path, options);
        else
            writeStl(mesh, path, options);
    };
    return handler;
}

} // namespace scandiff::io::detail
