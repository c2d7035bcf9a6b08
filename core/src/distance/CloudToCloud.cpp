// SPDX-License-Identifier: GPL-3.0-or-later
#include "LocalModels.h"

#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToCloud.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <optional>

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

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

//! The compared points in the reference's local frame (their origins may
//! differ); a copy only when they do.
struct Queries
{
    std::vector<Eigen::Vector3f> shifted;
    const Eigen::Vector3f* points = nullptr;
};

Queries queriesInReferenceFrame(const PointCloud& compared, const PointCloud& reference)
{
    Queries q;
    q.points = compared.positions().data();
    const Eigen::Vector3d shift = compared.origin() - reference.origin();
    if (!shift.isZero()) {
        q.shifted.resize(compared.size());
        for (std::size_t i = 0; i < compared.size(); ++i)
            q.shifted[i] = (compared.positions()[i].cast<double>() + shift).cast<float>();
        q.points = q.shifted.data();
    }
    return q;
}

//! The cube the octree divides: the reference's and every finite query's.
octree::CubicBox enclosingCube(const PointCloud& reference, const Eigen::Vector3f* queries, std::size_t n)
{
    octree::CubicBox cube = octree::CubicBox::enclosing(reference.positions().data(), reference.size());
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
    return cube;
}

//! The octree level of the search (thesis §2.2). Levels whose cells hold
//! about 30 reference points for the nearest neighbour (the batch prunes the
//! neighbour cells a query cannot need; level sweep in docs/benchmarks.md)
//! and about 3 k for k neighbours (the 27 cells around a query almost always
//! settle it, and the batch's guessed radius rarely reaches beyond them).
int searchLevel(const CloudToCloudParams& params, const octree::Octree& tree)
{
    if (params.octreeLevel != 0)
        return params.octreeLevel;
    const bool knnModel = params.model != LocalModel::None && !params.radius;
    return knnModel ? tree.levelNearestMeanPopulation(std::max(8.0, 3.0 * static_cast<double>(params.neighbours)))
                    : tree.levelNearestMeanPopulation(30.0);
}

//! The distance fields the options ask for, empty of values.
void prepareFields(CloudToCloudResult& result, const CloudToCloudParams& params, std::size_t n)
{
    result.distance = ScalarField("c2c_distance", n);
    if (params.splitComponents) {
        result.dx = ScalarField("c2c_dx", n);
        result.dy = ScalarField("c2c_dy", n);
        result.dz = ScalarField("c2c_dz", n);
    }
    if (params.reportReach)
        result.reach.assign(n, 0.0f);
}

//! The pass over the compared points, in Morton order and by chunks: the
//! points of one cell share their candidates in the batch query, memory stays
//! local, and the batch's own buffers stay chunk-sized. For each chunk: its
//! queries (hidden points as NaN), their nearest reference point (thesis
//! §2.2), then the distance: to that point, or to a local model of the
//! reference around it (§2.3.2) fitted on its k nearest neighbours or on
//! the reference points within a radius.
class DistancePass
{
public:
    DistancePass(const PointCloud& reference, const CloudToCloudParams& params, const octree::Octree& tree,
                 const std::vector<std::uint32_t>& order, const Eigen::Vector3f* queries, const std::vector<VisibilityLabel>& labels,
                 CloudToCloudResult& result, ProgressObserver* progress)
        : reference_(reference), params_(params), tree_(tree), order_(order), queries_(queries), labels_(labels), result_(result),
          ticker_(progress, params.model != LocalModel::None ? "Distances with local models" : "Nearest-neighbour distances",
                  order.size()),
          k_(static_cast<std::size_t>(params.neighbours)),
          sensorPosition_(reference.sensors().empty() ? std::nullopt
                                                      : std::optional<Eigen::Vector3d>(reference.sensors().front().position - reference.origin())),
          closestIndex_(params.closestPoints ? order.size() : 0, kNone),
          groupOf_(params.model != LocalModel::None && params.radius ? reference.size() : 0, kNone)
    {
    }

    void run()
    {
        const bool knnModel = params_.model != LocalModel::None && !params_.radius;
        for (std::size_t begin = 0; begin < order_.size(); begin += kChunk) {
            const std::size_t end = std::min(order_.size(), begin + kChunk);
            gatherQueries(begin, end);
            findNearest(knnModel);
            if (params_.model == LocalModel::None)
                nearestNeighbourDistances(begin, end);
            else if (knnModel)
                knnModelDistances(begin, end);
            else
                radiusModelDistances(begin);
        }
    }

