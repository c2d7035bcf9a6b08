// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What a file, a workbench entity or a tool's input holds: a point cloud or a
//! triangle mesh. Defined in core so that tools can take either.

#include <scandiff/core/Mesh.h>
#include <scandiff/core/PointCloud.h>

#include <variant>

namespace scandiff {

using Entity = std::variant<PointCloud, Mesh>;

//! The points of a cloud, or the vertices of a mesh.
inline const PointCloud& pointsOf(const Entity& entity)
{
    if (const auto* mesh = std::get_if<Mesh>(&entity))
        return mesh->vertices;
    return std::get<PointCloud>(entity);
}

inline PointCloud& pointsOf(Entity& entity)
{
    if (auto* mesh = std::get_if<Mesh>(&entity))
        return mesh->vertices;
    return std::get<PointCloud>(entity);
}

} // namespace scandiff
