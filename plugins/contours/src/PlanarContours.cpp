// SPDX-License-Identifier: GPL-3.0-or-later
// Plane frames, triangle filtering, parts and their rings (see PlanarContours.h).
#include <scandiff/plugins/contours/PlanarContours.h>

#include <scandiff/core/Error.h>
#include <scandiff/octree/Octree.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace scandiff::plugins {

namespace {

constexpr double kPi = 3.14159265358979323846;

using Triangle = std::array<std::uint32_t, 3>;

double longestEdge(const std::vector<Eigen::Vector2d>& p, const Triangle& t)
{
    return std::sqrt(std::max({(p[t[0]] - p[t[1]]).squaredNorm(), (p[t[1]] - p[t[2]]).squaredNorm(), (p[t[2]] - p[t[0]]).squaredNorm()}));
}

//! abc / (4 area); a degenerate (flat) triangle has an infinite circumradius.
double circumradius(const std::vector<Eigen::Vector2d>& p, const Triangle& t)
{
    const double a = (p[t[0]] - p[t[1]]).norm(), b = (p[t[1]] - p[t[2]]).norm(), c = (p[t[2]] - p[t[0]]).norm();
    const Eigen::Vector2d e1 = p[t[1]] - p[t[0]], e2 = p[t[2]] - p[t[0]];
    const double twiceArea = std::abs(e1.x() * e2.y() - e1.y() * e2.x());
    return twiceArea > 0 ? a * b * c / (2.0 * twiceArea) : std::numeric_limits<double>::infinity();
}

double triangleArea(const std::vector<Eigen::Vector2d>& p, const Triangle& t)
{
    const Eigen::Vector2d e1 = p[t[1]] - p[t[0]], e2 = p[t[2]] - p[t[0]];
    return 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x());
}

class DisjointSets
{
public:
    explicit DisjointSets(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0u); }
    std::uint32_t find(std::uint32_t x)
    {
        while (parent_[x] != x)
            x = parent_[x] = parent_[parent_[x]];
        return x;
    }
    void unite(std::uint32_t a, std::uint32_t b)
    {
        a = find(a);
        b = find(b);
        if (a != b)
            parent_[std::max(a, b)] = std::min(a, b);
    }

private:
    std::vector<std::uint32_t> parent_;
};

struct DirectedEdge
{
    std::uint32_t from, to;
};

//! Chains a part's boundary edges into closed rings. Where several boundary
//! edges leave one vertex (the part touches itself there), the walk takes the
//! first one clockwise from the edge it arrived by: with the part on the left
//! of every edge, that keeps each ring on one side of the touching point, so
//! no ring crosses itself.
std::vector<std::vector<std::uint32_t>> chainRings(std::vector<DirectedEdge> edges, const std::vector<Eigen::Vector2d>& p)
{
    std::sort(edges.begin(), edges.end(), [](const DirectedEdge& a, const DirectedEdge& b) {
        return a.from != b.from ? a.from < b.from : a.to < b.to;
    });
    std::vector<bool> used(edges.size(), false);
    auto outgoing = [&](std::uint32_t v) {
        const auto first = std::lower_bound(edges.begin(), edges.end(), v, [](const DirectedEdge& e, std::uint32_t x) { return e.from < x; });
        std::size_t begin = static_cast<std::size_t>(first - edges.begin()), end = begin;
        while (end < edges.size() && edges[end].from == v)
            ++end;
        return std::make_pair(begin, end);
    };
    std::vector<std::vector<std::uint32_t>> rings;
    for (std::size_t start = 0; start < edges.size(); ++start) {
        if (used[start])
            continue;
        std::vector<std::uint32_t> ring;
        std::size_t current = start;
        while (true) {
            used[current] = true;
            ring.push_back(edges[current].from);
            const std::uint32_t arrivedFrom = edges[current].from, at = edges[current].to;
            // The first edge clockwise among the unused ones and the ring's
            // first (taking it closes the ring).
            const auto [b, e] = outgoing(at);
            const Eigen::Vector2d back = p[arrivedFrom] - p[at];
            const double backAngle = std::atan2(back.y(), back.x());
            std::size_t next = edges.size();
            double bestTurn = 4 * kPi;
            for (std::size_t k = b; k < e; ++k) {
                if (used[k] && k != start)
                    continue;
                const Eigen::Vector2d d = p[edges[k].to] - p[at];
                double turn = backAngle - std::atan2(d.y(), d.x()); // clockwise from `back`
                while (turn <= 0)
                    turn += 2 * kPi;
                if (turn < bestTurn) {
                    bestTurn = turn;
                    next = k;
                }
            }
            if (next == start || next == edges.size())
                break; // closed (a set of triangles has no open boundary)
            current = next;
        }
        if (ring.size() >= 3)
            rings.push_back(std::move(ring));
    }
    return rings;
}