    std::size_t modelFallbacks() const { return fallbacks_; }
    //! For each compared point, its nearest reference point (kNone: none); with closestPoints only.
    const std::vector<std::uint32_t>& closestIndex() const { return closestIndex_; }

private:
    static constexpr std::size_t kChunk = 1 << 16;

    void gatherQueries(std::size_t begin, std::size_t end)
    {
        chunkQueries_.resize(end - begin);
        for (std::size_t j = begin; j < end; ++j) {
            const std::uint32_t i = order_[j];
            const bool hidden = !labels_.empty() && labels_[i] != VisibilityLabel::Visible;
            // A NaN query gets no neighbour: how hidden points are skipped cheaply.
            chunkQueries_[j - begin] = hidden ? Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()) : queries_[order_[j]];
        }
    }

    //! The nearest reference point of each query; with a k-neighbourhood
    //! model its k nearest (§2.3.2: "its k nearest neighbours instead of only
    //! the nearest one"), the first of which is the nearest: no separate pass.
    void findNearest(bool knnModel)
    {
        if (!knnModel) {
            tree_.nearestBatch(chunkQueries_.data(), chunkQueries_.size(), 1, result_.level, chunkNeighbours_);
            return;
        }
        tree_.nearestBatch(chunkQueries_.data(), chunkQueries_.size(), k_, result_.level, chunkLists_);
        chunkNeighbours_.resize(chunkQueries_.size());
        for (std::size_t j = 0; j < chunkQueries_.size(); ++j)
            chunkNeighbours_[j] = chunkLists_[j * k_];
    }

    //! §2.2: the distance to the nearest reference point, signed by the
    //! reference normal there when asked.
    void nearestNeighbourDistances(std::size_t begin, std::size_t end)
    {
        const auto& refPoints = reference_.positions();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t j = range.begin(); j != range.end(); ++j) {
                const octree::Neighbour nb = chunkNeighbours_[j - begin];
                if (nb.index == kNone)
                    continue; // NaN query, or not comparable: the value stays NaN
                double d = std::sqrt(static_cast<double>(nb.squaredDistance));
                if (params_.reportReach)
                    result_.reach[order_[j]] = static_cast<float>(params_.maxDistance ? std::min(d, *params_.maxDistance) : d);
                if (params_.signedDistances && reference_.normals()[nb.index].dot(chunkQueries_[j - begin] - refPoints[nb.index]) < 0)
                    d = -d; // sign by the reference normal at the nearest neighbour
                store(j, begin, d);
            }
            ticker_.step(range.size());
        });
    }

    //! §2.3.2 with k neighbours: each query's own model on its k nearest.
    void knnModelDistances(std::size_t begin, std::size_t end)
    {
        const auto& refPoints = reference_.positions();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
            Scratch& s = scratch_.local();
            std::size_t localFallbacks = 0;
            for (std::size_t j = range.begin(); j != range.end(); ++j) {
                const octree::Neighbour* list = chunkLists_.data() + (j - begin) * k_;
                // The reference points lie in file order, scattered in memory:
                // ask for the next point's neighbours while this one is fitted.
                if (j + 1 != range.end()) {
                    const octree::Neighbour* next = list + k_;
                    for (std::size_t m = 0; m < k_; ++m)
                        if (next[m].index != kNone)
                            __builtin_prefetch(&refPoints[next[m].index]);
                    __builtin_prefetch(&result_.distance.values()[order_[j + 1]], 1);
                }
                if (list[0].index == kNone)
                    continue; // NaN query, or not comparable: the value stays NaN
                if (params_.reportReach)
                    result_.reach[order_[j]] = list[k_ - 1].index == kNone ? std::numeric_limits<float>::infinity()
                                                                           : std::sqrt(list[k_ - 1].squaredDistance);
                s.points.clear();
                for (std::size_t m = 0; m < k_ && list[m].index != kNone; ++m)
                    s.points.push_back(refPoints[list[m].index].cast<double>());
                double d = std::sqrt(static_cast<double>(list[0].squaredDistance));
                double modelSigned = 0;
                if (detail::fitModel(params_.model, s.points, orientationAt(list[0].index), s.fitted, s.model) &&
                    detail::modelDistance(s.fitted, s.points, chunkQueries_[j - begin].cast<double>(), modelSigned, s.model))
                    d = params_.signedDistances ? modelSigned : std::abs(modelSigned);
                else
                    ++localFallbacks; // thesis: a degenerate neighbourhood is no worse than plain NN
                store(j, begin, d);
            }
            fallbacks_ += localFallbacks;
            ticker_.step(range.size());
        });
    }

    //! §2.3.2 within a radius: the neighbourhood, the reference points within
    //! the radius of the nearest one ([ISPRS05]), is a function of that point
    //! alone, so the queries are grouped by it and the model fitted once per
    //! group. On two samplings of one surface, about 6 in 10 reference points
    //! are someone's nearest neighbour.
    void radiusModelDistances(std::size_t begin)
    {
        groupByNearest();
        const auto& refPoints = reference_.positions();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groupPoint_.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
            Scratch& s = scratch_.local();
            std::size_t localFallbacks = 0, done = 0;
            for (std::size_t g = range.begin(); g != range.end(); ++g) {
                const std::uint32_t r = groupPoint_[g];
                s.points.clear();
                tree_.withinRadius(refPoints[r], static_cast<float>(*params_.radius), result_.level, s.neighbours);
                for (const auto& m : s.neighbours)
                    s.points.push_back(refPoints[m.index].cast<double>());
                const bool fitted = detail::fitModel(params_.model, s.points, orientationAt(r), s.fitted, s.model);
                for (std::uint32_t m = groupStart_[g]; m < groupStart_[g + 1]; ++m) {
                    const std::size_t j = begin + members_[m];
                    const octree::Neighbour nb = chunkNeighbours_[members_[m]];
                    double d = std::sqrt(static_cast<double>(nb.squaredDistance));
                    if (params_.reportReach)
                        result_.reach[order_[j]] = static_cast<float>(d + *params_.radius);
                    double modelSigned = 0;
                    if (fitted && detail::modelDistance(s.fitted, s.points, chunkQueries_[members_[m]].cast<double>(), modelSigned, s.model))
                        d = params_.signedDistances ? modelSigned : std::abs(modelSigned);
                    else
                        ++localFallbacks; // thesis: a degenerate neighbourhood is no worse than plain NN
                    store(j, begin, d);
                }
                done += groupStart_[g + 1] - groupStart_[g];
            }
            fallbacks_ += localFallbacks;
            ticker_.step(done);
        });
        // Points without a neighbour (NaN, hidden) count as done too.
        ticker_.step(chunkQueries_.size() - members_.size());
    }

    //! The chunk's queries grouped by nearest reference point, groups in order
    //! of first appearance, as lists of positions in the chunk (a counting sort).
    void groupByNearest()
    {
        groupPoint_.clear();
        groupStart_.clear();
        for (std::size_t j = 0; j < chunkQueries_.size(); ++j) {
            const std::uint32_t r = chunkNeighbours_[j].index;
            if (r == kNone)
                continue;
            if (groupOf_[r] == kNone) {
                groupOf_[r] = static_cast<std::uint32_t>(groupPoint_.size());
                groupPoint_.push_back(r);
                groupStart_.push_back(0);
            }
            ++groupStart_[groupOf_[r]];
        }
        std::uint32_t running = 0;
        for (auto& start : groupStart_) {
            const std::uint32_t size = start;
            start = running;
            running += size;
        }
        groupStart_.push_back(running);
        members_.resize(running);
        for (std::size_t j = 0; j < chunkQueries_.size(); ++j) {
            const std::uint32_t r = chunkNeighbours_[j].index;
            if (r != kNone)
                members_[groupStart_[groupOf_[r]]++] = static_cast<std::uint32_t>(j);
        }
        for (std::size_t g = groupPoint_.size(); g > 0; --g) // the increments above moved each start to the next one's
            groupStart_[g] = groupStart_[g - 1];
        groupStart_[0] = 0;
        for (const std::uint32_t r : groupPoint_)
            groupOf_[r] = kNone;
    }

    //! Which side of a model is "positive": the reference normal at the
    //! nearest point, else the scanner, else up.
    Eigen::Vector3d orientationAt(std::uint32_t r) const
    {
        if (reference_.hasNormals())
            return reference_.normals()[r].cast<double>();
        if (sensorPosition_)
            return *sensorPosition_ - reference_.positions()[r].cast<double>();
        return Eigen::Vector3d::UnitZ();
    }

    //! Writes the distance d of the compared point at position j of the order
    //! (its chunk starting at `begin`): the maximum distance, the closest
    //! point, the components.
    void store(std::size_t j, std::size_t begin, double d)
    {
        const std::uint32_t i = order_[j];
        const octree::Neighbour nb = chunkNeighbours_[j - begin];
        if (params_.maxDistance && std::abs(d) > *params_.maxDistance) {
            if (!params_.clampBeyondMax)
                return;
            d = d < 0 ? -*params_.maxDistance : *params_.maxDistance;
        }
        if (params_.closestPoints)
            closestIndex_[i] = nb.index;
        result_.distance.values()[i] = static_cast<float>(d);
        if (params_.splitComponents) {
            const Eigen::Vector3f v = chunkQueries_[j - begin] - reference_.positions()[nb.index];
            result_.dx->values()[i] = v.x();
            result_.dy->values()[i] = v.y();
            result_.dz->values()[i] = v.z();
        }
    }

    const PointCloud& reference_;
    const CloudToCloudParams& params_;
    const octree::Octree& tree_;
    const std::vector<std::uint32_t>& order_;
    const Eigen::Vector3f* queries_;
    const std::vector<VisibilityLabel>& labels_;
    CloudToCloudResult& result_;
    ProgressTicker ticker_;
    std::size_t k_;
    std::optional<Eigen::Vector3d> sensorPosition_;
    std::vector<std::uint32_t> closestIndex_;
    std::atomic<std::size_t> fallbacks_{0};
    tbb::enumerable_thread_specific<Scratch> scratch_;
    std::vector<Eigen::Vector3f> chunkQueries_;
    std::vector<octree::Neighbour> chunkNeighbours_; // the nearest reference point of each chunk query
    std::vector<octree::Neighbour> chunkLists_;      // with a k-neighbourhood model: the k nearest of each
    // Grouping by nearest reference point (radius models): reference point -> group within the chunk.
    std::vector<std::uint32_t> groupOf_, groupPoint_, groupStart_, members_;
};

} // namespace

