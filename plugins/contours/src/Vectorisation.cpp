// SPDX-License-Identifier: GPL-3.0-or-later
// Straight pieces and arcs of a contour ring, corners by intersection (thesis
// 001 §4.3). The thesis extracts lines by RANSAC on the unordered contour
// points; a ring is ordered, so here the pieces come from a split at the
// points farthest from their chord (Douglas-Peucker), each refitted by total
// least squares: the same lines, without random draws.
#include <scandiff/plugins/contours/Vectorisation.h>

#include <scandiff/core/Error.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace scandiff::plugins {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;

struct Line
{
    Eigen::Vector2d point = Eigen::Vector2d::Zero(), direction = Eigen::Vector2d::UnitX();
    double rms = 0.0;
};

//! Total least squares through the points, directed from the first to the last.
Line fitLine(const std::vector<Eigen::Vector2d>& p)
{
    Line line;
    for (const Eigen::Vector2d& q : p)
        line.point += q;
    line.point /= static_cast<double>(p.size());
    Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
    for (const Eigen::Vector2d& q : p)
        covariance += (q - line.point) * (q - line.point).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(covariance);
    line.direction = solver.eigenvectors().col(1).normalized();
    if (line.direction.dot(p.back() - p.front()) < 0)
        line.direction = -line.direction;
    const Eigen::Vector2d normal(-line.direction.y(), line.direction.x());
    double sum = 0.0;
    for (const Eigen::Vector2d& q : p)
        sum += std::pow((q - line.point).dot(normal), 2);
    line.rms = std::sqrt(sum / static_cast<double>(p.size()));
    return line;
}

struct Circle
{
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    double radius = 0.0, rms = std::numeric_limits<double>::infinity();
};

//! Kasa's algebraic fit (x² + y² + D x + E y + F = 0, linear least squares),
//! about the points' centroid for conditioning.
Circle fitCircle(const std::vector<Eigen::Vector2d>& p)
{
    Circle circle;
    if (p.size() < 3)
        return circle;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const Eigen::Vector2d& q : p)
        mean += q;
    mean /= static_cast<double>(p.size());
    Eigen::MatrixXd a(p.size(), 3);
    Eigen::VectorXd b(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) {
        const Eigen::Vector2d q = p[i] - mean;
        a.row(static_cast<Eigen::Index>(i)) << q.x(), q.y(), 1.0;
        b(static_cast<Eigen::Index>(i)) = -q.squaredNorm();
    }
    const Eigen::Vector3d x = a.colPivHouseholderQr().solve(b);
    const Eigen::Vector2d centre(-0.5 * x(0), -0.5 * x(1));
    const double r2 = centre.squaredNorm() - x(2);
    if (!(r2 > 0) || !x.allFinite())
        return circle;
    circle.centre = centre + mean;
    circle.radius = std::sqrt(r2);
    double sum = 0.0;
    for (const Eigen::Vector2d& q : p)
        sum += std::pow((q - circle.centre).norm() - circle.radius, 2);
    circle.rms = std::sqrt(sum / static_cast<double>(p.size()));
    return circle;
}

double distanceToChord(const Eigen::Vector2d& q, const Eigen::Vector2d& a, const Eigen::Vector2d& b)
{
    const Eigen::Vector2d d = b - a;
    const double length = d.norm();
    if (length == 0)
        return (q - a).norm();
    return std::abs(d.x() * (q.y() - a.y()) - d.y() * (q.x() - a.x())) / length;
}

//! Douglas-Peucker on ring[first..last] (indices modulo the size), adding the split points.
void split(const Ring2d& ring, std::size_t first, std::size_t last, double tolerance, std::vector<std::size_t>& breaks)
{
    const std::size_t n = ring.size();
    double worst = 0.0;
    std::size_t at = first;
    for (std::size_t i = first + 1; i < last; ++i) {
        const double d = distanceToChord(ring[i % n], ring[first % n], ring[last % n]);
        if (d > worst) {
            worst = d;
            at = i;
        }
    }
    if (worst <= tolerance)
        return;
    split(ring, first, at, tolerance, breaks);
    breaks.push_back(at % n);
    split(ring, at, last, tolerance, breaks);
}

struct Piece
{
    std::vector<Eigen::Vector2d> points; //!< in ring order, both ends included
    Line line;
    Circle circle;
    PieceKind kind = PieceKind::Inclined;
};

double turnAngle(const Eigen::Vector2d& a, const Eigen::Vector2d& b)
{
    return std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
}

//! Where two neighbouring lines meet; their junction when nearly parallel.
Eigen::Vector2d lineCorner(const Line& a, const Line& b, const Eigen::Vector2d& junction)
{
    const double cross = a.direction.x() * b.direction.y() - a.direction.y() * b.direction.x();
    if (std::abs(cross) < std::sin(15 * kDegree))
        return junction;
    const Eigen::Vector2d d = b.point - a.point;
    const double t = (d.x() * b.direction.y() - d.y() * b.direction.x()) / cross;
    return a.point + t * a.direction;
}