Ring2d coordinates(const std::vector<std::uint32_t>& ring, const std::vector<Eigen::Vector2d>& p)
{
    Ring2d out;
    out.reserve(ring.size());
    for (std::uint32_t i : ring)
        out.push_back(p[i]);
    return out;
}

//! The median distance of a point to its nearest neighbour, which is one of
//! its Delaunay neighbours.
double medianNearestDistance(const std::vector<Eigen::Vector2d>& points, const std::vector<Triangle>& triangles)
{
    std::vector<double> nearest(points.size(), std::numeric_limits<double>::infinity());
    for (const Triangle& t : triangles)
        for (int c = 0; c < 3; ++c) {
            const double d = (points[t[c]] - points[t[(c + 1) % 3]]).norm();
            nearest[t[c]] = std::min(nearest[t[c]], d);
            nearest[t[(c + 1) % 3]] = std::min(nearest[t[(c + 1) % 3]], d);
        }
    nearest.erase(std::remove_if(nearest.begin(), nearest.end(), [](double d) { return !std::isfinite(d); }), nearest.end());
    std::nth_element(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(nearest.size() / 2), nearest.end());
    return nearest.empty() ? 0.0 : nearest[nearest.size() / 2];
}

//! Each point's own spacing: the side of the square a point covers where it
//! lies, from the disc reaching its 6th nearest other point (pi r^2 / 6 per
//! point). A scan is denser near its station than at the far end of a wall
//! or at grazing incidence (three times on a façade 6 m from the scanner and
//! 8 m wide); a gap criterion in metres cut the sparse end into holes.
std::vector<double> localSpacings(const std::vector<Eigen::Vector2d>& points)
{
    constexpr std::size_t k = 7; // the point itself and 6 others
    std::vector<Eigen::Vector3f> planar(points.size());
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    for (const Eigen::Vector2d& p : points)
        centre += p / static_cast<double>(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        planar[i] = Eigen::Vector3f(static_cast<float>(points[i].x() - centre.x()), static_cast<float>(points[i].y() - centre.y()), 0.0f);
    const octree::Octree tree(planar.data(), planar.size());
    std::vector<octree::Neighbour> found;
    tree.nearestBatch(planar.data(), planar.size(), k, tree.levelNearestMeanPopulation(8.0), found);
    std::vector<double> spacing(points.size(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t i = 0; i < points.size(); ++i) {
        const octree::Neighbour& last = found[i * k + k - 1];
        if (last.index != UINT32_MAX)
            spacing[i] = std::sqrt(static_cast<double>(last.squaredDistance) * kPi / static_cast<double>(k - 1));
    }
    return spacing;
}

//! Each point joins the part with most of its kept triangles (partOfKept(k):
//! the final part of kept triangle k, -1 when dropped); a duplicate joins its
//! twin's part (the triangulation kept one of them).
template <class PartOfKept>
void assignPointsToParts(const std::vector<Eigen::Vector2d>& points, const std::vector<Triangle>& triangles,
                         const std::vector<std::uint32_t>& kept, PartOfKept&& partOfKept, OutlineResult& result)
{
    std::vector<std::uint64_t> votes; // point << 32 | final part
    votes.reserve(kept.size() * 3);
    for (std::uint32_t k = 0; k < kept.size(); ++k) {
        const std::int32_t part = partOfKept(k);
        if (part >= 0)
            for (std::uint32_t v : triangles[kept[k]])
                votes.push_back(static_cast<std::uint64_t>(v) << 32 | static_cast<std::uint32_t>(part));
    }
    std::sort(votes.begin(), votes.end());
    for (std::size_t i = 0; i < votes.size();) {
        const std::uint32_t point = static_cast<std::uint32_t>(votes[i] >> 32);
        std::size_t bestCount = 0;
        std::int32_t bestPart = -1;
        while (i < votes.size() && votes[i] >> 32 == point) {
            std::size_t j = i;
            while (j < votes.size() && votes[j] == votes[i])
                ++j;
            if (j - i > bestCount) {
                bestCount = j - i;
                bestPart = static_cast<std::int32_t>(votes[i] & 0xffffffffu);
            }
            i = j;
        }
        result.partOfPoint[point] = bestPart;
        ++result.parts[static_cast<std::size_t>(bestPart)].pointCount;
    }
    std::vector<std::uint32_t> byPosition(points.size());
    std::iota(byPosition.begin(), byPosition.end(), 0u);
    auto less = [&](std::uint32_t a, std::uint32_t b) {
        return points[a].x() != points[b].x() ? points[a].x() < points[b].x() : points[a].y() < points[b].y();
    };
    std::sort(byPosition.begin(), byPosition.end(), less);
    for (std::size_t i = 0; i < byPosition.size();) {
        std::size_t j = i + 1;
        std::int32_t part = result.partOfPoint[byPosition[i]];
        while (j < byPosition.size() && points[byPosition[j]] == points[byPosition[i]])
            part = std::max(part, result.partOfPoint[byPosition[j++]]);
        for (std::size_t k = i; k < j && j - i > 1; ++k)
            if (result.partOfPoint[byPosition[k]] < 0 && part >= 0) {
                result.partOfPoint[byPosition[k]] = part;
                ++result.parts[static_cast<std::size_t>(part)].pointCount;
            }
        i = j;
    }
}

} // namespace

PlaneFrame fitPlaneFrame(const std::vector<Eigen::Vector3d>& points)
{
    if (points.size() < 3)
        throw Error(ErrorCode::InvalidData, "plane fit: needs at least 3 points, got " + std::to_string(points.size()));
    PlaneFrame frame;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& p : points)
        sum += p;
    frame.origin = sum / static_cast<double>(points.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d& p : points) {
        const Eigen::Vector3d d = p - frame.origin;
        covariance += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    if (!(solver.eigenvalues()(1) > 1e-12 * solver.eigenvalues()(2)) || !std::isfinite(solver.eigenvalues()(2)))
        throw Error(ErrorCode::InvalidData, "plane fit: the points lie on a line (or are not finite)");
    frame.normal = solver.eigenvectors().col(0).normalized();
    // u horizontal, v up the slope; a horizontal plane keeps x and y.
    const Eigen::Vector3d horizontal = Eigen::Vector3d::UnitZ().cross(frame.normal);
    if (horizontal.norm() > 1e-6) {
        // The eigenvector's sign is arbitrary: a fixed rule (the normal's
        // horizontal part towards +y, else +x) keeps two scans of one wall
        // in the same frame, not mirrored. v = n x u then points up.
        if (frame.normal.y() < 0 || (frame.normal.y() == 0 && frame.normal.x() < 0))
            frame.normal = -frame.normal;
        frame.u = Eigen::Vector3d::UnitZ().cross(frame.normal).normalized();
        frame.v = frame.normal.cross(frame.u);
    } else {
        if (frame.normal.z() < 0)
            frame.normal = -frame.normal;
        frame.u = Eigen::Vector3d::UnitX();
        frame.u = (frame.u - frame.u.dot(frame.normal) * frame.normal).normalized();
        frame.v = frame.normal.cross(frame.u);
    }
    double sumSquares = 0.0;
    for (const Eigen::Vector3d& p : points) {
        const double d = std::abs((p - frame.origin).dot(frame.normal));
        sumSquares += d * d;
        frame.worst = std::max(frame.worst, d);
    }
    frame.rms = std::sqrt(sumSquares / static_cast<double>(points.size()));
    return frame;
}

OutlineMethod parseOutlineMethod(const std::string& name)
{
    if (name == "long-edges")
        return OutlineMethod::LongEdges;
    if (name == "alpha")
        return OutlineMethod::Alpha;
    throw Error(ErrorCode::InvalidArgument, "outline method '" + name + "': expected long-edges or alpha");
}

double kneeThreshold(std::vector<double> values, double floorFactor)
{
    values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }), values.end());
    if (values.empty())
        return 0.0;
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size(), mid = n / 2;
    // The chord ends at the 99th percentile, not at the largest value: a few
    // slivers along the convex hull (circumradii of kilometres) would
    // otherwise flatten the whole curve and put the knee among them.
    const std::size_t top = std::max(mid, static_cast<std::size_t>(0.99 * static_cast<double>(n - 1)));
    const double median = values[mid], high = values[top];
    const double floor = floorFactor * median;
    if (high <= floor || top == mid)
        return floor;
    // Farthest below the chord from (mid, median) to (top, high), normalised.
    double best = -1.0, knee = floor;
    for (std::size_t i = mid; i <= top; ++i) {
        const double x = static_cast<double>(i - mid) / static_cast<double>(top - mid);
        const double y = (values[i] - median) / (high - median);
        if (x - y > best) {
            best = x - y;
            knee = values[i];
        }
    }
    return std::max(knee, floor);
}

