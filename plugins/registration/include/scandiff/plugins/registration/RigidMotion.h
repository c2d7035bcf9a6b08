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

//! Below this share of the largest eigenvalue of a point-to-plane normal
//! matrix (unknowns in metres), a direction of the motion is not held by the
//! surfaces: the step does not move along it, and the report names it.
inline constexpr double kWeakDirectionRatio = 1e-3;

//! The directions a point-to-plane normal matrix does not hold (eigenvalue
//! under kWeakDirectionRatio of the largest), as orthonormal columns: what
//! the solver holds fixed and the degeneracy warning names. `eigenvalues`,
//! when given, receives every eigenvalue, increasing.
Eigen::MatrixXd weakDirections(const Eigen::MatrixXd& normalMatrix, std::vector<double>* eigenvalues = nullptr);

//! The linearised (small-motion) step minimising sum w_i (n_i . (x_i + omega x x_i + tau) - n_i . y_i)^2,
//! with omega = theta axis for Four and 0 for Translation: solves the normal
//! equations in the eigenvectors of their matrix, leaving out the directions
//! the surfaces do not hold (eigenvalue under kWeakDirectionRatio of the
//! largest: on flat ground, the horizontal translations and the turn about
//! the vertical; a least-squares step along them follows noise and a few
//! edges, and slid airborne epochs by up to 1.5 m), returns the step as a
//! motion (the rotation exact, from the rotation vector) and the normal
//! matrix (columns omega then tau, omega multiplied by `length`: the
//! displacement it gives at that distance, so both are metres) for the
//! degeneracy analysis. `held`, when given, holds orthonormal columns (in the
//! unknowns' space) the step must not move along whatever this system says:
//! the directions a converged run found weak, so that steps taken while the
//! clouds were still apart cannot leave a component there that no later step
//! corrects. False when no direction is held.
bool stepPointToPlane(const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3d>& y,
                      const std::vector<Eigen::Vector3d>& n, const std::vector<double>& w, const DofConstraint& constraint,
                      double length, Eigen::Isometry3d& step, Eigen::MatrixXd& normalMatrix,
                      const Eigen::MatrixXd* held = nullptr);

//! The motion as a 4 x 4 matrix acting on global coordinates, from one acting
//! on coordinates relative to `frameOrigin`.
Eigen::Matrix4d toGlobal(const Eigen::Isometry3d& local, const Eigen::Vector3d& frameOrigin);
//! The inverse of toGlobal.
Eigen::Isometry3d toLocal(const Eigen::Matrix4d& global, const Eigen::Vector3d& frameOrigin);

//! Rotation angle (degrees) and translation length of a motion.
double rotationDegrees(const Eigen::Matrix3d& rotation);

} // namespace scandiff::plugins
