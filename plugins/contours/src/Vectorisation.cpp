// SPDX-License-Identifier: GPL-3.0-or-later
// Straight pieces and arcs of a contour ring, corners by intersection (thesis
// 001 §4.3). The thesis extracts lines by RANSAC on the unordered contour
// points; a ring is ordered, so here it is cut into the pieces that explain
// its points best for their number: the optimal segmentation of the ring
// (dynamic programming over where pieces start and end), each piece a line
// (total least squares) or an arc (Kasa's circle), scored by its squared
// residuals over the boundary's scatter plus a penalty per piece (the
// Bayesian information criterion: each piece's parameters cost ln n). A
// split at the points farthest from their chord (Douglas-Peucker, what was
// here before) cuts a boundary that zigzags by a point spacing into many
// short pieces when the tolerance is near the spacing, and an arc grown
// while it fits took the first 20 cm of its jambs: both came out as 15-32
// vertices and spikes of 4-11 cm on windows scanned at 2.6 cm. Without
// random draws: the same ring gives the same pieces.
#include <scandiff/plugins/contours/Vectorisation.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/RobustStatistics.h>

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
    // Kasa's fit leans towards smaller circles on a partial arc with noise;
    // a few Gauss-Newton steps on the geometric distances |q - c| - r remove
    // that (the arc of a window's head is half a circle at most).
    for (int step = 0; step < 10; ++step) {
        Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
        Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
        for (const Eigen::Vector2d& q : p) {
            const Eigen::Vector2d d = q - circle.centre;
            const double length = d.norm();
            if (!(length > 0))
                continue;
            const Eigen::Vector3d j(-d.x() / length, -d.y() / length, -1.0);
            const double r = length - circle.radius;
            normal += j * j.transpose();
            rhs -= j * r;
        }
        const Eigen::Vector3d delta = normal.ldlt().solve(rhs);
        if (!delta.allFinite())
            break;
        circle.centre += delta.head<2>();
        circle.radius += delta(2);
        if (delta.norm() < 1e-9 * std::max(1.0, circle.radius))
            break;
    }
    double sum = 0.0;
    for (const Eigen::Vector2d& q : p)
        sum += std::pow((q - circle.centre).norm() - circle.radius, 2);
    circle.rms = std::sqrt(sum / static_cast<double>(p.size()));
    return circle;
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

//! Running sums of points (relative to the first one, for conditioning),
//! from which a line's and a circle's squared residuals come in O(1) as a
//! run grows point by point.
struct RunSums
{
    Eigen::Vector2d origin = Eigen::Vector2d::Zero();
    double n = 0, x = 0, y = 0, xx = 0, xy = 0, yy = 0;
    double xz = 0, yz = 0, z = 0, zz = 0; // z = x² + y², for Kasa's circle

    void add(const Eigen::Vector2d& q)
    {
        const Eigen::Vector2d d = q - origin;
        const double zq = d.squaredNorm();
        n += 1;
        x += d.x();
        y += d.y();
        xx += d.x() * d.x();
        xy += d.x() * d.y();
        yy += d.y() * d.y();
        xz += d.x() * zq;
        yz += d.y() * zq;
        z += zq;
        zz += zq * zq;
    }
    //! Total least squares: the smaller eigenvalue of the scatter matrix.
    double lineSquares() const
    {
        const double cxx = xx - x * x / n, cxy = xy - x * y / n, cyy = yy - y * y / n;
        const double half = 0.5 * (cxx + cyy), root = std::sqrt(std::max(0.0, 0.25 * (cxx - cyy) * (cxx - cyy) + cxy * cxy));
        return std::max(0.0, half - root);
    }
    //! Kasa's fit x² + y² + D x + E y + F = 0 by linear least squares; its
    //! algebraic residual (r² - R²) is about 2 R d for a point at distance d
    //! from the circle, so the geometric squares are the algebraic ones over
    //! 4 R². False when no circle fits (points in a line).
    bool circleSquares(double& squares, Eigen::Vector2d& centre, double& radius) const
    {
        Eigen::Matrix3d m;
        m << xx, xy, x, xy, yy, y, x, y, n;
        const Eigen::Vector3d b(-xz, -yz, -z);
        const Eigen::LDLT<Eigen::Matrix3d> solver(m);
        if (solver.info() != Eigen::Success)
            return false;
        const Eigen::Vector3d p = solver.solve(b);
        if (!p.allFinite())
            return false;
        centre = Eigen::Vector2d(-0.5 * p(0), -0.5 * p(1));
        const double r2 = centre.squaredNorm() - p(2);
        if (!(r2 > 0))
            return false;
        radius = std::sqrt(r2);
        const double algebraic = zz + 2 * (p(0) * xz + p(1) * yz + p(2) * z) + p.dot(m * p);
        squares = std::max(0.0, algebraic) / (4 * r2);
        centre += origin;
        return true;
    }
};

