// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/plugins/registration/RigidMotion.h>

#include <scandiff/core/Error.h>

#include <Eigen/Dense>

#include <cmath>

namespace scandiff::plugins {

namespace {

constexpr double kPi = 3.14159265358979323846;

} // namespace

Dof parseDof(const std::string& text)
{
    if (text == "6")
        return Dof::Six;
    if (text == "4")
        return Dof::Four;
    if (text == "translation" || text == "3")
        return Dof::Translation;
    throw Error(ErrorCode::InvalidArgument, "degrees of freedom: '" + text + "' is not 6, 4 or translation");
}

const char* dofName(Dof dof)
{
    switch (dof) {
    case Dof::Six: return "6";
    case Dof::Four: return "4";
    case Dof::Translation: return "translation";
    }
    return "";
}

int dofCount(Dof dof)
{
    return dof == Dof::Six ? 6 : dof == Dof::Four ? 4 : 3;
}

bool fitPointToPoint(const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3d>& y, const std::vector<double>& w,
                     const DofConstraint& constraint, Eigen::Isometry3d& motion)
{
    const std::size_t n = x.size();
    double total = 0;
    Eigen::Vector3d xm = Eigen::Vector3d::Zero(), ym = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
        total += w[i];
        xm += w[i] * x[i];
        ym += w[i] * y[i];
    }
    if (!(total > 0))
        return false;
    xm /= total;
    ym /= total;
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    if (constraint.dof == Dof::Six) {
        // Kabsch: the rotation from the SVD of the weighted cross-covariance,
        // its determinant forced to +1 (a reflection is never a motion).
        Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
        for (std::size_t i = 0; i < n; ++i)
            h.noalias() += w[i] * (x[i] - xm) * (y[i] - ym).transpose();
        const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
        if (!(svd.singularValues()[1] > 1e-12 * svd.singularValues()[0]))
            return false; // collinear pairs fix no rotation
        Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
        d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
        rotation = svd.matrixV() * d * svd.matrixU().transpose();
    } else if (constraint.dof == Dof::Four) {
        // The angle about the axis minimising the squared distances: the 2D
        // Procrustes angle of the pairs projected across the axis.
        const Eigen::Vector3d a = constraint.axis.normalized();
        double sine = 0, cosine = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const Eigen::Vector3d u = (x[i] - xm) - (x[i] - xm).dot(a) * a, v = (y[i] - ym) - (y[i] - ym).dot(a) * a;
            sine += w[i] * a.dot(u.cross(v));
            cosine += w[i] * u.dot(v);
        }
        if (!(std::hypot(sine, cosine) > 0))
            return false;
        rotation = Eigen::AngleAxisd(std::atan2(sine, cosine), a).toRotationMatrix();
    }
    motion = Eigen::Isometry3d::Identity();
    motion.linear() = rotation;
    motion.translation() = ym - rotation * xm;
    return true;
}

Eigen::MatrixXd weakDirections(const Eigen::MatrixXd& normalMatrix, std::vector<double>* eigenvalues)
{
    if (eigenvalues)
        eigenvalues->clear();
    if (normalMatrix.rows() == 0)
        return {};
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(normalMatrix);
    const Eigen::VectorXd values = solver.eigenvalues();
    if (eigenvalues)
        eigenvalues->assign(values.data(), values.data() + values.size());
    const double largest = values.maxCoeff();
    std::vector<Eigen::Index> weak;
    for (Eigen::Index i = 0; i < values.size(); ++i)
        if (!(values[i] >= kWeakDirectionRatio * largest && largest > 0))
            weak.push_back(i);
    Eigen::MatrixXd columns(normalMatrix.rows(), static_cast<Eigen::Index>(weak.size()));
    for (std::size_t k = 0; k < weak.size(); ++k)
        columns.col(static_cast<Eigen::Index>(k)) = solver.eigenvectors().col(weak[k]);
    return columns;
}

