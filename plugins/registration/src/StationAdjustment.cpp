// SPDX-License-Identifier: GPL-3.0-or-later
//! The multi-station adjustment's second half: every pose at once on the used
//! pairs' point-to-plane residuals (StationModel.h). The pairs themselves
//! are found and checked in Stations.cpp.

#include "StationModel.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/RobustStatistics.h>
#include <scandiff/plugins/registration/RegistrationReport.h>
#include <scandiff/plugins/registration/RigidMotion.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace scandiff::plugins::detail {

namespace {
constexpr double kInfinity = std::numeric_limits<double>::infinity();
} // namespace

//! The points of `from` (posed) matched on the surface of `on` (posed).
void match(const Station& from, const Eigen::Isometry3d& fromPose, const Station& on, const Eigen::Isometry3d& onPose,
           const Eigen::Vector3d& worldOrigin, std::size_t limit, Matched& m)
{
    const std::size_t count = std::min(limit, from.sample.size());
    m.x.resize(count);
    std::vector<Eigen::Vector3d> local(count);
    const Eigen::Isometry3d toOn = onPose.inverse();
    const Eigen::Vector3d toSurface = worldOrigin - on.surface->frameOrigin();
    for (std::size_t i = 0; i < count; ++i) {
        m.x[i] = fromPose * from.sample[i];
        local[i] = toOn * m.x[i] + toSurface;
    }
    detail::ClosestPoints closest;
    on.surface->closest(local, closest);
    m.q.assign(count, Eigen::Vector3d::Zero());
    m.n.assign(count, Eigen::Vector3d::Zero());
    m.residual.assign(count, std::numeric_limits<double>::quiet_NaN());
    m.distance.assign(count, kInfinity);
    // A surface is seen from its front: a point a scanner saw lies on a
    // surface that faces that scanner. The two faces of a thin wall (a
    // partition, a door leaf), each seen from its own side, are not one
    // surface; matched as one, they hold the stations on either side slid
    // by the wall's thickness.
    const bool sided = from.scanner && on.scanner;
    Eigen::Vector3d fromScanner = Eigen::Vector3d::Zero(), onScanner = Eigen::Vector3d::Zero();
    if (sided) {
        fromScanner = toOn * (fromPose * *from.scanner) + toSurface;
        onScanner = *on.scanner + toSurface;
    }
    for (std::size_t i = 0; i < count; ++i) {
        if (!closest.found[i] || closest.normals[i] == Eigen::Vector3d::Zero())
            continue;
        if (sided) {
            const Eigen::Vector3d& n = closest.normals[i];
            const double facingOn = n.dot(onScanner - closest.points[i]), facingFrom = n.dot(fromScanner - local[i]);
            if (facingOn * facingFrom < 0)
                continue;
        }
        m.q[i] = onPose * (closest.points[i] - toSurface);
        m.n[i] = onPose.linear() * closest.normals[i];
        const Eigen::Vector3d d = m.x[i] - m.q[i];
        m.distance[i] = d.norm();
        m.residual[i] = m.n[i].dot(d);
    }
}

//! The displacement a motion gives a point, and its angle.
void motionSize(const Eigen::Matrix4d& m, const Eigen::Vector3d& at, double& degrees, double& metres)
{
    degrees = rotationDegrees(m.topLeftCorner<3, 3>());
    metres = ((m * at.homogeneous()).head<3>() - at).norm();
}

namespace {

//! One correspondence: a point of station `moving` on the surface of station
//! `on`, for the used pair `pair`, with its signed residual r along n.
struct Row
{
    std::size_t moving, on, pair;
    Eigen::Vector3d x, q, n;
    double r;
};

//! The adjustment's unknowns: u per station but station 0 (held), u being
//! 6, 4 (a turn about the constraint's axis and a translation) or 3.
class Unknowns
{
public:
    Unknowns(const StationParams& params, std::size_t stationCount)
        : dof_(params.constraint.dof), axis_(params.constraint.axis.normalized()), u_(dofCount(dof_)), count_(stationCount)
    {
    }
    int perStation() const { return u_; }
    Eigen::Index total() const { return static_cast<Eigen::Index>(u_ * (count_ - 1)); }
    const Eigen::Vector3d& axis() const { return axis_; }

