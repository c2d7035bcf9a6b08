// SPDX-License-Identifier: GPL-3.0-or-later
#include "TiledCloudToCloud.h"

#include "ChunkedCloud.h"
#include "TiledRun.h"
#include "Tiling.h"

#include "CliSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToCloud.h>
#include <scandiff/core/distance/DistanceParameters.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace scandiff::mpi {

namespace {

//! The part of the reference a rank holds, in the reference file's frame.
struct ReferencePart
{
    std::vector<Eigen::Vector3f> positions, normals;
    std::uint64_t inOwnTiles = 0;
};

//! Up to `perTile` reference points of every tile, whatever its rank: an
//! upper bound on the distance to the k nearest reference points of a point
//! whose own halo held too few.
class Representatives
{
public:
    Representatives(const TileGrid& grid, std::size_t perTile) : grid_(grid), perTile_(perTile) {}
    void offer(const Eigen::Vector3d& p)
    {
        std::vector<Eigen::Vector3d>* list =
            last_.of(grid_.tileOf(p.x(), p.y()), [&](const TileKey& key) { return &byTile_[key]; });
        if (list->size() < perTile_)
            list->push_back(p);
    }
    //! Distance from p to its k-th nearest representative, +inf with fewer.
    double kthDistance(const Eigen::Vector3d& p, std::size_t k) const
    {
        std::vector<double> distances;
        for (const auto& [key, list] : byTile_)
            for (const Eigen::Vector3d& q : list)
                distances.push_back((q - p).norm());
        if (distances.size() < k || k == 0)
            return std::numeric_limits<double>::infinity();
        std::nth_element(distances.begin(), distances.begin() + static_cast<std::ptrdiff_t>(k - 1), distances.end());
        return distances[k - 1];
    }

    //! Every rank's representatives, the same on every rank (rank order, up
    //! to perTile per tile).
    void mergeOverRanks(const Communicator& c)
    {
        struct Entry
        {
            std::int64_t x, y;
            double p[3];
        };
        std::vector<Entry> mine;
        for (const auto& [key, list] : byTile_)
            for (const Eigen::Vector3d& q : list)
                mine.push_back({key.x, key.y, {q.x(), q.y(), q.z()}});
        byTile_.clear();
        last_.forget();
        for (const Entry& e : allGather(c, mine)) {
            std::vector<Eigen::Vector3d>& list = byTile_[{e.x, e.y}];
            if (list.size() < perTile_)
                list.emplace_back(e.p[0], e.p[1], e.p[2]);
        }
    }

private:
    TileGrid grid_;
    std::size_t perTile_;
    std::unordered_map<TileKey, std::vector<Eigen::Vector3d>, TileKeyHash> byTile_;
    LastTile<std::vector<Eigen::Vector3d>*> last_; // unordered_map keeps its values in place
};

//! How many reference points a compared point's value needs at least.
std::size_t pointsNeeded(const CloudToCloudParams& params)
{
    return params.model != LocalModel::None && !params.radius ? static_cast<std::size_t>(params.neighbours) : 1;
}

class CloudToCloudRun
{
public:
    CloudToCloudRun(const Communicator& c, const io::FormatRegistry& formats, const CloudToCloudJob& job)
        : c_(c), formats_(formats), job_(job),
          compared_(c, formats, job.compared, job.tiling.chunkPoints, job.read),
          reference_(c, formats, job.reference, job.tiling.chunkPoints, job.read),
          grid_(job.tiling.tileSize)
    {
        memoryNote("origins chosen");
        // The settings, and their errors, are scandiff-cli's.
        referenceLayout_ = reference_.layout().subset({});
        params_ = cloudToCloudSettings(job.values, referenceLayout_);
        if (cloudToCloudBothWays(job.values))
            throw Error(ErrorCode::Unsupported, "scandiff-mpi c2c: --both-ways is not supported yet (run it again with the clouds swapped)");
        if (!params_.viewpoints.empty())
            throw Error(ErrorCode::Unsupported, "scandiff-mpi c2c: the visibility test needs the whole reference's depth maps; "
                                                "it is not supported on tiles");
        if (params_.closestPoints)
            throw Error(ErrorCode::Unsupported, "scandiff-mpi c2c: --closest-points is not supported yet");
        params_.reportReach = true;
        halo_ = job.tiling.halo ? *job.tiling.halo : defaultHalo(job.values, job.tiling.tileSize);
        needNormals_ = params_.signedDistances && params_.model == LocalModel::None;
        checkChunkedOutput(formats, job.output);
    }