//! What the optimal segmentation weighs: the scatter of a boundary's points
//! about their edge (a point spacing's zigzag and the noise), the penalty of
//! one more piece, and the largest mean square a piece may have.
struct SegmentationCosts
{
    bool arcs = true;
    double variance = 1.0;
    double linePenalty = 0.0, arcPenalty = 0.0;
    double meanSquareLimit = 1.0;
    double smallestRadius = 0.0; //!< a tighter bend is a corner, not an arc
};

//! A candidate piece from the run p[i..j]: its cost, or infinity when no
//! line or arc holds it. Arcs must sweep 20 degrees or more, bulge from their
//! chord by the tolerance at least, and have a radius below ten chords:
//! anything flatter is a line.
struct Candidate
{
    double cost = std::numeric_limits<double>::infinity();
    bool arc = false;
};

Candidate bestPiece(const RunSums& sums, const Eigen::Vector2d& first, const Eigen::Vector2d& middle, const Eigen::Vector2d& last,
                    double tolerance, const SegmentationCosts& c)
{
    Candidate out;
    const double lineSq = sums.lineSquares();
    if (lineSq <= c.meanSquareLimit * sums.n)
        out.cost = lineSq / c.variance + c.linePenalty;
    double arcSq = 0, radius = 0;
    Eigen::Vector2d centre;
    if (c.arcs && sums.n >= 6 && sums.circleSquares(arcSq, centre, radius) && arcSq <= c.meanSquareLimit * sums.n) {
        const double span = (last - first).norm();
        const double swept = std::abs(turnAngle(first - centre, middle - centre)) + std::abs(turnAngle(middle - centre, last - centre));
        const double bulge = radius * (1 - std::cos(std::min(swept, kPi) / 2));
        const double cost = arcSq / c.variance + c.arcPenalty;
        if (swept >= 20 * kDegree && radius < 10 * span && radius >= c.smallestRadius && bulge >= tolerance && cost < out.cost) {
            out.cost = cost;
            out.arc = true;
        }
    }
    return out;
}

//! The index where the ring turns least over a few points either side: the
//! middle of a straight run or of an arc, where the segmentation of the ring
//! starts (a cut there costs one piece, joined again at the end; a cut at a
//! corner would leave the corner's rounded points no piece on one side).
std::size_t flattestPoint(const Ring2d& ring)
{
    const std::size_t n = ring.size(), w = std::max<std::size_t>(2, std::min<std::size_t>(6, n / 8));
    std::size_t best = 0;
    double least = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector2d in = ring[i] - ring[(i + n - w) % n], out = ring[(i + w) % n] - ring[i];
        const double turn = std::abs(turnAngle(in, out)) + std::abs(turnAngle(ring[(i + w) % n] - ring[(i + n - w) % n], out));
        if (turn < least) {
            least = turn;
            best = i;
        }
    }
    return best;
}