double ringPerimeter(const Ring2d& ring)
{
    double length = 0.0;
    for (std::size_t i = 0, n = ring.size(); i < n; ++i)
        length += (ring[(i + 1) % n] - ring[i]).norm();
    return length;
}

namespace {

//! Each triangle's gap measure (its longest edge or its circumradius; a
//! triangle across labels never kept) and the cut above which it spans a gap.
struct GapCut
{
    std::vector<double> measure;
    double cut = 0;       //!< on the measures
    double threshold = 0; //!< as reported: in metres
};

GapCut gapCut(const std::vector<Eigen::Vector2d>& points, const std::vector<Triangle>& triangles, const OutlineParams& params)
{
    GapCut g;
    auto mixed = [&](const Triangle& t) {
        if (params.labels.empty())
            return false;
        const std::int32_t a = params.labels[t[0]];
        return a < 0 || params.labels[t[1]] != a || params.labels[t[2]] != a;
    };
    g.measure.resize(triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t)
        g.measure[t] = mixed(triangles[t]) ? std::numeric_limits<double>::infinity()
                       : params.method == OutlineMethod::LongEdges ? longestEdge(points, triangles[t]) : circumradius(points, triangles[t]);
    // The automatic long-edge criterion is relative: each triangle's longest
    // edge over the spacing where it lies (the mean of its corners'), its
    // knee floored at 2.5 (a regular grid's diagonal is 1.4 spacings, one
    // stretched four times by an oblique view 2.1; a missing point leaves 2).
    // The threshold reported is that knee times the median spacing.
    const bool relative = params.threshold <= 0 && params.method == OutlineMethod::LongEdges && points.size() >= 16;
    double medianSpacing = 1.0;
    if (relative) {
        const std::vector<double> spacing = localSpacings(points);
        std::vector<double> finite;
        for (double d : spacing)
            if (std::isfinite(d) && d > 0)
                finite.push_back(d);
        if (!finite.empty()) {
            std::nth_element(finite.begin(), finite.begin() + static_cast<std::ptrdiff_t>(finite.size() / 2), finite.end());
            medianSpacing = finite[finite.size() / 2];
        }
        for (std::size_t t = 0; t < triangles.size(); ++t) {
            double local = 0;
            for (std::uint32_t v : triangles[t])
                local += std::isfinite(spacing[v]) && spacing[v] > 0 ? spacing[v] : medianSpacing;
            g.measure[t] /= local / 3.0;
        }
    }
    // Floors: 2 x the median longest edge (a regular grid's diagonals are the
    // longest edges of its triangles), 1.5 x the median circumradius.
    g.cut = params.threshold > 0 ? params.threshold
            : relative           ? std::max(2.5, kneeThreshold(g.measure, 1.0))
                                 : kneeThreshold(g.measure, params.method == OutlineMethod::LongEdges ? 2.0 : 1.5);
    g.threshold = relative ? g.cut * medianSpacing : g.cut;
    return g;
}

//! The kept triangles joined into parts across their shared edges: each
//! part's area and boundary edges (the edges of one kept triangle only).
struct TriangleParts
{
    explicit TriangleParts(std::size_t kept) : sets(kept), partOfRoot(kept, UINT32_MAX) {}
    DisjointSets sets;
    std::vector<std::uint32_t> partOfRoot; //!< a set's root -> its part
    std::vector<double> area;
    std::vector<std::vector<DirectedEdge>> boundary;
    std::uint32_t partOf(std::uint32_t k) { return partOfRoot[sets.find(k)]; }
};

TriangleParts joinTriangles(const std::vector<Eigen::Vector2d>& points, const std::vector<Triangle>& triangles,
                            const std::vector<std::uint32_t>& kept)
{
    // Edges of the kept triangles, sorted: a pair of equal keys joins two
    // triangles into one part, a single key is a boundary edge.
    struct EdgeOfTriangle
    {
        std::uint64_t key;
        std::uint32_t triangle; //!< position in `kept`
        std::uint8_t corner;    //!< the edge runs from corner to corner + 1
    };
    std::vector<EdgeOfTriangle> edges;
    edges.reserve(kept.size() * 3);
    for (std::uint32_t k = 0; k < kept.size(); ++k) {
        const Triangle& t = triangles[kept[k]];
        for (std::uint8_t c = 0; c < 3; ++c) {
            const std::uint64_t a = t[c], b = t[(c + 1) % 3];
            edges.push_back({std::min(a, b) << 32 | std::max(a, b), k, c});
        }
    }
    std::sort(edges.begin(), edges.end(), [](const EdgeOfTriangle& a, const EdgeOfTriangle& b) { return a.key < b.key; });
    TriangleParts parts(kept.size());
    std::vector<std::uint32_t> boundary; // positions in `edges`
    for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i + 1;
        while (j < edges.size() && edges[j].key == edges[i].key)
            ++j;
        if (j - i == 1)
            boundary.push_back(static_cast<std::uint32_t>(i));
        else
            for (std::size_t k = i + 1; k < j; ++k)
                parts.sets.unite(edges[i].triangle, edges[k].triangle);
        i = j;
    }
    for (std::uint32_t k = 0; k < kept.size(); ++k) {
        const std::uint32_t root = parts.sets.find(k);
        if (parts.partOfRoot[root] == UINT32_MAX) {
            parts.partOfRoot[root] = static_cast<std::uint32_t>(parts.area.size());
            parts.area.push_back(0.0);
        }
        parts.area[parts.partOfRoot[root]] += triangleArea(points, triangles[kept[k]]);
    }
    parts.boundary.resize(parts.area.size());
    for (std::uint32_t i : boundary) {
        const EdgeOfTriangle& e = edges[i];
        const Triangle& t = triangles[kept[e.triangle]];
        parts.boundary[parts.partOf(e.triangle)].push_back({t[e.corner], t[(e.corner + 1) % 3]});
    }
    return parts;
}

