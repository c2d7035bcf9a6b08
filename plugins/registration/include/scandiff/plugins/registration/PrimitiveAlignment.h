// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Registration on primitives (thesis 004: scans of a building consolidated
//! on the planes they share, and here on pipes and targets too): the shapes
//! found in each scan are matched, and the motion is the one that brings the
//! moving scan's shapes onto the reference's. Works from any start, since
//! shapes are matched by the angles and distances between them, not by
//! position (src/ShapeAlignment.cpp).

#include <scandiff/plugins/primitives/PrimitiveDetection.h>

#include <Eigen/Core>

#include <set>
#include <string>
#include <vector>

namespace scandiff::plugins {

struct PrimitiveAlignmentParams
{
    double angleToleranceDegrees = 2.0; //!< two matched pairs of planes make the same angle within this
    double distanceTolerance = 0.05;    //!< a matched plane's offset after the motion, m
    std::size_t maxPlanes = 24;         //!< the largest planes of each scan taken (by area)
};

struct PlaneMatch
{
    int moving = -1, reference = -1;   //!< ids of the primitives
    PrimitiveKind kind = PrimitiveKind::Plane;
    double angleDegrees = 0;           //!< between the reference shape's direction and the moved one's (0 for spheres)
    //! Distance between them at the moved shape's point (m): plane offset,
    //! axis to axis across the reference's axis, centre to centre.
    double offset = 0;
};

struct PrimitiveAlignment
{
    Eigen::Matrix4d matrix = Eigen::Matrix4d::Identity(); //!< moving -> reference, global coordinates
    std::vector<PlaneMatch> matches;
    double rmsAngleDegrees = 0, rmsOffset = 0;
    //! Empty when the matched planes fix every direction; else names the free one (translation along it is unknown).
    std::string degeneracy;
    std::vector<std::string> notes;
};

//! Registration on any mix of planes, cylinders (pipes, columns) and spheres
//! (`kinds`, a subset of those three): every three shapes of the reference
//! whose constraints fix the six degrees of freedom (a plane its normal and
//! offset, a cylinder its axis line, a sphere its centre: three planes facing
//! three ways, two pipes that are not parallel, a column and two walls, three
//! targets...) and three moving shapes of the same kinds and sizes making the
//! same angles and distances give a hypothesis, scored by the shapes it brings
//! onto shapes of the reference (weighted by support), the best refined by
//! weighted Gauss-Newton on every match. Throws Error(InvalidData) when no
//! three reference shapes fix the motion or no motion brings three onto three.
//! Cancel (`progress`) is heard between hypotheses.
PrimitiveAlignment alignOnShapes(const std::vector<DetectedPrimitive>& moving, const std::vector<DetectedPrimitive>& reference,
                                 const std::set<PrimitiveKind>& kinds, const PrimitiveAlignmentParams& params,
                                 ProgressObserver* progress = nullptr);

} // namespace scandiff::plugins