//! A piece's line fitted on its middle: a boundary rounds at corners (the
//! triangles there are the first to go), so the points near a piece's ends
//! tilt its total-least-squares line; a tenth of them at each end (two at
//! least, a quarter at most) are left out, then the points farther than
//! 2.5 scatters from that line, and the line is fitted again.
Line robustLine(const std::vector<Eigen::Vector2d>& points, double scatter)
{
    const std::size_t n = points.size();
    const std::size_t trim = std::min(std::max<std::size_t>(2, n / 10), n / 4);
    if (n < 8)
        return fitLine(points);
    std::vector<Eigen::Vector2d> middle(points.begin() + static_cast<std::ptrdiff_t>(trim), points.end() - static_cast<std::ptrdiff_t>(trim));
    Line line = fitLine(middle);
    const Eigen::Vector2d normal(-line.direction.y(), line.direction.x());
    std::vector<Eigen::Vector2d> near;
    for (const Eigen::Vector2d& q : middle)
        if (std::abs((q - line.point).dot(normal)) <= 2.5 * scatter)
            near.push_back(q);
    if (near.size() >= 3) {
        line = fitLine(near);
        if (line.direction.dot(points.back() - points.front()) < 0)
            line.direction = -line.direction;
    }
    return line;
}

std::vector<Piece> mergeStraight(std::vector<Piece> pieces, double tolerance, double scatter);
void refineArcJunctions(std::vector<Piece>& pieces, double scatter);

//! How far a boundary's points stray from its edge (the zigzag of the
//! points a gap criterion leaves at the edge, about a third of a spacing,
//! and the noise): 1.4826 times the median distance of a point from the
//! chord of its neighbours two places either side (times 0.8: the distance
//! to a chord of noisy points overstates a point's own scatter). Corners and
//! arcs are few among the points and leave the median alone. Between a
//! tenth and a third of the tolerance.
double boundaryScatter(const std::vector<Eigen::Vector2d>& p, double tolerance)
{
    const std::size_t n = p.size() - 1; // p is closed
    std::vector<double> off;
    off.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector2d a = p[(i + n - 2) % n], b = p[(i + 2) % n], d = b - a;
        const double length = d.norm();
        if (length > 0)
            off.push_back(std::abs(d.x() * (p[i].y() - a.y()) - d.y() * (p[i].x() - a.x())) / length);
    }
    if (off.empty())
        return tolerance / 3;
    std::nth_element(off.begin(), off.begin() + static_cast<std::ptrdiff_t>(off.size() / 2), off.end());
    return std::clamp(0.8 * kMadToSigma * off[off.size() / 2], tolerance / 10, tolerance / 3);
}