//! A part's rings chained from its boundary edges: the outer one (the largest
//! counter-clockwise) and the holes (clockwise) above the smallest hole
//! area. False when no ring runs counter-clockwise.
bool ringsOfPart(std::vector<DirectedEdge> boundary, const std::vector<Eigen::Vector2d>& points, double minHoleArea, OutlinePart& out)
{
    const auto rings = chainRings(std::move(boundary), points);
    std::size_t outerRing = rings.size();
    double largest = 0.0;
    for (std::size_t r = 0; r < rings.size(); ++r) {
        const double a = signedArea(coordinates(rings[r], points));
        if (a > largest) {
            largest = a;
            outerRing = r;
        }
    }
    if (outerRing == rings.size())
        return false;
    out.outerIndices = rings[outerRing];
    out.outer = coordinates(rings[outerRing], points);
    for (std::size_t r = 0; r < rings.size(); ++r) {
        if (r == outerRing)
            continue;
        Ring2d ring = coordinates(rings[r], points);
        // A counter-clockwise ring besides the outer one can only come from
        // a part touching itself around an island of another part: it is
        // the outline of that island's surroundings, kept as a hole-free
        // detail of the outer ring; holes are the clockwise rings.
        if (signedArea(ring) < 0 && -signedArea(ring) >= minHoleArea) {
            out.holes.push_back(std::move(ring));
            out.holeIndices.push_back(rings[r]);
        }
    }
    return true;
}

} // namespace