    void run(std::ostream& out)
    {
        const auto start = Clock::now();
        compared_.settleFieldsLeftOut(c_);
        owned_ = collectOwnedPoints(c_, compared_, grid_);
        report_.tiles = owned_.tiles.size();
        report_.points = owned_.index.size();
        Representatives representatives(grid_, std::min<std::size_t>(pointsNeeded(params_), 64));
        memoryNote("compared collected");
        ReferencePart part = collectReference(representatives);
        memoryNote("reference collected");
        report_.held = part.positions.size();
        report_.heldInTiles = part.inOwnTiles;
        computeOwnTiles(std::move(part));
        memoryNote("computed");
        widen(representatives);
        report_.seconds = std::chrono::duration<double>(Clock::now() - start).count();

        const DistanceStatistics statistics = statisticsOverRanks(c_, distance_);
        comparedCloud_ = PointCloud(); // only the values and their indices are needed from here on
        if (c_.rank() == 0)
            cli::printStatistics(out, "c2c " + std::string(localModelName(params_.model)) + " (compared -> reference)", statistics);
        reportRanks(c_, report_, {"c2c", "compared points", "reference points"}, grid_.size(), halo_,
                    compared_.streamed() && reference_.streamed(), out);
        memoryNote("reported");
        if (!job_.output.empty())
            writeOutput(out);
        finishRun(c_, start, out);
    }

private:
    //! The reference points `keep` accepts, streamed from the file (this rank
    //! alone: the points it widens).
    template <class Keep>
    ReferencePart streamReference(Keep&& keep)
    {
        ReferencePart part;
        for (std::size_t k = 0; k < reference_.chunkCount(); ++k) {
            const PointCloud chunk = reference_.read(k, true);
            for (std::size_t i = 0; i < chunk.size(); ++i) {
                if (!keep(chunk.globalPosition(i)))
                    continue;
                part.positions.push_back(chunk.positions()[i]);
                if (needNormals_ && chunk.hasNormals())
                    part.normals.push_back(chunk.normals()[i]);
            }
        }
        return part;
    }

    //! The reference read once across the ranks, each point sent to every
    //! rank whose halo holds it; the representatives from every rank's share.
    ReferencePart collectReference(Representatives& representatives)
    {
        const RegionRouter router(grid_, owned_.owners, c_.size(), halo_);
        // Room for this rank's part of the reference, estimated from its share
        // of the compared points with a margin for the halo: room never
        // touched costs no memory, while growing the vector copied it into
        // fresh pages again and again.
        const double share = owned_.total() ? static_cast<double>(owned_.index.size()) / static_cast<double>(owned_.total()) : 0.0;
        const auto expected = static_cast<std::size_t>(share * static_cast<double>(reference_.recordCount()) * 1.3);
        ReceivedPoints received =
            distributePoints(c_, reference_, {needNormals_, false, expected}, router,
                             [&](const Eigen::Vector3d& p) { representatives.offer(p); });
        representatives.mergeOverRanks(c_);
        totalReference_ = received.chunkStarts.back();
        ReferencePart part;
        part.inOwnTiles = countInTiles(received.positions, reference_.origin(), grid_, owned_.tiles);
        part.positions = std::move(received.positions);
        part.normals = std::move(received.normals);
        return part;
    }

    //! Distances of this rank's points on its part of the reference; the points
    //! whose reach pokes out of their tile's halo are left for widen().
    void computeOwnTiles(ReferencePart&& part)
    {
        const std::size_t n = owned_.positions.size();
        if (n == 0)
            comparedCloud_ = makeCloud(compared_.origin(), {});
        distance_.assign(n, std::numeric_limits<float>::quiet_NaN());
        if (params_.splitComponents)
            for (auto* plane : {&dx_, &dy_, &dz_})
                plane->assign(n, std::numeric_limits<float>::quiet_NaN());
        if (n == 0)
            return;
        if (part.positions.empty()) {
            comparedCloud_ = makeCloud(compared_.origin(), std::move(owned_.positions));
            for (std::size_t j = 0; j < n; ++j)
                pending_.push_back({j, std::numeric_limits<double>::infinity()});
            return;
        }
        const PointCloud reference =
            makeCloud(reference_.origin(), std::move(part.positions), std::move(part.normals), referenceLayout_.sensors());
        comparedCloud_ = makeCloud(compared_.origin(), std::move(owned_.positions));
        const PointCloud& compared = comparedCloud_;
        const CloudToCloudResult result = cloudToCloud(compared, reference, params_);
        for (std::size_t j = 0; j < n; ++j) {
            const Eigen::Vector3d p = compared.globalPosition(j);
            const double depth = grid_.depthInGrownTile(grid_.tileOf(p.x(), p.y()), halo_, p.x(), p.y());
            const double reach = result.reach[j];
            if (reach + margin(compared.positions()[j], reach) <= depth)
                store(j, result, j);
            else
                pending_.push_back({j, reach});
        }
    }