//! Steps 1-3: the ring, from its flattest point, cut into the pieces of least
//! total cost (a piece's squared residuals over the boundary's variance plus
//! its penalty), by dynamic programming over the cut points: for each start,
//! the run grows while its mean square stays within the limit (beyond, no
//! longer run from that start can fit either). Between two pieces a few
//! points may belong to neither, each at the cost of a residual of three
//! scatters: the boundary rounds every corner (its triangles are the first a
//! gap criterion removes), and those points, forced into a piece, tilted it
//! or made a short chamfer or a small arc of the corner; the corner itself
//! comes from the neighbours' intersection (step 5). Each piece is refitted
//! from its points.
std::vector<Piece> segmentRing(const Ring2d& input, double tolerance, bool arcs)
{
    const std::size_t n = input.size();
    const std::size_t start = flattestPoint(input);
    std::vector<Eigen::Vector2d> p(n + 1);
    for (std::size_t k = 0; k <= n; ++k)
        p[k] = input[(start + k) % n]; // closed: p[n] is p[0]
    SegmentationCosts c;
    c.arcs = arcs;
    // The scatter of boundary points about their edge, measured on the ring;
    // one more piece costs what its parameters cost in the information
    // criterion (a line 4, with its two ends; an arc 6: a circle's three, its
    // ends, and the doubt that a corner the scan rounded is no arc).
    const double scatter = boundaryScatter(p, tolerance);
    c.variance = scatter * scatter;
    const double logN = std::log(static_cast<double>(std::max<std::size_t>(n, 8)));
    c.linePenalty = 4 * logN;
    c.arcPenalty = 6 * logN;
    c.meanSquareLimit = tolerance * tolerance / 4;
    c.smallestRadius = 4 * tolerance;
    constexpr std::size_t kCornerPoints = 5; // points a corner may leave to neither piece
    constexpr double kCornerPointCost = 9.0;  // each: a residual of three scatters
    constexpr double kInfinity = std::numeric_limits<double>::infinity();
    // best[k]: the least cost of the points up to k, a piece ending at k
    // (best[0]: nothing yet); the last piece runs from[k]..k after the
    // piece that ended at previous[k].
    std::vector<double> best(n + 1, kInfinity);
    std::vector<std::size_t> from(n + 1, 0), previous(n + 1, 0);
    std::vector<char> arcTo(n + 1, 0), ended(n + 1, 0);
    best[0] = 0;
    const auto grow = [&](std::size_t before, std::size_t a, double base) {
        RunSums sums;
        sums.origin = p[a];
        sums.add(p[a]);
        for (std::size_t j = a + 1; j <= n; ++j) {
            sums.add(p[j]);
            const Candidate piece = bestPiece(sums, p[a], p[(a + j) / 2], p[j], tolerance, c);
            if (!std::isfinite(piece.cost)) {
                if (j - a >= 3)
                    break; // too far from any line or arc: longer runs are too
                continue;
            }
            if (base + piece.cost < best[j]) {
                best[j] = base + piece.cost;
                from[j] = a;
                previous[j] = before;
                arcTo[j] = piece.arc;
                ended[j] = 1;
            }
        }
    };
    grow(0, 0, 0.0);
    for (std::size_t i = 1; i < n; ++i) {
        if (!ended[i])
            continue;
        for (std::size_t a = i; a <= i + kCornerPoints + 1 && a < n; ++a)
            grow(i, a, best[i] + static_cast<double>(a > i ? a - i - 1 : 0) * kCornerPointCost);
    }
    const std::size_t last = n;
    std::vector<Piece> pieces;
    for (std::size_t j = last; j > 0 && ended[j]; j = previous[j]) {
        Piece piece;
        piece.points.assign(p.begin() + static_cast<std::ptrdiff_t>(from[j]), p.begin() + static_cast<std::ptrdiff_t>(j + 1));
        piece.line = robustLine(piece.points, scatter);
        if (arcTo[j]) {
            piece.kind = PieceKind::Arc;
            piece.circle = fitCircle(piece.points);
        }
        pieces.push_back(std::move(piece));
    }
    std::reverse(pieces.begin(), pieces.end());
    // The start was a cut by construction: where the first and last pieces
    // are one line or one arc (a ring without corners), they become one.
    if (pieces.size() > 2) {
        const auto costOf = [&](const std::vector<Eigen::Vector2d>& q) {
            RunSums sums;
            sums.origin = q.front();
            for (const Eigen::Vector2d& r : q)
                sums.add(r);
            return bestPiece(sums, q.front(), q[q.size() / 2], q.back(), tolerance, c);
        };
        std::vector<Eigen::Vector2d> joined = pieces.back().points;
        joined.insert(joined.end(), pieces.front().points.begin(), pieces.front().points.end());
        const Candidate one = costOf(joined);
        if (one.cost < costOf(pieces.back().points).cost + costOf(pieces.front().points).cost) {
            Piece merged;
            merged.points = std::move(joined);
            merged.line = robustLine(merged.points, scatter);
            if (one.arc) {
                merged.kind = PieceKind::Arc;
                merged.circle = fitCircle(merged.points);
            }
            pieces.back() = std::move(merged);
            pieces.erase(pieces.begin());
        }
    }
    pieces = mergeStraight(std::move(pieces), tolerance, scatter);
    refineArcJunctions(pieces, scatter);
    return pieces;
}

