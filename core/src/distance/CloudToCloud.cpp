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
        std::vector<Eigen::Vector3f> finite;
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
    const octree::Octree tree = buildOctree(reference, cube);
    // About 4 reference points per cell: the batch's 27-cell candidate sets stay
    // near a hundred points (docs/benchmarks.md, level sweep).
    result.level = params.octreeLevel > 0 ? params.octreeLevel : tree.levelForMeanPopulation(4.0);

    std::vector<VisibilityLabel> labels;
    if (!params.viewpoints.empty()) {
        labels = visibilityLabels(compared, reference, params.viewpoints, params.visibility, progress);
        ScalarField field("visibility", n);
        for (std::size_t i = 0; i < n; ++i)
            field.values()[i] = static_cast<float>(labels[i]);
        result.visibility = std::move(field);
    }

    // With a k-neighbourhood model, the k nearest reference points of each
    // compared point (§2.3.2: "its k nearest neighbours instead of only the
    // nearest one") come from one batch query per chunk, and the first of them
    // is the nearest neighbour: no separate NN pass.
    const bool useModel = params.model != LocalModel::None;
    const bool batchNeighbourhoods = useModel && !params.radius;
    const auto k = static_cast<std::size_t>(params.neighbours);
    std::vector<octree::Neighbour> nearest;
    if (!batchNeighbourhoods) {
        ProgressTicker ticker(progress, "Nearest neighbours", 1);
        tree.nearestBatch(queries, n, 1, result.level, nearest);
        ticker.step();
    } else {
        nearest.assign(n, octree::Neighbour{std::numeric_limits<std::uint32_t>::max(), 0.0f});
    }

    if (params.splitComponents) {
        result.dx = ScalarField("c2c_dx", n);
        result.dy = ScalarField("c2c_dy", n);
        result.dz = ScalarField("c2c_dz", n);
    }
    const auto& refPoints = reference.positions();
    Eigen::Vector3d sensorDirectionOrigin = Eigen::Vector3d::Zero();
    const bool haveSensor = !reference.sensors().empty();
    if (haveSensor)
        sensorDirectionOrigin = reference.sensors().front().position - reference.origin();
    std::atomic<std::size_t> fallbacks{0};
    tbb::enumerable_thread_specific<Scratch> scratch;
    ProgressTicker modelTicker(progress, useModel ? "Local models" : "Distances", n);
    // The batch's level for k neighbours: at most about 1.5 k reference points per
    // cell, so the 27 cells around a query almost always settle its k nearest.
    const int modelLevel = params.octreeLevel > 0 ? params.octreeLevel
                                                  : tree.levelForMeanPopulation(std::max(4.0, 1.5 * static_cast<double>(k)));
    // Chunks keep the k-neighbour lists small (k x 8 bytes per point).
    // Chunks follow the Morton order of the compared points, so the points of
    // one cell fall in the same chunk and share their candidates in the batch.
    constexpr std::size_t kChunk = 1 << 16;
    std::vector<std::uint32_t> order;
    if (batchNeighbourhoods)
        order = octree::mortonOrder(queries, n, cube);
    std::vector<Eigen::Vector3f> chunkQueries;
    std::vector<octree::Neighbour> chunkNeighbours;
    std::vector<std::uint32_t> slotOf(batchNeighbourhoods ? n : 0);
    for (std::size_t chunkBegin = 0; chunkBegin < n; chunkBegin += kChunk) {
        const std::size_t chunkEnd = std::min(n, chunkBegin + kChunk);
        if (batchNeighbourhoods) {
            chunkQueries.resize(chunkEnd - chunkBegin);
            for (std::size_t j = chunkBegin; j < chunkEnd; ++j) {
                chunkQueries[j - chunkBegin] = queries[order[j]];
                slotOf[order[j]] = static_cast<std::uint32_t>(j - chunkBegin);
            }
            tree.nearestBatch(chunkQueries.data(), chunkQueries.size(), k, modelLevel, chunkNeighbours);
            for (std::size_t j = chunkBegin; j < chunkEnd; ++j)
                nearest[order[j]] = chunkNeighbours[(j - chunkBegin) * k];
        }
        tbb::parallel_for(tbb::blocked_range<std::size_t>(chunkBegin, chunkEnd, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
            Scratch& s = scratch.local();
            std::size_t localFallbacks = 0;
            for (std::size_t position = range.begin(); position != range.end(); ++position) {
                const std::size_t i = batchNeighbourhoods ? order[position] : position;
                const octree::Neighbour nb = nearest[i];
                const bool hidden = !labels.empty() && labels[i] != VisibilityLabel::Visible;
                if (nb.index == std::numeric_limits<std::uint32_t>::max() || hidden)
                    continue; // NaN query, or not comparable: the value stays NaN
                const Eigen::Vector3f& q = queries[i];
                const Eigen::Vector3f& p = refPoints[nb.index];
                double d = std::sqrt(static_cast<double>(nb.squaredDistance));
                if (params.signedDistances && !useModel) {
                    // Sign by the reference normal at the nearest neighbour.
                    if (reference.normals()[nb.index].dot(q - p) < 0)
                        d = -d;
                }
                if (useModel) {
                    s.points.clear();
                    if (batchNeighbourhoods) {
                        const octree::Neighbour* list = chunkNeighbours.data() + static_cast<std::size_t>(slotOf[i]) * k;
                        for (std::size_t r = 0; r < k && list[r].index != std::numeric_limits<std::uint32_t>::max(); ++r)
                            s.points.push_back(refPoints[list[r].index].cast<double>());
                    } else {
                        tree.withinRadius(p, static_cast<float>(*params.radius), modelLevel, s.neighbours);
                        for (const auto& m : s.neighbours)
                            s.points.push_back(refPoints[m.index].cast<double>());
                    }
                    // Which side is "positive": the reference normal, else the scanner, else up.
                    Eigen::Vector3d orientation = Eigen::Vector3d::UnitZ();
                    if (reference.hasNormals())
                        orientation = reference.normals()[nb.index].cast<double>();
                    else if (haveSensor)
                        orientation = sensorDirectionOrigin - p.cast<double>();
                    double modelSigned = 0;
                    if (detail::modelDistance(params.model, s.points, q.cast<double>(), orientation, modelSigned, s.model))
                        d = params.signedDistances ? modelSigned : std::abs(modelSigned);
                    else
                        ++localFallbacks; // thesis: a degenerate neighbourhood is no worse than plain NN
                }
                if (params.maxDistance && std::abs(d) > *params.maxDistance) {
                    if (!params.clampBeyondMax)
                        continue;
                    d = d < 0 ? -*params.maxDistance : *params.maxDistance;
                }
                result.distance.values()[i] = static_cast<float>(d);
                if (params.splitComponents) {
                    const Eigen::Vector3f v = q - p;
                    result.dx->values()[i] = v.x();
                    result.dy->values()[i] = v.y();
                    result.dz->values()[i] = v.z();
                }
            }
            fallbacks += localFallbacks;
            modelTicker.step(range.size());
        });
    }
    result.modelFallbacks = fallbacks;

    if (params.closestPoints) {
        std::vector<std::size_t> matched;
        matched.reserve(n);
        for (const auto& nb : nearest)
            if (nb.index != std::numeric_limits<std::uint32_t>::max())
                matched.push_back(nb.index);
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
