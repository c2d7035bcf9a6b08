// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! 2.5D meshing (thesis 000 annex C: "2D triangulation: direct (vertical = Z
//! axis); by projecting points on an LS-fitted plane"): the points projected
//! on a plane, triangulated there by Delaunay (CGAL), the triangles lifted back
//! onto the 3D points. Suits terrain, walls and façades, not closed objects.

#include <scandiff/core/Mesh.h>
#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>

#include <optional>

namespace scandiff::plugins {

enum class ProjectionPlane {
    AlongZ,  //!< the plane z = 0: terrain (the thesis's "direct" triangulation)
    AlongX,  //!< x = 0
    AlongY,  //!< y = 0
    BestFit  //!< the points' least-squares plane: a wall, a façade
};

struct Delaunay25DParams
{
    ProjectionPlane projection = ProjectionPlane::AlongZ;
    //! Triangles with a 3D edge longer than this are dropped, leaving holes
    //! and concave borders open; absent: the whole convex hull is meshed.
    std::optional<double> maxEdgeLength;
};

struct Delaunay25DResult
{
    Mesh mesh;                    //!< the input's points (every attribute) as vertices
    std::size_t duplicates = 0;   //!< points at the same projected place as an earlier one (not in any triangle)
    std::size_t dropped = 0;      //!< triangles removed by the edge length limit
    double area = 0;              //!< of the kept triangles, in 3D (m^2)
};

//! Triangles are counter-clockwise seen from the plane's positive side (+Z,
//! +X, +Y, or the fitted normal turned towards +Z), so their normals face it.
//! Throws Error(InvalidArgument) for a limit that is not > 0, Error(InvalidData)
//! for fewer than 3 points, non-finite coordinates, or points that project onto
//! a line; Error(Cancelled).
Delaunay25DResult delaunay25D(const PointCloud& cloud, const Delaunay25DParams& params, ProgressObserver* progress = nullptr);

} // namespace scandiff::plugins
