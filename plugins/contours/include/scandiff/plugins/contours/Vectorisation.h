// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Vectorisation of a contour ring (thesis 001 §4.3): the ring's points are
//! split into straight pieces and arcs, straight pieces are classified as
//! horizontal, vertical or inclined in the plane's frame (u horizontal, v up),
//! and the corners are the intersections of neighbouring pieces only (§4.3.3),
//! so a window gets its four true corners although the scan has no point there.

#include <scandiff/plugins/contours/PlanarContours.h>

#include <string>
#include <vector>

namespace scandiff::plugins {

struct VectoriseParams
{
    double tolerance = 0.02;   //!< largest distance of a ring point to its piece (m)
    double snapDegrees = 2.0;  //!< a piece this close to horizontal or vertical is made exactly so
    //! Straight pieces are moved this far away from the surface (m): the true
    //! edge lies beyond the last scanned points, on average half a point
    //! spacing on a regular scan (thesis 001 §5.6.2 notes the contour points
    //! fall short of the edges). 0: none.
    double edgeOffset = 0.0;
    double arcStepDegrees = 2.0; //!< arcs are written as polylines with this angular step
    bool arcs = true;            //!< false: straight pieces only (a stone's sides)
};

enum class PieceKind { Horizontal, Vertical, Inclined, Arc, Chain };
const char* pieceKindName(PieceKind kind);

struct VectorPiece
{
    PieceKind kind = PieceKind::Inclined;
    Eigen::Vector2d start = Eigen::Vector2d::Zero(), end = Eigen::Vector2d::Zero(); //!< corners
    Eigen::Vector2d centre = Eigen::Vector2d::Zero(); //!< Arc only
    double radius = 0.0;                              //!< Arc only
    double sagitta = 0.0; //!< Arc only: distance from the chord's middle to the arc (thesis 001 Fig. 4.19)
    double bulge = 0.0;   //!< Arc only: DXF's tan(θ/4) of its signed angle θ in the plane's (u, v) frame
};

struct VectorRing
{
    Ring2d vertices;                //!< the closed outline: corners, arcs as polylines
    std::vector<VectorPiece> pieces;
};

//! `ring` as extractOutlines gives it (the surface on its left). A ring too
//! small to split (fewer than 4 points) comes back as it is, one Chain piece.
VectorRing vectoriseRing(const Ring2d& ring, const VectoriseParams& params);

} // namespace scandiff::plugins
