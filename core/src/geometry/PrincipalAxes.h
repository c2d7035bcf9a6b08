// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Principal axes of a 3 x 3 covariance matrix, fast on the neighbourhoods of
//! surfaces (internal to core: local models, normals, local features).

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>

namespace scandiff::detail {

//! A unit vector in the kernel of the rank-2 symmetric matrix m (an
//! eigenvector of the matrix it was shifted from): the longest cross product
//! of its largest-diagonal column with the two others, as Eigen's direct
//! solver extracts it. `other` receives that column, orthogonal to the kernel.
inline Eigen::Vector3d kernelOf(const Eigen::Matrix3d& m, Eigen::Vector3d& other)
{
    Eigen::Index i0 = 0;
    m.diagonal().cwiseAbs().maxCoeff(&i0);
    other = m.col(i0);
    const Eigen::Vector3d c0 = other.cross(m.col((i0 + 1) % 3)), c1 = other.cross(m.col((i0 + 2) % 3));
    const double n0 = c0.squaredNorm(), n1 = c1.squaredNorm();
    return n0 > n1 ? Eigen::Vector3d(c0 * (1 / std::sqrt(n0))) : Eigen::Vector3d(c1 * (1 / std::sqrt(n1)));
}

//! The smallest and largest principal axes of a covariance matrix (values in
//! increasing order). A neighbourhood of a surface has one eigenvalue far
//! below the others, so Newton's method on the characteristic polynomial,
//! started at 0, reaches it in a few steps (the polynomial is convex and
//! decreasing below its smallest root, so the steps rise monotonically), and
//! the two others follow from the trace and the sum of the 2x2 minors. This
//! avoids the trigonometric closed form of Eigen's computeDirect (atan2 and
//! sincos per point were a twentieth of the Delaunay model's time); Eigen
//! still answers when the two smallest eigenvalues are too close for Newton.
inline void principalAxes(const Eigen::Matrix3d& covariance, Eigen::Vector3d& values, Eigen::Vector3d& smallest,
                   Eigen::Vector3d& largest)
{
    const double scale = covariance.cwiseAbs().maxCoeff();
    if (!(scale > 0) || !std::isfinite(scale)) {
        values.setZero();
        return;
    }
    const Eigen::Matrix3d m = covariance * (1 / scale);
    const double trace = m.trace();
    const double minors = m(0, 0) * m(1, 1) - m(0, 1) * m(0, 1) + m(0, 0) * m(2, 2) - m(0, 2) * m(0, 2) +
                          m(1, 1) * m(2, 2) - m(1, 2) * m(1, 2);
    const double det = m.determinant();
    double low = 0;
    bool converged = !(det > 0); // a flat (or rounding-negative) determinant: the smallest is 0
    for (int step = 0; step < 32 && !converged; ++step) {
        const double value = det - low * (minors - low * (trace - low));
        const double slope = -3 * low * low + 2 * trace * low - minors;
        const double next = low - value / slope;
        converged = !(next > low); // no more progress: at the root to rounding
        if (!converged)
            low = next;
    }
    const double rest = trace - low, product = minors - low * rest; // sum and product of the two others
    const double high = 0.5 * (rest + std::sqrt(std::max(0.0, rest * rest - 4 * product)));
    const double middle = high > 0 ? product / high : 0;
    // Near a double root the polynomial is flat: its rounding stops Newton
    // early, and the kernel of a matrix shifted by an inexact value tilts by
    // about the error over the gap. With the two smallest a thousandth of the
    // largest apart, the axis is good to about 1e-10; closer, Eigen decides
    // (any axis is then almost as good a normal as another).
    if (!converged || !(middle - low > 1e-3 * high)) {
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
        solver.computeDirect(covariance);
        values = solver.eigenvalues();
        smallest = solver.eigenvectors().col(0);
        largest = solver.eigenvectors().col(2);
        return;
    }
    values = Eigen::Vector3d(low, middle, high) * scale;
    Eigen::Vector3d other;
    smallest = kernelOf(m - low * Eigen::Matrix3d::Identity(), other);
    // The largest axis from its own kernel unless the two largest values are
    // equal to rounding (any axis of the plane is then as good): either way
    // made exactly orthogonal to the smallest.
    if (high - middle > 2 * std::numeric_limits<double>::epsilon() * (middle - low)) {
        Eigen::Vector3d unused;
        largest = kernelOf(m - high * Eigen::Matrix3d::Identity(), unused);
    } else {
        largest = other;
    }
    largest -= largest.dot(smallest) * smallest;
    largest.normalize();
}

} // namespace scandiff::detail