OutlineResult extractOutlines(const std::vector<Eigen::Vector2d>& points, const OutlineParams& params)
{
    if (!(params.threshold >= 0.0) || !(params.minPartArea >= 0.0) || !(params.minHoleArea >= 0.0))
        throw Error(ErrorCode::InvalidArgument, "outlines: the threshold and the smallest areas must be >= 0");
    for (const Eigen::Vector2d& p : points)
        if (!p.allFinite())
            throw Error(ErrorCode::InvalidData, "outlines: a point has a non-finite coordinate");
    if (!params.labels.empty() && params.labels.size() != points.size())
        throw Error(ErrorCode::InvalidArgument, "outlines: one label per point expected");
    OutlineResult result;
    result.partOfPoint.assign(points.size(), -1);
    // The Delaunay triangles, those spanning gaps dropped (thesis 001's long
    // edges, or alpha shapes), the rest joined into parts with their rings.
    const std::vector<Triangle> triangles = delaunayTriangles(points);
    result.triangles = triangles.size();
    if (triangles.empty())
        return result;
    result.spacing = medianNearestDistance(points, triangles);
    const GapCut gaps = gapCut(points, triangles, params);
    result.threshold = gaps.threshold;
    std::vector<std::uint32_t> kept;
    for (std::size_t t = 0; t < triangles.size(); ++t)
        if (gaps.measure[t] <= gaps.cut)
            kept.push_back(static_cast<std::uint32_t>(t));
    result.keptTriangles = kept.size();
    TriangleParts parts = joinTriangles(points, triangles, kept);

    // Largest first; small parts dropped.
    std::vector<std::uint32_t> order(parts.area.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return parts.area[a] > parts.area[b]; });
    std::vector<std::int32_t> finalIndex(parts.area.size(), -1);
    for (std::uint32_t part : order) {
        if (parts.area[part] < params.minPartArea)
            continue;
        OutlinePart out;
        out.area = parts.area[part];
        if (!ringsOfPart(std::move(parts.boundary[part]), points, params.minHoleArea, out))
            continue;
        finalIndex[part] = static_cast<std::int32_t>(result.parts.size());
        result.parts.push_back(std::move(out));
    }
    assignPointsToParts(points, triangles, kept, [&](std::uint32_t k) { return finalIndex[parts.partOf(k)]; }, result);
    return result;
}

} // namespace scandiff::plugins