    //! A station's column block; -1 for station 0.
    Eigen::Index block(std::size_t station) const
    {
        return station == 0 ? -1 : static_cast<Eigen::Index>(u_ * (station - 1));
    }
    //! A full (rotation, translation) derivative reduced to the unknowns.
    Eigen::VectorXd reduce(const Eigen::Matrix<double, 6, 1>& full) const
    {
        Eigen::VectorXd v(u_);
        if (dof_ == Dof::Six)
            v = full;
        else if (dof_ == Dof::Four)
            v << axis_.dot(full.head<3>()), full.tail<3>();
        else
            v = full.tail<3>();
        return v;
    }
    //! Station k's rotation vector (scaled back by `length`) and translation in `delta`.
    void motionOf(const Eigen::VectorXd& delta, std::size_t k, double length, Eigen::Vector3d& omega, Eigen::Vector3d& tau) const
    {
        const Eigen::Index at = static_cast<Eigen::Index>(u_ * (k - 1));
        omega = Eigen::Vector3d::Zero();
        if (dof_ == Dof::Six) {
            omega = delta.segment<3>(at) / length;
            tau = delta.segment<3>(at + 3);
        } else if (dof_ == Dof::Four) {
            omega = axis_ * (delta[at] / length);
            tau = delta.segment<3>(at + 1);
        } else {
            tau = delta.segment<3>(at);
        }
    }

private:
    Dof dof_;
    Eigen::Vector3d axis_;
    int u_;
    std::size_t count_;
};

//! The root mean square distance of the samples from the world origin: the
//! length that brings rotations to the translations' scale.
double sampleRadius(const std::vector<Station>& stations)
{
    double spread = 0;
    std::size_t points = 0;
    for (const Station& s : stations)
        for (const auto& p : s.sample) {
            spread += p.squaredNorm();
            ++points;
        }
    return std::max(std::sqrt(spread / static_cast<double>(points)), 1e-9);
}

//! Every used pair matched both ways at the current poses; rows within the
//! maximum distance and the residual threshold, with their match distances.
void gatherRows(const std::vector<Station>& stations, const std::vector<StationPair>& pairs, const std::vector<Eigen::Isometry3d>& pose,
                const Eigen::Vector3d& worldOrigin, const StationParams& params, double threshold, std::vector<Row>& rows,
                std::vector<double>& distances)
{
    for (std::size_t e = 0; e < pairs.size(); ++e)
        for (int way = 0; way < 2; ++way) {
            const std::size_t from = way ? pairs[e].a : pairs[e].b, on = way ? pairs[e].b : pairs[e].a;
            Matched m;
            match(stations[from], pose[from], stations[on], pose[on], worldOrigin, params.sampleCount, m);
            for (std::size_t i = 0; i < m.x.size(); ++i)
                if (m.distance[i] <= params.maxDistance && std::abs(m.residual[i]) <= threshold) {
                    rows.push_back({from, on, e, m.x[i], m.q[i], m.n[i], m.residual[i]});
                    distances.push_back(m.distance[i]);
                }
        }
}

//! The weighted normal equations h delta = -g of the rows (Cauchy weights at
//! `scale`), each pair's sum of squares and count; returns the rows' RMS.
double accumulateNormalEquations(const std::vector<Row>& rows, double scale, double length, const Unknowns& unknowns,
                                 Eigen::MatrixXd& h, Eigen::VectorXd& g, std::vector<double>& pairSquares,
                                 std::vector<double>& pairCount)
{
    const int u = unknowns.perStation();
    double sum2 = 0;
    std::fill(pairSquares.begin(), pairSquares.end(), 0.0);
    std::fill(pairCount.begin(), pairCount.end(), 0.0);
    for (const Row& row : rows) {
        // Cauchy weights (tuning 2.3849: 95 % efficiency on Gaussian noise).
        const double v = row.r / scale / 2.3849, w = 1.0 / (1.0 + v * v);
        sum2 += row.r * row.r;
        pairSquares[row.pair] += row.r * row.r;
        pairCount[row.pair] += 1;
        // d r / d(station moved): rotation x × n, translation n; the
        // surface's station: rotation n × (x - q) - q × n, translation -n.
        const Eigen::Vector3d d = row.x - row.q;
        Eigen::Matrix<double, 6, 1> jm, jo;
        jm << row.x.cross(row.n) / length, row.n;
        jo << (row.n.cross(d) - row.q.cross(row.n)) / length, -row.n;
        // Only the two stations' blocks of the normal matrix change.
        const Eigen::VectorXd a = unknowns.reduce(jm), b = unknowns.reduce(jo);
        const Eigen::Index am = unknowns.block(row.moving), ao = unknowns.block(row.on);
        if (am >= 0) {
            h.block(am, am, u, u).noalias() += w * a * a.transpose();
            g.segment(am, u).noalias() += w * row.r * a;
        }
        if (ao >= 0) {
            h.block(ao, ao, u, u).noalias() += w * b * b.transpose();
            g.segment(ao, u).noalias() += w * row.r * b;
        }
        if (am >= 0 && ao >= 0) {
            h.block(am, ao, u, u).noalias() += w * a * b.transpose();
            h.block(ao, am, u, u).noalias() += w * b * a.transpose();
        }
    }
    return std::sqrt(sum2 / static_cast<double>(rows.size()));
}

struct StepSize
{
    double rotationDegrees = 0, translation = 0, move = 0; //!< the largest over the stations
};

//! Every station but 0 moved by its part of `delta`.
StepSize applyStep(const Eigen::VectorXd& delta, const Unknowns& unknowns, double length, std::vector<Eigen::Isometry3d>& pose)
{
    StepSize size;
    for (std::size_t k = 1; k < pose.size(); ++k) {
        Eigen::Vector3d omega, tau;
        unknowns.motionOf(delta, k, length, omega, tau);
        Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
        if (omega.norm() > 0)
            step.linear() = Eigen::AngleAxisd(omega.norm(), omega.normalized()).toRotationMatrix();
        step.translation() = tau;
        pose[k] = step * pose[k];
        size.rotationDegrees = std::max(size.rotationDegrees, rotationDegrees(step.linear()));
        size.translation = std::max(size.translation, tau.norm());
        size.move = std::max(size.move, omega.norm() * 2 * length + tau.norm());
    }
    return size;
}

} // namespace

