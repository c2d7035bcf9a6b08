// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Rigid motions with constrained degrees of freedom, and their closed-form
//! and linearised estimators: what every registration method of the plugin
//! solves (ICP, point pairs, global alignment, stations).
//!
//! The constraint lives inside the estimator, not projected afterwards (as
//! CloudCompare does): a four-degree-of-freedom motion is a rotation about the
//! given axis and a translation, so the tilt of a levelled scanner stays
//! exactly as it was (thesis 004 §2.5, eq. 37: x_j = R(kappa) x_i + t).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace scandiff::plugins {

enum class Dof {
    Six,        //!< rotation and translation
    Four,       //!< rotation about `axis` and translation (levelled scanners: axis = Z)
    Translation //!< translation only
};

struct DofConstraint
{
    Dof dof = Dof::Six;
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ(); //!< Four: the rotation axis (unit)
};

//! "6", "4", "translation"; throws Error(InvalidArgument).
Dof parseDof(const std::string& text);
const char* dofName(Dof dof);
//! The number of free parameters: 6, 4 or 3.
int dofCount(Dof dof);

//! The motion minimising sum w_i |R x_i + t - y_i|^2 under the constraint, in
//! closed form: Kabsch with weights (6), the 2D Procrustes angle about the axis
//! (4), the weighted mean difference (translation). At least 3 pairs not on a
//! line for Six, 2 distinct ones for Four, 1 for Translation; false otherwise.
bool fitPointToPoint(const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3d>& y, const std::vector<double>& w,
                     const DofConstraint& constraint, Eigen::Isometry3d& motion);

//! The linearised (small-motion) step minimising sum w_i (n_i . (x_i + omega x x_i + tau) - n_i . y_i)^2,
//! with omega = theta axis for Four and 0 for Translation: solves the normal
//! equations, returns the step as a motion (the rotation exact, from the
//! rotation vector) and the normal matrix (columns omega then tau, omega
//! multiplied by `length`: the displacement it gives at that distance, so both
//! are metres) for the degeneracy analysis. False when the system is singular.
bool stepPointToPlane(const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3d>& y,
                      const std::vector<Eigen::Vector3d>& n, const std::vector<double>& w, const DofConstraint& constraint,
                      double length, Eigen::Isometry3d& step, Eigen::MatrixXd& normalMatrix);

//! The motion as a 4 x 4 matrix acting on global coordinates, from one acting
//! on coordinates relative to `frameOrigin`.
Eigen::Matrix4d toGlobal(const Eigen::Isometry3d& local, const Eigen::Vector3d& frameOrigin);
//! The inverse of toGlobal.
Eigen::Isometry3d toLocal(const Eigen::Matrix4d& global, const Eigen::Vector3d& frameOrigin);

//! Rotation angle (degrees) and translation length of a motion.
double rotationDegrees(const Eigen::Matrix3d& rotation);

} // namespace scandiff::plugins
