// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/processing/Normals.h>

#include "distance/LocalModels.h"
#include "processing/LocalPlane.h"
#include "processing/PointNeighbourhoods.h"

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>

namespace scandiff {

namespace {

struct FitScratch
{
    std::vector<Eigen::Vector3d> points; //!< relative to the point whose normal is fitted, which comes first
    detail::ModelScratch model;
    std::vector<std::array<int, 3>> triangles;
};

double surfaceVariationOf(const detail::LocalPlane& plane)
{
    return std::max(0.0, plane.values[0]) / plane.values.sum();
}

//! The normal of the fitted quadric above the neighbourhood's first point.
Eigen::Vector3d quadricNormal(const detail::FittedModel& fitted, const Eigen::Vector3d& at)
{
    const detail::PlaneFrame& f = fitted.frame;
    const Eigen::Matrix<double, 6, 1>& c = fitted.quadric;
    const Eigen::Vector3d d = at - f.centroid;
    // u, v and the height share one scale, so the slopes need no rescaling.
    const double u = d.dot(f.u) / fitted.extent, v = d.dot(f.v) / fitted.extent;
    const double du = 2 * c[0] * u + c[1] * v + c[3], dv = c[1] * u + 2 * c[2] * v + c[4];
    return (f.normal - du * f.u - dv * f.v).normalized();
}

//! The mean normal of the Delaunay triangles around the first point, each
//! weighted as Max (1999) proposed: the cross product of its two edges from
//! the point over their squared lengths, which gives the exact normal for
//! points on a sphere whatever the triangles' shapes (area weights are off by
//! the edges' length over the radius on an irregular star). Triangle normals
//! are turned to the plane's side. False if no triangle holds the point.
bool triangulationNormal(const std::vector<Eigen::Vector3d>& points, const detail::PlaneFrame& frame, FitScratch& s,
                         Eigen::Vector3d& normal)
{
    detail::delaunay2d(s.model, s.triangles);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& t : s.triangles) {
        const int at = t[0] == 0 ? 0 : t[1] == 0 ? 1 : t[2] == 0 ? 2 : -1;
        if (at < 0)
            continue;
        const Eigen::Vector3d& p = points[static_cast<std::size_t>(t[static_cast<std::size_t>(at)])];
        const Eigen::Vector3d e1 = points[static_cast<std::size_t>(t[static_cast<std::size_t>((at + 1) % 3)])] - p;
        const Eigen::Vector3d e2 = points[static_cast<std::size_t>(t[static_cast<std::size_t>((at + 2) % 3)])] - p;
        const double lengths = e1.squaredNorm() * e2.squaredNorm();
        if (!(lengths > 0))
            continue;
        Eigen::Vector3d n = e1.cross(e2) / lengths;
        if (n.dot(frame.normal) < 0)
            n = -n;
        sum += n;
    }
    if (!(sum.squaredNorm() > 0) || !sum.allFinite())
        return false;
    normal = sum.normalized();
    return true;
}

void checkParams(const NormalParams& params)
{
    if (params.radius && !(*params.radius > 0 && std::isfinite(*params.radius)))
        throw Error(ErrorCode::InvalidArgument, "normals: the radius must be > 0");
    const std::size_t minimum = params.model == NormalModel::Quadric ? 6 : 3;
    if (params.minNeighbours != 0 && (params.minNeighbours < 3 || params.minNeighbours > 10000))
        throw Error(ErrorCode::InvalidArgument, "normals: the minimum neighbours must be 0 (off) or in [3, 10000]");
    if (params.minNeighbours != 0 && !(params.radius && params.model == NormalModel::Plane))
        throw Error(ErrorCode::InvalidArgument, "normals: a minimum of neighbours goes with a radius and the plane model");
    if (!params.radius && (params.knn < minimum || params.knn > 10000))
        throw Error(ErrorCode::InvalidArgument, "normals: --knn must be in [" + std::to_string(minimum) +
                                                    ", 10000] for this model (the fit needs that many points)");
}

void checkCloud(const PointCloud& cloud, const char* what)
{
    if (cloud.empty())
        throw Error(ErrorCode::InvalidData, std::string(what) + ": cloud '" + cloud.name + "' is empty");
}

//! Plane normals of the points `indices` on their `knn` nearest points,
//! unoriented, with their surface variation when `variation` is given.
void fitOnNearest(const PointCloud& cloud, const octree::Octree& tree, const std::vector<std::uint32_t>& indices, std::size_t knn,
                  std::vector<Eigen::Vector3f>& normals, std::vector<float>* variation, std::vector<float>* spread = nullptr);

} // namespace

