// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Outlines of points lying on a plane: a façade segment's outline and its
//! openings (thesis 001 §4.2), a stone's contour (thesis 003 §III.1.1).
//!
//! The points are expressed in their best-fit plane (PCA), triangulated
//! (2D Delaunay), and the triangles that do not belong to the surface are
//! dropped: by the thesis 001 long-edge criterion (a triangle with an edge
//! longer than L spans a gap) or by the alpha-shape criterion of thesis 003
//! (circumradius above alpha). The kept triangles that share an edge form one
//! part; the edges of a part that border a single kept triangle are its outline,
//! chained into closed rings: one outer ring per part (counter-clockwise) and
//! one ring per hole (clockwise). Two parts meeting at a single point stay two
//! parts, and a ring passing twice through a point is chained so that it never
//! crosses itself: a hole touching the outline at one point stays in the outer
//! ring, which then passes twice through that point (its signed area is still
//! the part's).

#include <scandiff/core/geometry/PlanarRings.h>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace scandiff::plugins {

//! A plane with an orthonormal frame (u, v, normal), right-handed. For a plane
//! that is not horizontal, u is horizontal and v points up the slope (a
//! façade's x and z), so straight pieces can be classified as horizontal or
//! vertical; its normal's horizontal part points towards +y (else +x). A
//! horizontal plane's normal points up.
struct PlaneFrame
{
    Eigen::Vector3d origin = Eigen::Vector3d::Zero(); //!< the points' centroid, global
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
    Eigen::Vector3d u = Eigen::Vector3d::UnitX(), v = Eigen::Vector3d::UnitY();
    double rms = 0.0;   //!< of the points' distances to the plane
    double worst = 0.0; //!< largest of those distances

    Eigen::Vector2d toPlane(const Eigen::Vector3d& p) const
    {
        const Eigen::Vector3d d = p - origin;
        return {d.dot(u), d.dot(v)};
    }
    Eigen::Vector3d toWorld(const Eigen::Vector2d& q) const { return origin + q.x() * u + q.y() * v; }
};

//! The least-squares plane of the points (smallest eigenvector of their
//! covariance, computed about the centroid in double: UTM coordinates lose
//! nothing). Throws Error(InvalidData) for fewer than 3 points or points on a line.
PlaneFrame fitPlaneFrame(const std::vector<Eigen::Vector3d>& points);

enum class OutlineMethod { LongEdges, Alpha };
OutlineMethod parseOutlineMethod(const std::string& name); //!< "long-edges", "alpha"

struct OutlineParams
{
    OutlineMethod method = OutlineMethod::LongEdges;
    //! LongEdges: the longest edge a surface triangle may have; Alpha: the
    //! largest circumradius. 0: found at the knee of the sorted values (see kneeThreshold).
    double threshold = 0.0;
    //! A part smaller than this area (plane units squared) is dropped; holes
    //! smaller than it are filled (a few missed points inside a stone).
    double minPartArea = 0.0;
    double minHoleArea = 0.0;
    //! Optional label per point (a region grown on intensity): a triangle
    //! joining points of different labels, or of a negative one, is dropped.
    std::vector<std::int32_t> labels;
};

using Ring2d = std::vector<Eigen::Vector2d>; //!< closed: the last vertex joins the first

struct OutlinePart
{
    Ring2d outer;              //!< counter-clockwise
    std::vector<Ring2d> holes; //!< clockwise
    std::vector<std::uint32_t> outerIndices;              //!< the input point of each outer vertex
    std::vector<std::vector<std::uint32_t>> holeIndices;  //!< the input point of each hole vertex
    double area = 0.0;         //!< of the kept triangles (outer minus holes)
    std::size_t pointCount = 0; //!< input points that are vertices of the part's triangles
};

struct OutlineResult
{
    std::vector<OutlinePart> parts; //!< largest area first
    //! The part each input point belongs to (-1: in no kept triangle, e.g. an
    //! isolated point, or in a dropped small part). A point where two parts
    //! touch belongs to the one with more of its triangles.
    std::vector<std::int32_t> partOfPoint;
    double threshold = 0.0; //!< the one used (the knee when automatic)
    double spacing = 0.0;   //!< median distance of a point to its nearest neighbour (in the plane)
    std::size_t triangles = 0, keptTriangles = 0;
};

//! Outlines of 2D points (the plane coordinates of a segment). Duplicate points
//! count once (the first); fewer than 3 distinct, non-collinear points give no
//! part; a duplicate belongs to the part of its twin. Throws
//! Error(InvalidArgument) for a negative threshold and
//! Error(InvalidData) for a non-finite coordinate.
OutlineResult extractOutlines(const std::vector<Eigen::Vector2d>& points, const OutlineParams& params);

//! The knee of a set of lengths: sorted ascending, the value where the curve
//! turns from the slow rise of the surface's own edges to the steep rise of the
//! edges spanning gaps (the thesis picks it by eye on this curve; here it is
//! the point farthest below the chord from the median to the 99th percentile,
//! in normalised coordinates), never below `floorFactor` x the median, so that
//! a surface without gaps keeps all its triangles. Empty input: 0.
double kneeThreshold(std::vector<double> values, double floorFactor);

//! Perimeter of a closed ring (its signed area: signedArea() of core's PlanarRings.h).
double ringPerimeter(const Ring2d& ring);

//! The triangles of the 2D Delaunay triangulation of the points (indices into
//! `points`, counter-clockwise). Of several equal points, one is a vertex.
//! Internal to the plugin, declared here for its tests. Through CGAL.
std::vector<std::array<std::uint32_t, 3>> delaunayTriangles(const std::vector<Eigen::Vector2d>& points);

} // namespace scandiff::plugins
