// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/Mesh.h>

namespace scandiff {

Mesh Mesh::clone() const
{
    Mesh copy;
    copy.name = name;
    copy.vertices = vertices.clone();
    copy.triangles = triangles;
    return copy;
}

void Mesh::checkConsistency() const
{
    vertices.checkConsistency();
    const std::size_t n = vertices.size();
    for (std::size_t t = 0; t < triangles.size(); ++t)
        for (std::uint32_t v : triangles[t])
            if (v >= n)
                throw Error(ErrorCode::InvalidData, "mesh '" + name + "': triangle " + std::to_string(t) +
                                                        " uses vertex " + std::to_string(v) + " but there are only " +
                                                        std::to_string(n) + " vertices");
}

std::size_t Mesh::countDegenerateTriangles() const
{
    std::size_t count = 0;
    const auto& p = vertices.positions();
    for (const auto& t : triangles) {
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
            ++count;
            continue;
        }
        const Eigen::Vector3f n = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
        if (!(n.squaredNorm() > 0.0f))
            ++count;
    }
    return count;
}

} // namespace scandiff