NormalResult computeNormals(const PointCloud& cloud, const NormalParams& params, ProgressObserver* progress)
{
    checkParams(params);
    checkCloud(cloud, "normals");
    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    const std::size_t n = cloud.size();
    const auto& positions = cloud.positions();
    NormalResult result;
    result.normals.assign(n, Eigen::Vector3f::Zero());
    result.surfaceVariation = ScalarField(fields::kSurfaceVariation, n);
    std::vector<float>& variation = result.surfaceVariation.values();

    ProgressTicker ticker(progress, "Fitting normals", n);
    if (params.radius && params.model == NormalModel::Plane) {
        // The plane needs only the neighbourhood's moments.
        std::vector<char> sparse(params.minNeighbours ? n : 0, 0);
        detail::forEachPointMoments(tree, *params.radius, ticker, [&](std::size_t i, const octree::NeighbourhoodMoments& moments) {
            if (moments.count < params.minNeighbours) {
                sparse[i] = 1;
                return;
            }
            detail::LocalPlane plane;
            if (!detail::fitLocalPlane(moments, false, plane))
                return;
            result.normals[i] = plane.normal.cast<float>();
            variation[i] = static_cast<float>(surfaceVariationOf(plane));
        });
        std::vector<std::uint32_t> widened;
        for (std::size_t i = 0; i < sparse.size(); ++i)
            if (sparse[i])
                widened.push_back(static_cast<std::uint32_t>(i));
        fitOnNearest(cloud, tree, widened, params.minNeighbours, result.normals, &variation);
    } else {
        detail::forEachPointNeighbourhood(tree, params.radius, params.knn, ticker, [&](std::size_t i, const octree::Neighbour* list, std::size_t count) {
            const Eigen::Vector3f& p = positions[i];
            detail::LocalPlane plane;
            // The plane from the list itself (the point is in it, at offset 0).
            if (!detail::fitLocalPlane(positions.data(), p, list, count, plane))
                return;
            Eigen::Vector3d normal = plane.normal;
            if (params.model != NormalModel::Plane) {
                // Per worker thread: a thread_local costs less per point than TBB's lookup.
                thread_local FitScratch s;
                s.points.clear();
                s.points.emplace_back(Eigen::Vector3d::Zero());
                for (std::size_t j = 0; j < count; ++j)
                    if (list[j].index != i)
                        s.points.push_back((positions[list[j].index] - p).cast<double>());
                const LocalModel model = params.model == NormalModel::Quadric ? LocalModel::Quadric : LocalModel::Delaunay;
                detail::FittedModel fitted;
                if (detail::fitModel(model, s.points, normal, fitted, s.model)) {
                    Eigen::Vector3d refined = normal;
                    const bool ok = model == LocalModel::Quadric ? (refined = quadricNormal(fitted, s.points.front())).allFinite()
                                                                 : triangulationNormal(s.points, fitted.frame, s, refined);
                    if (ok)
                        normal = refined;
                }
            }
            const double surfaceVariation = surfaceVariationOf(plane);
            result.normals[i] = normal.cast<float>();
            variation[i] = static_cast<float>(surfaceVariation);
        });
    }
    result.unfitted = static_cast<std::size_t>(std::count(result.normals.begin(), result.normals.end(), Eigen::Vector3f::Zero()));
    result.components = orientNormals(cloud, result.normals, params.orientation, progress);
    if (params.flip)
        for (auto& normal : result.normals)
            normal = -normal;
    return result;
}