//! Step 3b: neighbouring straight pieces merged when their directions are
//! within 15 degrees and one line holds all their points within the
//! tolerance: the optimal cut splits an edge the scan bent a little (a
//! station's pattern, a seam), and a CAD user wants it whole.
std::vector<Piece> mergeStraight(std::vector<Piece> pieces, double tolerance, double scatter)
{
    const auto tryMerge = [&](const Piece& a, const Piece& b, Piece& out) {
        if (a.kind == PieceKind::Arc || b.kind == PieceKind::Arc)
            return false;
        out.points = a.points;
        out.points.insert(out.points.end(), b.points.begin() + 1, b.points.end());
        out.kind = PieceKind::Inclined;
        if (std::abs(a.line.direction.dot(b.line.direction)) < std::cos(15 * kDegree))
            return false;
        out.line = robustLine(out.points, scatter);
        const Eigen::Vector2d normal(-out.line.direction.y(), out.line.direction.x());
        for (const Eigen::Vector2d& q : out.points)
            if (std::abs((q - out.line.point).dot(normal)) > tolerance)
                return false;
        return true;
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

//! Step 3c: where a line meets an arc, the cut moved along the ring to where
//! the two geometric fits leave the least squared distances: near a tangent
//! point a line and an arc are alike, and the arc took the first decimetres
//! of a jamb, bulging past it.
void refineArcJunctions(std::vector<Piece>& pieces, double scatter)
{
    const auto squares = [&](const std::vector<Eigen::Vector2d>& q, bool arc) {
        if (arc) {
            const Circle c = fitCircle(q);
            return std::isfinite(c.rms) ? c.rms * c.rms * static_cast<double>(q.size()) : std::numeric_limits<double>::infinity();
        }
        const Line l = robustLine(q, scatter);
        const Eigen::Vector2d normal(-l.direction.y(), l.direction.x());
        double sum = 0;
        for (const Eigen::Vector2d& r : q)
            sum += std::pow((r - l.point).dot(normal), 2);
        return sum;
    };
    const std::size_t m = pieces.size();
    for (std::size_t k = 0; k < m && m >= 2; ++k) {
        Piece& a = pieces[k];
        Piece& b = pieces[(k + 1) % m];
        const bool arcA = a.kind == PieceKind::Arc, arcB = b.kind == PieceKind::Arc;
        if (arcA == arcB)
            continue;
        // The joined run (the points a corner left to neither stay out), and
        // the cut searched a quarter of the shorter piece either side.
        const bool shared = a.points.back() == b.points.front();
        std::vector<Eigen::Vector2d> run = a.points;
        run.insert(run.end(), b.points.begin() + (shared ? 1 : 0), b.points.end());
        const std::size_t at = a.points.size() - 1;
        const std::size_t reach = std::min(a.points.size(), b.points.size()) / 4;
        std::size_t bestCut = at;
        double least = std::numeric_limits<double>::infinity();
        for (std::size_t cut = at - reach; cut <= at + reach; ++cut) {
            if (cut < 3 || cut + 4 > run.size())
                continue;
            const std::vector<Eigen::Vector2d> head(run.begin(), run.begin() + static_cast<std::ptrdiff_t>(cut + 1));
            const std::vector<Eigen::Vector2d> tail(run.begin() + static_cast<std::ptrdiff_t>(cut), run.end());
            if ((arcA && head.size() < 6) || (arcB && tail.size() < 6))
                continue;
            const double total = squares(head, arcA) + squares(tail, arcB);
            if (total < least) {
                least = total;
                bestCut = cut;
            }
        }
        if (bestCut == at)
            continue;
        a.points.assign(run.begin(), run.begin() + static_cast<std::ptrdiff_t>(bestCut + 1));
        b.points.assign(run.begin() + static_cast<std::ptrdiff_t>(bestCut + (shared ? 0 : 1)), run.end());
        for (Piece* piece : {&a, &b}) {
            piece->line = robustLine(piece->points, scatter);
            if (piece->kind == PieceKind::Arc)
                piece->circle = fitCircle(piece->points);
        }
    }
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
        // Snapped when within the snap angle, or within 10 degrees when the
        // façade's direction holds the piece's points within the tolerance
        // ("when they fit": a short edge of a few noisy points tilts its own
        // line by more than the snap angle, not its points off the façade's).
        const auto fits = [&](const Eigen::Vector2d& direction) {
            const Eigen::Vector2d normal(-direction.y(), direction.x());
            double offset = 0;
            for (const Eigen::Vector2d& q : piece.points)
                offset += q.dot(normal) / static_cast<double>(piece.points.size());
            const std::size_t trim = std::min<std::size_t>(2, piece.points.size() / 4);
            for (std::size_t k = trim; k + trim < piece.points.size(); ++k)
                if (std::abs(piece.points[k].dot(normal) - offset) > params.tolerance)
                    return false;
            return true;
        };
        const double loose = std::max(params.snapDegrees, 10.0) * kDegree;
        const Eigen::Vector2d horizontal(line.direction.x() >= 0 ? 1.0 : -1.0, 0.0), vertical(0.0, line.direction.y() >= 0 ? 1.0 : -1.0);
        const auto snapTo = [&](const Eigen::Vector2d& direction, PieceKind kind) {
            piece.kind = kind;
            line.direction = direction;
            // Through the points' mean across the new direction.
            const Eigen::Vector2d normal(-direction.y(), direction.x());
            double offset = 0;
            for (const Eigen::Vector2d& q : piece.points)
                offset += (q - line.point).dot(normal) / static_cast<double>(piece.points.size());
            line.point += offset * normal;
        };
        if (params.snapDegrees > 0 && fromHorizontal <= loose && (fromHorizontal <= params.snapDegrees * kDegree || fits(horizontal)))
            snapTo(horizontal, PieceKind::Horizontal);
        else if (params.snapDegrees > 0 && fromVertical <= loose && (fromVertical <= params.snapDegrees * kDegree || fits(vertical)))
            snapTo(vertical, PieceKind::Vertical);
        else
            piece.kind = PieceKind::Inclined;
        // The surface is on the left of the ring: away from it is the right.
        line.point += params.edgeOffset * Eigen::Vector2d(line.direction.y(), -line.direction.x());
        kept.push_back(std::move(piece));
    }
    auto snapped = [](const Piece& p) { return p.kind == PieceKind::Horizontal || p.kind == PieceKind::Vertical; };
    // Neighbours snapped to the same direction along one line (within the
    // tolerance across it) are one edge: a vertex between them is no corner.
    for (std::size_t k = 0; kept.size() > 3 && k < kept.size();) {
        Piece& a = kept[k];
        Piece& b = kept[(k + 1) % kept.size()];
        const Eigen::Vector2d normal(-a.line.direction.y(), a.line.direction.x());
        if (snapped(a) && a.kind == b.kind && a.line.direction.dot(b.line.direction) > 0 &&
            std::abs((b.line.point - a.line.point).dot(normal)) <= params.tolerance) {
            const double na = static_cast<double>(a.points.size()), nb = static_cast<double>(b.points.size());
            a.line.point += nb / (na + nb) * (b.line.point - a.line.point).dot(normal) * normal;
            a.points.insert(a.points.end(), b.points.begin(), b.points.end());
            kept.erase(kept.begin() + static_cast<std::ptrdiff_t>((k + 1) % kept.size()));
            if ((k + 1) % (kept.size() + 1) == 0 && k > 0)
                --k; // erased the first piece: the merged one moved down
        } else {
            ++k;
        }
    }
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
    const std::vector<Piece> kept = ring.size() < 4 ? std::vector<Piece>{} : classifyPieces(segmentRing(ring, params.tolerance, params.arcs), params);
    if (kept.size() < 2) { // too small to split: the ring as it is
        VectorRing out;
        out.vertices = ring;
        out.pieces.push_back({PieceKind::Chain, ring.empty() ? Eigen::Vector2d::Zero() : ring.front(),
                              ring.empty() ? Eigen::Vector2d::Zero() : ring.back()});
        return out;
    }
    return assemble(kept, params);
}

} // namespace scandiff::plugins
