// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Registration by point pairs: a point of the moving cloud and the same
//! point on the reference (targets, picked corners), the motion fitted in
//! closed form (Horn 1987 / Umeyama 1991, without scale; the 2D form about an
//! axis for four degrees of freedom), each pair's residual reported.

#include <scandiff/plugins/registration/RegistrationReport.h>
#include <scandiff/plugins/registration/RigidMotion.h>

#include <Eigen/Core>

#include <string>
#include <vector>

namespace scandiff::plugins {

struct PointPair
{
    Eigen::Vector3d moving;    //!< global coordinates
    Eigen::Vector3d reference; //!< global coordinates
};

//! The motion moving -> reference, in global coordinates, with every pair's
//! residual distance in `report.pairResiduals` and their RMS. At least 3 pairs
//! not on a line (2 distinct for four degrees of freedom, 1 for a
//! translation); throws Error(InvalidArgument) otherwise.
RegistrationReport fitPointPairs(const std::vector<PointPair>& pairs, const DofConstraint& constraint);

//! "MX,MY,MZ,RX,RY,RZ;..." (6 numbers a pair, pairs separated by ';' or line
//! breaks), or the name of a text or CSV file of such lines (a header line is
//! skipped). Throws Error(InvalidArgument).
std::vector<PointPair> parsePointPairs(const std::string& text);

} // namespace scandiff::plugins
