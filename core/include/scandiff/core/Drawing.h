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

} // namespace scandiff
