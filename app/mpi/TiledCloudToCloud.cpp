// SPDX-License-Identifier: GPL-3.0-or-later
#include "TiledCloudToCloud.h"

#include "ChunkedCloud.h"
#include "Tiling.h"

#include "CliSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToCloud.h>
#include <scandiff/core/distance/DistanceParameters.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <fstream>
#include <cstdlib>
#include <limits>
#include <unordered_map>

namespace scandiff::mpi {

namespace {

//! With SCANDIFF_MPI_MEMORY set, a rank's resident and peak memory after a
//! stage, on stderr: how the per-rank figures of docs/benchmarks.md were taken apart.
void memoryNote(const char* what)
{
    if (!std::getenv("SCANDIFF_MPI_MEMORY"))
        return;
    std::ifstream status("/proc/self/status");
    std::string line, out;
    while (std::getline(status, line))
        if (line.rfind("VmHWM", 0) == 0 || line.rfind("VmRSS", 0) == 0 || line.rfind("RssFile", 0) == 0 || line.rfind("RssAnon", 0) == 0)
            out += " " + line;
    std::cerr << what << ":" << out << std::endl;
}

using Clock = std::chrono::steady_clock;

//! What each rank tells rank 0 for the report.
struct RankReport
{
    double seconds = 0;
    std::uint64_t tiles = 0, compared = 0, referenceHeld = 0, referenceInTiles = 0, widened = 0, widenings = 0;
};

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
        const TileKey key = grid_.tileOf(p.x(), p.y());
        if (!last_ || !(key == lastKey_)) { // consecutive points mostly share a tile
            last_ = &byTile_[key];
            lastKey_ = key;
        }
        if (last_->size() < perTile_)
            last_->push_back(p);
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

private:
    TileGrid grid_;
    std::size_t perTile_;
    std::unordered_map<TileKey, std::vector<Eigen::Vector3d>, TileKeyHash> byTile_;
    std::vector<Eigen::Vector3d>* last_ = nullptr; // unordered_map keeps its values in place
    TileKey lastKey_;
};

//! How many reference points a compared point's value needs at least.
std::size_t pointsNeeded(const CloudToCloudParams& params)
{
    return params.model != LocalModel::None && !params.radius ? static_cast<std::size_t>(params.neighbours) : 1;
}

//! Rounding allowance of the exactness test: reach is computed in float32 from
//! local coordinates, the tile's edges in double from world ones.
double margin(const Eigen::Vector3f& local, double reach)
{
    return 1e-6 + 5e-7 * static_cast<double>(local.cwiseAbs().maxCoeff()) + 1e-6 * reach;
}

PointCloud makeCloud(const Eigen::Vector3d& origin, std::vector<Eigen::Vector3f>&& positions,
                     std::vector<Eigen::Vector3f>&& normals, const std::vector<SensorPose>& sensors)
{
    PointCloud cloud;
    cloud.setOrigin(origin);
    cloud.resize(positions.size());
    cloud.positions() = std::move(positions);
    if (!normals.empty())
        cloud.enableNormals() = std::move(normals);
    cloud.sensors() = sensors;
    return cloud;
}

//! Pass 1: the compared points of every tile, counted by each rank on its
//! share of the chunks, summed over the ranks.
std::map<TileKey, std::uint64_t> countTilePoints(const Communicator& c, const ChunkedCloud& compared, const TileGrid& grid)
{
    std::map<TileKey, std::uint64_t> mine;
    for (std::size_t k = static_cast<std::size_t>(c.rank()); k < compared.chunkCount(); k += static_cast<std::size_t>(c.size())) {
        const PointCloud chunk = compared.read(k, true);
        for (std::size_t i = 0; i < chunk.size(); ++i) {
            const Eigen::Vector3d p = chunk.globalPosition(i);
            ++mine[grid.tileOf(p.x(), p.y())];
        }
    }
    struct Entry
    {
        std::int64_t x, y;
        std::uint64_t count;
    };
    std::vector<Entry> entries;
    for (const auto& [key, count] : mine)
        entries.push_back({key.x, key.y, count});
    std::map<TileKey, std::uint64_t> all;
    for (const Entry& e : allGather(c, entries))
        all[{e.x, e.y}] += e.count;
    return all;
}

class TiledRun
{
public:
    TiledRun(const Communicator& c, const io::FormatRegistry& formats, const CloudToCloudJob& job)
        : c_(c), formats_(formats), job_(job),
          compared_(formats, job.compared, job.tiling.chunkPoints, job.read),
          reference_(formats, job.reference, job.tiling.chunkPoints, job.read),
          grid_(job.tiling.tileSize)
    {
        // The settings, and their errors, are scandiff-cli's.
        referenceLayout_ = reference_.read(0, true);
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
        if (!job.output.empty() && !formats.forPath(job.output).openChunkWriter)
            throw Error(ErrorCode::Unsupported, job.output.string() + ": scandiff-mpi writes its output chunk by chunk, which " +
                                                    formats.forPath(job.output).name + " files cannot be yet (use .ply)");
    }

