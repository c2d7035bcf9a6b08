// SPDX-License-Identifier: GPL-3.0-or-later
#include "LocalModels.h"

#include "geometry/PrincipalAxes.h"

#include <scandiff/core/geometry/PointTriangleDistance.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace scandiff::detail {

namespace {

double orient2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c)
{
    return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

//! Least-squares plane through the points; false if they are (nearly) collinear.
bool fitPlane(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& orientation, PlaneFrame& frame)
{
    if (points.size() < 3)
        return false;
    // One pass: the sums of the points and of their products, taken relative
    // to the first point so that georeferenced magnitudes cancel before the
    // squares; only the six distinct products are accumulated.
    const Eigen::Vector3d origin = points.front();
    double sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
    for (const auto& p : points) {
        const double x = p.x() - origin.x(), y = p.y() - origin.y(), z = p.z() - origin.z();
        sx += x;
        sy += y;
        sz += z;
        sxx += x * x;
        sxy += x * y;
        sxz += x * z;
        syy += y * y;
        syz += y * z;
        szz += z * z;
    }
    const double count = static_cast<double>(points.size());
    const Eigen::Vector3d mean(sx / count, sy / count, sz / count);
    const Eigen::Vector3d centroid = origin + mean;
    Eigen::Matrix3d covariance;
    covariance(0, 0) = sxx - sx * mean.x();
    covariance(1, 0) = covariance(0, 1) = sxy - sx * mean.y();
    covariance(2, 0) = covariance(0, 2) = sxz - sx * mean.z();
    covariance(1, 1) = syy - sy * mean.y();
    covariance(2, 1) = covariance(1, 2) = syz - sy * mean.z();
    covariance(2, 2) = szz - sz * mean.z();
    Eigen::Vector3d values, smallest, largest; // values increasing
    principalAxes(covariance, values, smallest, largest);
    // A line (second eigenvalue ~ 0 relative to the largest) fixes no plane.
    if (!(values[2] > 0) || values[1] <= 1e-12 * values[2])
        return false;
    frame.centroid = centroid;
    frame.normal = smallest.normalized();
    if (frame.normal.dot(orientation) < 0)
        frame.normal = -frame.normal;
    frame.u = largest.normalized();
    frame.v = frame.normal.cross(frame.u);
    return true;
}

//! The quadric's coefficients over the plane frame; false if the points do not determine one.
bool fitQuadric(const std::vector<Eigen::Vector3d>& points, FittedModel& m)
{
    // h = a u^2 + b uv + c v^2 + d u + e v + f0 over the plane, by linear least
    // squares (the thesis used gradient descent; the closed form is exact).
    // Normal equations in fixed 6x6 size: no allocation per point; u and v are
    // scaled by the neighbourhood's extent so the system stays well conditioned.
    const PlaneFrame& f = m.frame;
    if (points.size() < 6)
        return false;
    double extent = 0;
    for (const auto& p : points)
        extent = std::max(extent, (p - f.centroid).norm());
    if (!(extent > 0))
        return false;
    const double scale = 1.0 / extent;
    Eigen::Matrix<double, 6, 6> normal = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
    for (const auto& p : points) {
        const Eigen::Vector3d d = p - f.centroid;
        const double u = d.dot(f.u) * scale, v = d.dot(f.v) * scale;
        Eigen::Matrix<double, 6, 1> row;
        row << u * u, u * v, v * v, u, v, 1.0;
        normal.noalias() += row * row.transpose();
        rhs += row * (d.dot(f.normal) * scale);
    }
    const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> solver(normal);
    if (solver.info() != Eigen::Success || !solver.isPositive() ||
        solver.vectorD().minCoeff() <= 1e-12 * solver.vectorD().maxCoeff())
        return false; // the points do not determine a quadric (e.g. all on a line)
    m.quadric = solver.solve(rhs);
    m.extent = extent;
    return true;
}

bool quadricDistance(const FittedModel& m, const Eigen::Vector3d& q, double& out)
{
    const PlaneFrame& f = m.frame;
    const Eigen::Matrix<double, 6, 1>& c = m.quadric;
    const double scale = 1.0 / m.extent;
    const Eigen::Vector3d d = q - f.centroid;
    const double u = d.dot(f.u) * scale, v = d.dot(f.v) * scale, hq = d.dot(f.normal) * scale;
    const double surface = c[0] * u * u + c[1] * u * v + c[2] * v * v + c[3] * u + c[4] * v + c[5];
    const double du = 2 * c[0] * u + c[1] * v + c[3], dv = c[1] * u + 2 * c[2] * v + c[4];
    // Height difference brought to the surface normal (first order), back in metres.
    out = (hq - surface) / std::sqrt(1.0 + du * du + dv * dv) * m.extent;
    return std::isfinite(out);
}

//! Whether planar point `i` coincides with an earlier one: the triangulation
//! keeps only the first of coincident points (see delaunay2d).
bool coincidesWithEarlier(const std::vector<Eigen::Vector2d>& p, std::size_t i, double span)
{
    // Without an early exit (coincident points are rare), so the loop vectorises.
    const double tolerance2 = 1e-24 * span * span;
    bool coincides = false;
    for (std::size_t j = 0; j < i; ++j) {
        const double dx = p[j].x() - p[i].x(), dy = p[j].y() - p[i].y();
        coincides |= dx * dx + dy * dy <= tolerance2;
    }
    return coincides;
}

double nearestTriangle(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector2d>& planar,
                       const std::vector<std::array<int, 3>>& triangles, const Eigen::Vector3d& q,
                       const Eigen::Vector2d& qPlanar, Eigen::Vector3d& closest, std::size_t first = 0);

//! Marks the planar points that coincide with an earlier one, once per fit:
//! the stars and the whole triangulation skip them. Only a fit that needs
//! more than one triangle pays for this (wedgeTriangle passes over the sites
//! on its centre alone).
void markDuplicates(ModelScratch& s)
{
    if (s.duplicatesMarked)
        return;
    const std::vector<Eigen::Vector2d>& p = s.planar;
    s.duplicate.resize(p.size());
    for (std::size_t i = 0; i < p.size(); ++i)
        s.duplicate[i] = coincidesWithEarlier(p, i, s.span);
    s.duplicatesMarked = true;
}

//! The triangles around planar point c in the Delaunay triangulation of the
//! planar points and the super-triangle that delaunay2d uses: the dual of c's
//! Voronoi cell, a convex polygon clipped out of a large square by the
//! bisector of c and every other site; each remaining edge names a Delaunay
//! neighbour, and two consecutive neighbours make a triangle with c. This
//! costs one small polygon clip per site instead of a whole triangulation.
//! Returns false when c is a skipped duplicate, touches the super-triangle (it
//! is on the hull: the real triangles around it do not close) or the clip
//! degenerates. Uses the span and super-triangle fitDelaunay prepared.
bool starOf(ModelScratch& s, int c, std::vector<std::array<int, 3>>& star)
{
    markDuplicates(s);
    const std::vector<Eigen::Vector2d>& p = s.planar;
    const int n = static_cast<int>(p.size());
    star.clear();
    if (n < 3 || s.duplicate[static_cast<std::size_t>(c)])
        return false;
    const Eigen::Vector2d* super = s.superVertices.data();
    const Eigen::Vector2d& centre = p[static_cast<std::size_t>(c)];
    // The cell, relative to c, counter-clockwise; generator[i] is the site
    // across the edge from corner i to corner i + 1 (-1: the initial square).
    const double r = 100 * s.span;
    // A convex polygon cut by a half-plane gains at most one corner, so the
    // cell never has more than n + 6; one clip of a cell of m corners writes
    // at most 2 m even when rounding makes the cut inconsistent, and a cell
    // grown past n + 8 (only possible then) abandons the star. The buffers are
    // sized once, and the corners are counted in `m`.
    const std::size_t maxCorners = static_cast<std::size_t>(n) + 8;
    const std::size_t capacity = 2 * maxCorners;
    bool degenerate = false;
    for (auto* buffer : {&s.cell, &s.nextCell})
        if (buffer->size() < capacity)
            buffer->resize(capacity);
    for (auto* buffer : {&s.generator, &s.nextGenerator})
        if (buffer->size() < capacity)
            buffer->resize(capacity);
    if (s.side.size() < capacity)
        s.side.resize(capacity);
    Eigen::Vector2d* cell = s.cell.data();
    Eigen::Vector2d* nextCell = s.nextCell.data();
    int* generator = s.generator.data();
    int* nextGenerator = s.nextGenerator.data();
    double* side = s.side.data();
    std::size_t m = 4;
    cell[0] = {-r, -r};
    cell[1] = {r, -r};
    cell[2] = {r, r};
    cell[3] = {-r, r};
    std::fill(generator, generator + 4, -1);
    double cellRadius2 = 2 * r * r; // the largest squared norm of a corner
    auto clip = [&](const Eigen::Vector2d& w, double w2, int id) {
        // Keep the points x (relative to c) closer to c than to the site:
        // 2 x . w <= |w|^2 with w the site relative to c.
        bool cut = false;
        for (std::size_t i = 0; i < m; ++i) {
            side[i] = 2 * cell[i].dot(w) - w2;
            cut = cut || side[i] > 0;
        }
        if (!cut)
            return;
        std::size_t next = 0;
        for (std::size_t i = 0; i < m; ++i) {
            const std::size_t j = i + 1 == m ? 0 : i + 1;
            const double fa = side[i], fb = side[j];
            if (fa <= 0) {
                nextCell[next] = cell[i];
                nextGenerator[next++] = generator[i];
            }
            if ((fa <= 0) != (fb <= 0)) {
                nextCell[next] = cell[i] + (cell[j] - cell[i]) * (fa / (fa - fb));
                nextGenerator[next++] = fa <= 0 ? id : generator[i];
            }
        }
        std::swap(cell, nextCell);
        std::swap(generator, nextGenerator);
        m = next;
        if (m > maxCorners) {
            degenerate = true;
            m = 0; // no corner left: later sites pass over, the star is refused below
        }
        cellRadius2 = 0;
        for (std::size_t i = 0; i < m; ++i)
            cellRadius2 = std::max(cellRadius2, cell[i].squaredNorm());
    };
    // A site farther than twice the cell's farthest corner cannot cut it
    // (2 x.w <= 2 |x| |w| < |w|^2) and is passed over. The neighbourhood comes
    // nearest to the compared point first, which is near point 0, so the near
    // sites usually shrink the cell at once and most of the others are passed.
    auto clipBy = [&](const Eigen::Vector2d& site, int id) {
        const Eigen::Vector2d w = site - centre;
        const double w2 = w.squaredNorm();
        if (w2 <= 4 * cellRadius2 * (1 + 1e-6))
            clip(w, w2, id);
    };
    for (int i = 0; i < n; ++i)
        if (i != c && !s.duplicate[static_cast<std::size_t>(i)])
            clipBy(p[static_cast<std::size_t>(i)], i);
    for (int i = 0; i < 3; ++i)
        clipBy(super[i], n + i);
    if (degenerate || m < 3)
        return false;
    for (std::size_t i = 0; i < m; ++i) {
        const int a = generator[i], b = generator[i + 1 == m ? 0 : i + 1];
        if (a < 0 || a >= n || b < 0 || b >= n)
            return false; // on the hull, or the square survived
        if (a != b)
            star.push_back({c, a, b});
    }
    return star.size() >= 3;
}

//! Whether a squared 3D distance is below the squared in-plane distance from
//! a point to the line through a and b, given cross = orient2d(a, b, point):
//! |cross|^2 / |b - a|^2 (a zero-length edge gives NaN, which refuses). A
//! bound a little short of the line's distance keeps rounding on the safe
//! side and only sends a rare point on to the slower, equally exact paths.
bool nearerThanEdgeLine(double squaredDistance, double cross, const Eigen::Vector2d& a, const Eigen::Vector2d& b)
{
    return squaredDistance < cross * cross / (b - a).squaredNorm() * (1 - 1e-9);
}

//! Whether the triangles around one point (starOf) settle q: true when q
//! projects inside them, farther from their outer boundary than from the
//! nearest of them. Every other triangle lies beyond that boundary, and the
//! distance to a triangle is at least the in-plane distance to its projection;
//! the small margin keeps rounding on the safe side.
bool starSettles(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector2d>& p,
                 const std::vector<std::array<int, 3>>& star, const Eigen::Vector3d& q, const Eigen::Vector2d& qPlanar,
                 double& best, Eigen::Vector3d& closest)
{
    std::size_t under = star.size(); // the triangle q projects into
    for (std::size_t i = 0; i < star.size() && under == star.size(); ++i) {
        const auto& t = star[i];
        const Eigen::Vector2d& c = p[static_cast<std::size_t>(t[0])];
        const Eigen::Vector2d& a = p[static_cast<std::size_t>(t[1])];
        const Eigen::Vector2d& b = p[static_cast<std::size_t>(t[2])];
        if (orient2d(c, a, qPlanar) >= 0 && orient2d(a, b, qPlanar) >= 0 && orient2d(b, c, qPlanar) >= 0)
            under = i;
    }
    if (under == star.size())
        return false;
    best = nearestTriangle(points, p, star, q, qPlanar, closest, under);
    // The outer boundary is at least as far as each outer edge's line (the
    // segment lies on it).
    for (const auto& t : star) {
        const Eigen::Vector2d& a = p[static_cast<std::size_t>(t[1])];
        const Eigen::Vector2d& b = p[static_cast<std::size_t>(t[2])];
        if (!nearerThanEdgeLine(best, orient2d(a, b, qPlanar), a, b))
            return false;
    }
    return true;
}

//! The triangle around planar point c whose angle at c holds the direction
//! `towards` (from c): the corner of c's Voronoi cell farthest along that
//! direction is the circumcentre of that triangle, and
//! the two cell edges meeting there name its other vertices. The corner is a
//! two-variable linear program (maximise x . towards over the cell, one half-
//! plane per site), solved incrementally (Seidel): a site whose half-plane
//! holds the current corner costs one dot product, and only a site that cuts
//! it off moves the corner along its own bisector. Nearest sites come first,
//! so the corner settles after a few moves: much less work than clipping the
//! whole cell (starOf) when one triangle decides. False when the corner is
//! not between two real sites (c on the hull), or when a tie or a
//! contradiction of rounding makes it ambiguous; the caller then uses starOf.
bool wedgeTriangle(ModelScratch& s, int c, const Eigen::Vector2d& towards, int& a, int& b)
{
    const std::vector<Eigen::Vector2d>& p = s.planar;
    const int n = static_cast<int>(p.size());
    if (n < 3 || towards.x() == 0 || towards.y() == 0)
        return false;
    // The cell starts as the square |x|, |y| <= r around c (sites -1..-4),
    // as in starOf; its corner farthest along `towards` is fixed by two sides.
    // At most n + 6 half-planes: the buffers are sized once.
    const double r = 100 * s.span;
    const std::size_t capacity = static_cast<std::size_t>(n) + 7;
    for (auto* buffer : {&s.planeX, &s.planeY, &s.planeH})
        if (buffer->size() < capacity)
            buffer->resize(capacity);
    if (s.planeSite.size() < capacity)
        s.planeSite.resize(capacity);
    double* wx = s.planeX.data();
    double* wy = s.planeY.data();
    double* height = s.planeH.data();
    int* site = s.planeSite.data();
    std::size_t planes = 4;
    wx[0] = 1, wy[0] = 0, height[0] = r, site[0] = -1;
    wx[1] = -1, wy[1] = 0, height[1] = r, site[1] = -2;
    wx[2] = 0, wy[2] = 1, height[2] = r, site[2] = -3;
    wx[3] = 0, wy[3] = -1, height[3] = r, site[3] = -4;
    Eigen::Vector2d corner(towards.x() > 0 ? r : -r, towards.y() > 0 ? r : -r);
    a = towards.x() > 0 ? -1 : -2;
    b = towards.y() > 0 ? -3 : -4;
    const Eigen::Vector2d& centre = p[static_cast<std::size_t>(c)];
    auto meet = [&](const Eigen::Vector2d& w, int id) {
        // The half-plane of the points closer to c than to the site: w . x <= |w|^2 / 2.
        const double h = 0.5 * w.squaredNorm();
        if (w.dot(corner) > h) {
            // The new corner lies on the bisector x = foot + t e: the farthest
            // along `towards` that every earlier half-plane allows.
            const Eigen::Vector2d foot = 0.5 * w, e(-w.y(), w.x());
            const double gain = e.dot(towards);
            if (gain == 0)
                return false; // the bisector is square to the direction: a tie
            // The bounds on t as fractions (numerator, positive denominator;
            // 0 for infinite), compared by cross-multiplying: one division in
            // the end instead of one per half-plane.
            double lowerNum = -1, lowerDen = 0, upperNum = 1, upperDen = 0;
            int lowerId = 0, upperId = 0;
            for (std::size_t j = 0; j < planes; ++j) {
                const double slope = wx[j] * e.x() + wy[j] * e.y();
                const double room = height[j] - (wx[j] * foot.x() + wy[j] * foot.y());
                if (slope > 0) {
                    if (room * upperDen < upperNum * slope) { // t <= room / slope is tighter
                        upperNum = room;
                        upperDen = slope;
                        upperId = site[j];
                    }
                } else if (slope < 0) {
                    if (room * lowerDen < lowerNum * slope) { // t >= room / slope is tighter
                        lowerNum = -room;
                        lowerDen = -slope;
                        lowerId = site[j];
                    }
                } else if (room < 0) {
                    return false; // parallel and disjoint: rounding contradicts the cell
                }
            }
            if (lowerDen > 0 && upperDen > 0 && !(lowerNum * upperDen <= upperNum * lowerDen))
                return false;
            const double t = gain > 0 ? upperNum / upperDen : lowerNum / lowerDen;
            if (!std::isfinite(t))
                return false;
            corner = foot + t * e;
            a = id;
            b = gain > 0 ? upperId : lowerId;
        }
        wx[planes] = w.x();
        wy[planes] = w.y();
        height[planes] = h;
        site[planes++] = id;
        return true;
    };
    // A site on c (one of starOf's duplicates) would cut the cell down to the
    // point and is passed over. Two other sites that coincide give the same
    // half-plane twice: the second leaves the corner where the first put it
    // (at most naming itself instead), so they need no marking here.
    const double tolerance2 = 1e-24 * s.span * s.span;
    for (int i = 0; i < n; ++i) {
        const Eigen::Vector2d w = p[static_cast<std::size_t>(i)] - centre;
        if (i != c && w.squaredNorm() > tolerance2 && !meet(w, i))
            return false;
    }
    for (int i = 0; i < 3; ++i)
        if (!meet(s.superVertices[static_cast<std::size_t>(i)] - centre, n + i))
            return false;
    if (a < 0 || a >= n || b < 0 || b >= n || a == b)
        return false;
    if (orient2d(centre, p[static_cast<std::size_t>(a)], p[static_cast<std::size_t>(b)]) < 0)
        std::swap(a, b);
    return true;
}

//! Whether the one triangle (c, a, b), counter-clockwise, settles q: q
//! projects inside it and lies nearer to it than to the lines of its edges in
//! the plane. Every other triangle lies outside it, so its projection is at
//! least that far from q's.
bool triangleSettles(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector2d>& p, int c, int a,
                     int b, const Eigen::Vector3d& q, const Eigen::Vector2d& qPlanar, double& best, Eigen::Vector3d& closest)
{
    const std::array<std::size_t, 3> t = {static_cast<std::size_t>(c), static_cast<std::size_t>(a), static_cast<std::size_t>(b)};
    std::array<double, 3> cross;
    for (std::size_t e = 0; e < 3; ++e) {
        cross[e] = orient2d(p[t[e]], p[t[(e + 1) % 3]], qPlanar);
        if (cross[e] < 0)
            return false;
    }
    const geometry::PointTriangleResult r = geometry::pointTriangleDistance(q, points[t[0]], points[t[1]], points[t[2]]);
    for (std::size_t e = 0; e < 3; ++e)
        if (!nearerThanEdgeLine(r.squaredDistance, cross[e], p[t[e]], p[t[(e + 1) % 3]]))
            return false;
    best = r.squaredDistance;
    closest = r.closestPoint;
    return true;
}

//! Prepares the Delaunay model: the planar coordinates, their span and the
//! super-triangle. The triangles are found per compared point
//! (delaunayDistance): one or two, usually; the stars and the whole
//! triangulation only when those do not settle it.
bool fitDelaunay(const std::vector<Eigen::Vector3d>& points, const PlaneFrame& f, ModelScratch& scratch)
{
    scratch.planar.clear();
    for (const auto& p : points) {
        const Eigen::Vector3d d = p - f.centroid;
        scratch.planar.emplace_back(d.dot(f.u), d.dot(f.v));
    }
    // What the stars and the whole triangulation of this fit share: the span,
    // the super-triangle's vertices, the duplicates they skip.
    const std::vector<Eigen::Vector2d>& p = scratch.planar;
    if (p.size() < 3)
        return false;
    Eigen::Vector2d lo = p[0], hi = p[0];
    for (const auto& x : p) {
        lo = lo.cwiseMin(x);
        hi = hi.cwiseMax(x);
    }
    const double span = std::max((hi - lo).maxCoeff(), 1e-12);
    const Eigen::Vector2d mid = 0.5 * (lo + hi);
    scratch.span = span;
    scratch.superVertices = {Eigen::Vector2d(mid.x() - 20 * span, mid.y() - span), Eigen::Vector2d(mid.x(), mid.y() + 20 * span),
                             Eigen::Vector2d(mid.x() + 20 * span, mid.y() - span)};
    scratch.duplicatesMarked = false;
    scratch.triangulated = false;
    scratch.keep.clear();
    scratch.starComputed = false; // built on first need (delaunayDistance)
    scratch.otherStarCentre = -1;
    return true;
}

//! Smallest squared distance from q to the given triangles, and the closest point.
double nearestTriangle(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector2d>& planar,
                       const std::vector<std::array<int, 3>>& triangles, const Eigen::Vector3d& q,
                       const Eigen::Vector2d& qPlanar, Eigen::Vector3d& closest, std::size_t first)
{
    // Triangle `first` (the caller's best guess, e.g. the one under q) is
    // measured first, so that its distance prunes the others early.
    double best = std::numeric_limits<double>::infinity();
    const std::size_t count = triangles.size();
    for (std::size_t step = 0; step < count; ++step) {
        const std::size_t at = first + step < count ? first + step : first + step - count;
        const auto& t = triangles[at];
        // Projection onto the plane shortens distances, so the in-plane gap to
        // the triangle's box is a lower bound: skip triangles that cannot win.
        const Eigen::Vector2d& a = planar[static_cast<std::size_t>(t[0])];
        const Eigen::Vector2d& b = planar[static_cast<std::size_t>(t[1])];
        const Eigen::Vector2d& c = planar[static_cast<std::size_t>(t[2])];
        const Eigen::Vector2d lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
        const Eigen::Vector2d gap = (lo - qPlanar).cwiseMax(qPlanar - hi).cwiseMax(Eigen::Vector2d::Zero());
        if (gap.squaredNorm() > best)
            continue;
        const geometry::PointTriangleResult r = geometry::pointTriangleDistance(q, points[static_cast<std::size_t>(t[0])],
                                                            points[static_cast<std::size_t>(t[1])],
                                                            points[static_cast<std::size_t>(t[2])]);
        if (r.squaredDistance < best) {
            best = r.squaredDistance;
            closest = r.closestPoint;
        }
    }
    return best;
}

bool delaunayDistance(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& q, const PlaneFrame& f,
                      ModelScratch& scratch, double& out)
{
    const Eigen::Vector3d dq = q - f.centroid;
    const Eigen::Vector2d qPlanar(dq.dot(f.u), dq.dot(f.v));
    Eigen::Vector3d closest = Eigen::Vector3d::Zero();
    double best = std::numeric_limits<double>::infinity();
    bool settled = false;
    // The triangle around point 0 towards the compared point usually decides
    // alone (84 % of the points of the benchmark's scans). When it does not,
    // the same with the other planar point nearest to the projection (the
    // compared point may project beyond point 0's triangles, where an angle at
    // point 0 is obtuse); then all the triangles around point 0 (a point near
    // an edge may need both of its triangles), those around the other point
    // (kept for the next compared point of the group), and last the whole
    // triangulation.
    const std::vector<Eigen::Vector2d>& p = scratch.planar;
    int nearest = -1;
    if (p.size() > 1) {
        nearest = 1;
        for (std::size_t i = 2; i < p.size(); ++i)
            if ((p[i] - qPlanar).squaredNorm() < (p[static_cast<std::size_t>(nearest)] - qPlanar).squaredNorm())
                nearest = static_cast<int>(i);
    }
    for (const int c : {0, nearest}) {
        int a = 0, b = 0;
        if (c >= 0 && wedgeTriangle(scratch, c, qPlanar - p[static_cast<std::size_t>(c)], a, b) &&
            triangleSettles(points, p, c, a, b, q, qPlanar, best, closest)) {
            out = std::sqrt(best) * ((q - closest).dot(f.normal) < 0 ? -1.0 : 1.0);
            return true;
        }
    }
    if (!scratch.starComputed) {
        scratch.starUsable = starOf(scratch, 0, scratch.star);
        scratch.starComputed = true;
    }
    if (scratch.starUsable)
        settled = starSettles(points, scratch.planar, scratch.star, q, qPlanar, best, closest);
    if (!settled && !scratch.triangulated && nearest >= 0) {
        if (nearest != scratch.otherStarCentre) {
            scratch.otherStarCentre = nearest;
            scratch.otherStarUsable = starOf(scratch, nearest, scratch.otherStar);
        }
        if (scratch.otherStarUsable)
            settled = starSettles(points, scratch.planar, scratch.otherStar, q, qPlanar, best, closest);
    }
    if (!settled) {
        if (!scratch.triangulated) {
            delaunay2d(scratch, scratch.keep);
            scratch.triangulated = true;
        }
        if (scratch.keep.empty())
            return false;
        best = nearestTriangle(points, scratch.planar, scratch.keep, q, qPlanar, closest);
    }
    const double side = (q - closest).dot(f.normal);
    out = std::sqrt(best) * (side < 0 ? -1.0 : 1.0);
    return true;
}

} // namespace

