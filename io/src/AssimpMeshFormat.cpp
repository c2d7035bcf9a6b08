// SPDX-License-Identifier: GPL-3.0-or-later
//! OBJ, STL and OFF meshes. Reading goes through assimp, which knows the many
//! dialects of these formats (ASCII and binary STL, OBJ groups and polygons, OFF
//! variants). Writing is done here by hand: assimp's exporters take a float
//! scene, while these text formats can carry the full double precision of
//! georeferenced coordinates, and the three writers are a few lines each.
//!
//! Known limit: Debian's assimp is built with float coordinates, so a mesh file
//! with coordinates beyond ~1e4 m loses sub-millimetre precision when read
//! (STL is float32 by definition anyway). PLY keeps doubles: prefer it for
//! georeferenced meshes.

#include "internal/Formats.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/AtomicFile.h>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <charconv>
#include <cstring>
#include <functional>

namespace scandiff::io::detail {

namespace fs = std::filesystem;

namespace {

Entity readWithAssimp(const fs::path& path, const ReadOptions& options)
{
    ProgressTicker ticker(options.progress, "Reading " + path.filename().string(), 1);
    Assimp::Importer importer;
    // Triangulate polygons, merge the per-face vertices of STL, keep everything
    // else as stored (no normals invented, no vertices reordered beyond merging).
    unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices;
    // STL stores one normal per facet; copied to the corners they would keep
    // every shared vertex apart, so they are dropped before merging.
    if (lowerExtension(path) == "stl")
        flags |= aiProcess_DropNormals;
    const aiScene* scene = importer.ReadFile(path.string(), flags);
    if (!scene || !scene->mRootNode)
        throw Error(ErrorCode::InvalidData, path.string() + ": cannot read mesh: " + importer.GetErrorString());

    std::vector<Eigen::Vector3d> vertices;
    std::vector<Eigen::Vector3f> normals;
    bool allHaveNormals = true;
    std::vector<Triangle> triangles;
    std::function<void(const aiNode*, const aiMatrix4x4&)> visit = [&](const aiNode* node, const aiMatrix4x4& parent) {
        const aiMatrix4x4 transform = parent * node->mTransformation;
        aiMatrix3x3 rotation(transform);
        for (unsigned m = 0; m < node->mNumMeshes; ++m) {
            const aiMesh* mesh = scene->mMeshes[node->mMeshes[m]];
            const auto base = static_cast<std::uint32_t>(vertices.size());
            for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
                const aiVector3D p = transform * mesh->mVertices[v];
                vertices.emplace_back(p.x, p.y, p.z);
                if (mesh->HasNormals()) {
                    aiVector3D n = rotation * mesh->mNormals[v];
                    normals.emplace_back(n.x, n.y, n.z);
                }
            }
            allHaveNormals = allHaveNormals && mesh->HasNormals();
            for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
                const aiFace& face = mesh->mFaces[f];
                if (face.mNumIndices != 3)
                    continue; // points and lines left by Triangulate
                triangles.push_back({base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
            }
        }
        for (unsigned c = 0; c < node->mNumChildren; ++c)
            visit(node->mChildren[c], transform);
    };
    visit(scene->mRootNode, aiMatrix4x4());

    Mesh mesh;
    BoundingBox box;
    for (const auto& v : vertices) {
        if (!v.allFinite())
            throw Error(ErrorCode::InvalidData, path.string() + ": a vertex has a non-finite coordinate");
        box.min = box.empty ? v : box.min.cwiseMin(v);
        box.max = box.empty ? v : box.max.cwiseMax(v);
        box.empty = false;
    }
    if (triangles.empty())
        throw Error(ErrorCode::InvalidData, path.string() + ": the file holds no triangle");
    const Eigen::Vector3d origin = options.origin ? *options.origin : suggestOrigin(box);
    mesh.vertices.setOrigin(origin);
    mesh.vertices.resize(vertices.size());
    auto& positions = mesh.vertices.positions();
    for (std::size_t i = 0; i < vertices.size(); ++i)
        positions[i] = (vertices[i] - origin).cast<float>();
    if (allHaveNormals && normals.size() == vertices.size())
        mesh.vertices.enableNormals() = std::move(normals);
    mesh.triangles = std::move(triangles);
    mesh.checkConsistency();
    ticker.step();
    return mesh;
}

//! Shortest text that reads back to the same double.
void appendNumber(std::string& out, double v)
{
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
    out.append(buffer, result.ptr);
}

void writeObj(const Mesh& mesh, const fs::path& path, const WriteOptions& options)
{
    AtomicFile file(path);
    auto& out = file.stream();
    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), mesh.vertices.size() + mesh.triangles.size());
    std::string line;
    out << "# written by scandiff\n";
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Eigen::Vector3d p = mesh.vertices.globalPosition(i);
        line = "v ";
        appendNumber(line, p.x());
        line += ' ';
        appendNumber(line, p.y());
        line += ' ';
        appendNumber(line, p.z());
        line += '\n';
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
    out << "OFF\n" << mesh.vertices.size() << ' ' << mesh.triangles.size() << " 0\n";
    std::string line;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Eigen::Vector3d p = mesh.vertices.globalPosition(i);
        line.clear();
        appendNumber(line, p.x());
        line += ' ';
        appendNumber(line, p.y());
        line += ' ';
        appendNumber(line, p.z());
        line += '\n';
        out << line;
        ticker.step();
    }
    for (const auto& t : mesh.triangles) {
        out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
        ticker.step();
    }
    file.commit();
}

//! Binary STL (the compact, universal variant): float32 by definition.
void writeStl(const Mesh& mesh, const fs::path& path, const WriteOptions& options)
{
    AtomicFile file(path);
    auto& out = file.stream();
    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), mesh.triangles.size());
    if (options.encoding == Encoding::Ascii) {
        out << "solid scandiff\n";
        for (const auto& t : mesh.triangles) {
            const Eigen::Vector3d a = mesh.vertices.globalPosition(t[0]), b = mesh.vertices.globalPosition(t[1]),
                                  c = mesh.vertices.globalPosition(t[2]);
            Eigen::Vector3d n = (b - a).cross(c - a);
            if (n.norm() > 0)
                n.normalize();
            out << " facet normal " << n.x() << ' ' << n.y() << ' ' << n.z() << "\n  outer loop\n";
            for (const auto* p : {&a, &b, &c})
                out << "   vertex " << p->x() << ' ' << p->y() << ' ' << p->z() << '\n';
            out << "  endloop\n endfacet\n";
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
            const Eigen::Vector3d a = mesh.vertices.globalPosition(t[0]), b = mesh.vertices.globalPosition(t[1]),
                                  c = mesh.vertices.globalPosition(t[2]);
            Eigen::Vector3d n = (b - a).cross(c - a);
            if (n.norm() > 0)
                n.normalize();
            float record[12];
            const Eigen::Vector3d* vectors[4] = {&n, &a, &b, &c};
            for (int v = 0; v < 4; ++v)
                for (int a2 = 0; a2 < 3; ++a2)
                    record[v * 3 + a2] = static_cast<float>((*vectors[v])[a2]);
            out.write(reinterpret_cast<const char*>(record), sizeof record);
            const std::uint16_t attributes = 0;
            out.write(reinterpret_cast<const char*>(&attributes), 2);
            ticker.step();
        }
    }
    file.commit();
}

} // namespace

FormatHandler assimpMeshFormat()
{
    FormatHandler handler;
    handler.name = "Mesh (OBJ/STL/OFF)";
    handler.extensions = {"obj", "stl", "off"};
    handler.read = readWithAssimp;
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
