// SPDX-License-Identifier: GPL-3.0-or-later
// Polygon areas and overlaps through CGAL's 2D Boolean operations (exact
// kernel: a model edge lying on a reference edge is no special case).
#include <scandiff/plugins/contours/PolygonMeasures.h>

#include <scandiff/core/Error.h>

#include <CGAL/Boolean_set_operations_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_set_2.h>
#include <CGAL/Polygon_with_holes_2.h>

#include <algorithm>
#include <cmath>
#include <list>

namespace scandiff::plugins {

namespace {

using Kernel = CGAL::Exact_predicates_exact_constructions_kernel;
using CgalPolygon = CGAL::Polygon_2<Kernel>;
using CgalPolygonWithHoles = CGAL::Polygon_with_holes_2<Kernel>;

//! A ring touching itself at vertices (two stones joined by one point, a
//! hole meeting the outline) cut into simple loops there.
std::vector<Ring2d> simpleLoops(const Ring2d& ring)
{
    std::vector<Ring2d> loops;
    Ring2d stack;
    for (const Eigen::Vector2d& q : ring) {
        if (!stack.empty() && stack.back() == q)
            continue;
        const auto again = std::find(stack.begin(), stack.end(), q);
        if (again != stack.end()) {
            loops.emplace_back(again, stack.end());
            stack.erase(again + 1, stack.end());
            continue;
        }
        stack.push_back(q);
    }
    while (stack.size() > 1 && stack.front() == stack.back())
        stack.pop_back();
    loops.push_back(stack);
    loops.erase(std::remove_if(loops.begin(), loops.end(), [](const Ring2d& loop) { return loop.size() < 3; }), loops.end());
    return loops;
}

CgalPolygon toCgal(const Ring2d& loop)
{
    CgalPolygon polygon;
    for (const Eigen::Vector2d& q : loop)
        polygon.push_back(Kernel::Point_2(q.x(), q.y()));
    if (!polygon.is_simple())
        throw Error(ErrorCode::InvalidData, "polygon comparison: a ring of " + std::to_string(loop.size()) + " vertices crosses itself");
    if (polygon.orientation() == CGAL::CLOCKWISE)
        polygon.reverse_orientation();
    return polygon;
}

//! The polygon as a set: the loops of its outer ring turning as its largest
//! joined, those turning the other way (a hole touching the outline at a
//! point, chained into it) and its holes' loops removed.
CGAL::Polygon_set_2<Kernel> toSet(const Polygon2d& p)
{
    CGAL::Polygon_set_2<Kernel> set;
    const std::vector<Ring2d> loops = simpleLoops(p.outer);
    double largest = 0.0;
    for (const Ring2d& loop : loops)
        if (std::abs(signedArea(loop)) > std::abs(largest))
            largest = signedArea(loop);
    for (const Ring2d& loop : loops)
        if (signedArea(loop) * largest > 0)
            set.join(toCgal(loop));
    for (const Ring2d& loop : loops)
        if (signedArea(loop) * largest < 0)
            set.difference(toCgal(loop));
    for (const Ring2d& hole : p.holes)
        for (const Ring2d& loop : simpleLoops(hole))
            if (std::abs(signedArea(loop)) > 0)
                set.difference(toCgal(loop));
    return set;
}

double area(const CgalPolygonWithHoles& p)
{
    double a = CGAL::to_double(p.outer_boundary().area());
    for (auto hole = p.holes_begin(); hole != p.holes_end(); ++hole)
        a -= std::abs(CGAL::to_double(hole->area()));
    return a;
}

double pointToSegment(const Eigen::Vector2d& q, const Eigen::Vector2d& a, const Eigen::Vector2d& b)
{
    const Eigen::Vector2d d = b - a;
    const double length2 = d.squaredNorm();
    const double t = length2 > 0 ? std::clamp((q - a).dot(d) / length2, 0.0, 1.0) : 0.0;
    return (a + t * d - q).norm();
}

double directedHausdorff(const Ring2d& from, const Ring2d& to, double step)
{
    double worst = 0.0;
    auto distance = [&](const Eigen::Vector2d& q) {
        double best = std::numeric_limits<double>::infinity();
        for (std::size_t j = 0; j < to.size(); ++j)
            best = std::min(best, pointToSegment(q, to[j], to[(j + 1) % to.size()]));
        return best;
    };
    for (std::size_t i = 0; i < from.size(); ++i) {
        const Eigen::Vector2d& a = from[i];
        const Eigen::Vector2d& b = from[(i + 1) % from.size()];
        const int samples = static_cast<int>(std::clamp(std::ceil((b - a).norm() / step), 1.0, 1e7));
        for (int s = 0; s < samples; ++s)
            worst = std::max(worst, distance(a + (b - a) * (static_cast<double>(s) / samples)));
    }
    return worst;
}

} // namespace

bool crossesItself(const Ring2d& ring)
{
    if (ring.size() < 3)
        return false;
    // Predicates only (no new points): the inexact-constructions kernel is exact here.
    CGAL::Polygon_2<CGAL::Exact_predicates_inexact_constructions_kernel> polygon;
    for (const Eigen::Vector2d& q : ring)
        polygon.push_back({q.x(), q.y()});
    return !polygon.is_simple();
}

double polygonArea(const Polygon2d& p)
{
    double a = std::abs(signedArea(p.outer));
    for (const Ring2d& hole : p.holes)
        a -= std::abs(signedArea(hole));
    return a;
}

double intersectionArea(const Polygon2d& a, const Polygon2d& b)
{
    CGAL::Polygon_set_2<Kernel> common = toSet(a);
    common.intersection(toSet(b));
    std::list<CgalPolygonWithHoles> pieces;
    common.polygons_with_holes(std::back_inserter(pieces));
    double sum = 0.0;
    for (const CgalPolygonWithHoles& piece : pieces)
        sum += area(piece);
    return sum;
}

AreaMeasures compareAreas(const Polygon2d& model, const Polygon2d& reference)
{
    AreaMeasures m;
    m.reference = polygonArea(reference);
    m.model = polygonArea(model);
    m.intersection = intersectionArea(model, reference);
    m.excess = std::max(0.0, m.model - m.intersection);
    m.deficit = std::max(0.0, m.reference - m.intersection);
    const double unionArea = m.model + m.reference - m.intersection;
    m.detection = m.reference > 0 ? m.intersection / m.reference : 0.0;
    m.quality = unionArea > 0 ? m.intersection / unionArea : 0.0;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    m.branching = m.intersection > 0 ? m.deficit / m.intersection : nan;
    m.miss = m.intersection > 0 ? m.excess / m.intersection : nan;
    m.failure = m.reference > 0 ? m.excess / m.reference : nan;
    return m;
}

double boundaryHausdorff(const Ring2d& a, const Ring2d& b, double step)
{
    if (a.empty() || b.empty() || !(step > 0))
        throw Error(ErrorCode::InvalidArgument, "Hausdorff distance: two non-empty rings and a positive step are needed");
    return std::max(directedHausdorff(a, b, step), directedHausdorff(b, a, step));
}

PolygonMatching matchPolygons(const std::vector<Polygon2d>& model, const std::vector<Polygon2d>& reference, double minIou)
{
    PolygonMatching out;
    out.referenceOfModel.assign(model.size(), -1);
    out.iouOfModel.assign(model.size(), 0.0);
    struct Box
    {
        Eigen::Vector2d min, max;
    };
    auto boxOf = [](const Polygon2d& p) {
        Box box{p.outer.front(), p.outer.front()};
        for (const Eigen::Vector2d& q : p.outer) {
            box.min = box.min.cwiseMin(q);
            box.max = box.max.cwiseMax(q);
        }
        return box;
    };
    std::vector<Box> referenceBoxes;
    std::vector<double> referenceArea;
    for (const Polygon2d& r : reference) {
        referenceBoxes.push_back(r.outer.empty() ? Box{Eigen::Vector2d::Constant(INFINITY), Eigen::Vector2d::Constant(-INFINITY)} : boxOf(r));
        referenceArea.push_back(r.outer.size() < 3 ? 0.0 : polygonArea(r));
    }
    std::vector<bool> found(reference.size(), false);
    for (std::size_t m = 0; m < model.size(); ++m) {
        if (model[m].outer.size() < 3)
            continue;
        const Box box = boxOf(model[m]);
        const double modelArea = polygonArea(model[m]);
        int best = -1, overlapping = 0;
        double bestIou = 0.0;
        for (std::size_t r = 0; r < reference.size(); ++r) {
            const Box& rb = referenceBoxes[r];
            if (reference[r].outer.size() < 3 || (box.max.array() < rb.min.array()).any() || (box.min.array() > rb.max.array()).any())
                continue;
            const double common = intersectionArea(model[m], reference[r]);
            if (common > 0.1 * referenceArea[r])
                ++overlapping;
            const double iou = common / (modelArea + referenceArea[r] - common);
            if (iou > bestIou) {
                bestIou = iou;
                best = static_cast<int>(r);
            }
        }
        out.iouOfModel[m] = bestIou;
        if (best >= 0 && bestIou >= minIou && overlapping == 1 && !found[static_cast<std::size_t>(best)]) {
            out.referenceOfModel[m] = best;
            found[static_cast<std::size_t>(best)] = true;
            ++out.correct;
        }
    }
    const std::size_t incorrect = static_cast<std::size_t>(std::count(out.referenceOfModel.begin(), out.referenceOfModel.end(), -1));
    out.detectionRate = reference.empty() ? 0.0 : static_cast<double>(out.correct) / static_cast<double>(reference.size());
    out.falseRate = model.empty() ? 0.0 : static_cast<double>(incorrect) / static_cast<double>(model.size());
    return out;
}

} // namespace scandiff::plugins