bool stepPointToPlane(const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3d>& y,
                      const std::vector<Eigen::Vector3d>& n, const std::vector<double>& w, const DofConstraint& constraint,
                      double length, Eigen::Isometry3d& step, Eigen::MatrixXd& normalMatrix, const Eigen::MatrixXd* held)
{
    const int unknowns = dofCount(constraint.dof);
    const Eigen::Vector3d axis = constraint.axis.normalized();
    const double scale = length > 0 ? length : 1.0;
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(unknowns, unknowns);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(unknowns);
    Eigen::VectorXd row(unknowns);
    for (std::size_t i = 0; i < x.size(); ++i) {
        // n . (omega x x) = omega . (x x n). The unknown is the rotation times
        // `scale` (the displacement it gives at that distance, in metres like
        // the translation), so its column is divided by it.
        const Eigen::Vector3d moment = x[i].cross(n[i]) / scale;
        switch (constraint.dof) {
        case Dof::Six: row << moment, n[i]; break;
        case Dof::Four: row << moment.dot(axis), n[i]; break;
        case Dof::Translation: row << n[i]; break;
        }
        const double r = n[i].dot(x[i] - y[i]);
        a.noalias() += w[i] * row * row.transpose();
        b.noalias() -= w[i] * r * row;
    }
    normalMatrix = a;
    if (!(a.diagonal().maxCoeff() > 0) || !a.allFinite())
        return false;
    if (held && held->cols() > 0) {
        // The system restricted to the complement of the held directions.
        const Eigen::MatrixXd project = Eigen::MatrixXd::Identity(unknowns, unknowns) - *held * held->transpose();
        a = project * a * project;
        b = project * b;
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(a);
    if (solver.info() != Eigen::Success)
        return false;
    const Eigen::VectorXd values = solver.eigenvalues();
    const double largest = values.maxCoeff();
    Eigen::VectorXd delta = Eigen::VectorXd::Zero(unknowns);
    for (Eigen::Index i = 0; i < values.size(); ++i)
        if (values[i] >= kWeakDirectionRatio * largest && values[i] > 0) {
            const Eigen::VectorXd v = solver.eigenvectors().col(i);
            delta += v * (v.dot(b) / values[i]);
        }
    if (!delta.allFinite())
        return false;
    Eigen::Vector3d omega = Eigen::Vector3d::Zero(), tau = Eigen::Vector3d::Zero();
    switch (constraint.dof) {
    case Dof::Six:
        omega = delta.head<3>() / scale;
        tau = delta.tail<3>();
        break;
    case Dof::Four:
        omega = delta[0] / scale * axis;
        tau = delta.tail<3>();
        break;
    case Dof::Translation: tau = delta.head<3>(); break;
    }
    step = Eigen::Isometry3d::Identity();
    const double angle = omega.norm();
    if (angle > 0)
        step.linear() = Eigen::AngleAxisd(angle, omega / angle).toRotationMatrix();
    step.translation() = tau;
    return true;
}

Eigen::Matrix4d toGlobal(const Eigen::Isometry3d& local, const Eigen::Vector3d& frameOrigin)
{
    // g' = O + R (g - O) + t = R g + (O - R O + t).
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = local.linear();
    m.topRightCorner<3, 1>() = frameOrigin - local.linear() * frameOrigin + local.translation();
    return m;
}

Eigen::Isometry3d toLocal(const Eigen::Matrix4d& global, const Eigen::Vector3d& frameOrigin)
{
    Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
    local.linear() = global.topLeftCorner<3, 3>();
    local.translation() = global.topRightCorner<3, 1>() - frameOrigin + local.linear() * frameOrigin;
    return local;
}

double rotationDegrees(const Eigen::Matrix3d& rotation)
{
    return Eigen::AngleAxisd(rotation).angle() * 180.0 / kPi;
}

} // namespace scandiff::plugins
