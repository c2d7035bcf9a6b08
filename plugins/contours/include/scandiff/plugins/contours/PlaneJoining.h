// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The outlines of a façade's planes made to meet (thesis 001 §4.4: the 3D
//! model is the planes' polygons lifted back and assembled). Each plane's
//! outline is drawn from its own points, which stop short of the edge it
//! shares with its neighbour; vertices near the line where two planes meet
//! are moved onto that line (onto the point where three planes meet at a
//! corner of three), and the vertices of the two outlines there are made one.

#include <scandiff/core/Drawing.h>
#include <scandiff/plugins/contours/PlanarContours.h>

#include <array>
#include <map>
#include <vector>

namespace scandiff::plugins {

struct OutlinedPlane
{
    PlaneFrame frame;                  //!< the plane the outlines lie in
    std::vector<std::size_t> outer;    //!< indices of its outer rings in the drawing
    std::vector<std::size_t> holes;    //!< indices of its holes in the drawing
};

struct PlaneJoinParams
{
    double tolerance = 0.05;     //!< largest distance of a vertex from the shared line, and from the other plane's outline (m)
    double minAngleDegrees = 20; //!< planes closer to parallel than this do not meet along a line
};

struct PlaneJoinResult
{
    std::size_t joints = 0;       //!< pairs of planes that meet
    std::size_t movedVertices = 0;
    //! Every moved vertex: its position before (exact bits) and after, to update other outputs.
    std::map<std::array<double, 3>, Eigen::Vector3d> moves;
};

//! Moves the vertices of `drawing`'s polylines listed in `planes`. A vertex
//! of plane A joins plane B when it lies within the tolerance of the line
//! A ∩ B and inside B's outline (or within the tolerance of it); it is moved
//! onto that line, or onto the point of the three planes when it joins two.
//! Vertices of different planes that then lie within the tolerance of each
//! other on the same planes become one point. Every moved vertex stays in its plane.
PlaneJoinResult joinNeighbouringPlanes(Drawing& drawing, const std::vector<OutlinedPlane>& planes, const PlaneJoinParams& params);

} // namespace scandiff::plugins
