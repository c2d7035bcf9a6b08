// SPDX-License-Identifier: GPL-3.0-or-later
// Registration on planes (thesis 004): hypotheses from three planes of each
// scan making the same angles, each scored by the planes it brings onto
// planes of the other scan (area-weighted), the best refined on all its
// matches. Every computation is in frames centred on each scan's planes, in
// double, so UTM coordinates lose nothing.
#include <scandiff/plugins/registration/PrimitiveAlignment.h>

#include "ShapeGeometry.h"

#include <scandiff/core/Error.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace scandiff::plugins {

namespace {

using detail::lineAngle;
using detail::rotationBetween;

constexpr double kDegree = M_PI / 180.0;

struct Plane
{
    int id = -1;
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
    Eigen::Vector3d point = Eigen::Vector3d::Zero(); //!< in the scan's centred frame
    double area = 0;
};

struct Motion
{
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    Eigen::Vector3d translation = Eigen::Vector3d::Zero(); //!< centred moving frame -> centred reference frame
};

std::vector<Plane> planesOf(const std::vector<DetectedPrimitive>& shapes, std::size_t maxPlanes, Eigen::Vector3d& centre)
{
    std::vector<const DetectedPrimitive*> planes;
    for (const DetectedPrimitive& s : shapes)
        if (s.primitive.kind == PrimitiveKind::Plane)
            planes.push_back(&s);
    std::stable_sort(planes.begin(), planes.end(), [](const DetectedPrimitive* a, const DetectedPrimitive* b) { return a->area > b->area; });
    if (planes.size() > maxPlanes)
        planes.resize(maxPlanes);
    // Each plane's point where its inliers are (the centroid on the plane): the
    // point a plane carries may lie anywhere on it, and the matching compares places.
    auto placeOf = [](const DetectedPrimitive& p) -> Eigen::Vector3d {
        const Eigen::Vector3d n = p.primitive.direction.normalized();
        return p.centroid - n * n.dot(p.centroid - p.primitive.point);
    };
    centre = Eigen::Vector3d::Zero();
    for (const DetectedPrimitive* p : planes)
        centre += placeOf(*p);
    if (!planes.empty())
        centre /= static_cast<double>(planes.size());
    std::vector<Plane> out;
    for (const DetectedPrimitive* p : planes)
        out.push_back(Plane{p->id, p->primitive.direction.normalized(), placeOf(*p) - centre, std::max(p->area, 1e-9)});
    return out;
}



struct Scored
{
    double score = 0;
    std::vector<std::pair<std::size_t, std::size_t>> pairs; //!< (moving, reference) indices
};

//! The planes the motion brings onto planes of the reference: each reference
//! plane takes the nearest moving one within the tolerances (angle, offset,
//! and their centres no farther apart than the planes' sizes), scored by area.
Scored score(const Motion& m, const std::vector<Plane>& moving, const std::vector<Plane>& reference, double angleTol, double distanceTol)
{
    Scored out;
    std::vector<bool> used(moving.size(), false);
    for (std::size_t r = 0; r < reference.size(); ++r) {
        double best = std::numeric_limits<double>::infinity();
        std::size_t chosen = moving.size();
        for (std::size_t k = 0; k < moving.size(); ++k) {
            if (used[k])
                continue;
            const Eigen::Vector3d n = m.rotation * moving[k].normal;
            if (lineAngle(n, reference[r].normal) > angleTol)
                continue;
            const Eigen::Vector3d p = m.rotation * moving[k].point + m.translation;
            const double offset = std::abs(reference[r].normal.dot(p - reference[r].point));
            const double ratio = std::min(moving[k].area, reference[r].area) / std::max(moving[k].area, reference[r].area);
            const double reach = 0.5 * (std::sqrt(moving[k].area) + std::sqrt(reference[r].area)) + distanceTol;
            if (offset > distanceTol || ratio < 1.0 / 3.0 || (p - reference[r].point).norm() > reach)
                continue;
            if (offset < best) {
                best = offset;
                chosen = k;
            }
        }
        if (chosen < moving.size()) {
            used[chosen] = true;
            out.pairs.emplace_back(chosen, r);
            out.score += std::min(moving[chosen].area, reference[r].area);
        }
    }
    return out;
}

//! The motion fitted on matched planes: rotation from their normals (the
//! moving normal's sign taken from the current motion), translation from
//! their offsets by weighted least squares; `free` gets the direction the
//! offsets leave unknown, if any.
Motion refine(const Motion& current, const std::vector<std::pair<std::size_t, std::size_t>>& pairs, const std::vector<Plane>& moving,
              const std::vector<Plane>& reference, Eigen::Vector3d* free)
{
    std::vector<Eigen::Vector3d> from, to;
    std::vector<double> w;
    for (const auto& [k, r] : pairs) {
        const double sign = (current.rotation * moving[k].normal).dot(reference[r].normal) < 0 ? -1.0 : 1.0;
        from.push_back(sign * moving[k].normal);
        to.push_back(reference[r].normal);
        w.push_back(std::min(moving[k].area, reference[r].area));
    }
    Motion out;
    out.rotation = rotationBetween(from, to, w);
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (std::size_t q = 0; q < pairs.size(); ++q) {
        const auto [k, r] = pairs[q];
        const Eigen::Vector3d& n = reference[r].normal;
        // n . (R p_m + t - p_r) = 0 for every matched pair.
        a += w[q] * n * n.transpose();
        b += w[q] * n * n.dot(reference[r].point - out.rotation * moving[k].point);
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(a);
    const Eigen::Vector3d values = solver.eigenvalues();
    Eigen::Vector3d t = Eigen::Vector3d::Zero();
    // Directions the planes' normals barely span are left where the
    // hypothesis put them (the ICP that follows fixes them).
    for (int e = 0; e < 3; ++e) {
        const Eigen::Vector3d v = solver.eigenvectors().col(e);
        if (values[e] > 1e-3 * values[2])
            t += v * (v.dot(b) / values[e]);
        else {
            t += v * v.dot(current.translation);
            if (free)
                *free = v;
        }
    }
    out.translation = t;
    return out;
}

} // namespace

PrimitiveAlignment alignOnPlanes(const std::vector<DetectedPrimitive>& movingShapes, const std::vector<DetectedPrimitive>& referenceShapes,
                                 const PrimitiveAlignmentParams& params)
{
    Eigen::Vector3d movingCentre, referenceCentre;
    const std::vector<Plane> moving = planesOf(movingShapes, params.maxPlanes, movingCentre);
    const std::vector<Plane> reference = planesOf(referenceShapes, params.maxPlanes, referenceCentre);
    const double angleTol = params.angleToleranceDegrees * kDegree;
    // Triplets whose normals span space well (no two parallel, not all along one plane).
    auto triplets = [](const std::vector<Plane>& planes) {
        std::vector<std::array<std::size_t, 3>> out;
        for (std::size_t i = 0; i < planes.size(); ++i)
            for (std::size_t j = i + 1; j < planes.size(); ++j)
                for (std::size_t k = j + 1; k < planes.size(); ++k)
                    if (std::abs(planes[i].normal.dot(planes[j].normal.cross(planes[k].normal))) >= 0.25)
                        out.push_back({i, j, k});
        return out;
    };
    const auto referenceTriplets = triplets(reference);
    if (referenceTriplets.empty() || triplets(moving).empty())
        throw Error(ErrorCode::InvalidData, "primitive alignment: each scan needs three planes facing three ways (two walls and a "
                                            "floor); found " + std::to_string(moving.size()) + " planes in the moving scan and " +
                                                std::to_string(reference.size()) + " in the reference");

    Motion best;
    Scored bestScore;
    for (const auto& [i, j, k] : referenceTriplets) {
        const double aij = lineAngle(reference[i].normal, reference[j].normal), aik = lineAngle(reference[i].normal, reference[k].normal),
                     ajk = lineAngle(reference[j].normal, reference[k].normal);
        for (std::size_t a = 0; a < moving.size(); ++a)
            for (std::size_t b = 0; b < moving.size(); ++b) {
                if (b == a || std::abs(lineAngle(moving[a].normal, moving[b].normal) - aij) > 2 * angleTol)
                    continue;
                for (std::size_t c = 0; c < moving.size(); ++c) {
                    if (c == a || c == b || std::abs(lineAngle(moving[a].normal, moving[c].normal) - aik) > 2 * angleTol ||
                        std::abs(lineAngle(moving[b].normal, moving[c].normal) - ajk) > 2 * angleTol)
                        continue;
                    // Normals have no sign of their own: the signs that make a rotation.
                    for (int signs = 0; signs < 8; ++signs) {
                        const double sa = signs & 1 ? -1 : 1, sb = signs & 2 ? -1 : 1, sc = signs & 4 ? -1 : 1;
                        const std::vector<Eigen::Vector3d> from = {sa * moving[a].normal, sb * moving[b].normal, sc * moving[c].normal};
                        const std::vector<Eigen::Vector3d> to = {reference[i].normal, reference[j].normal, reference[k].normal};
                        Motion m;
                        m.rotation = rotationBetween(from, to, {1.0, 1.0, 1.0});
                        bool fits = true;
                        for (int q = 0; q < 3 && fits; ++q)
                            fits = (m.rotation * from[q]).dot(to[q]) >= std::cos(2 * angleTol);
                        if (!fits)
                            continue;
                        // The translation from the three offsets.
                        Eigen::Matrix3d n;
                        Eigen::Vector3d rhs;
                        const std::array<std::pair<std::size_t, std::size_t>, 3> trio = {{{a, i}, {b, j}, {c, k}}};
                        for (int q = 0; q < 3; ++q) {
                            const auto [mk, rk] = trio[q];
                            n.row(q) = reference[rk].normal.transpose();
                            rhs[q] = reference[rk].normal.dot(reference[rk].point - m.rotation * moving[mk].point);
                        }
                        m.translation = n.colPivHouseholderQr().solve(rhs);
                        Scored s = score(m, moving, reference, angleTol, params.distanceTolerance);
                        if (s.score > bestScore.score * (1 + 1e-9)) {
                            bestScore = std::move(s);
                            best = m;
                        }
                    }
                }
            }
    }
    if (bestScore.pairs.size() < 3)
        throw Error(ErrorCode::InvalidData, "primitive alignment: no motion brings three planes of the moving scan onto three of the "
                                            "reference (are they scans of the same place?)");

    // Refined on every match, then matched again with the refined motion.
    Eigen::Vector3d free = Eigen::Vector3d::Zero();
    for (int round = 0; round < 3; ++round) {
        free.setZero();
        best = refine(best, bestScore.pairs, moving, reference, &free);
        bestScore = score(best, moving, reference, angleTol, params.distanceTolerance);
    }

    PrimitiveAlignment result;
    // Global: y = R (x - cm) + t + cr.
    result.matrix.block<3, 3>(0, 0) = best.rotation;
    result.matrix.block<3, 1>(0, 3) = best.translation + referenceCentre - best.rotation * movingCentre;
    double sumAngles = 0, sumOffsets = 0;
    for (const auto& [k, r] : bestScore.pairs) {
        PlaneMatch match;
        match.moving = moving[k].id;
        match.reference = reference[r].id;
        match.angleDegrees = lineAngle(best.rotation * moving[k].normal, reference[r].normal) / kDegree;
        match.offset = std::abs(reference[r].normal.dot(best.rotation * moving[k].point + best.translation - reference[r].point));
        sumAngles += match.angleDegrees * match.angleDegrees;
        sumOffsets += match.offset * match.offset;
        result.matches.push_back(match);
    }
    result.rmsAngleDegrees = std::sqrt(sumAngles / static_cast<double>(result.matches.size()));
    result.rmsOffset = std::sqrt(sumOffsets / static_cast<double>(result.matches.size()));
    if (free.norm() > 0) {
        char text[160];
        std::snprintf(text, sizeof text, "the matched planes do not fix the translation along (%.3f, %.3f, %.3f): ICP must finish it",
                      free.x(), free.y(), free.z());
        result.degeneracy = text;
    }
    result.notes.push_back(std::to_string(result.matches.size()) + " planes matched of " + std::to_string(moving.size()) + " (moving) and " +
                           std::to_string(reference.size()) + " (reference)");
    return result;
}

namespace {

struct Target
{
    int id = -1;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero(); //!< in the scan's centred frame
    double radius = 0;
};

std::vector<Target> targetsOf(const std::vector<DetectedPrimitive>& shapes, Eigen::Vector3d& centre)
{
    std::vector<Target> out;
    centre = Eigen::Vector3d::Zero();
    for (const DetectedPrimitive& s : shapes)
        if (s.primitive.kind == PrimitiveKind::Sphere) {
            out.push_back(Target{s.id, s.primitive.point, s.primitive.radius});
            centre += s.primitive.point;
        }
    if (!out.empty())
        centre /= static_cast<double>(out.size());
    for (Target& t : out)
        t.centre -= centre;
    return out;
}

//! The rotation and translation taking the `from` points onto the `to` ones (Kabsch, proper).
Motion rigidBetween(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to)
{
    Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < from.size(); ++k) {
        a += from[k];
        b += to[k];
    }
    a /= static_cast<double>(from.size());
    b /= static_cast<double>(to.size());
    std::vector<Eigen::Vector3d> x, y;
    for (std::size_t k = 0; k < from.size(); ++k) {
        x.push_back(from[k] - a);
        y.push_back(to[k] - b);
    }
    Motion m;
    m.rotation = rotationBetween(x, y, std::vector<double>(x.size(), 1.0));
    m.translation = b - m.rotation * a;
    return m;
}

std::vector<std::pair<std::size_t, std::size_t>> matchTargets(const Motion& m, const std::vector<Target>& moving,
                                                              const std::vector<Target>& reference, double tolerance)
{
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    std::vector<bool> used(moving.size(), false);
    for (std::size_t r = 0; r < reference.size(); ++r) {
        double best = tolerance;
        std::size_t chosen = moving.size();
        for (std::size_t k = 0; k < moving.size(); ++k) {
            const double d = (m.rotation * moving[k].centre + m.translation - reference[r].centre).norm();
            if (!used[k] && d <= best && std::abs(moving[k].radius - reference[r].radius) <= tolerance) {
                best = d;
                chosen = k;
            }
        }
        if (chosen < moving.size()) {
            used[chosen] = true;
            pairs.emplace_back(chosen, r);
        }
    }
    return pairs;
}

} // namespace