    void run(std::ostream& out)
    {
        const auto start = Clock::now();
        const std::map<TileKey, std::uint64_t> counts = countTilePoints(c_, compared_, grid_);
        const std::map<TileKey, int> owners = assignTiles(counts, c_.size());
        std::vector<TileKey> mine;
        for (const auto& [key, rank] : owners)
            if (rank == c_.rank()) {
                mine.push_back(key);
                expectedCompared_ += counts.at(key);
            }
        report_.tiles = mine.size();
        memoryNote("counted");
        const HaloRegion region(grid_, mine, halo_);
        collectCompared(region);
        Representatives representatives(grid_, std::min<std::size_t>(pointsNeeded(params_), 64));
        memoryNote("compared collected");
        ReferencePart part = collectReference(region, &representatives);
        memoryNote("reference collected");
        report_.referenceHeld = part.positions.size();
        report_.referenceInTiles = part.inOwnTiles;
        computeOwnTiles(std::move(part));
        memoryNote("computed");
        widen(representatives);
        report_.seconds = std::chrono::duration<double>(Clock::now() - start).count();

        const DistanceStatistics statistics = statisticsOverRanks();
        comparedCloud_ = PointCloud(); // only the values and their indices are needed from here on
        const std::vector<RankReport> reports = allGather(c_, std::vector<RankReport>{report_});
        if (c_.rank() == 0) {
            cli::printStatistics(out, "c2c " + std::string(localModelName(params_.model)) + " (compared -> reference)", statistics);
            printReport(out, reports);
        }
        if (!job_.output.empty())
            writeOutput(out);
        if (c_.rank() == 0)
            out << std::fixed << std::setprecision(3) << std::chrono::duration<double>(Clock::now() - start).count() << " s\n"
                << std::defaultfloat;
        memoryNote("done");
        c_.barrier();
    }

private:
    //! Pass 2: this rank's compared points (positions, input indices).
    void collectCompared(const HaloRegion& region)
    {
        std::uint64_t index = 0;
        comparedPositions_.reserve(static_cast<std::size_t>(expectedCompared_));
        comparedIndex_.reserve(static_cast<std::size_t>(expectedCompared_));
        for (std::size_t k = 0; k < compared_.chunkCount(); ++k) {
            chunkStarts_.push_back(index);
            const PointCloud chunk = compared_.read(k, true);
            for (std::size_t i = 0; i < chunk.size(); ++i) {
                const Eigen::Vector3d p = chunk.globalPosition(i);
                if (region.owns(grid_.tileOf(p.x(), p.y()))) {
                    comparedPositions_.push_back(chunk.positions()[i]);
                    comparedIndex_.push_back(index + i);
                }
            }
            index += chunk.size();
        }
        chunkStarts_.push_back(index);
        totalCompared_ = index;
        report_.compared = comparedIndex_.size();
    }

