// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What every registration run reports, whatever its method: the motion, the
//! residuals, how it got there, and whether the geometry held it.

#include <scandiff/core/Table.h>

#include <Eigen/Core>

#include <string>
#include <vector>

namespace scandiff::plugins {

struct RegistrationIteration
{
    std::size_t iteration = 0;
    double rms = 0;              //!< of the residuals used (m)
    std::size_t used = 0;        //!< correspondences used
    double threshold = 0;        //!< distance beyond which correspondences were left out (inf: none)
    double rotationStep = 0;     //!< degrees
    double translationStep = 0;  //!< metres
};

struct RegistrationReport
{
    std::string method;
    //! Moving -> reference, in global (unshifted) coordinates.
    Eigen::Matrix4d matrix = Eigen::Matrix4d::Identity();
    //! The moving points' centroid (global): the motion's shift is reported
    //! there, since the matrix's own translation, for georeferenced data, is
    //! mostly the rotation of the coordinates' magnitude.
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    double rms = 0;                 //!< final residuals used
    double median = 0, p90 = 0, p95 = 0, p99 = 0; //!< of |residual| over the points used
    double overlap = 0;             //!< fraction of the moving points used at the end (NaN: not a measure of the method)
    std::size_t iterations = 0;
    bool converged = false;
    std::vector<RegistrationIteration> trace;
    //! Eigenvalues of the final normal matrix (increasing, rotation in metres
    //! at the cloud's scale) and the directions they weigh, for the degeneracy test.
    std::vector<double> eigenvalues;
    std::string degeneracy; //!< empty when every direction is held, else a warning naming the weak ones
    //! Per pair (point pairs): the residual distance after the fit.
    std::vector<double> pairResiduals;
    std::vector<std::string> notes;
};

//! One row per figure: metric, value (the matrix row by row, the rotation
//! angle and translation, RMS and percentiles, overlap, iterations,
//! convergence, eigenvalues, the warning).
Table reportTable(const RegistrationReport& report);
//! One row per iteration: iteration, rms, used, threshold, rotation_step_deg, translation_step_m.
Table traceTable(const RegistrationReport& report);
//! A few lines for the console: the matrix, the motion, the residuals, the warning.
std::string reportSummary(const RegistrationReport& report);

//! "weak: translation along (0.00, 1.00, 0.00)"... from a normal matrix whose
//! unknowns are (rotation x y z in metres, translation x y z), or the reduced
//! sets of Four and Translation; empty when the smallest eigenvalue is at least
//! kWeakDirectionRatio (1e-3) of the largest. Fills `eigenvalues`.
std::string degeneracyWarning(const Eigen::MatrixXd& normalMatrix, int dofCount, const Eigen::Vector3d& axis,
                              std::vector<double>& eigenvalues);

} // namespace scandiff::plugins
