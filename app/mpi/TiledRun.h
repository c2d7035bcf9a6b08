// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What every tiled comparison of scandiff-mpi does alike (docs/scale-out.md):
//! share out the tiles of the cloud it measures (the compared cloud, or the
//! M3C2 core points) by their point counts, collect a rank's points, reduce
//! the statistics, write the output in input order from rank 0, report.

#include "ChunkedCloud.h"
#include "Mpi.h"
#include "Tiling.h"

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/distance/DistanceStatistics.h>
#include <scandiff/io/FileIO.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <unordered_map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace scandiff::mpi {

struct TilingOptions
{
    double tileSize = 100.0;              //!< metres, > 0
    std::optional<double> halo;           //!< metres, >= 0; default from the command's options
    std::uint64_t chunkPoints = 1u << 20; //!< records read at a time
};

//! Throws Error(InvalidArgument) for a tile size or a halo out of range.
void checkTilingOptions(const TilingOptions& options);

using Clock = std::chrono::steady_clock;

//! With SCANDIFF_MPI_MEMORY set, a rank's resident and peak memory after a
//! stage, on stderr: how the per-rank figures of docs/benchmarks.md were taken apart.
void memoryNote(const char* what);

//! Rounding allowance of an exactness test: a reach computed in float32 from
//! local coordinates (magnitude `localMagnitude`), a tile's edges in double
//! from world ones.
double roundingMargin(double localMagnitude, double reach);

PointCloud makeCloud(const Eigen::Vector3d& origin, std::vector<Eigen::Vector3f>&& positions,
                     std::vector<Eigen::Vector3f>&& normals = {}, const std::vector<SensorPose>& sensors = {});

//! The points of the measured cloud this rank owns, and where they sit in the file.
struct OwnedPoints
{
    std::map<TileKey, int> owners; //!< every tile's rank
    std::vector<TileKey> tiles;    //!< this rank's
    std::vector<Eigen::Vector3f> positions;  //!< in the file's frame, in input order
    std::vector<std::uint64_t> index;        //!< their input indices, increasing
    std::vector<std::uint64_t> chunkStarts;  //!< each chunk's first input index, then the total
    std::uint64_t total() const { return chunkStarts.empty() ? 0 : chunkStarts.back(); }
};

//! Collective. Counts the points of every tile (each rank on its share of the
//! chunks), gives the tiles out by point counts (assignTiles) and reads this
//! rank's points.
OwnedPoints collectOwnedPoints(const Communicator& c, const ChunkedCloud& cloud, const TileGrid& grid);

//! Points a rank receives from a file read once across the ranks.
struct ReceivedPoints
{
    std::vector<Eigen::Vector3f> positions, normals; //!< in the file's frame, in input order (normals if asked and present)
    std::vector<std::uint64_t> index;                //!< their input indices, increasing (if asked)
    std::vector<std::uint64_t> chunkStarts;          //!< each chunk's first input index, then the file's total
};

//! Which ranks a point goes to (world coordinates; `ranks` comes cleared).
using Destinations = std::function<void(const Eigen::Vector3d& world, std::vector<int>& ranks)>;

struct DistributeOptions
{
    bool withNormals = false; //!< send the normals (when the file has them)
    bool withIndex = false;   //!< send the input indices
    std::size_t expected = 0; //!< points this rank will receive, when known (room made at once)
    //! This rank's chunks (chunk qN + r at q) when an earlier pass read them
    //! already; taken from here instead of read again.
    std::vector<PointCloud>* alreadyRead = nullptr;
};

//! Collective. Reads `cloud` once across the ranks, one round of N chunks at a
//! time (rank r reads chunk qN + r in round q), and delivers each point to the
//! ranks `destinations` names (MPI_Alltoallv), so a rank decodes 1/N of the
//! file and holds one chunk of it in transit. `seen` is called on every point
//! this rank reads.
ReceivedPoints distributePoints(const Communicator& c, const ChunkedCloud& cloud, const DistributeOptions& options,
                                const Destinations& destinations,
                                const std::function<void(const Eigen::Vector3d&)>& seen = {});

//! How many of `positions` (in the frame of `origin`) lie in `tiles`: the
//! report's points held in a rank's own tiles.
std::uint64_t countInTiles(const std::vector<Eigen::Vector3f>& positions, const Eigen::Vector3d& origin, const TileGrid& grid,
                           const std::vector<TileKey>& tiles);

//! The ranks whose halo region holds a point, from every rank's tiles: what a
//! reference point's destinations are.
class RegionRouter
{
public:
    RegionRouter(const TileGrid& grid, const std::map<TileKey, int>& owners, int ranks, double halo);
    void operator()(const Eigen::Vector3d& world, std::vector<int>& ranks) const;

private:
    const std::vector<int>& candidatesOf(const TileKey& key) const;
    TileGrid grid_;
    std::unordered_map<TileKey, int, TileKeyHash> owner_;
    std::vector<HaloRegion> regions_;
    double halo_;
    std::int64_t reach_;
    mutable std::unordered_map<TileKey, std::vector<int>, TileKeyHash> candidates_;
    mutable LastTile<int> lastOwner_; //!< -1 for a tile no rank owns
};

//! Collective. scandiff-cli's statistics of the non-NaN values, summed over
//! the ranks (in another order: the last digits of the mean may differ).
DistanceStatistics statisticsOverRanks(const Communicator& c, const std::vector<float>& values);

//! Attaches the values of one chunk (one vector per plane, one value per point
//! of the chunk) to the chunk as read from the file, as scandiff-cli would.
using AttachValues = std::function<void(PointCloud& chunk, std::vector<std::vector<float>>&& planes)>;

//! Collective. Rank 0 writes `cloud` with its new values in input order,
//! chunk by chunk; for each chunk every rank sends it the values it owns there
//! (`planes[f][j]` belongs to owned.index[j]), so no rank holds more than one
//! chunk of them at a time.
void writeInInputOrder(const Communicator& c, const io::FormatRegistry& formats, const ChunkedCloud& cloud,
                       const OwnedPoints& owned, const std::vector<const std::vector<float>*>& planes,
                       const AttachValues& attach, const std::filesystem::path& output, const io::WriteOptions& write,
                       std::ostream& out);

//! Throws Error(Unsupported) when the output's format cannot be written chunk by chunk.
void checkChunkedOutput(const io::FormatRegistry& formats, const std::filesystem::path& output);

//! What each rank tells rank 0 for the report.
struct RankReport
{
    double seconds = 0;
    std::uint64_t tiles = 0, points = 0, held = 0, heldInTiles = 0, widened = 0, widenings = 0;
};

//! How the report names its counts: "compared points", "reference points".
struct ReportWords
{
    std::string command, points, held;
};

//! Collective; rank 0 prints the per-rank report on `out`.
void reportRanks(const Communicator& c, const RankReport& mine, const ReportWords& words, double tileSize, double halo,
                 bool allStreamed, std::ostream& out);

//! Collective. The end of every command: rank 0 prints the wall time since
//! `start`; the ranks meet before leaving.
void finishRun(const Communicator& c, Clock::time_point start, std::ostream& out);

//! Runs the collective part of a command: an exception on one rank prints
//! "error: (rank R) ..." and aborts the job, so no rank waits forever.
void runCollectively(const Communicator& c, const std::function<void()>& body);

} // namespace scandiff::mpi