void planeNormalsOf(const PointCloud& cloud, const octree::Octree& tree, const std::vector<std::uint32_t>& indices, std::size_t knn,
                    std::vector<Eigen::Vector3f>& normals, std::vector<float>* spread)
{
    if (knn < 3)
        throw Error(ErrorCode::InvalidArgument, "normals: at least 3 neighbours");
    if (normals.size() != cloud.size())
        throw Error(ErrorCode::InvalidArgument, "normals: one slot per point of the cloud");
    if (spread && spread->size() != cloud.size())
        throw Error(ErrorCode::InvalidArgument, "normals: one spread slot per point of the cloud");
    fitOnNearest(cloud, tree, indices, knn, normals, nullptr, spread);
    for (std::uint32_t i : indices)
        if (normals[i].z() < 0)
            normals[i] = -normals[i];
}

namespace {

void fitOnNearest(const PointCloud& cloud, const octree::Octree& tree, const std::vector<std::uint32_t>& indices, std::size_t knn,
                  std::vector<Eigen::Vector3f>& normals, std::vector<float>* variation, std::vector<float>* spread)
{
    if (indices.empty())
        return;
    const auto& positions = cloud.positions();
    std::vector<Eigen::Vector3f> queries(indices.size());
    for (std::size_t q = 0; q < indices.size(); ++q)
        queries[q] = positions[indices[q]];
    const int level = tree.levelNearestMeanPopulation(std::max(8.0, 3.0 * static_cast<double>(knn)));
    std::vector<octree::Neighbour> found;
    tree.nearestBatch(queries.data(), queries.size(), knn, level, found);
    tbb::parallel_for(std::size_t(0), indices.size(), [&](std::size_t q) {
        const octree::Neighbour* list = found.data() + q * knn;
        std::size_t count = 0;
        while (count < knn && list[count].index != std::numeric_limits<std::uint32_t>::max())
            ++count;
        detail::LocalPlane plane;
        Eigen::Vector3f normal = Eigen::Vector3f::Zero();
        if (detail::fitLocalPlane(positions.data(), queries[q], list, count, plane)) {
            normal = plane.normal.cast<float>();
            if (variation)
                (*variation)[indices[q]] = static_cast<float>(surfaceVariationOf(plane));
            if (spread)
                (*spread)[indices[q]] = static_cast<float>(std::sqrt(std::max(0.0, plane.values[0]) / static_cast<double>(count)));
        } else if (spread) {
            (*spread)[indices[q]] = 0.0f;
        }
        normals[indices[q]] = normal;
    });
}

void orientTowards(const PointCloud& cloud, std::vector<Eigen::Vector3f>& normals,
                   const std::function<Eigen::Vector3d(std::size_t)>& target)
{
    const auto& positions = cloud.positions();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, normals.size(), 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
            if (normals[i].cast<double>().dot(target(i) - positions[i].cast<double>()) < 0)
                normals[i] = -normals[i];
    });
}

//! Hoppe et al. 1992: on the graph of each point's nearest neighbours, with
//! weight 1 - |n_i . n_j| (small where the normals agree, whichever side they
//! face), the minimum spanning tree links points along smooth surfaces first;
//! walking it from a point of known side, each normal takes the side of its
//! parent's. Kruskal's algorithm on the sorted edges; ties broken by the
//! points' indices so that the tree, hence the result, never depends on the
//! number of threads.
constexpr std::size_t kEdgesPerPoll = 1 << 20;