//! Where a line meets a circle, the solution nearer the junction (thesis 001
//! Fig. 4.18); the junction's projection on the line when they do not meet.
Eigen::Vector2d lineArcCorner(const Line& line, const Circle& circle, const Eigen::Vector2d& junction)
{
    const Eigen::Vector2d h = line.point + (circle.centre - line.point).dot(line.direction) * line.direction;
    const double oh = (circle.centre - h).norm();
    if (oh > circle.radius)
        return line.point + (junction - line.point).dot(line.direction) * line.direction;
    const double half = std::sqrt(circle.radius * circle.radius - oh * oh);
    const Eigen::Vector2d a = h + half * line.direction, b = h - half * line.direction;
    return (a - junction).norm() < (b - junction).norm() ? a : b;
}

Eigen::Vector2d chord(const Piece& p) { return p.points.back() - p.points.front(); }

//! The points of list[first, last) as one piece (shared end points once).
Piece joined(const std::vector<Piece>& list, std::size_t first, std::size_t last)
{
    Piece piece;
    for (std::size_t j = first; j < last; ++j)
        piece.points.insert(piece.points.end(), list[j].points.begin() + (j == first ? 0 : 1), list[j].points.end());
    return piece;
}

double maxDeviation(const std::vector<Eigen::Vector2d>& points, const Line& line)
{
    const Eigen::Vector2d normal(-line.direction.y(), line.direction.x());
    double worst = 0.0;
    for (const Eigen::Vector2d& q : points)
        worst = std::max(worst, std::abs((q - line.point).dot(normal)));
    return worst;
}

//! Step 1: the ring split where a point lies farthest from its chord, at half
//! the tolerance (so that no piece straddles a corner), from the two points
//! farthest apart; each piece with its total-least-squares line.
std::vector<Piece> splitRing(const Ring2d& ring, double tolerance)
{
    const std::size_t n = ring.size();
    std::size_t far = 0;
    for (std::size_t i = 1; i < n; ++i)
        if ((ring[i] - ring[0]).squaredNorm() > (ring[far] - ring[0]).squaredNorm())
            far = i;
    std::vector<std::size_t> breaks{0};
    split(ring, 0, far, 0.5 * tolerance, breaks);
    breaks.push_back(far);
    split(ring, far, n, 0.5 * tolerance, breaks);
    std::vector<Piece> pieces;
    for (std::size_t k = 0; k < breaks.size(); ++k) {
        const std::size_t a = breaks[k], b = k + 1 < breaks.size() ? breaks[k + 1] : n; // n: back to the ring's start
        Piece piece;
        for (std::size_t i = a; i <= b; ++i)
            piece.points.push_back(ring[i % n]);
        piece.line = fitLine(piece.points);
        pieces.push_back(std::move(piece));
    }
    return pieces;
}

//! Whether pieces[first, last) make one arc (into `arc`): their points fit a
//! circle within a third of the tolerance, at least twice better than a line,
//! sweeping 30 degrees or more, bulging from their chord by twice the
//! tolerance at least, and not two lines (a corner the scan rounded).
bool arcOf(const std::vector<Piece>& pieces, std::size_t first, std::size_t last, double tolerance, Piece& arc)
{
    arc = joined(pieces, first, last);
    arc.circle = fitCircle(arc.points);
    arc.line = fitLine(arc.points);
    const Eigen::Vector2d a = arc.points.front() - arc.circle.centre, b = arc.points.back() - arc.circle.centre;
    const Eigen::Vector2d m = arc.points[arc.points.size() / 2] - arc.circle.centre;
    const double swept = std::abs(turnAngle(a, m)) + std::abs(turnAngle(m, b));
    if (!(arc.circle.rms <= tolerance / 3 && arc.circle.rms < 0.5 * arc.line.rms &&
          arc.circle.radius < 10.0 * (arc.points.back() - arc.points.front()).norm() && swept >= 30 * kDegree))
        return false;
    std::size_t splitAt = 0;
    double farthest = -1.0;
    for (std::size_t i = 0; i < arc.points.size(); ++i) {
        const double d = distanceToChord(arc.points[i], arc.points.front(), arc.points.back());
        if (d > farthest) {
            farthest = d;
            splitAt = i;
        }
    }
    if (farthest < 2.0 * tolerance)
        return false; // a line within the tolerance, or a zigzag with a corner
    if (splitAt < 2 || splitAt + 2 >= arc.points.size())
        return true;
    const std::vector<Eigen::Vector2d> head(arc.points.begin(), arc.points.begin() + static_cast<std::ptrdiff_t>(splitAt + 1));
    const std::vector<Eigen::Vector2d> tail(arc.points.begin() + static_cast<std::ptrdiff_t>(splitAt), arc.points.end());
    return !(maxDeviation(head, fitLine(head)) <= tolerance && maxDeviation(tail, fitLine(tail)) <= tolerance);
}

