// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A CAD drawing a tool gives as one of its outputs (cross-section outlines,
//! plane outlines, contours): polylines and labels in global coordinates,
//! each on a named layer. The CLI writes it as DXF (io), the workbench offers
//! to save it.

#include <Eigen/Core>

#include <string>
#include <vector>

namespace scandiff {

struct DrawingPolyline
{
    std::string layer;
    std::vector<Eigen::Vector3d> points; //!< global coordinates, at least 2
    bool closed = false;
    //! Arcs, as DXF writes them: empty (all straight), or one bulge per
    //! vertex for the segment from it to the next (the last one's: back to the
    //! first, when closed): tan(θ/4) of the arc's angle θ, positive
    //! counter-clockwise seen from the tip of `normal`, 0 for a straight segment.
    std::vector<double> bulges = {};
    //! The polyline's plane (unit) when it has bulges.
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

struct DrawingText
{
    std::string layer;
    Eigen::Vector3d position = Eigen::Vector3d::Zero(); //!< start of the baseline, global
    double height = 1.0;
    std::string text;
};

struct Drawing
{
    std::vector<DrawingPolyline> polylines;
    std::vector<DrawingText> texts;
};

//! The polyline's vertices with each arc (bulge) replaced by points at most
//! `stepDegrees` apart along it; a straight polyline's own points. For what
//! draws or measures the line.
std::vector<Eigen::Vector3d> polylineVertices(const DrawingPolyline& polyline, double stepDegrees = 2.0);

} // namespace scandiff