    //! The reference points `keep` accepts, streamed from the file.
    template <class Keep>
    ReferencePart streamReference(Keep&& keep, Representatives* representatives)
    {
        ReferencePart part;
        std::uint64_t total = 0;
        for (std::size_t k = 0; k < reference_.chunkCount(); ++k) {
            const PointCloud chunk = reference_.read(k, true);
            total += chunk.size();
            for (std::size_t i = 0; i < chunk.size(); ++i) {
                const Eigen::Vector3d p = chunk.globalPosition(i);
                if (representatives)
                    representatives->offer(p);
                if (!keep(p))
                    continue;
                part.positions.push_back(chunk.positions()[i]);
                if (needNormals_ && chunk.hasNormals())
                    part.normals.push_back(chunk.normals()[i]);
            }
        }
        totalReference_ = total;
        return part;
    }

    ReferencePart collectReference(const HaloRegion& region, Representatives* representatives)
    {
        std::uint64_t inOwn = 0;
        ReferencePart part = streamReference(
            [&](const Eigen::Vector3d& p) {
                if (!region.contains(p.x(), p.y()))
                    return false;
                inOwn += region.owns(grid_.tileOf(p.x(), p.y()));
                return true;
            },
            representatives);
        part.inOwnTiles = inOwn;
        return part;
    }

    //! Distances of this rank's points on its part of the reference; the points
    //! whose reach pokes out of their tile's halo are left for widen().
    void computeOwnTiles(ReferencePart&& part)
    {
        const std::size_t n = comparedPositions_.size();
        if (n == 0)
            comparedCloud_ = makeCloud(compared_.origin(), {}, {}, {});
        distance_.assign(n, std::numeric_limits<float>::quiet_NaN());
        if (params_.splitComponents)
            for (auto* plane : {&dx_, &dy_, &dz_})
                plane->assign(n, std::numeric_limits<float>::quiet_NaN());
        if (n == 0)
            return;
        if (part.positions.empty()) {
            comparedCloud_ = makeCloud(compared_.origin(), std::move(comparedPositions_), {}, {});
            for (std::size_t j = 0; j < n; ++j)
                pending_.push_back({j, std::numeric_limits<double>::infinity()});
            return;
        }
        const PointCloud reference =
            makeCloud(reference_.origin(), std::move(part.positions), std::move(part.normals), referenceLayout_.sensors());
        comparedCloud_ = makeCloud(compared_.origin(), std::move(comparedPositions_), {}, {});
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
            const bool all = std::any_of(pending_.begin(), pending_.end(), [](const Pending& w) { return !std::isfinite(w.radius); });
            // Pending points by cells as large as the largest radius: a reference
            // point then only looks at the 3 x 3 cells around it.
            double largest = 0;
            for (const Pending& w : pending_)
                largest = std::max(largest, w.radius);
            const TileGrid cells(std::max(largest, grid_.size()));
            std::unordered_map<TileKey, std::vector<std::size_t>, TileKeyHash> byCell;
            std::vector<Eigen::Vector3d> centres(pending_.size());
            for (std::size_t m = 0; m < pending_.size(); ++m) {
                centres[m] = comparedCloud_.globalPosition(pending_[m].index);
                byCell[cells.tileOf(centres[m].x(), centres[m].y())].push_back(m);
            }
            ReferencePart part = streamReference(
                [&](const Eigen::Vector3d& q) {
                    if (all)
                        return true;
                    const TileKey cell = cells.tileOf(q.x(), q.y());
                    for (std::int64_t dx = -1; dx <= 1; ++dx)
                        for (std::int64_t dy = -1; dy <= 1; ++dy) {
                            const auto found = byCell.find({cell.x + dx, cell.y + dy});
                            if (found == byCell.end())
                                continue;
                            for (const std::size_t m : found->second)
                                if (std::abs(q.x() - centres[m].x()) <= pending_[m].radius &&
                                    std::abs(q.y() - centres[m].y()) <= pending_[m].radius)
                                    return true;
                        }
                    return false;
                },
                nullptr);
            const bool wholeReference = part.positions.size() == totalReference_;
            std::vector<Eigen::Vector3f> queries;
            for (const Pending& w : pending_)
                queries.push_back(comparedCloud_.positions()[w.index]);
            if (part.positions.empty())
                throw Error(ErrorCode::InvalidData, job_.reference.string() + ": no reference point to compare with");
            const PointCloud reference =
                makeCloud(reference_.origin(), std::move(part.positions), std::move(part.normals), referenceLayout_.sensors());
            const PointCloud compared = makeCloud(compared_.origin(), std::move(queries), {}, {});
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

    //! Those of scandiff-cli, summed over the ranks (in another order: the
    //! last digits of the mean may differ).
    DistanceStatistics statisticsOverRanks() const
    {
        double local[3] = {0, 0, 0}; // count, sum, sum of squares
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (const float v : distance_)
            if (!std::isnan(v)) {
                local[0] += 1;
                local[1] += v;
                local[2] += static_cast<double>(v) * v;
                lo = std::min(lo, static_cast<double>(v));
                hi = std::max(hi, static_cast<double>(v));
            }
        double total[3];
        MPI_Allreduce(local, total, 3, MPI_DOUBLE, MPI_SUM, c_.comm);
        MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_DOUBLE, MPI_MIN, c_.comm);
        MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_DOUBLE, MPI_MAX, c_.comm);
        DistanceStatistics s;
        s.count = static_cast<std::size_t>(total[0]);
        if (s.count == 0)
            return s;
        s.mean = total[1] / total[0];
        double deviations = 0;
        for (const float v : distance_)
            if (!std::isnan(v))
                deviations += (v - s.mean) * (v - s.mean);
        MPI_Allreduce(MPI_IN_PLACE, &deviations, 1, MPI_DOUBLE, MPI_SUM, c_.comm);
        s.standardDeviation = std::sqrt(deviations / total[0]);
        s.min = lo;
        s.max = hi;
        s.rms = std::sqrt(total[2] / total[0]);
        return s;
    }

