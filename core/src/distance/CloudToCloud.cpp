// SPDX-License-Identifier: GPL-3.0-or-later
#include "LocalModels.h"

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToCloud.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <atomic>
#include <limits>

namespace scandiff {

LocalModel parseLocalModel(const std::string& name)
{
    if (name == "none")
        return LocalModel::None;
    if (name == "plane")
        return LocalModel::Plane;
    if (name == "delaunay")
        return LocalModel::Delaunay;
    if (name == "quadric")
        return LocalModel::Quadric;
    throw Error(ErrorCode::InvalidArgument, "unknown local model '" + name + "' (none, plane, delaunay, quadric)");
}

const char* localModelName(LocalModel model)
{
    switch (model) {
    case LocalModel::None: return "none";
    case LocalModel::Plane: return "plane";
    case LocalModel::Delaunay: return "delaunay";
    case LocalModel::Quadric: return "quadric";
    }
    return "none";
}

namespace {

void checkParams(const CloudToCloudParams& p, const PointCloud& reference)
{
    auto bad = [](const std::string& what) { throw Error(ErrorCode::InvalidArgument, "c2c: " + what); };
    if (p.maxDistance && !(*p.maxDistance > 0 && std::isfinite(*p.maxDistance)))
        bad("the maximum distance must be a positive number of metres");
    if (p.neighbours < 3 || p.neighbours > 500)
        bad("the model neighbourhood must hold 3 to 500 points (k = " + std::to_string(p.neighbours) + ")");
    if (p.radius && !(*p.radius > 0 && std::isfinite(*p.radius)))
        bad("the model radius must be a positive number of metres");
    if (p.octreeLevel < 0 || p.octreeLevel > octree::kMaxLevel)
        bad("the octree level must be in 1.." + std::to_string(octree::kMaxLevel) + " (0: automatic)");
    if (p.signedDistances && p.model == LocalModel::None && !reference.hasNormals())
        bad("signed distances need normals on the reference cloud or a local model (--model plane|delaunay|quadric)");
    if (reference.empty())
        throw Error(ErrorCode::InvalidData, "c2c: the reference cloud '" + reference.name + "' is empty");
}

struct Scratch
{
    std::vector<octree::Neighbour> neighbours;
    std::vector<Eigen::Vector3d> points;
    detail::FittedModel fitted;
    detail::ModelScratch model;
};

} // namespace

CloudToCloudResult cloudToCloud(const PointCloud& compared, const PointCloud& reference, const CloudToCloudParams& params,
                                ProgressObserver* progress)
{
    checkParams(params, reference);
    const std::size_t n = compared.size();
    CloudToCloudResult result;
    result.distance = ScalarField("c2c_distance", n);

    // Both clouds in the reference's local frame (their origins may differ).
    const Eigen::Vector3d shift = compared.origin() - reference.origin();
    std::vector<Eigen::Vector3f> shifted;
    const Eigen::Vector3f* queries = compared.positions().data();
    if (!shift.isZero()) {
        shifted.resize(n);
        for (std::size_t i = 0; i < n; ++i)
            shifted[i] = (compared.positions()[i].cast<double>() + shift).cast<float>();
        queries = shifted.data();
    }
    octree::CubicBox cube = octree::CubicBox::enclosing(reference.positions().data(), reference.size());
    {
        Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity()), hi = -lo;
        bool any = false;
        for (std::size_t i = 0; i < n; ++i)
            if (queries[i].allFinite()) {
                lo = lo.cwiseMin(queries[i]);
                hi = hi.cwiseMax(queries[i]);
                any = true;
            }
        if (any) {
            const Eigen::Vector3f corners[2] = {lo, hi};
            cube = octree::CubicBox::enclosingBoth(cube, octree::CubicBox::enclosing(corners, 2));
        }
    }
    // The compared points are visited in Morton order, in chunks: the points of
    // one cell share their candidates in the batch query, memory stays local,
    // and the batch's own sorting buffers stay chunk-sized. The order is computed
    // before the octree so their temporary buffers never coexist.
    // A stage of its own, so the bar moves and Cancel is heard between the two
    // (each is linear, about 0.1 s per million points on two cores).
    ProgressTicker preparing(progress, "Ordering the points and building the octree", 2);
    const std::vector<std::uint32_t> order = octree::mortonOrder(queries, n, cube, [&preparing] { preparing.checkCancel(); });
    preparing.step();
    const octree::Octree tree = buildOctree(reference, cube, progress);
    preparing.step();

