// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A triangle mesh: its vertices are a PointCloud (so they share the origin
//! convention, colours, normals and scalar fields), plus vertex-index triangles.
//! Move-only, like PointCloud.

#include <scandiff/core/PointCloud.h>

#include <array>
#include <cstdint>
#include <vector>

namespace scandiff {

using Triangle = std::array<std::uint32_t, 3>;

class Mesh
{
public:
    Mesh() = default;
    Mesh(Mesh&&) noexcept = default;
    Mesh& operator=(Mesh&&) noexcept = default;
    Mesh(const Mesh&) = delete;
    Mesh& operator=(const Mesh&) = delete;
    Mesh clone() const;

    std::string name;
    PointCloud vertices;
    std::vector<Triangle> triangles;

    //! Throws Error(InvalidData) if a triangle references a missing vertex.
    void checkConsistency() const;
    //! Number of triangles with a repeated vertex or zero area (kept, never dropped silently).
    std::size_t countDegenerateTriangles() const;
};

} // namespace scandiff
