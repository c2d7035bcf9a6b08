// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The OBJ, STL and OFF readers (MeshReaders.cpp) and the DXF mesh reader
//! (DxfReader.cpp), internal to io/.

#include <scandiff/core/Mesh.h>
#include <scandiff/io/FileIO.h>

#include <filesystem>
#include <vector>

namespace scandiff::io::detail {

//! What a reader collects before the mesh is built: vertices in double.
struct MeshParts
{
    std::vector<Eigen::Vector3d> vertices;
    std::vector<Eigen::Vector3f> normals; //!< one per vertex, or empty
    std::vector<Rgb8> colors;             //!< one per vertex, or empty
    std::vector<ScalarField> fields;      //!< per vertex
    std::vector<Triangle> triangles;
};

//! The mesh of `parts`, around an origin chosen from its bounds (or the
//! options'). Throws Error(InvalidData) naming `path` for no triangle or a
//! non-finite vertex.
Mesh meshFromParts(MeshParts parts, const std::filesystem::path& path, const ReadOptions& options);

//! Reads an OBJ, STL (binary or ASCII) or OFF file, chosen by its extension.
//! Throws Error(InvalidData) naming the file and the problem (the line for
//! text files), Error(Io) when it cannot be opened, Error(Cancelled).
Mesh readMeshFile(const std::filesystem::path& path, const ReadOptions& options);

//! Reads the meshes of an ASCII DXF: 3DFACE entities and polyface and
//! polygon-mesh POLYLINEs of the ENTITIES section, as one mesh with a vertex
//! field `dxf_layer` (the index of each face's layer, in order of first use).
Mesh readDxfMesh(const std::filesystem::path& path, const ReadOptions& options);

} // namespace scandiff::io::detail