namespace {

//! Whether d lies strictly inside the circumcircle of the triangle t of p.
bool inCircumcircle(const std::vector<Eigen::Vector2d>& p, const std::array<int, 3>& t, const Eigen::Vector2d& d)
{
    const Eigen::Vector2d a = p[static_cast<std::size_t>(t[0])] - d, b = p[static_cast<std::size_t>(t[1])] - d,
                          c = p[static_cast<std::size_t>(t[2])] - d;
    const double det = (a.squaredNorm()) * (b.x() * c.y() - c.x() * b.y()) -
                       (b.squaredNorm()) * (a.x() * c.y() - c.x() * a.y()) +
                       (c.squaredNorm()) * (a.x() * b.y() - b.x() * a.y());
    const double orientation = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    return orientation > 0 ? det > 0 : det < 0;
}

//! The plain Bowyer-Watson insertion: every triangle is tested against every
//! new point and the cavity's boundary is found by matching edges pairwise,
//! O(n^2) per point. Used when the fast insertion meets a configuration its
//! floating-point tests cannot walk through consistently (nearly cocircular or
//! collinear points), where this version needs no adjacency to stay coherent.
void delaunay2dQuadratic(const std::vector<Eigen::Vector2d>& p, int n, const std::vector<char>& duplicate,
                         std::vector<std::array<int, 3>>& work, std::vector<std::array<int, 2>>& edges)
{
    work.assign(1, {n, n + 1, n + 2});
    for (int i = 0; i < n; ++i) {
        const Eigen::Vector2d& d = p[static_cast<std::size_t>(i)];
        if (duplicate[static_cast<std::size_t>(i)])
            continue;
        edges.clear();
        std::size_t kept = 0;
        for (std::size_t t = 0; t < work.size(); ++t) {
            if (inCircumcircle(p, work[t], d)) {
                for (int e = 0; e < 3; ++e)
                    edges.push_back({work[t][static_cast<std::size_t>(e)], work[t][static_cast<std::size_t>((e + 1) % 3)]});
            } else {
                work[kept++] = work[t];
            }
        }
        work.resize(kept);
        for (std::size_t e = 0; e < edges.size(); ++e) {
            bool shared = false;
            for (std::size_t f = 0; f < edges.size() && !shared; ++f)
                shared = f != e && edges[f][0] == edges[e][1] && edges[f][1] == edges[e][0];
            if (!shared)
                work.push_back({edges[e][0], edges[e][1], i});
        }
    }
}

//! Bowyer-Watson with triangle adjacency: a walk finds the triangle holding
//! the new point, the cavity grows from it through neighbours only, and its
//! boundary comes from the adjacency, so a point costs about the size of its
//! cavity instead of the whole triangulation. Returns false (the caller then
//! uses delaunay2dQuadratic) if a floating-point test contradicts the
//! structure: a walk that does not end, a cavity that is not star-shaped.
bool delaunay2dAdjacency(const std::vector<Eigen::Vector2d>& p, int n, ModelScratch& s)
{
    auto& mesh = s.mesh;
    mesh.clear();
    // Counter-clockwise super-triangle (the vertices n, n+2, n+1 of the caller's layout).
    mesh.push_back({{n, n + 2, n + 1}, {-1, -1, -1}, true});
    const std::size_t vertices = static_cast<std::size_t>(n) + 3;
    s.startAt.assign(vertices, -1);
    s.startStamp.assign(vertices, -1);
    int last = 0;
    for (int i = 0; i < n; ++i) {
        const Eigen::Vector2d& d = p[static_cast<std::size_t>(i)];
        if (s.duplicate[static_cast<std::size_t>(i)])
            continue;
        // Walk towards d: leave through an edge that d lies strictly beyond.
        int t = last;
        std::size_t steps = 0;
        for (;; ++steps) {
            if (steps > mesh.size())
                return false;
            const auto& tri = mesh[static_cast<std::size_t>(t)];
            int next = -1;
            for (int e = 0; e < 3; ++e) {
                const auto a = static_cast<std::size_t>(tri.v[static_cast<std::size_t>(e)]);
                const auto b = static_cast<std::size_t>(tri.v[static_cast<std::size_t>((e + 1) % 3)]);
                if (orient2d(p[a], p[b], d) < 0) {
                    next = tri.nb[static_cast<std::size_t>(e)];
                    if (next < 0)
                        return false; // beyond the super-triangle: cannot happen with exact tests
                    break;
                }
            }
            if (next < 0)
                break;
            t = next;
        }
        if (!inCircumcircle(p, mesh[static_cast<std::size_t>(t)].v, d))
            return false;
        // The cavity: the connected triangles whose circumcircle holds d.
        s.cavity.clear();
        s.cavity.push_back(t);
        mesh[static_cast<std::size_t>(t)].alive = false;
        for (std::size_t c = 0; c < s.cavity.size(); ++c) {
            const auto& tri = mesh[static_cast<std::size_t>(s.cavity[c])];
            for (int e = 0; e < 3; ++e) {
                const int w = tri.nb[static_cast<std::size_t>(e)];
                if (w >= 0 && mesh[static_cast<std::size_t>(w)].alive && inCircumcircle(p, mesh[static_cast<std::size_t>(w)].v, d)) {
                    mesh[static_cast<std::size_t>(w)].alive = false;
                    s.cavity.push_back(w);
                }
            }
        }
        // One new triangle (a, b, i) per boundary edge (a, b), linked to the
        // triangle outside it; the new triangles are then linked to each other
        // through the boundary vertex they share.
        const std::size_t firstNew = mesh.size();
        for (const int c : s.cavity) {
            for (int e = 0; e < 3; ++e) {
                const auto& tri = mesh[static_cast<std::size_t>(c)];
                const int w = tri.nb[static_cast<std::size_t>(e)];
                if (w >= 0 && !mesh[static_cast<std::size_t>(w)].alive)
                    continue;
                const int a = tri.v[static_cast<std::size_t>(e)], b = tri.v[static_cast<std::size_t>((e + 1) % 3)];
                if (orient2d(p[static_cast<std::size_t>(a)], p[static_cast<std::size_t>(b)], d) <= 0)
                    return false; // the cavity is not star-shaped from d
                if (s.startStamp[static_cast<std::size_t>(a)] == i)
                    return false; // two boundary edges leave a: not a simple cycle
                const int created = static_cast<int>(mesh.size());
                s.startAt[static_cast<std::size_t>(a)] = created;
                s.startStamp[static_cast<std::size_t>(a)] = i;
                mesh.push_back({{a, b, i}, {w, -1, -1}, true});
                if (w >= 0) {
                    auto& outside = mesh[static_cast<std::size_t>(w)];
                    for (int f = 0; f < 3; ++f)
                        if (outside.v[static_cast<std::size_t>(f)] == b && outside.v[static_cast<std::size_t>((f + 1) % 3)] == a)
                            outside.nb[static_cast<std::size_t>(f)] = created;
                }
            }
        }
        for (std::size_t m = firstNew; m < mesh.size(); ++m) {
            const auto b = static_cast<std::size_t>(mesh[m].v[1]);
            if (s.startStamp[b] != i)
                return false; // the boundary is not closed
            const int following = s.startAt[b];
            mesh[m].nb[1] = following;
            mesh[static_cast<std::size_t>(following)].nb[2] = static_cast<int>(m);
        }
        last = static_cast<int>(mesh.size()) - 1;
    }
    return true;
}

} // namespace

