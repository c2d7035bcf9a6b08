// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/plugins/registration/RegistrationReport.h>
#include <scandiff/plugins/registration/RigidMotion.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <iomanip>
#include <sstream>

namespace scandiff::plugins {

namespace {


std::string vectorText(const Eigen::Vector3d& v)
{
    std::ostringstream s;
    s << std::fixed << std::setprecision(2) << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
    return s.str();
}

double centreShift(const RegistrationReport& r)
{
    return ((r.matrix * r.centre.homogeneous()).head<3>() - r.centre).norm();
}

} // namespace

std::string degeneracyWarning(const Eigen::MatrixXd& normalMatrix, int dofCount, const Eigen::Vector3d& axis,
                              std::vector<double>& eigenvalues)
{
    const Eigen::MatrixXd weakColumns = weakDirections(normalMatrix, &eigenvalues);
    std::string weak;
    for (Eigen::Index i = 0; i < weakColumns.cols(); ++i) {
        // The direction's rotation and translation parts (unknowns in the
        // order of the solver: rotation first for Six and Four).
        const Eigen::VectorXd v = weakColumns.col(i);
        Eigen::Vector3d rotation = Eigen::Vector3d::Zero(), translation = Eigen::Vector3d::Zero();
        if (dofCount == 6) {
            rotation = v.head<3>();
            translation = v.tail<3>();
        } else if (dofCount == 4) {
            rotation = v[0] * axis.normalized();
            translation = v.tail<3>();
        } else {
            translation = v.head<3>();
        }
        if (!weak.empty())
            weak += "; ";
        if (rotation.norm() >= translation.norm())
            weak += "rotation about " + vectorText(rotation.normalized());
        else
            weak += "translation along " + vectorText(translation.normalized());
    }
    if (weak.empty())
        return {};
    return "degenerate geometry: the surfaces do not hold " + weak +
           " (the motion was held fixed that way: what the start had there stays; add overlap with other surfaces, or "
           "constrain the degrees of freedom)";
}

Table reportTable(const RegistrationReport& r)
{
    Table t;
    t.columns = {"metric", "value"};
    const auto add = [&](const std::string& name, TableCell value) { t.rows.push_back({name, std::move(value)}); };
    add("method", r.method);
    for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 4; ++col)
            add("m" + std::to_string(row) + std::to_string(col), r.matrix(row, col));
    add("rotation_deg", rotationDegrees(r.matrix.topLeftCorner<3, 3>()));
    add("translation_m", r.matrix.topRightCorner<3, 1>().norm());
    add("centre_shift_m", centreShift(r));
    add("rms_m", r.rms);
    add("median_m", r.median);
    add("p90_m", r.p90);
    add("p95_m", r.p95);
    add("p99_m", r.p99);
    add("overlap", r.overlap);
    add("iterations", static_cast<double>(r.iterations));
    add("converged", r.converged ? 1.0 : 0.0);
    for (std::size_t i = 0; i < r.eigenvalues.size(); ++i)
        add("eigenvalue_" + std::to_string(i), r.eigenvalues[i]);
    for (std::size_t i = 0; i < r.pairResiduals.size(); ++i)
        add("pair_" + std::to_string(i + 1) + "_residual_m", r.pairResiduals[i]);
    add("warning", r.degeneracy);
    for (const auto& note : r.notes)
        add("note", note);
    return t;
}

Table traceTable(const RegistrationReport& r)
{
    Table t;
    t.columns = {"iteration", "rms_m", "used", "threshold_m", "rotation_step_deg", "translation_step_m"};
    for (const auto& it : r.trace)
        t.rows.push_back({static_cast<double>(it.iteration), it.rms, static_cast<double>(it.used), it.threshold, it.rotationStep,
                          it.translationStep});
    return t;
}

std::string reportSummary(const RegistrationReport& r)
{
    std::ostringstream s;
    s << r.method << ": rotation " << std::setprecision(6) << rotationDegrees(r.matrix.topLeftCorner<3, 3>()) << " deg, centre moved "
      << centreShift(r) << " m; RMS " << r.rms << " m";
    if (!r.pairResiduals.empty()) {
        s << "; pair residuals (m):";
        for (std::size_t i = 0; i < r.pairResiduals.size(); ++i)
            s << (i ? ", " : " ") << r.pairResiduals[i];
    } else {
        if (std::isfinite(r.median))
            s << " (median " << r.median << ", p95 " << r.p95 << ")";
        if (std::isfinite(r.overlap))
            s << "; overlap " << std::setprecision(3) << 100 * r.overlap << " %";
        if (!r.trace.empty())
            s << "; " << r.iterations << " iterations" << (r.converged ? "" : " (not converged)");
    }
    for (const auto& note : r.notes)
        s << "; " << note;
    if (!r.degeneracy.empty())
        s << "; WARNING " << r.degeneracy;
    return s.str();
}

} // namespace scandiff::plugins