JointAdjustment adjustJointly(const std::vector<Station>& stations, const std::vector<StationPair>& pairs,
                              const std::vector<Eigen::Matrix4d>& chain, const StationParams& params,
                              const Eigen::Vector3d& worldOrigin, RegistrationReport& report, ProgressObserver* progress)
{
    const std::size_t count = stations.size();
    JointAdjustment out;
    out.pose.resize(count);
    for (std::size_t k = 0; k < count; ++k)
        out.pose[k] = toLocal(chain[k], worldOrigin);
    out.pairSquares.assign(pairs.size(), 0.0);
    out.pairCount.assign(pairs.size(), 0.0);
    const double length = sampleRadius(stations);
    const Unknowns unknowns(params, count);
    const Eigen::Index total = unknowns.total();
    double threshold = params.maxDistance, previousRms = kInfinity, rmsTwoBefore = kInfinity;
    double graduatedScale = params.maxDistance / 3;
    ProgressTicker ticker(progress, "Stations: joint adjustment", params.maxIterations);
    Eigen::MatrixXd h;
    for (std::size_t iteration = 1; iteration <= params.maxIterations; ++iteration) {
        h = Eigen::MatrixXd::Zero(total, total);
        Eigen::VectorXd g = Eigen::VectorXd::Zero(total);
        std::vector<Row> rows;
        std::vector<double> distances;
        gatherRows(stations, pairs, out.pose, worldOrigin, params, threshold, rows, distances);
        if (rows.size() < static_cast<std::size_t>(total) + 3)
            throw Error(ErrorCode::InvalidData, "stations: only " + std::to_string(rows.size()) + " correspondences between the stations");
        std::vector<double> magnitudes(rows.size());
        for (std::size_t i = 0; i < rows.size(); ++i)
            magnitudes[i] = std::abs(rows[i].r);
        // Graduated: the weights start wide (a third of the maximum
        // distance) and narrow by half each iteration to the residuals' own
        // robust scale. Narrow from the start, a station slid along a hall
        // by a pair that saw little across it stays slid: the few surfaces
        // across the slide (an end wall, a column) are outliers to the many
        // along it.
        const double robustScale = std::max(kMadToSigma * medianOf(magnitudes), 1e-12 * length);
        const double scale = std::max(robustScale, graduatedScale);
        graduatedScale /= 2;
        const double rms = accumulateNormalEquations(rows, scale, length, unknowns, h, g, out.pairSquares, out.pairCount);
        const Eigen::LDLT<Eigen::MatrixXd> solver(h);
        const Eigen::VectorXd delta = solver.solve(-g);
        if (solver.info() != Eigen::Success || !delta.allFinite())
            throw Error(ErrorCode::InvalidData, "stations: the overlaps do not determine every pose (degenerate geometry)");
        const StepSize step = applyStep(delta, unknowns, length, out.pose);
        report.trace.push_back({iteration, rms, rows.size(), threshold, step.rotationDegrees, step.translation});
        report.iterations = iteration;
        out.finalResiduals = magnitudes;
        // The threshold shrinks with the residuals, as in the change-robust
        // ICP: 3 robust sigmas, never below the median match distance.
        threshold = std::min(threshold, std::max(3 * scale, medianOf(distances)));
        ticker.step();
        const double tolerance = 1e-7 * std::max(rms, 1e-12);
        const bool graduated = scale <= robustScale;
        if (graduated && (step.move < 1e-7 || std::abs(previousRms - rms) <= tolerance || std::abs(rmsTwoBefore - rms) <= tolerance)) {
            report.converged = true;
            break;
        }
        rmsTwoBefore = previousRms;
        previousRms = rms;
    }
    // Each station's own block: the directions its overlaps do not hold, the
    // other stations held fixed.
    const int u = unknowns.perStation();
    for (std::size_t k = 1; k < count; ++k) {
        std::vector<double> eigenvalues;
        const std::string weak = degeneracyWarning(h.block(unknowns.block(k), unknowns.block(k), u, u), u, unknowns.axis(), eigenvalues);
        if (!weak.empty())
            report.degeneracy += (report.degeneracy.empty() ? "" : "; ") + std::string("station ") + std::to_string(k) + ": " + weak;
    }
    return out;
}

} // namespace scandiff::plugins::detail