void delaunay2d(ModelScratch& scratch, std::vector<std::array<int, 3>>& triangles)
{
    triangles.clear();
    const int n = static_cast<int>(scratch.planar.size());
    if (n < 3)
        return;
    markDuplicates(scratch);
    // The super-triangle's vertices appended for the insertion, removed after.
    std::vector<Eigen::Vector2d>& p = scratch.planar;
    p.insert(p.end(), scratch.superVertices.begin(), scratch.superVertices.end());
    if (delaunay2dAdjacency(p, n, scratch)) {
        for (const auto& t : scratch.mesh)
            if (t.alive && t.v[0] < n && t.v[1] < n && t.v[2] < n)
                triangles.push_back(t.v);
    } else {
        delaunay2dQuadratic(p, n, scratch.duplicate, scratch.triangles, scratch.edges);
        for (const auto& t : scratch.triangles)
            if (t[0] < n && t[1] < n && t[2] < n)
                triangles.push_back(t);
    }
    p.resize(static_cast<std::size_t>(n));
}

bool fitModel(LocalModel model, const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& orientation,
              FittedModel& fitted, ModelScratch& scratch)
{
    fitted.model = model;
    if (!fitPlane(points, orientation, fitted.frame))
        return false;
    switch (model) {
    case LocalModel::Plane:
        return true;
    case LocalModel::Quadric:
        return fitQuadric(points, fitted);
    case LocalModel::Delaunay:
        return fitDelaunay(points, fitted.frame, scratch);
    case LocalModel::None:
        break;
    }
    return false;
}

bool modelDistance(const FittedModel& fitted, const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& q,
                   double& signedDistance, ModelScratch& scratch)
{
    switch (fitted.model) {
    case LocalModel::Plane:
        signedDistance = (q - fitted.frame.centroid).dot(fitted.frame.normal);
        return true;
    case LocalModel::Quadric:
        return quadricDistance(fitted, q, signedDistance);
    case LocalModel::Delaunay:
        return delaunayDistance(points, q, fitted.frame, scratch, signedDistance);
    case LocalModel::None:
        break;
    }
    return false;
}

} // namespace scandiff::detail
