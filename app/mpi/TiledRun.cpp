// SPDX-License-Identifier: GPL-3.0-or-later
#include "TiledRun.h"

#include <scandiff/core/Error.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>

namespace scandiff::mpi {

void checkTilingOptions(const TilingOptions& options)
{
    if (!(options.tileSize > 0) || !std::isfinite(options.tileSize))
        throw Error(ErrorCode::InvalidArgument, "--tile-size must be a positive number of metres");
    if (options.halo && !(*options.halo >= 0 && std::isfinite(*options.halo)))
        throw Error(ErrorCode::InvalidArgument, "--halo must be a non-negative number of metres");
    if (options.chunkPoints == 0)
        throw Error(ErrorCode::InvalidArgument, "--chunk-points must be at least 1");
}

void memoryNote(const char* what)
{
    if (!std::getenv("SCANDIFF_MPI_MEMORY"))
        return;
    std::ifstream status("/proc/self/status");
    std::string line, out;
    while (std::getline(status, line))
        if (line.rfind("VmHWM", 0) == 0 || line.rfind("VmRSS", 0) == 0 || line.rfind("RssFile", 0) == 0 ||
            line.rfind("RssAnon", 0) == 0)
            out += " " + line;
    std::cerr << what << ":" << out << std::endl;
}

double roundingMargin(double localMagnitude, double reach)
{
    return 1e-6 + 5e-7 * localMagnitude + 1e-6 * reach;
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

namespace {

//! Pass 1: the points of every tile, counted by each rank on its share of the
//! chunks, summed over the ranks.
std::map<TileKey, std::uint64_t> countTilePoints(const Communicator& c, const ChunkedCloud& cloud, const TileGrid& grid)
{
    std::map<TileKey, std::uint64_t> mine;
    for (std::size_t k = static_cast<std::size_t>(c.rank()); k < cloud.chunkCount(); k += static_cast<std::size_t>(c.size())) {
        const PointCloud chunk = cloud.read(k, true);
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

} // namespace

OwnedPoints collectOwnedPoints(const Communicator& c, const ChunkedCloud& cloud, const TileGrid& grid)
{
    const std::map<TileKey, std::uint64_t> counts = countTilePoints(c, cloud, grid);
    OwnedPoints owned;
    std::uint64_t expected = 0;
    for (const auto& [key, rank] : assignTiles(counts, c.size()))
        if (rank == c.rank()) {
            owned.tiles.push_back(key);
            expected += counts.at(key);
        }
    memoryNote("counted");
    // Pass 2: this rank's points, positions and input indices.
    const HaloRegion region(grid, owned.tiles, 0.0);
    owned.positions.reserve(static_cast<std::size_t>(expected));
    owned.index.reserve(static_cast<std::size_t>(expected));
    std::uint64_t index = 0;
    for (std::size_t k = 0; k < cloud.chunkCount(); ++k) {
        owned.chunkStarts.push_back(index);
        const PointCloud chunk = cloud.read(k, true);
        for (std::size_t i = 0; i < chunk.size(); ++i) {
            const Eigen::Vector3d p = chunk.globalPosition(i);
            if (region.owns(grid.tileOf(p.x(), p.y()))) {
                owned.positions.push_back(chunk.positions()[i]);
                owned.index.push_back(index + i);
            }
        }
        index += chunk.size();
    }
    owned.chunkStarts.push_back(index);
    return owned;
}

DistanceStatistics statisticsOverRanks(const Communicator& c, const std::vector<float>& values)
{
    double local[3] = {0, 0, 0}; // count, sum, sum of squares
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const float v : values)
        if (!std::isnan(v)) {
            local[0] += 1;
            local[1] += v;
            local[2] += static_cast<double>(v) * v;
            lo = std::min(lo, static_cast<double>(v));
            hi = std::max(hi, static_cast<double>(v));
        }
    double total[3];
    MPI_Allreduce(local, total, 3, MPI_DOUBLE, MPI_SUM, c.comm);
    MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_DOUBLE, MPI_MIN, c.comm);
    MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_DOUBLE, MPI_MAX, c.comm);
    DistanceStatistics s;
    s.count = static_cast<std::size_t>(total[0]);
    double deviations = 0;
    const double mean = total[0] > 0 ? total[1] / total[0] : 0.0;
    for (const float v : values)
        if (!std::isnan(v))
            deviations += (v - mean) * (v - mean);
    MPI_Allreduce(MPI_IN_PLACE, &deviations, 1, MPI_DOUBLE, MPI_SUM, c.comm);
    if (s.count == 0)
        return s;
    s.mean = mean;
    s.standardDeviation = std::sqrt(deviations / total[0]);
    s.min = lo;
    s.max = hi;
    s.rms = std::sqrt(total[2] / total[0]);
    return s;
}

void checkChunkedOutput(const io::FormatRegistry& formats, const std::filesystem::path& output)
{
    if (!output.empty() && !formats.forPath(output).openChunkWriter)
        throw Error(ErrorCode::Unsupported, output.string() + ": scandiff-mpi writes its output chunk by chunk, which " +
                                                formats.forPath(output).name + " files cannot be yet (use .ply)");
}

void writeInInputOrder(const Communicator& c, const io::FormatRegistry& formats, const ChunkedCloud& cloud,
                       const OwnedPoints& owned, const std::vector<const std::vector<float>*>& planes,
                       const AttachValues& attach, const std::filesystem::path& output, const io::WriteOptions& write,
                       std::ostream& out)
{
    const std::size_t planeCount = planes.size();
    std::unique_ptr<io::PointChunkWriter> writer;
    std::size_t next = 0; // this rank's first value not sent yet (its indices are increasing)
    for (std::size_t k = 0; k + 1 < owned.chunkStarts.size(); ++k) {
        std::vector<std::uint32_t> offsets;
        std::vector<float> values;
        for (; next < owned.index.size() && owned.index[next] < owned.chunkStarts[k + 1]; ++next) {
            offsets.push_back(static_cast<std::uint32_t>(owned.index[next] - owned.chunkStarts[k]));
            for (std::size_t f = 0; f < planeCount; ++f)
                values.push_back((*planes[f])[next]);
        }
        const std::vector<std::uint32_t> gatheredOffsets = gatherToRoot(c, offsets);
        const std::vector<float> gatheredValues = gatherToRoot(c, values);
        if (c.rank() != 0)
            continue;
        PointCloud chunk = cloud.read(k, false);
        const std::size_t n = chunk.size();
        if (gatheredOffsets.size() != n)
            throw Error(ErrorCode::Internal, "chunk " + std::to_string(k) + " of " + cloud.path().string() + ": " +
                                                 std::to_string(gatheredOffsets.size()) + " values for " + std::to_string(n) +
                                                 " points");
        std::vector<std::vector<float>> chunkPlanes(planeCount, std::vector<float>(n, std::numeric_limits<float>::quiet_NaN()));
        for (std::size_t m = 0; m < gatheredOffsets.size(); ++m)
            for (std::size_t f = 0; f < planeCount; ++f)
                chunkPlanes[f][gatheredOffsets[m]] = gatheredValues[m * planeCount + f];
        attach(chunk, std::move(chunkPlanes));
        if (!writer)
            writer = io::openPointChunkWriter(formats, output, chunk, owned.total(), write);
        writer->append(chunk);
    }
    if (c.rank() != 0)
        return;
    if (!writer) { // an empty cloud gives an empty output all the same
        PointCloud layout = cloud.read(0, false);
        attach(layout, std::vector<std::vector<float>>(planeCount));
        writer = io::openPointChunkWriter(formats, output, layout, 0, write);
    }
    writer->commit();
    out << "wrote " << output.string() << '\n';
}

void reportRanks(const Communicator& c, const RankReport& mine, const ReportWords& words, double tileSize, double halo,
                 bool allStreamed, std::ostream& out)
{
    const std::vector<RankReport> reports = allGather(c, std::vector<RankReport>{mine});
    if (c.rank() != 0)
        return;
    std::uint64_t points = 0, held = 0, inTiles = 0, widened = 0, most = 0;
    out << "scandiff-mpi " << words.command << ": " << reports.size() << " ranks, tiles of " << tileSize << " m, halo " << halo
        << " m" << (allStreamed ? "" : " (a file whose format cannot be streamed was read whole)") << '\n';
    for (std::size_t r = 0; r < reports.size(); ++r) {
        const RankReport& rr = reports[r];
        out << "  rank " << r << ": " << rr.tiles << " tiles, " << rr.points << " " << words.points << ", " << rr.held << " "
            << words.held << " held (" << rr.heldInTiles << " in its tiles), " << rr.widened << " widened in "
            << rr.widenings << " passes, " << std::fixed << std::setprecision(3) << rr.seconds << " s\n"
            << std::defaultfloat;
        points += rr.points;
        held += rr.held;
        inTiles += rr.heldInTiles;
        widened += rr.widened;
        most = std::max(most, rr.points);
    }
    const double mean = static_cast<double>(points) / static_cast<double>(reports.size());
    out << "  halo overhead " << std::setprecision(3)
        << (inTiles ? 100.0 * static_cast<double>(held - inTiles) / static_cast<double>(inTiles) : 0.0) << " % of the "
        << words.held << ", imbalance " << (mean > 0 ? static_cast<double>(most) / mean : 1.0)
        << " (most points on a rank / mean), " << widened << " points widened\n";
}

void runCollectively(const Communicator& c, const std::function<void()>& body)
{
    try {
        body();
    } catch (const Error& e) {
        std::cerr << "error: (rank " << c.rank() << ") " << e.what() << std::endl;
        MPI_Abort(c.comm, e.exitStatus());
    } catch (const std::exception& e) {
        std::cerr << "error: (rank " << c.rank() << ") " << e.what() << std::endl;
        MPI_Abort(c.comm, static_cast<int>(ErrorCode::Internal));
    }
}

} // namespace scandiff::mpi
