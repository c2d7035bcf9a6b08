// SPDX-License-Identifier: GPL-3.0-or-later
// Registration on any mix of planes, cylinders and spheres (thesis 004
// consolidates scans on the primitives they share: walls and floors, pipes
// and columns, targets). Each shape constrains the motion in its own way: a
// plane its normal and its offset (1 distance), a cylinder its axis and the
// axis's place across it (2 distances), a sphere its centre (3). Three shapes
// whose constraints together fix the six degrees of freedom make a hypothesis;
// a hypothesis is scored by the shapes it brings onto shapes of the other
// scan, and the best is refined by weighted Gauss-Newton on every match.
// Every computation is in frames centred on each scan's shapes, in double.
#include <scandiff/plugins/registration/PrimitiveAlignment.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/Progress.h>

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>

namespace scandiff::plugins {

namespace {

constexpr double kDegree = M_PI / 180.0;

//! The angle between two lines (radians, 0 to pi/2): a direction's sign does not count.
double lineAngle(const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
    return std::acos(std::min(1.0, std::abs(a.dot(b))));
}

//! The proper rotation taking the `from` directions onto the `to` ones, each
//! weighted by `w` (all 1 when empty): Kabsch's SVD solution.
Eigen::Matrix3d rotationBetween(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to,
                                       const std::vector<double>& w = {})
{
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    for (std::size_t k = 0; k < from.size(); ++k)
        h += (w.empty() ? 1.0 : w[k]) * from[k] * to[k].transpose();
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
    d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
    return svd.matrixV() * d * svd.matrixU().transpose();
}

struct Shape
{
    int id = -1;
    PrimitiveKind kind = PrimitiveKind::Plane;
    Eigen::Vector3d direction = Eigen::Vector3d::Zero(); //!< plane: normal; cylinder: axis; sphere: zero
    Eigen::Vector3d point = Eigen::Vector3d::Zero();     //!< in the scan's centred frame
    double radius = 0;
    double extent = 1;  //!< sqrt(area): how far a tilt of the shape moves its points per radian (m)
    double area = 0;
    double support = 0; //!< inlier count: the weight of its constraints (each shape's noise is alike)