    // With a k-neighbourhood model, the k nearest reference points of each
    // compared point (§2.3.2: "its k nearest neighbours instead of only the
    // nearest one") come from the same batch query; the first is the nearest
    // neighbour, so there is no separate NN pass. Levels whose cells hold about
    // 30 reference points for NN (the batch prunes the neighbour cells a query
    // cannot need; level sweep in docs/benchmarks.md) and about 3 k for k
    // neighbours (the 27 cells around a query almost always settle it, and the
    // batch's guessed radius rarely reaches beyond the first few cells).
    const bool useModel = params.model != LocalModel::None;
    const bool knnModel = useModel && !params.radius;
    const std::size_t k = static_cast<std::size_t>(params.neighbours);
    result.level = params.octreeLevel != 0 ? params.octreeLevel
                   : knnModel            ? tree.levelNearestMeanPopulation(std::max(8.0, 3.0 * static_cast<double>(k)))
                                         : tree.levelNearestMeanPopulation(30.0);

    std::vector<VisibilityLabel> labels;
    if (!params.viewpoints.empty()) {
        labels = visibilityLabels(compared, reference, params.viewpoints, params.visibility, progress);
        ScalarField field("visibility", n);
        for (std::size_t i = 0; i < n; ++i)
            field.values()[i] = static_cast<float>(labels[i]);
        result.visibility = std::move(field);
    }
    if (params.splitComponents) {
        result.dx = ScalarField("c2c_dx", n);
        result.dy = ScalarField("c2c_dy", n);
        result.dz = ScalarField("c2c_dz", n);
    }
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    if (params.reportReach)
        result.reach.assign(n, 0.0f);
    constexpr float kUnbounded = std::numeric_limits<float>::infinity();
    std::vector<std::uint32_t> closestIndex(params.closestPoints ? n : 0, kNone);

    const auto& refPoints = reference.positions();
    const bool haveSensor = !reference.sensors().empty();
    const Eigen::Vector3d sensorPosition = haveSensor ? Eigen::Vector3d(reference.sensors().front().position - reference.origin())
                                                      : Eigen::Vector3d::Zero();
    std::atomic<std::size_t> fallbacks{0};
    tbb::enumerable_thread_specific<Scratch> scratch;
    ProgressTicker ticker(progress, useModel ? "Distances with local models" : "Nearest-neighbour distances", n);
    constexpr std::size_t kChunk = 1 << 16;
    std::vector<Eigen::Vector3f> chunkQueries;
    std::vector<octree::Neighbour> chunkNeighbours; // the nearest reference point of each chunk point
    std::vector<octree::Neighbour> chunkLists;      // with --knn: the k nearest of each

    // Writes the distance d of the compared point at position j of the order
    // (maximum distance, closest point, components).
    auto store = [&](std::size_t j, double d) {
        const std::uint32_t i = order[j];
        const octree::Neighbour nb = chunkNeighbours[j % kChunk];
        if (params.maxDistance && std::abs(d) > *params.maxDistance) {
            if (!params.clampBeyondMax)
                return;
            d = d < 0 ? -*params.maxDistance : *params.maxDistance;
        }
        if (params.closestPoints)
            closestIndex[i] = nb.index;
        result.distance.values()[i] = static_cast<float>(d);
        if (params.splitComponents) {
            const Eigen::Vector3f v = chunkQueries[j % kChunk] - refPoints[nb.index];
            result.dx->values()[i] = v.x();
            result.dy->values()[i] = v.y();
            result.dz->values()[i] = v.z();
        }
    };

    // With --radius, the compared points of a chunk are grouped by nearest
    // reference point: the neighbourhood, the reference points within the
    // radius of that point ([ISPRS05]), is a function of it alone, so the model
    // is fitted once per group. On two samplings of one surface, about 6 in 10
    // reference points are someone's nearest neighbour.
    const bool radiusModel = useModel && params.radius;
    std::vector<std::uint32_t> groupOf(radiusModel ? reference.size() : 0, kNone); // reference point -> group, within a chunk
    std::vector<std::uint32_t> groupPoint, groupStart, members;