PrimitiveAlignment alignOnSpheres(const std::vector<DetectedPrimitive>& movingShapes, const std::vector<DetectedPrimitive>& referenceShapes,
                                  const PrimitiveAlignmentParams& params)
{
    Eigen::Vector3d movingCentre, referenceCentre;
    const std::vector<Target> moving = targetsOf(movingShapes, movingCentre);
    const std::vector<Target> reference = targetsOf(referenceShapes, referenceCentre);
    const double tol = params.distanceTolerance;
    auto spread = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) { return (b - a).cross(c - a).norm(); };
    Motion best;
    std::vector<std::pair<std::size_t, std::size_t>> bestPairs;
    for (std::size_t i = 0; i < reference.size(); ++i)
        for (std::size_t j = i + 1; j < reference.size(); ++j)
            for (std::size_t k = j + 1; k < reference.size(); ++k) {
                // Three centres on a line leave the rotation about it free.
                if (spread(reference[i].centre, reference[j].centre, reference[k].centre) < 100 * tol * tol)
                    continue;
                const double dij = (reference[i].centre - reference[j].centre).norm(), dik = (reference[i].centre - reference[k].centre).norm(),
                             djk = (reference[j].centre - reference[k].centre).norm();
                for (std::size_t a = 0; a < moving.size(); ++a) {
                    if (std::abs(moving[a].radius - reference[i].radius) > tol)
                        continue;
                    for (std::size_t b = 0; b < moving.size(); ++b) {
                        if (b == a || std::abs(moving[b].radius - reference[j].radius) > tol ||
                            std::abs((moving[a].centre - moving[b].centre).norm() - dij) > 2 * tol)
                            continue;
                        for (std::size_t c = 0; c < moving.size(); ++c) {
                            if (c == a || c == b || std::abs(moving[c].radius - reference[k].radius) > tol ||
                                std::abs((moving[a].centre - moving[c].centre).norm() - dik) > 2 * tol ||
                                std::abs((moving[b].centre - moving[c].centre).norm() - djk) > 2 * tol)
                                continue;
                            const Motion m = rigidBetween({moving[a].centre, moving[b].centre, moving[c].centre},
                                                          {reference[i].centre, reference[j].centre, reference[k].centre});
                            auto pairs = matchTargets(m, moving, reference, tol);
                            if (pairs.size() > bestPairs.size()) {
                                bestPairs = std::move(pairs);
                                best = m;
                            }
                        }
                    }
                }
            }
    if (bestPairs.size() < 3)
        throw Error(ErrorCode::InvalidData, "sphere alignment: no motion brings three spheres of the moving scan onto three of the reference "
                                            "(found " + std::to_string(moving.size()) + " and " + std::to_string(reference.size()) +
                                                " spheres; three not on a line are needed in both)");
    // Refitted on every matched centre, matched again.
    for (int round = 0; round < 2; ++round) {
        std::vector<Eigen::Vector3d> from, to;
        for (const auto& [k, r] : bestPairs) {
            from.push_back(moving[k].centre);
            to.push_back(reference[r].centre);
        }
        best = rigidBetween(from, to);
        bestPairs = matchTargets(best, moving, reference, tol);
    }
    PrimitiveAlignment result;
    result.matrix.block<3, 3>(0, 0) = best.rotation;
    result.matrix.block<3, 1>(0, 3) = best.translation + referenceCentre - best.rotation * movingCentre;
    double sum = 0;
    for (const auto& [k, r] : bestPairs) {
        PlaneMatch match;
        match.moving = moving[k].id;
        match.reference = reference[r].id;
        match.kind = PrimitiveKind::Sphere;
        match.offset = (best.rotation * moving[k].centre + best.translation - reference[r].centre).norm();
        sum += match.offset * match.offset;
        result.matches.push_back(match);
    }
    result.rmsOffset = std::sqrt(sum / static_cast<double>(result.matches.size()));
    result.notes.push_back(std::to_string(result.matches.size()) + " spheres matched of " + std::to_string(moving.size()) + " (moving) and " +
                           std::to_string(reference.size()) + " (reference)");
    return result;
}

} // namespace scandiff::plugins