    bool directed() const { return kind != PrimitiveKind::Sphere; }
};

struct Motion
{
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    Eigen::Vector3d translation = Eigen::Vector3d::Zero(); //!< centred moving frame -> centred reference frame
};

using Pairs = std::vector<std::pair<std::size_t, std::size_t>>; //!< (moving, reference) indices

std::vector<Shape> shapesOf(const std::vector<DetectedPrimitive>& detected, const std::set<PrimitiveKind>& kinds,
                            const PrimitiveAlignmentParams& params, Eigen::Vector3d& centre)
{
    std::vector<const DetectedPrimitive*> chosen;
    for (PrimitiveKind kind : {PrimitiveKind::Plane, PrimitiveKind::Cylinder, PrimitiveKind::Sphere}) {
        if (!kinds.count(kind))
            continue;
        std::vector<const DetectedPrimitive*> ofKind;
        for (const DetectedPrimitive& s : detected)
            if (s.primitive.kind == kind)
                ofKind.push_back(&s);
        std::stable_sort(ofKind.begin(), ofKind.end(), [](auto* a, auto* b) { return a->inliers.size() > b->inliers.size(); });
        const std::size_t keep = kind == PrimitiveKind::Plane ? params.maxPlanes : params.maxPlanes / 2;
        if (ofKind.size() > keep)
            ofKind.resize(keep);
        chosen.insert(chosen.end(), ofKind.begin(), ofKind.end());
    }
    // Each shape's point where its inliers are: the centroid on the plane, its
    // foot on the axis, the sphere's centre (a plane's or an axis's own point
    // may lie anywhere on it, and the matching compares places).
    auto placeOf = [](const DetectedPrimitive& s) -> Eigen::Vector3d {
        const Primitive& p = s.primitive;
        const Eigen::Vector3d d = p.direction.normalized();
        switch (p.kind) {
        case PrimitiveKind::Plane: return s.centroid - d * d.dot(s.centroid - p.point);
        case PrimitiveKind::Cylinder: return p.point + d * d.dot(s.centroid - p.point);
        default: return p.point;
        }
    };
    centre = Eigen::Vector3d::Zero();
    for (const DetectedPrimitive* s : chosen)
        centre += placeOf(*s);
    if (!chosen.empty())
        centre /= static_cast<double>(chosen.size());
    std::vector<Shape> out;
    for (const DetectedPrimitive* s : chosen) {
        Shape shape;
        shape.id = s->id;
        shape.kind = s->primitive.kind;
        if (shape.directed())
            shape.direction = s->primitive.direction.normalized();
        shape.point = placeOf(*s) - centre;
        shape.radius = s->primitive.radius;
        shape.area = std::max(s->area, 1e-9);
        shape.extent = std::sqrt(shape.area);
        shape.support = static_cast<double>(std::max<std::size_t>(s->inliers.size(), 1));
        out.push_back(shape);
    }
    return out;
}


Eigen::Matrix3d skew(const Eigen::Vector3d& v)
{
    Eigen::Matrix3d m;
    m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
    return m;
}

//! The part of v across the line of direction d.
Eigen::Vector3d across(const Eigen::Vector3d& d, const Eigen::Vector3d& v)
{
    return v - d * d.dot(v);
}

//! How far the moved shape `m` (its direction and point already moved) lies
//! from the reference shape `r`: plane offset, axis-to-axis distance at the
//! moved axis point, or centre distance (m).
double positionGap(const Shape& r, const Eigen::Vector3d& movedPoint)
{
    const Eigen::Vector3d gap = movedPoint - r.point;
    switch (r.kind) {
    case PrimitiveKind::Plane: return std::abs(r.direction.dot(gap));
    case PrimitiveKind::Cylinder: return across(r.direction, gap).norm();
    default: return gap.norm();
    }
}

//! Whether `m` (moving) and `r` (reference) can be the same shape by their
//! own sizes: same kind, radii within the tolerance.
bool sameKindAndSize(const Shape& m, const Shape& r, double distanceTol)
{
    return m.kind == r.kind && (m.kind == PrimitiveKind::Plane || std::abs(m.radius - r.radius) <= distanceTol);
}

//! What two shapes of one scan keep whatever the motion, compared between
//! the scans: the angle between their directions; the distance between a
//! sphere's centre and the other shape (centre, plane, axis).
bool sameRelation(const Shape& a, const Shape& b, const Shape& ra, const Shape& rb, double angleTol, double distanceTol)
{
    if (a.directed() && b.directed())
        return std::abs(lineAngle(a.direction, b.direction) - lineAngle(ra.direction, rb.direction)) <= 2 * angleTol;
    auto distance = [](const Shape& sphere, const Shape& other) {
        return other.kind == PrimitiveKind::Sphere ? (sphere.point - other.point).norm() : positionGap(other, sphere.point);
    };
    const Shape& sphere = a.directed() ? b : a;
    const Shape& other = a.directed() ? a : b;
    const Shape& rSphere = a.directed() ? rb : ra;
    const Shape& rOther = a.directed() ? ra : rb;
    return std::abs(distance(sphere, other) - distance(rSphere, rOther)) <= 2 * distanceTol;
}

//! Weighted rows of the linearised problem for one matched pair, at the
//! current motion: residuals e and their Jacobian J with respect to a small
//! motion (w, dt) applied after it (x -> x + w x x + dt), accumulated into the
//! normal equations. Directions count by the displacement their tilt gives
//! the shape's extent; `sign` turns the moving direction to face the reference's.
void accumulate(const Shape& m, const Shape& r, const Motion& motion, double sign, double weight, Eigen::Matrix<double, 6, 6>& a,
                Eigen::Matrix<double, 6, 1>& b, double& cost)
{
    auto add = [&](const Eigen::Matrix<double, Eigen::Dynamic, 6>& j, const Eigen::VectorXd& e) {
        a += weight * j.transpose() * j;
        b -= weight * j.transpose() * e;
        cost += weight * e.squaredNorm();
    };
    const Eigen::Vector3d p = motion.rotation * m.point + motion.translation;
    if (m.directed()) {
        const Eigen::Vector3d d = sign * (motion.rotation * m.direction);
        const Eigen::Matrix3d flat = Eigen::Matrix3d::Identity() - r.direction * r.direction.transpose();
        Eigen::Matrix<double, 3, 6> j = Eigen::Matrix<double, 3, 6>::Zero();
        j.leftCols<3>() = -r.extent * flat * skew(d);
        add(j, r.extent * flat * d);
    }
    switch (r.kind) {
    case PrimitiveKind::Plane: {
        Eigen::Matrix<double, 1, 6> j;
        j << p.cross(r.direction).transpose(), r.direction.transpose();
        add(j, Eigen::VectorXd::Constant(1, r.direction.dot(p - r.point)));
        break;
    }
    case PrimitiveKind::Cylinder: {
        const Eigen::Matrix3d flat = Eigen::Matrix3d::Identity() - r.direction * r.direction.transpose();
        Eigen::Matrix<double, 3, 6> j;
        j << -flat * skew(p), flat;
        add(j, flat * (p - r.point));
        break;
    }
    default: {
        Eigen::Matrix<double, 3, 6> j;
        j << -skew(p), Eigen::Matrix3d::Identity();
        add(j, p - r.point);
        break;
    }
    }
}

//! The sign that turns the moved direction of m towards r's.
double facing(const Shape& m, const Shape& r, const Motion& motion)
{
    return m.directed() && (motion.rotation * m.direction).dot(r.direction) < 0 ? -1.0 : 1.0;
}

//! Whether the shapes, matched to themselves, fix all six degrees of
//! freedom: the smallest eigenvalue of their normal matrix (angles scaled by
//! `length`) against the largest.
bool fixesTheMotion(const std::vector<const Shape*>& shapes, double length)
{
    Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    double cost = 0;
    for (const Shape* s : shapes)
        accumulate(*s, *s, Motion{}, 1.0, 1.0, a, b, cost);
    Eigen::Matrix<double, 6, 6> scale = Eigen::Matrix<double, 6, 6>::Identity();
    scale.topLeftCorner<3, 3>() /= length;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> solver(scale * a * scale);
    return solver.eigenvalues()[0] > 1e-3 * solver.eigenvalues()[5];
}

//! Weighted Gauss-Newton on the matched pairs from `start`; a direction of
//! the motion the matches do not fix keeps its value and is named in `free`.
Motion refine(Motion motion, const Pairs& pairs, const std::vector<Shape>& moving, const std::vector<Shape>& reference, double length,
              std::string* free)
{
    for (int iteration = 0; iteration < 10; ++iteration) {
        Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Zero();
        Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
        double cost = 0;
        for (const auto& [k, r] : pairs)
            accumulate(moving[k], reference[r], motion, facing(moving[k], reference[r], motion),
                       std::min(moving[k].support, reference[r].support), a, b, cost);
        // Rotations in metres at the shapes' spread, so both halves compare.
        Eigen::Matrix<double, 6, 6> scale = Eigen::Matrix<double, 6, 6>::Identity();
        scale.topLeftCorner<3, 3>() /= length;
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> solver(scale * a * scale);
        Eigen::Matrix<double, 6, 1> step = Eigen::Matrix<double, 6, 1>::Zero();
        const Eigen::Matrix<double, 6, 1> rhs = scale * b;
        if (free)
            free->clear();
        for (int e = 0; e < 6; ++e) {
            const Eigen::Matrix<double, 6, 1> v = solver.eigenvectors().col(e);
            if (solver.eigenvalues()[e] > 1e-6 * solver.eigenvalues()[5]) {
                step += v * (v.dot(rhs) / solver.eigenvalues()[e]);
            } else if (free) {
                char text[200];
                std::snprintf(text, sizeof text,
                              "the matched shapes do not fix the motion along (rotation %.2f, %.2f, %.2f; translation %.2f, %.2f, "
                              "%.2f): ICP must finish it",
                              v[0], v[1], v[2], v[3], v[4], v[5]);
                *free = text;
            }
        }
        step = scale * step;
        const Eigen::Vector3d w = step.head<3>();
        const Eigen::Matrix3d turn = w.norm() > 0 ? Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix() : Eigen::Matrix3d::Identity();
        motion.rotation = turn * motion.rotation;
        motion.translation = turn * motion.translation + step.tail<3>();
        if (w.norm() * length + step.tail<3>().norm() < 1e-10 * length)
            break;
    }
    return motion;
}

//! The shapes the motion brings onto shapes of the reference: each reference
//! shape takes the nearest unused moving one of its kind and size within the
//! tolerances (and, for planes and cylinders, near it: the moved point no
//! farther from the reference's than their sizes), scored by support.
struct Scored
{
    double score = 0;
    Pairs pairs;
};

Scored score(const Motion& m, const std::vector<Shape>& moving, const std::vector<Shape>& reference, double angleTol, double distanceTol)
{
    Scored out;
    std::vector<bool> used(moving.size(), false);
    for (std::size_t r = 0; r < reference.size(); ++r) {
        double best = std::numeric_limits<double>::infinity();
        std::size_t chosen = moving.size();
        for (std::size_t k = 0; k < moving.size(); ++k) {
            if (used[k] || !sameKindAndSize(moving[k], reference[r], distanceTol))
                continue;
            if (moving[k].directed() && lineAngle(m.rotation * moving[k].direction, reference[r].direction) > angleTol)
                continue;
            const Eigen::Vector3d p = m.rotation * moving[k].point + m.translation;
            const double gap = positionGap(reference[r], p);
            if (gap > distanceTol)
                continue;
            if (moving[k].directed()) {
                const double ratio = std::min(moving[k].area, reference[r].area) / std::max(moving[k].area, reference[r].area);
                const double reach = 0.5 * (moving[k].extent + reference[r].extent) + distanceTol;
                if (ratio < 1.0 / 3.0 || (p - reference[r].point).norm() > reach)
                    continue;
            }
            if (gap < best) {
                best = gap;
                chosen = k;
            }
        }
        if (chosen < moving.size()) {
            used[chosen] = true;
            out.pairs.emplace_back(chosen, r);
            out.score += std::min(moving[chosen].support, reference[r].support);
        }
    }
    return out;
}


//! The motion that brings three moving shapes onto three reference shapes,
//! for one choice of the directions' signs, or nothing when it does not fit
//! them within twice the tolerances. Rotation from the directions and the
//! spheres' centre-to-centre vectors; then Gauss-Newton on the three.
std::optional<Motion> hypothesis(const std::array<const Shape*, 3>& m, const std::array<const Shape*, 3>& r, int signs, double length,
                                 double angleTol, double distanceTol)
{
    std::vector<Eigen::Vector3d> from, to;
    const Shape* firstSphere = nullptr;
    const Shape* firstReferenceSphere = nullptr;
    for (int q = 0; q < 3; ++q) {
        if (m[q]->directed()) {
            from.push_back((signs >> q & 1 ? -1.0 : 1.0) * m[q]->direction);
            to.push_back(r[q]->direction);
        } else if (!firstSphere) {
            firstSphere = m[q];
            firstReferenceSphere = r[q];
        } else {
            const Eigen::Vector3d a = m[q]->point - firstSphere->point, b = r[q]->point - firstReferenceSphere->point;
            if (a.norm() > 0 && b.norm() > 0) {
                from.push_back(a.normalized());
                to.push_back(b.normalized());
            }
        }
    }
    // Vectors across parallel axes, and from an axis to a sphere's centre:
    // they turn with the scan, and fix the rotation about the axes where the
    // directions alone (two columns and a floor) leave it free.
    for (int q = 0; q < 3; ++q)
        for (int w = 0; w < 3; ++w) {
            if (q == w || m[q]->kind != PrimitiveKind::Cylinder || (m[w]->kind == PrimitiveKind::Cylinder && w < q) ||
                m[w]->kind == PrimitiveKind::Plane)
                continue;
            if (m[w]->kind == PrimitiveKind::Cylinder && lineAngle(m[q]->direction, m[w]->direction) > 4 * angleTol)
                continue; // not parallel: the two directions already hold the rotation
            const Eigen::Vector3d a = across(m[q]->direction, m[w]->point - m[q]->point);
            const Eigen::Vector3d b = across(r[q]->direction, r[w]->point - r[q]->point);
            if (a.norm() > distanceTol && b.norm() > distanceTol) {
                from.push_back(a.normalized());
                to.push_back(b.normalized());
            }
        }
    if (from.size() < 2)
        return std::nullopt;
    Motion motion;
    motion.rotation = rotationBetween(from, to);
    for (std::size_t q = 0; q < from.size(); ++q)
        if ((motion.rotation * from[q]).dot(to[q]) < std::cos(2 * angleTol))
            return std::nullopt;
    // The translation: the shapes' points brought together, then the
    // constraints each shape really sets (Gauss-Newton from there).
    Eigen::Vector3d mc = Eigen::Vector3d::Zero(), rc = Eigen::Vector3d::Zero();
    for (int q = 0; q < 3; ++q) {
        mc += m[q]->point / 3;
        rc += r[q]->point / 3;
    }
    motion.translation = rc - motion.rotation * mc;
    std::vector<Shape> ms, rs;
    Pairs trio;
    for (std::size_t q = 0; q < 3; ++q) {
        ms.push_back(*m[q]);
        rs.push_back(*r[q]);
        trio.emplace_back(q, q);
    }
    motion = refine(motion, trio, ms, rs, length, nullptr);
    for (int q = 0; q < 3; ++q) {
        if (m[q]->directed() && lineAngle(motion.rotation * m[q]->direction, r[q]->direction) > 2 * angleTol)
            return std::nullopt;
        if (positionGap(*r[q], motion.rotation * m[q]->point + motion.translation) > 2 * distanceTol)
            return std::nullopt;
    }
    return motion;
}

std::string counted(std::size_t count, PrimitiveKind kind)
{
    return std::to_string(count) + " " + primitiveKindName(kind) + (count == 1 ? "" : "s");
}

} // namespace

PrimitiveAlignment alignOnShapes(const std::vector<DetectedPrimitive>& movingShapes, const std::vector<DetectedPrimitive>& referenceShapes,
                                 const std::set<PrimitiveKind>& kinds, const PrimitiveAlignmentParams& params, ProgressObserver* progress)
{
    for (PrimitiveKind kind : kinds)
        if (kind != PrimitiveKind::Plane && kind != PrimitiveKind::Cylinder && kind != PrimitiveKind::Sphere)
            throw Error(ErrorCode::InvalidArgument, "shape alignment: only planes, cylinders and spheres are matched");
    Eigen::Vector3d movingCentre, referenceCentre;
    const std::vector<Shape> moving = shapesOf(movingShapes, kinds, params, movingCentre);
    const std::vector<Shape> reference = shapesOf(referenceShapes, kinds, params, referenceCentre);
    const double angleTol = params.angleToleranceDegrees * kDegree;
    const double distanceTol = params.distanceTolerance;
    // The shapes' spread: the lever arm that turns a rotation into metres.
    double spread = 0;
    for (const Shape& s : reference)
        spread += s.point.squaredNorm() + s.area;
    const double length = std::max(std::sqrt(spread / std::max<std::size_t>(reference.size(), 1)), 1e-3);

    Motion best;
    Scored bestScore;
    std::size_t usableTriples = 0;
    const std::size_t nr = reference.size(), nm = moving.size();
    ProgressTicker ticker(progress, "Registration: matching shapes", nr);
    for (std::size_t i = 0; i < nr; ++i, ticker.step())
        for (std::size_t j = i + 1; j < nr; ++j)
            for (std::size_t k = j + 1; k < nr; ++k) {
                ticker.checkCancel();
                const std::array<const Shape*, 3> r = {&reference[i], &reference[j], &reference[k]};
                if (!fixesTheMotion({r[0], r[1], r[2]}, length))
                    continue;
                ++usableTriples;
                for (std::size_t a = 0; a < nm; ++a) {
                    if (!sameKindAndSize(moving[a], *r[0], distanceTol))
                        continue;
                    for (std::size_t b = 0; b < nm; ++b) {
                        if (b == a || !sameKindAndSize(moving[b], *r[1], distanceTol) ||
                            !sameRelation(moving[a], moving[b], *r[0], *r[1], angleTol, distanceTol))
                            continue;
                        for (std::size_t c = 0; c < nm; ++c) {
                            if (c == a || c == b || !sameKindAndSize(moving[c], *r[2], distanceTol) ||
                                !sameRelation(moving[a], moving[c], *r[0], *r[2], angleTol, distanceTol) ||
                                !sameRelation(moving[b], moving[c], *r[1], *r[2], angleTol, distanceTol))
                                continue;
                            const std::array<const Shape*, 3> m = {&moving[a], &moving[b], &moving[c]};
                            // Directions have no sign of their own: every choice that makes a rotation.
                            for (int signs = 0; signs < 8; ++signs) {
                                bool redundant = false;
                                for (int q = 0; q < 3; ++q)
                                    redundant = redundant || (!m[q]->directed() && (signs >> q & 1));
                                if (redundant)
                                    continue;
                                const std::optional<Motion> motion = hypothesis(m, r, signs, length, angleTol, distanceTol);
                                if (!motion)
                                    continue;
                                Scored s = score(*motion, moving, reference, angleTol, distanceTol);
                                if (s.score > bestScore.score * (1 + 1e-9)) {
                                    bestScore = std::move(s);
                                    best = *motion;
                                }
                            }
                        }
                    }
                }
            }
    std::string found = std::to_string(nm) + " shapes in the moving scan and " + std::to_string(nr) + " in the reference";
    if (usableTriples == 0)
        throw Error(ErrorCode::InvalidData, "shape alignment: no three shapes of the reference fix the motion (three planes facing three "
                                            "ways, two pipes that are not parallel, a pipe and two planes, three spheres not on a "
                                            "line...); found " + found);
    if (bestScore.pairs.size() < 3)
        throw Error(ErrorCode::InvalidData, "shape alignment: no motion brings three shapes of the moving scan onto three of the reference "
                                            "(are they scans of the same place?); found " + found);

    std::string free;
    for (int round = 0; round < 3; ++round) {
        best = refine(best, bestScore.pairs, moving, reference, length, &free);
        bestScore = score(best, moving, reference, angleTol, distanceTol);
    }

    PrimitiveAlignment result;
    result.matrix.block<3, 3>(0, 0) = best.rotation;
    result.matrix.block<3, 1>(0, 3) = best.translation + referenceCentre - best.rotation * movingCentre;
    double sumAngles = 0, sumOffsets = 0;
    std::size_t directed = 0;
    std::map<PrimitiveKind, std::size_t> counts;
    for (const auto& [k, r] : bestScore.pairs) {
        PlaneMatch match;
        match.moving = moving[k].id;
        match.reference = reference[r].id;
        match.kind = moving[k].kind;
        if (moving[k].directed()) {
            match.angleDegrees = lineAngle(best.rotation * moving[k].direction, reference[r].direction) / kDegree;
            sumAngles += match.angleDegrees * match.angleDegrees;
            ++directed;
        }
        match.offset = positionGap(reference[r], best.rotation * moving[k].point + best.translation);
        sumOffsets += match.offset * match.offset;
        ++counts[moving[k].kind];
        result.matches.push_back(match);
    }
    result.rmsAngleDegrees = directed ? std::sqrt(sumAngles / static_cast<double>(directed)) : 0.0;
    result.rmsOffset = std::sqrt(sumOffsets / static_cast<double>(result.matches.size()));
    result.degeneracy = free;
    std::string matched;
    for (const auto& [kind, count] : counts)
        matched += (matched.empty() ? "" : ", ") + counted(count, kind);
    result.notes.push_back("matched " + matched + "; " + found);
    return result;
}

} // namespace scandiff::plugins