    for (std::size_t chunkBegin = 0; chunkBegin < n; chunkBegin += kChunk) {
        const std::size_t chunkEnd = std::min(n, chunkBegin + kChunk);
        chunkQueries.resize(chunkEnd - chunkBegin);
        for (std::size_t j = chunkBegin; j < chunkEnd; ++j) {
            const std::uint32_t i = order[j];
            const bool hidden = !labels.empty() && labels[i] != VisibilityLabel::Visible;
            // A NaN query gets no neighbour: how hidden points are skipped cheaply.
            chunkQueries[j - chunkBegin] = hidden ? Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()) : queries[i];
        }
        if (knnModel) {
            tree.nearestBatch(chunkQueries.data(), chunkQueries.size(), k, result.level, chunkLists);
            chunkNeighbours.resize(chunkQueries.size());
            for (std::size_t j = 0; j < chunkQueries.size(); ++j)
                chunkNeighbours[j] = chunkLists[j * k];
        } else {
            tree.nearestBatch(chunkQueries.data(), chunkQueries.size(), 1, result.level, chunkNeighbours);
        }
        // Which side of a model is "positive": the reference normal at the
        // nearest point, else the scanner, else up.
        auto orientationAt = [&](std::uint32_t r) -> Eigen::Vector3d {
            if (reference.hasNormals())
                return reference.normals()[r].cast<double>();
            if (haveSensor)
                return sensorPosition - refPoints[r].cast<double>();
            return Eigen::Vector3d::UnitZ();
        };
        if (knnModel) {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(chunkBegin, chunkEnd, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
                Scratch& s = scratch.local();
                std::size_t localFallbacks = 0;
                for (std::size_t j = range.begin(); j != range.end(); ++j) {
                    const octree::Neighbour* list = chunkLists.data() + (j - chunkBegin) * k;
                    // The reference points lie in file order, scattered in memory:
                    // ask for the next point's neighbours while this one is fitted.
                    if (j + 1 != range.end()) {
                        const octree::Neighbour* next = list + k;
                        for (std::size_t m = 0; m < k; ++m)
                            if (next[m].index != kNone)
                                __builtin_prefetch(&refPoints[next[m].index]);
                        __builtin_prefetch(&result.distance.values()[order[j + 1]], 1);
                    }
                    if (list[0].index == kNone)
                        continue; // NaN query, or not comparable: the value stays NaN
                    if (params.reportReach)
                        result.reach[order[j]] = list[k - 1].index == kNone ? kUnbounded
                                                                            : std::sqrt(list[k - 1].squaredDistance);
                    s.points.clear();
                    for (std::size_t m = 0; m < k && list[m].index != kNone; ++m)
                        s.points.push_back(refPoints[list[m].index].cast<double>());
                    double d = std::sqrt(static_cast<double>(list[0].squaredDistance));
                    double modelSigned = 0;
                    if (detail::fitModel(params.model, s.points, orientationAt(list[0].index), s.fitted, s.model) &&
                        detail::modelDistance(s.fitted, s.points, chunkQueries[j - chunkBegin].cast<double>(), modelSigned, s.model))
                        d = params.signedDistances ? modelSigned : std::abs(modelSigned);
                    else
                        ++localFallbacks; // thesis: a degenerate neighbourhood is no worse than plain NN
                    store(j, d);
                }
                fallbacks += localFallbacks;
                ticker.step(range.size());
            });
            continue;
        }
        if (!useModel) {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(chunkBegin, chunkEnd, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
                for (std::size_t j = range.begin(); j != range.end(); ++j) {
                    const octree::Neighbour nb = chunkNeighbours[j - chunkBegin];
                    if (nb.index == kNone)
                        continue; // NaN query, or not comparable: the value stays NaN
                    double d = std::sqrt(static_cast<double>(nb.squaredDistance));
                    if (params.reportReach)
                        result.reach[order[j]] = static_cast<float>(params.maxDistance ? std::min(d, *params.maxDistance) : d);
                    if (params.signedDistances && reference.normals()[nb.index].dot(chunkQueries[j - chunkBegin] - refPoints[nb.index]) < 0)
                        d = -d; // sign by the reference normal at the nearest neighbour
                    store(j, d);
                }
                ticker.step(range.size());
            });
            continue;
        }

        // --radius: groups by nearest reference point, in order of first appearance, as
        // lists of positions in the chunk (a counting sort).
        groupPoint.clear();
        groupStart.clear();
        for (std::size_t j = 0; j < chunkQueries.size(); ++j) {
            const std::uint32_t r = chunkNeighbours[j].index;
            if (r == kNone)
                continue;
            if (groupOf[r] == kNone) {
                groupOf[r] = static_cast<std::uint32_t>(groupPoint.size());
                groupPoint.push_back(r);
                groupStart.push_back(0);
            }
            ++groupStart[groupOf[r]];
        }
        std::uint32_t running = 0;
        for (auto& start : groupStart) {
            const std::uint32_t size = start;
            start = running;
            running += size;
        }
        groupStart.push_back(running);
        members.resize(running);
        for (std::size_t j = 0; j < chunkQueries.size(); ++j) {
            const std::uint32_t r = chunkNeighbours[j].index;
            if (r != kNone)
                members[groupStart[groupOf[r]]++] = static_cast<std::uint32_t>(j);
        }
        for (std::size_t g = groupPoint.size(); g > 0; --g) // the increments above moved each start to the next one's
            groupStart[g] = groupStart[g - 1];
        groupStart[0] = 0;
        for (const std::uint32_t r : groupPoint)
            groupOf[r] = kNone;

        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groupPoint.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
            Scratch& s = scratch.local();
            std::size_t localFallbacks = 0, done = 0;
            for (std::size_t g = range.begin(); g != range.end(); ++g) {
                const std::uint32_t r = groupPoint[g];
                const Eigen::Vector3f& p = refPoints[r];
                s.points.clear();
                tree.withinRadius(p, static_cast<float>(*params.radius), result.level, s.neighbours);
                for (const auto& m : s.neighbours)
                    s.points.push_back(refPoints[m.index].cast<double>());
                const bool fitted = detail::fitModel(params.model, s.points, orientationAt(r), s.fitted, s.model);
                for (std::uint32_t m = groupStart[g]; m < groupStart[g + 1]; ++m) {
                    const std::size_t j = chunkBegin + members[m];
                    const octree::Neighbour nb = chunkNeighbours[members[m]];
                    const Eigen::Vector3f& q = chunkQueries[members[m]];
                    double d = std::sqrt(static_cast<double>(nb.squaredDistance));
                    if (params.reportReach)
                        result.reach[order[j]] = static_cast<float>(d + *params.radius);
                    double modelSigned = 0;
                    if (fitted && detail::modelDistance(s.fitted, s.points, q.cast<double>(), modelSigned, s.model))
                        d = params.signedDistances ? modelSigned : std::abs(modelSigned);
                    else
                        ++localFallbacks; // thesis: a degenerate neighbourhood is no worse than plain NN
                    store(j, d);
                }
                done += groupStart[g + 1] - groupStart[g];
            }
            fallbacks += localFallbacks;
            ticker.step(done);
        });
        // Points without a neighbour (NaN, hidden) count as done too.
        ticker.step(chunkQueries.size() - members.size());
    }
    result.modelFallbacks = fallbacks;

    if (params.closestPoints) {
        std::vector<std::size_t> matched;
        matched.reserve(n);
        for (const std::uint32_t index : closestIndex)
            if (index != kNone)
                matched.push_back(index);
        result.closest = reference.subset(matched);
        result.closest->name = reference.name + "_closest";
    }
    result.statistics = computeStatistics(result.distance);
    return result;
}

void attachFields(PointCloud& cloud, CloudToCloudResult&& result)
{
    cloud.addField(std::move(result.distance));
    for (auto* field : {&result.dx, &result.dy, &result.dz, &result.visibility})
        if (*field)
            cloud.addField(std::move(**field));
}

} // namespace scandiff