//! Sorts [first, last) on both cores by a quicksort whose splits depend on
//! the data alone (median-of-three pivots, three-way partitions, ranges of up
//! to 2^16 left to std::sort), asking for Cancel before each partition and
//! each small sort: a sort of tens of millions of edges hears Cancel within a
//! fraction of a second, and polls the same number of times on every run
//! (TBB's parallel_sort, polled from its comparisons, did not: how its ranges
//! fell on the threads changed the count, and a test pressing Cancel at the
//! last poll missed it). A depth past twice log2 of the size, which
//! median-of-three pivots do not reach on these weights, hands over to
//! std::sort.
template <typename T>
void sortHearingCancel(T* first, T* last, const ProgressTicker& ticker, int depthLeft)
{
    constexpr std::ptrdiff_t kLeaf = 1 << 16;
    ticker.checkCancel();
    if (last - first <= kLeaf || depthLeft == 0) {
        std::sort(first, last);
        return;
    }
    const T& a = *first;
    const T& b = first[(last - first) / 2];
    const T& c = last[-1];
    const T pivot = a < b ? (b < c ? b : (a < c ? c : a)) : (a < c ? a : (b < c ? c : b));
    T* const equalBegin = std::partition(first, last, [&](const T& e) { return e < pivot; });
    T* const equalEnd = std::partition(equalBegin, last, [&](const T& e) { return !(pivot < e); });
    tbb::parallel_invoke([&] { sortHearingCancel(first, equalBegin, ticker, depthLeft - 1); },
                         [&] { sortHearingCancel(equalEnd, last, ticker, depthLeft - 1); });
}

template <typename T>
void sortHearingCancel(T* first, T* last, const ProgressTicker& ticker)
{
    int depth = 0;
    for (std::size_t size = static_cast<std::size_t>(last - first); size > 1; size /= 2)
        depth += 2;
    sortHearingCancel(first, last, ticker, depth);
}

