// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Cloud-to-mesh distance (thesis 000 §2.2, the Metro-like comparison): for
//! every point of the compared cloud, the exact distance to the nearest
//! triangle of the reference mesh, optionally signed.
//!
//! Method (thesis §2.2.2 and §4.4):
//! - a grid of cubic cells, the octree cells at one level of a cube enclosing
//!   the mesh and the (finite) compared points; every triangle is referenced in
//!   every cell it intersects (the separating-axis triangle/box test of
//!   Akenine-Möller, on cells enlarged by 1e-6 of their size so that rounding
//!   never loses a reference); the references form an array sorted by (cell
//!   Morton code, triangle index), so the triangles of a cell are a contiguous
//!   range found by binary search;
//! - the compared points are grouped by cell, in Morton order, and the cells
//!   run in parallel (TBB, per-thread scratch, no lock). For a cell, rings
//!   j = 0, 1, 2 of cells around it are visited; the triangles of each ring are
//!   gathered once and tested against every point of the cell still searching;
//!   a point stops when its best distance is below the radius of the sphere
//!   inscribed in the rings visited, r_j = j*l + (distance from the point to its
//!   own cell's faces) (eq. 4.1), or once r_j exceeds maxDistance;
//! - the points of a cell that rings 0..2 do not settle (far from the mesh, or
//!   a deep level) switch to a best-first traversal of the cell hierarchy over
//!   the sorted cell codes, shared by those points: nodes by increasing distance
//!   to the points' bounding box, grid cells bounded by their box clipped to
//!   their triangles' boxes, the traversal ending when the next node is farther
//!   than every point's best distance; its cost grows with log(cells) rather
//!   than with the ring volume;
//! - before the exact point/triangle distance, a triangle is skipped when its
//!   bounding box or its plane is already farther than the point's best.
//! Every pruning test is conservative (a relative slack of 1e-9 and an absolute
//! one of 1e-9 x the cube size), so the result is exact: each distance equals
//! the minimum over all triangles of geometry::pointTriangleDistance, whatever
//! the level. The level changes the speed only.
//!
//! Frames: distances are computed in double in the mesh's local frame, a point
//! p of the compared cloud becoming q = (compared.origin() - mesh origin) + p,
//! with the triangle vertices cast from float to double. The two inputs may have
//! different origins (georeferenced data).

#include <scandiff/core/Mesh.h>
#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/ScalarField.h>
#include <scandiff/core/distance/DistanceStatistics.h>

#include <cstddef>
#include <optional>

namespace scandiff {

struct CloudToMeshParams
{
    //! Sign the distances by the side of the closest triangle's plane: + on the
    //! side its normal points to, the normal being (b - a) x (c - a) for the
    //! triangle's vertex order (a, b, c) (right-hand rule; CloudCompare also uses
    //! the face normal). When the closest point lies on an edge or a vertex the
    //! plane of the triangle found closest is used; when several triangles are at
    //! exactly the same distance (their shared edge or vertex is the closest
    //! point), the sign comes from the one whose plane the point is farthest from
    //! (largest |(q - closest) . n / |n||, the face that faces the point most
    //! directly, which gives the outer side at a convex edge of a closed,
    //! consistently oriented mesh), then from the smallest triangle index.
    //! A degenerate triangle has no normal: it only gives the sign when no other
    //! triangle ties with it, and that sign is +. Points on the surface get 0.
    //! Default false (unsigned distances, >= 0).
    bool signedDistances = false;
    //! Metres (the clouds' unit), finite and > 0; default none (no limit). Points
    //! whose distance exceeds it get NaN, or maxDistance itself if clampBeyondMax
    //! (always +maxDistance, even with signedDistances: the search stops at
    //! maxDistance, so the side is not known). The search radius is bounded by it,
    //! which makes far points cheap.
    std::optional<double> maxDistance;
    //! With maxDistance: report maxDistance instead of NaN beyond it. Default
    //! false; true without maxDistance is an InvalidArgument.
    bool clampBeyondMax = false;
    //! Grid level, 1..21 (cell edge = cube size / 2^level); default 0 = automatic:
    //! the level whose cell edge is closest (in log2) to 2 x the mean edge length
    //! of the non-degenerate triangles, so a cell holds a few triangles and a
    //! triangle spans a few cells. Any level whose estimated number of triangle
    //! references, sum over triangles of (2 area / l^2 + 2 perimeter / l + 1),
    //! exceeds max(2^23, 32 x triangle count) is lowered to the deepest level
    //! within that budget (explicit levels too, with a log warning): references
    //! cost 12 bytes each and a deep level on large triangles would need
    //! gigabytes. CloudToMeshResult::level tells the level used.
    int octreeLevel = 0;
    //! Also give, per compared point, the index of the closest triangle (the
    //! one whose distance was kept; registration needs it). Default false.
    bool closestTriangles = false;
};

struct CloudToMeshResult
{
    //! "c2m_distance": one value per compared point, in metres (offset 0). NaN
    //! for a point with a non-finite coordinate (such points are skipped, with a
    //! log warning), and beyond maxDistance unless clamped.
    ScalarField distance;
    //! Over the non-NaN values of `distance` (signed values when signed).
    DistanceStatistics statistics;
    int level = 0;                       //!< grid level used
    std::size_t degenerateTriangles = 0; //!< triangles used as a segment or a point (geometry::isDegenerateTriangle)
    //! With closestTriangles: per compared point, its closest triangle, or
    //! kNoClosestTriangle where the distance is NaN (no finite coordinate, or
    //! beyond maxDistance).
    std::vector<std::uint32_t> closestTriangle;
};

inline constexpr std::uint32_t kNoClosestTriangle = 0xffffffffu;

//! Distances from every point of `compared` to the mesh `reference`.
//! Throws Error(InvalidArgument) for parameters out of range, Error(InvalidData)
//! for an empty cloud, a mesh with no triangle, a triangle referencing a missing
//! vertex (Mesh::checkConsistency) or a vertex of a triangle with a non-finite
//! coordinate, and Error(Cancelled) if `progress` asks to stop. The inputs are
//! never modified (the result is a new field: add it to the cloud yourself).
CloudToMeshResult cloudToMesh(const PointCloud& compared, const Mesh& reference, const CloudToMeshParams& params,
                              ProgressObserver* progress = nullptr);

} // namespace scandiff
