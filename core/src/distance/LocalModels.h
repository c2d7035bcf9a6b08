// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The local surface models of thesis 000 §2.3.2, fitted on a few reference
//! points around a nearest neighbour (internal to core/).

#include <scandiff/core/distance/CloudToCloud.h>

#include <Eigen/Core>

#include <array>
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
};

//! Signed distance from q to the model of `points` (positive on the side of the
//! model normal, oriented to agree with `orientation`). Returns false when the
//! neighbourhood is too small or degenerate (collinear, coincident) for the model.
bool modelDistance(LocalModel model, const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& q,
                   const Eigen::Vector3d& orientation, double& signedDistance, ModelScratch& scratch);

//! 2D Delaunay triangulation (Bowyer-Watson in a super-triangle, points inserted
//! in their given order, coincident points skipped) of up to a few hundred
//! points, the size of a local neighbourhood. Written here because core may not
//! use CGAL (it lives in the GPL plugins), and for so few points a direct
//! incremental insertion is faster than setting up a general-purpose triangulation.
void delaunay2d(const std::vector<Eigen::Vector2d>& points, std::vector<std::array<int, 3>>& triangles, ModelScratch& scratch);

} // namespace scandiff::detail
