// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The local surface models of thesis 000 §2.3.2, fitted on a few reference
//! points around a nearest neighbour (internal to core/).

#include <scandiff/core/distance/CloudToCloud.h>

#include <Eigen/Core>

#include <array>
#include <utility>
#include <vector>

namespace scandiff::detail {

//! A triangle of the 2D triangulation under construction: its vertices counter-
//! clockwise and, across each edge (v[e], v[e+1]), the neighbouring triangle (-1: none).
struct DelaunayTriangle
{
    std::array<int, 3> v;
    std::array<int, 3> nb;
    bool alive;
};

//! Buffers reused from point to point, so that a model costs no allocation.
struct ModelScratch
{
    std::vector<Eigen::Vector2d> planar;
    std::vector<std::array<int, 3>> triangles;
    std::vector<std::array<int, 3>> keep;
    std::vector<std::array<int, 2>> edges;
    std::vector<DelaunayTriangle> mesh;
    std::vector<int> cavity, startAt, startStamp;
    //! The Delaunay model: the triangles around point 0 and around another
    //! point, and whether they can be used; whether `keep` holds the whole
    //! triangulation of `planar`.
    std::vector<std::array<int, 3>> star, otherStar;
    bool starComputed = false, starUsable = false, triangulated = false;
    int otherStarCentre = -1; //!< the point otherStar surrounds (-1: none yet)
    bool otherStarUsable = false;
    std::vector<Eigen::Vector2d> cell, nextCell; //!< point 0's Voronoi cell while it is clipped
    std::vector<int> generator, nextGenerator;
    std::vector<double> side;
    //! The half-planes wx x + wy y <= h of a point's Voronoi cell met so far
    //! by the corner search (wedgeTriangle), and the site each comes from.
    std::vector<double> planeX, planeY, planeH;
    std::vector<int> planeSite;
    //! Shared by the stars and the whole triangulation of one fit: the planar
    //! points' span, the super-triangle's vertices, and which points repeat an
    //! earlier one (skipped; marked on first need, see markDuplicates).
    double span = 0;
    std::array<Eigen::Vector2d, 3> superVertices;
    std::vector<char> duplicate;
    bool duplicatesMarked = false;
};

//! The least-squares plane of a neighbourhood: centroid, normal (the smallest
//! principal axis, oriented to agree with the caller's orientation) and two
//! in-plane axes (u the largest principal axis, v = normal x u).
struct PlaneFrame
{
    Eigen::Vector3d centroid;
    Eigen::Vector3d u, v, normal;
};

//! A model fitted on one neighbourhood; the Delaunay triangles live in the
//! ModelScratch that fitted it until the next fit.
struct FittedModel
{
    LocalModel model = LocalModel::None;
    PlaneFrame frame;
    Eigen::Matrix<double, 6, 1> quadric; //!< a u^2 + b uv + c v^2 + d u + e v + f, u and v divided by extent
    double extent = 0;
};

//! Fits `model` on `points`. Returns false when the neighbourhood is too small
//! or degenerate (collinear, coincident) for the model. The model depends on the
//! points and their order only, so one fit serves every compared point that has
//! the same neighbourhood.
bool fitModel(LocalModel model, const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& orientation,
              FittedModel& fitted, ModelScratch& scratch);

//! Signed distance from q to a fitted model (positive on the side of the model
//! normal); `points` and `scratch` are those of the fit (the Delaunay model may
//! complete its triangulation in `scratch` on demand). False if not finite.
//! For the Delaunay model, q should lie near point 0, the neighbourhood's
//! centre: the triangles around it then decide alone (faster, same result).
bool modelDistance(const FittedModel& fitted, const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& q,
                   double& signedDistance, ModelScratch& scratch);

//! 2D Delaunay triangulation of scratch.planar (Bowyer-Watson in the super-
//! triangle fitModel placed, points inserted in their given order, the
//! duplicates skipped) of up to a few hundred points, the size of a
//! local neighbourhood. Written here because core may not use CGAL (it lives in
//! the GPL plugins), and for so few points a direct incremental insertion is
//! faster than setting up a general-purpose triangulation.
void delaunay2d(ModelScratch& scratch, std::vector<std::array<int, 3>>& triangles);

} // namespace scandiff::detail