    //! The values of one chunk of the compared cloud as a rank sends them:
    //! each point's place in the chunk and its value in every output field.
    struct ChunkValue
    {
        std::uint32_t offset;
        float values[4];
    };

    //! Rank 0 writes the compared cloud with its new fields in input order,
    //! chunk by chunk; for each chunk every rank sends it the values it owns
    //! there, so no rank ever holds more than one chunk of them.
    void writeOutput(std::ostream& out)
    {
        const std::size_t planeCount = params_.splitComponents ? 4 : 1;
        const std::vector<float>* planes[4] = {&distance_, &dx_, &dy_, &dz_};
        std::unique_ptr<io::PointChunkWriter> writer;
        std::size_t next = 0; // this rank's first value not sent yet (its indices are sorted)
        for (std::size_t k = 0; k + 1 < chunkStarts_.size(); ++k) {
            std::vector<ChunkValue> mine;
            for (; next < comparedIndex_.size() && comparedIndex_[next] < chunkStarts_[k + 1]; ++next) {
                ChunkValue v{static_cast<std::uint32_t>(comparedIndex_[next] - chunkStarts_[k]), {}};
                for (std::size_t f = 0; f < planeCount; ++f)
                    v.values[f] = (*planes[f])[next];
                mine.push_back(v);
            }
            const std::vector<ChunkValue> gathered = gatherToRoot(c_, mine);
            if (c_.rank() != 0)
                continue;
            PointCloud chunk = compared_.read(k, false);
            const std::size_t n = chunk.size();
            if (gathered.size() != n)
                throw Error(ErrorCode::Internal, "chunk " + std::to_string(k) + " of the compared cloud: " +
                                                     std::to_string(gathered.size()) + " values for " + std::to_string(n) + " points");
            CloudToCloudResult result;
            result.distance = ScalarField("c2c_distance", n);
            ScalarField* fields[4] = {&result.distance, nullptr, nullptr, nullptr};
            if (params_.splitComponents) {
                result.dx = ScalarField("c2c_dx", n);
                result.dy = ScalarField("c2c_dy", n);
                result.dz = ScalarField("c2c_dz", n);
                fields[1] = &*result.dx;
                fields[2] = &*result.dy;
                fields[3] = &*result.dz;
            }
            for (const ChunkValue& v : gathered)
                for (std::size_t f = 0; f < planeCount; ++f)
                    fields[f]->values()[v.offset] = v.values[f];
            attachFields(chunk, std::move(result));
            if (!writer)
                writer = io::openPointChunkWriter(formats_, job_.output, chunk, totalCompared_, job_.write);
            writer->append(chunk);
        }
        if (c_.rank() != 0)
            return;
        if (!writer) // an empty compared cloud gives an empty output all the same
            writer = io::openPointChunkWriter(formats_, job_.output, compared_.read(0, false), 0, job_.write);
        writer->commit();
        out << "wrote " << job_.output.string() << '\n';
    }