//! Step 2: runs of pieces that make an arc replaced by it, each run grown
//! while the circle holds (a zigzag or two inside it allowed).
std::vector<Piece> findArcs(std::vector<Piece> pieces, double tolerance)
{
    std::vector<Piece> out;
    for (std::size_t k = 0; k < pieces.size();) {
        Piece best, candidate;
        std::size_t bestLast = 0;
        int failures = 0;
        for (std::size_t last = k + 3; last <= pieces.size() && failures < 3; ++last) {
            if (arcOf(pieces, k, last, tolerance, candidate)) {
                best = std::move(candidate);
                bestLast = last;
                failures = 0;
            } else if (bestLast) {
                ++failures;
            } else if (last - k >= 8) {
                break;
            }
        }
        if (bestLast) {
            best.kind = PieceKind::Arc;
            out.push_back(std::move(best));
            k = bestLast;
        } else {
            out.push_back(std::move(pieces[k++]));
        }
    }
    return out;
}

//! Step 3: neighbouring straight pieces merged while one line holds all their
//! points within the tolerance (a sampled edge zigzags, so step 1 cut each
//! side into many short pieces; a corner never passes).
std::vector<Piece> mergeStraight(std::vector<Piece> pieces, double tolerance)
{
    auto tryMerge = [&](const Piece& a, const Piece& b, Piece& out) {
        if (a.kind == PieceKind::Arc || b.kind == PieceKind::Arc)
            return false;
        out = joined(std::vector<Piece>{a, b}, 0, 2);
        out.line = fitLine(out.points);
        return maxDeviation(out.points, out.line) <= tolerance;
    };
    std::vector<Piece> merged;
    for (Piece& piece : pieces) {
        Piece combined;
        if (!merged.empty() && tryMerge(merged.back(), piece, combined))
            merged.back() = std::move(combined);
        else
            merged.push_back(std::move(piece));
    }
    Piece combined;
    if (merged.size() > 2 && tryMerge(merged.back(), merged.front(), combined)) { // across the ring's start
        merged.front() = std::move(combined);
        merged.pop_back();
    }
    return merged;
}

//! Step 4: straight pieces classified, snapped and moved away from the
//! surface (arcs' radii likewise); short ones dropped, and short inclined
//! ones between a horizontal and a vertical one (corners the scan rounded):
//! the corner then comes from their neighbours.
std::vector<Piece> classifyPieces(std::vector<Piece> merged, const VectoriseParams& params)
{
    const double minLine = 3.0 * params.tolerance;
    std::vector<Piece> kept;
    for (Piece& piece : merged) {
        if (piece.kind == PieceKind::Arc) {
            // An arc turning right (clockwise) has its centre on the right,
            // away from the surface: moving away from the surface shrinks it.
            const Eigen::Vector2d a = piece.points.front() - piece.circle.centre;
            const Eigen::Vector2d m = piece.points[piece.points.size() / 2] - piece.circle.centre;
            const bool centreOnRight = turnAngle(a, m) < 0;
            piece.circle.radius += centreOnRight ? -params.edgeOffset : params.edgeOffset;
            if (piece.circle.radius > 0)
                kept.push_back(std::move(piece));
            continue;
        }
        if (chord(piece).norm() < minLine && merged.size() > 3)
            continue;
        Line& line = piece.line;
        const double angle = std::atan2(line.direction.y(), line.direction.x());
        const double fromHorizontal = std::abs(std::remainder(angle, kPi));
        const double fromVertical = std::abs(std::remainder(angle - kPi / 2, kPi));
        if (fromHorizontal <= params.snapDegrees * kDegree) {
            piece.kind = PieceKind::Horizontal;
            line.direction = Eigen::Vector2d(line.direction.x() >= 0 ? 1.0 : -1.0, 0.0);
        } else if (fromVertical <= params.snapDegrees * kDegree) {
            piece.kind = PieceKind::Vertical;
            line.direction = Eigen::Vector2d(0.0, line.direction.y() >= 0 ? 1.0 : -1.0);
        } else {
            piece.kind = PieceKind::Inclined;
        }
        // The surface is on the left of the ring: away from it is the right.
        line.point += params.edgeOffset * Eigen::Vector2d(line.direction.y(), -line.direction.x());
        kept.push_back(std::move(piece));
    }
    auto snapped = [](const Piece& p) { return p.kind == PieceKind::Horizontal || p.kind == PieceKind::Vertical; };
    for (std::size_t k = 0; k < kept.size() && kept.size() > 3;) {
        const Piece& before = kept[(k + kept.size() - 1) % kept.size()];
        const Piece& after = kept[(k + 1) % kept.size()];
        const double shorter = std::min(chord(before).norm(), chord(after).norm());
        if (kept[k].kind == PieceKind::Inclined && snapped(before) && snapped(after) && before.kind != after.kind &&
            chord(kept[k]).norm() < 0.2 * shorter)
            kept.erase(kept.begin() + static_cast<std::ptrdiff_t>(k));
        else
            ++k;
    }
    return kept;
}