CloudToCloudResult cloudToCloud(const PointCloud& compared, const PointCloud& reference, const CloudToCloudParams& params,
                                ProgressObserver* progress)
{
    checkParams(params, reference);
    const std::size_t n = compared.size();
    CloudToCloudResult result;
    prepareFields(result, params, n);

    // The octree of the reference over a cube that holds the compared points
    // too. The compared points' Morton order is computed first, so that
    // their temporary buffers and the octree's never coexist; a stage of its
    // own, so the bar moves and Cancel is heard between the two (each is
    // linear, about 0.1 s per million points on two cores).
    const Queries queries = queriesInReferenceFrame(compared, reference);
    const octree::CubicBox cube = enclosingCube(reference, queries.points, n);
    ProgressTicker preparing(progress, "Ordering the points and building the octree", 2);
    const std::vector<std::uint32_t> order = octree::mortonOrder(queries.points, n, cube, [&preparing] { preparing.checkCancel(); });
    preparing.step();
    const octree::Octree tree = buildOctree(reference, cube, progress);
    preparing.step();
    result.level = searchLevel(params, tree);

    // Visibility from the reference's scanners (§2.3.3): points the
    // reference could not see get no distance.
    std::vector<VisibilityLabel> labels;
    if (!params.viewpoints.empty()) {
        labels = visibilityLabels(compared, reference, params.viewpoints, params.visibility, progress);
        ScalarField field("visibility", n);
        for (std::size_t i = 0; i < n; ++i)
            field.values()[i] = static_cast<float>(labels[i]);
        result.visibility = std::move(field);
    }

    DistancePass pass(reference, params, tree, order, queries.points, labels, result, progress);
    pass.run();
    result.modelFallbacks = pass.modelFallbacks();
    if (params.closestPoints) {
        std::vector<std::size_t> matched;
        matched.reserve(n);
        for (const std::uint32_t index : pass.closestIndex())
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