std::size_t orientByMinimumSpanningTree(const PointCloud& cloud, std::vector<Eigen::Vector3f>& normals, std::size_t neighbours,
                                        ProgressObserver* progress)
{
    if (neighbours < 1 || neighbours > 1000)
        throw Error(ErrorCode::InvalidArgument, "normals: the MST's neighbours must be in [1, 1000]");
    const std::size_t n = cloud.size();
    const octree::Octree tree = buildOctree(cloud, std::nullopt, progress);
    struct Edge
    {
        float weight;
        std::uint32_t a, b;
        bool operator<(const Edge& o) const { return weight < o.weight || (weight == o.weight && (a < o.a || (a == o.a && b < o.b))); }
    };
    const auto hasNormal = [&](std::size_t i) { return normals[i] != Eigen::Vector3f::Zero(); };
    const std::size_t k = std::min(neighbours + 1, n);
    // Left uninitialised: each point's slots are set by its own task (a
    // serial fill of these hundreds of megabytes took 0.3 s unheard).
    const std::size_t edgeCount = n * (k - 1);
    std::unique_ptr<Edge[]> edges(new Edge[edgeCount]);
    {
        ProgressTicker ticker(progress, "Normal orientation: neighbour graph", n);
        detail::forEachPointNeighbourhood(tree, std::nullopt, k, ticker, [&](std::size_t i, const octree::Neighbour* list, std::size_t count) {
            std::fill(&edges[i * (k - 1)], &edges[(i + 1) * (k - 1)], Edge{std::numeric_limits<float>::infinity(), 0, 0});
            std::size_t slot = i * (k - 1);
            for (std::size_t j = 0; j < count && slot < (i + 1) * (k - 1); ++j) {
                const std::uint32_t other = list[j].index;
                if (other == i)
                    continue;
                if (hasNormal(i) && hasNormal(other)) {
                    const float w = 1.0f - std::abs(normals[i].dot(normals[other]));
                    edges[slot] = Edge{std::max(0.0f, w), static_cast<std::uint32_t>(std::min<std::size_t>(i, other)),
                                       static_cast<std::uint32_t>(std::max<std::size_t>(i, other))};
                }
                ++slot;
            }
        });
    }
    ProgressTicker sorting(progress, "Normal orientation: spanning tree", 2 + edgeCount / kEdgesPerPoll);
    // The sort of tens of millions of edges takes a second or more: it asks
    // for Cancel as it goes (an exception thrown in a TBB algorithm stops it;
    // the edges are ours to drop).
    sortHearingCancel(edges.get(), edges.get() + edgeCount, sorting);
    sorting.step();
    std::vector<std::uint32_t> parent(n), size(n, 1);
    std::iota(parent.begin(), parent.end(), 0u);
    const auto root = [&](std::uint32_t x) {
        while (parent[x] != x) {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        return x;
    };
    std::vector<std::uint32_t> degree(n + 1, 0);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> treeEdges;
    treeEdges.reserve(n);
    for (std::size_t at = 0; at < edgeCount; ++at) {
        const Edge& e = edges[at];
        if (!std::isfinite(e.weight))
            break;
        if (at % kEdgesPerPoll == kEdgesPerPoll - 1)
            sorting.step();
        std::uint32_t ra = root(e.a), rb = root(e.b);
        if (ra == rb)
            continue;
        if (size[ra] < size[rb])
            std::swap(ra, rb);
        parent[rb] = ra;
        size[ra] += size[rb];
        treeEdges.emplace_back(e.a, e.b);
        ++degree[e.a + 1];
        ++degree[e.b + 1];
    }
    edges.reset();
    sorting.step();
    // The tree as adjacency lists (compressed rows).
    std::partial_sum(degree.begin(), degree.end(), degree.begin());
    std::vector<std::uint32_t> adjacency(2 * treeEdges.size()), fill(degree.begin(), degree.end() - 1);
    for (const auto& [a, b] : treeEdges) {
        adjacency[fill[a]++] = b;
        adjacency[fill[b]++] = a;
    }
    // Each connected part starts from its highest point, turned upwards.
    const auto& positions = cloud.positions();
    std::vector<std::uint32_t> seedOf(n, std::numeric_limits<std::uint32_t>::max());
    for (std::uint32_t i = 0; i < n; ++i) {
        if (!hasNormal(i))
            continue;
        std::uint32_t& seed = seedOf[root(i)];
        if (seed == std::numeric_limits<std::uint32_t>::max() || positions[i].z() > positions[seed].z())
            seed = i;
    }
    ProgressTicker walking(progress, "Normal orientation: propagation", n);
    std::vector<char> visited(n, 0);
    std::vector<std::uint32_t> queue;
    std::size_t components = 0;
    for (std::uint32_t r = 0; r < n; ++r) {
        const std::uint32_t seed = seedOf[r];
        if (seed == std::numeric_limits<std::uint32_t>::max())
            continue;
        ++components;
        if (normals[seed].z() < 0)
            normals[seed] = -normals[seed];
        queue.assign(1, seed);
        visited[seed] = 1;
        for (std::size_t head = 0; head < queue.size(); ++head) {
            const std::uint32_t at = queue[head];
            for (std::uint32_t e = degree[at]; e < degree[at + 1]; ++e) {
                const std::uint32_t next = adjacency[e];
                if (visited[next])
                    continue;
                visited[next] = 1;
                if (normals[next].dot(normals[at]) < 0)
                    normals[next] = -normals[next];
                queue.push_back(next);
            }
            walking.step();
        }
    }
    return components;
}

} // namespace

