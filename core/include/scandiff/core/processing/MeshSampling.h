// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Points sampled on a mesh's surface (thesis 000 annex C: "point sampling on
//! the surface"): a cloud to compare with C2C, or a denser stand-in for a model.

#include <scandiff/core/Mesh.h>
#include <scandiff/core/Progress.h>

#include <cstdint>
#include <optional>

namespace scandiff {

struct MeshSamplingParams
{
    //! Exactly this many points in all; or, when absent, `density` points per
    //! square metre (the total rounded to the nearest integer).
    std::optional<std::size_t> count;
    double density = 0;
    std::uint64_t seed = 0; //!< the same seed gives the same points, whatever the number of threads
    bool normals = true;    //!< each point gets its triangle's normal (the vertex order's side)
};

namespace fields {
//! The triangle a sampled point lies on (its index in the mesh); left out for
//! meshes of more than 2^24 triangles, whose indices a float cannot hold.
inline constexpr const char* kTriangleIndex = "triangle_index";
} // namespace fields

//! Each triangle gets the share of the total its area is of the mesh's
//! (cumulative rounding, so the shares add up to the total exactly and differ
//! from count x area / total area by less than one), placed uniformly at
//! random inside it. Colours and scalar fields of the vertices are
//! interpolated at each point (barycentric), and fields::kTriangleIndex is
//! added. Degenerate triangles get no point. Throws Error(InvalidArgument) for
//! no count and a density that is not > 0, or a total the machine's memory
//! could not hold; Error(InvalidData) for a mesh with no area.
PointCloud sampleMesh(const Mesh& mesh, const MeshSamplingParams& params, ProgressObserver* progress = nullptr);

} // namespace scandiff