    void printReport(std::ostream& out, const std::vector<RankReport>& reports) const
    {
        std::uint64_t compared = 0, held = 0, inTiles = 0, widened = 0;
        std::uint64_t most = 0;
        double slowest = 0;
        out << "scandiff-mpi c2c: " << reports.size() << " ranks, tiles of " << grid_.size() << " m, halo " << halo_ << " m"
            << (compared_.streamed() && reference_.streamed() ? "" : " (a file whose format cannot be streamed was read whole)")
            << '\n';
        for (std::size_t r = 0; r < reports.size(); ++r) {
            const RankReport& rr = reports[r];
            out << "  rank " << r << ": " << rr.tiles << " tiles, " << rr.compared << " compared points, " << rr.referenceHeld
                << " reference points held (" << rr.referenceInTiles << " in its tiles), " << rr.widened
                << " widened in " << rr.widenings << " passes, " << std::fixed << std::setprecision(3) << rr.seconds << " s\n"
                << std::defaultfloat;
            compared += rr.compared;
            held += rr.referenceHeld;
            inTiles += rr.referenceInTiles;
            widened += rr.widened;
            most = std::max(most, rr.compared);
            slowest = std::max(slowest, rr.seconds);
        }
        const double mean = static_cast<double>(compared) / static_cast<double>(reports.size());
        out << "  halo overhead " << std::setprecision(3)
            << (inTiles ? 100.0 * static_cast<double>(held - inTiles) / static_cast<double>(inTiles) : 0.0)
            << " % of the reference points, imbalance " << (mean > 0 ? static_cast<double>(most) / mean : 1.0)
            << " (most points on a rank / mean), " << widened << " points widened\n";
    }

    struct Pending
    {
        std::size_t index; //!< in this rank's compared points
        double radius;     //!< the reach to fetch (+inf: unknown)
    };

    const Communicator& c_;
    const io::FormatRegistry& formats_;
    const CloudToCloudJob& job_;
    ChunkedCloud compared_, reference_;
    TileGrid grid_;
    PointCloud referenceLayout_;
    CloudToCloudParams params_;
    double halo_ = 0;
    bool needNormals_ = false;
    std::vector<Eigen::Vector3f> comparedPositions_; //!< while collecting; then in comparedCloud_
    PointCloud comparedCloud_;
    std::vector<std::uint64_t> chunkStarts_; //!< index of each compared chunk's first point, and the total
    std::vector<std::uint64_t> comparedIndex_;
    std::uint64_t totalCompared_ = 0, totalReference_ = 0, expectedCompared_ = 0;
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
    if (!(job.tiling.tileSize > 0) || !std::isfinite(job.tiling.tileSize))
        throw Error(ErrorCode::InvalidArgument, "--tile-size must be a positive number of metres");
    if (job.tiling.halo && !(*job.tiling.halo >= 0))
        throw Error(ErrorCode::InvalidArgument, "--halo must be a non-negative number of metres");
    TiledRun run(c, formats, job);
    // From here on the ranks meet in collective calls: one that fails alone
    // would leave the others waiting, so it stops them all.
    try {
        run.run(out);
    } catch (const Error& e) {
        std::cerr << "error: (rank " << c.rank() << ") " << e.what() << std::endl;
        MPI_Abort(c.comm, e.exitStatus());
    } catch (const std::exception& e) {
        std::cerr << "error: (rank " << c.rank() << ") " << e.what() << std::endl;
        MPI_Abort(c.comm, static_cast<int>(ErrorCode::Internal));
    }
}

} // namespace scandiff::mpi