//! Step 5: the corners (intersections of neighbouring pieces) and the
//! outline, arcs as polylines every arcStepDegrees.
VectorRing assemble(const std::vector<Piece>& kept, const VectoriseParams& params)
{
    VectorRing out;
    const std::size_t m = kept.size();
    std::vector<Eigen::Vector2d> corner(m); // corner[k]: where piece k - 1 ends and piece k starts
    for (std::size_t k = 0; k < m; ++k) {
        const Piece& before = kept[(k + m - 1) % m];
        const Piece& after = kept[k];
        const Eigen::Vector2d junction = 0.5 * (before.points.back() + after.points.front());
        const bool lineBefore = before.kind != PieceKind::Arc, lineAfter = after.kind != PieceKind::Arc;
        if (lineBefore && lineAfter)
            corner[k] = lineCorner(before.line, after.line, junction);
        else if (lineBefore)
            corner[k] = lineArcCorner(before.line, after.circle, junction);
        else if (lineAfter)
            corner[k] = lineArcCorner(after.line, before.circle, junction);
        else
            corner[k] = junction;
    }
    for (std::size_t k = 0; k < m; ++k) {
        const Piece& piece = kept[k];
        VectorPiece vp;
        vp.kind = piece.kind;
        vp.start = corner[k];
        vp.end = corner[(k + 1) % m];
        out.vertices.push_back(vp.start);
        if (piece.kind == PieceKind::Arc) {
            vp.centre = piece.circle.centre;
            vp.radius = piece.circle.radius;
            // Sweep from start to end on the side of the arc's own points.
            const Eigen::Vector2d a = vp.start - vp.centre, b = vp.end - vp.centre;
            const Eigen::Vector2d middle = piece.points[piece.points.size() / 2] - vp.centre;
            double sweep = turnAngle(a, b);
            const double toMiddle = turnAngle(a, middle);
            if (sweep * toMiddle < 0 || std::abs(toMiddle) > std::abs(sweep))
                sweep += sweep > 0 ? -2 * kPi : 2 * kPi;
            const int steps = static_cast<int>(std::clamp(std::ceil(std::abs(sweep) / (params.arcStepDegrees * kDegree)), 1.0, 100000.0));
            const double start = std::atan2(a.y(), a.x());
            for (int s = 1; s < steps; ++s) {
                const double t = start + sweep * s / steps;
                out.vertices.push_back(vp.centre + vp.radius * Eigen::Vector2d(std::cos(t), std::sin(t)));
            }
            vp.sagitta = vp.radius * (1.0 - std::cos(std::abs(sweep) / 2));
            vp.bulge = std::tan(sweep / 4);
        }
        out.pieces.push_back(vp);
    }
    return out;
}

} // namespace

const char* pieceKindName(PieceKind kind)
{
    switch (kind) {
    case PieceKind::Horizontal: return "horizontal";
    case PieceKind::Vertical: return "vertical";
    case PieceKind::Inclined: return "inclined";
    case PieceKind::Arc: return "arc";
    case PieceKind::Chain: return "chain";
    }
    return "";
}

VectorRing vectoriseRing(const Ring2d& ring, const VectoriseParams& params)
{
    if (!(params.tolerance > 0) || !(params.snapDegrees >= 0) || !(params.edgeOffset >= 0) || !(params.arcStepDegrees > 0))
        throw Error(ErrorCode::InvalidArgument, "vectorisation: the tolerance and the arc step must be > 0, the snap angle and offset >= 0");
    const std::vector<Piece> kept =
        ring.size() < 4 ? std::vector<Piece>{}
                        : classifyPieces(mergeStraight(findArcs(splitRing(ring, params.tolerance), params.tolerance), params.tolerance), params);
    if (kept.size() < 3) { // too small to split: the ring as it is
        VectorRing out;
        out.vertices = ring;
        out.pieces.push_back({PieceKind::Chain, ring.empty() ? Eigen::Vector2d::Zero() : ring.front(),
                              ring.empty() ? Eigen::Vector2d::Zero() : ring.back()});
        return out;
    }
    return assemble(kept, params);
}

} // namespace scandiff::plugins