std::size_t orientNormals(const PointCloud& cloud, std::vector<Eigen::Vector3f>& normals, const NormalOrientation& orientation,
                          ProgressObserver* progress)
{
    using Kind = NormalOrientation::Kind;
    if (normals.size() != cloud.size())
        throw Error(ErrorCode::Internal, "normals: one normal per point is needed");
    if (cloud.empty())
        return 0;
    switch (orientation.kind) {
    case Kind::None:
        return 0;
    case Kind::Direction: {
        if (!(orientation.direction.norm() > 0) || !orientation.direction.allFinite())
            throw Error(ErrorCode::InvalidArgument, "normals: the orientation direction must be a non-zero vector");
        const Eigen::Vector3f d = orientation.direction.cast<float>();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, normals.size(), 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i)
                if (normals[i].dot(d) < 0)
                    normals[i] = -normals[i];
        });
        return 0;
    }
    case Kind::TowardsSensor: {
        std::vector<Eigen::Vector3d> sensors;
        if (orientation.sensor)
            sensors.push_back(*orientation.sensor - cloud.origin());
        else
            for (const auto& pose : cloud.sensors())
                sensors.push_back(pose.position - cloud.origin());
        if (sensors.empty())
            throw Error(ErrorCode::InvalidArgument, "normals: cloud '" + cloud.name +
                                                        "' has no sensor position; give one (--orient sensor:X,Y,Z)");
        orientTowards(cloud, normals, [&](std::size_t i) {
            const Eigen::Vector3d p = cloud.positions()[i].cast<double>();
            const Eigen::Vector3d* best = &sensors.front();
            for (const auto& s : sensors)
                if ((s - p).squaredNorm() < (*best - p).squaredNorm())
                    best = &s;
            return *best;
        });
        return 0;
    }
    case Kind::AwayFromCentroid:
    case Kind::TowardsCentroid: {
        Eigen::Vector3d centroid = orientation.centroid ? *orientation.centroid : Eigen::Vector3d::Zero();
        if (!orientation.centroid) {
            for (const auto& p : cloud.positions())
                centroid += p.cast<double>();
            centroid /= static_cast<double>(cloud.size());
        }
        orientTowards(cloud, normals, [&](std::size_t) { return centroid; });
        if (orientation.kind == Kind::AwayFromCentroid)
            for (auto& normal : normals)
                normal = -normal;
        return 0;
    }
    case Kind::MinimumSpanningTree:
        return orientByMinimumSpanningTree(cloud, normals, orientation.mstNeighbours, progress);
    }
    return 0;
}

NormalOrientation parseNormalOrientation(const std::string& text)
{
    using Kind = NormalOrientation::Kind;
    NormalOrientation o;
    if (text == "none") {
        o.kind = Kind::None;
        return o;
    }
    if (text == "mst") {
        o.kind = Kind::MinimumSpanningTree;
        return o;
    }
    if (text == "centroid" || text == "-centroid") {
        o.kind = text == "centroid" ? Kind::AwayFromCentroid : Kind::TowardsCentroid;
        return o;
    }
    if (text == "sensor") {
        o.kind = Kind::TowardsSensor;
        return o;
    }
    if (text.rfind("sensor:", 0) == 0) {
        const std::vector<double> xyz = parseNumberList(text.substr(7), "the sensor position");
        if (xyz.size() != 3)
            throw Error(ErrorCode::InvalidArgument, "normals: the sensor position is X,Y,Z");
        o.kind = Kind::TowardsSensor;
        o.sensor = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
        return o;
    }
    o.kind = Kind::Direction;
    if (text.size() == 2 && (text[0] == '+' || text[0] == '-') && text[1] >= 'x' && text[1] <= 'z') {
        o.direction = Eigen::Vector3d::Zero();
        o.direction[text[1] - 'x'] = text[0] == '+' ? 1.0 : -1.0;
        return o;
    }
    std::vector<double> d;
    try {
        d = parseNumberList(text, "the orientation");
    } catch (const Error&) {
    }
    if (d.size() != 3 || !(Eigen::Vector3d(d[0], d[1], d[2]).norm() > 0))
        throw Error(ErrorCode::InvalidArgument, "normals: orientation '" + text +
                                                    "' is not one of +x -x +y -y +z -z, a direction DX,DY,DZ, sensor, "
                                                    "sensor:X,Y,Z, centroid, -centroid, mst, none");
    o.direction = Eigen::Vector3d(d[0], d[1], d[2]).normalized();
    return o;
}

} // namespace scandiff