    //! The points whose halo was too narrow, on every reference point within
    //! their reach (or a bound of it from the representatives), again with a
    //! doubled radius until their reach fits or the whole reference is held.
    void widen(const Representatives& representatives)
    {
        report_.widened = pending_.size();
        const std::size_t needed = pointsNeeded(params_);
        for (Pending& w : pending_) {
            const Eigen::Vector3d p = comparedCloud_.globalPosition(w.index);
            if (!std::isfinite(w.radius)) {
                w.radius = representatives.kthDistance(p, needed);
                if (params_.radius)
                    w.radius += *params_.radius;
            }
            w.radius += margin(comparedCloud_.positions()[w.index], w.radius);
        }
        while (!pending_.empty()) {
            ++report_.widenings;
            std::vector<Eigen::Vector2d> centres;
            std::vector<double> radii;
            for (const Pending& w : pending_) {
                centres.push_back(comparedCloud_.globalPosition(w.index).head<2>());
                radii.push_back(w.radius);
            }
            const ReachIndex reach(std::move(centres), std::move(radii), grid_.size());
            ReferencePart part = streamReference([&](const Eigen::Vector3d& q) { return reach.touches(q.head<2>(), q.head<2>()); });
            const bool wholeReference = part.positions.size() == totalReference_;
            std::vector<Eigen::Vector3f> queries;
            for (const Pending& w : pending_)
                queries.push_back(comparedCloud_.positions()[w.index]);
            if (part.positions.empty())
                throw Error(ErrorCode::InvalidData, job_.reference.string() + ": no reference point to compare with");
            const PointCloud reference =
                makeCloud(reference_.origin(), std::move(part.positions), std::move(part.normals), referenceLayout_.sensors());
            const PointCloud compared = makeCloud(compared_.origin(), std::move(queries));
            const CloudToCloudResult result = cloudToCloud(compared, reference, params_);
            std::vector<Pending> still;
            for (std::size_t m = 0; m < pending_.size(); ++m) {
                const double reach = result.reach[m];
                if (wholeReference || reach + margin(comparedCloud_.positions()[pending_[m].index], reach) <= pending_[m].radius)
                    store(pending_[m].index, result, m);
                else
                    still.push_back({pending_[m].index, 2 * std::max(pending_[m].radius, reach)});
            }
            pending_ = std::move(still);
        }
    }

    void store(std::size_t j, const CloudToCloudResult& result, std::size_t m)
    {
        distance_[j] = result.distance.values()[m];
        if (params_.splitComponents) {
            dx_[j] = result.dx->values()[m];
            dy_[j] = result.dy->values()[m];
            dz_[j] = result.dz->values()[m];
        }
    }

    //! Rank 0 writes the compared cloud with its new fields in input order.
    void writeOutput(std::ostream& out)
    {
        std::vector<const std::vector<float>*> planes{&distance_};
        if (params_.splitComponents)
            planes.insert(planes.end(), {&dx_, &dy_, &dz_});
        const bool split = params_.splitComponents;
        writeInInputOrder(
            c_, formats_, compared_, owned_, planes,
            [split](PointCloud& chunk, std::vector<std::vector<float>>&& values) {
                const std::size_t n = chunk.size();
                CloudToCloudResult result;
                result.distance = ScalarField("c2c_distance", n);
                if (split) {
                    result.dx = ScalarField("c2c_dx", n);
                    result.dy = ScalarField("c2c_dy", n);
                    result.dz = ScalarField("c2c_dz", n);
                }
                ScalarField* fields[4] = {&result.distance, split ? &*result.dx : nullptr, split ? &*result.dy : nullptr,
                                          split ? &*result.dz : nullptr};
                for (std::size_t f = 0; f < values.size(); ++f)
                    if (values[f].size() == n)
                        fields[f]->values() = std::move(values[f]);
                attachFields(chunk, std::move(result));
            },
            job_.output, job_.write, out);
    }

    struct Pending
    {
        std::size_t index; //!< in this rank's compared points
        double radius;     //!< the reach to fetch (+inf: unknown)
    };

    static double margin(const Eigen::Vector3f& local, double reach)
    {
        return roundingMargin(static_cast<double>(local.cwiseAbs().maxCoeff()), reach);
    }

    const Communicator& c_;
    const io::FormatRegistry& formats_;
    const CloudToCloudJob& job_;
    ChunkedCloud compared_, reference_;
    TileGrid grid_;
    PointCloud referenceLayout_;
    CloudToCloudParams params_;
    double halo_ = 0;
    bool needNormals_ = false;
    OwnedPoints owned_;        //!< positions moved into comparedCloud_ once collected
    PointCloud comparedCloud_;
    std::uint64_t totalReference_ = 0;
    std::vector<float> distance_, dx_, dy_, dz_;
    std::vector<Pending> pending_;
    RankReport report_;
};

} // namespace

double defaultHalo(const ParameterValues& values, double tileSize)
{
    if (values.has("max-dist"))
        return values.real("max-dist");
    if (values.has("radius"))
        return 2 * values.real("radius");
    return tileSize / 10;
}

void runTiledCloudToCloud(const Communicator& c, const io::FormatRegistry& formats, const CloudToCloudJob& job, std::ostream& out)
{
    checkTilingOptions(job.tiling);
    CloudToCloudRun run(c, formats, job);
    // From here on the ranks meet in collective calls.
    runCollectively(c, [&] { run.run(out); });
}

} // namespace scandiff::mpi
