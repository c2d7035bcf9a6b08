// SPDX-License-Identifier: GPL-3.0-or-later
#include "TiledRun.h"

#include <scandiff/core/Error.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
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
    static const auto start = Clock::now();
    std::cerr << what << " at " << std::chrono::duration<double>(Clock::now() - start).count() << " s:" << out << std::endl;
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
//! chunks, summed over the ranks. The positions of the chunks read are kept
//! in `positions` (chunk qN + r at q), for pass 2.
std::map<TileKey, std::uint64_t> countTilePoints(const Communicator& c, const ChunkedCloud& cloud, const TileGrid& grid,
                                                 std::vector<PointCloud>& positions)
{
    std::unordered_map<TileKey, std::uint64_t, TileKeyHash> mine;
    LastTile<std::uint64_t*> count; // the map's values stay in place
    for (std::size_t k = static_cast<std::size_t>(c.rank()); k < cloud.chunkCount(); k += static_cast<std::size_t>(c.size())) {
        PointCloud chunk = cloud.read(k, true);
        for (std::size_t i = 0; i < chunk.size(); ++i) {
            const Eigen::Vector3d p = chunk.globalPosition(i);
            ++*count.of(grid.tileOf(p.x(), p.y()), [&](const TileKey& key) { return &mine[key]; });
        }
        // Positions only (12 bytes a point, this rank's share): reading the
        // chunk again in pass 2 cost more than keeping them.
        PointCloud kept;
        kept.setOrigin(chunk.origin());
        kept.positions() = std::move(chunk.positions());
        positions.push_back(std::move(kept));
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
    std::vector<PointCloud> positions;
    const std::map<TileKey, std::uint64_t> counts = countTilePoints(c, cloud, grid, positions);
    OwnedPoints owned;
    owned.owners = assignTiles(counts, c.size());
    std::unordered_map<TileKey, int, TileKeyHash> owner(owned.owners.begin(), owned.owners.end());
    for (const auto& [key, rank] : owned.owners)
        if (rank == c.rank())
            owned.tiles.push_back(key);
    memoryNote("counted");
    // Pass 2: every point to its tile's rank.
    DistributeOptions options;
    options.withIndex = true;
    options.alreadyRead = &positions;
    for (const TileKey& key : owned.tiles)
        options.expected += static_cast<std::size_t>(counts.at(key));
    LastTile<int> ownerOf;
    ReceivedPoints mine = distributePoints(c, cloud, options, [&](const Eigen::Vector3d& p, std::vector<int>& ranks) {
        ranks.push_back(ownerOf.of(grid.tileOf(p.x(), p.y()), [&](const TileKey& key) { return owner.at(key); }));
    });
    owned.positions = std::move(mine.positions);
    owned.index = std::move(mine.index);
    owned.chunkStarts = std::move(mine.chunkStarts);
    return owned;
}

ReceivedPoints distributePoints(const Communicator& c, const ChunkedCloud& cloud, const DistributeOptions& options,
                                const Destinations& destinations, const std::function<void(const Eigen::Vector3d&)>& seen)
{
    // A record: position, then the normal and the input index when asked.
    const std::size_t recordFloats = 3 + (options.withNormals ? 3 : 0) + (options.withIndex ? 2 : 0);
    const auto ranks = static_cast<std::size_t>(c.size());
    ReceivedPoints received;
    received.positions.reserve(options.expected);
    if (options.withIndex)
        received.index.reserve(options.expected);
    std::uint64_t base = 0;
    std::vector<int> targets, sendCounts(ranks), sendOffsets(ranks);
    std::vector<std::uint32_t> destinationsOf; // every point's targets, flattened, for the second pass
    std::vector<std::uint32_t> targetCounts;
    std::vector<float> sendBuffer, receiveBuffer;
    for (std::size_t round = 0; round * ranks < cloud.chunkCount(); ++round) {
        const std::size_t chunkIndex = round * ranks + static_cast<std::size_t>(c.rank());
        PointCloud chunk;
        if (chunkIndex < cloud.chunkCount())
            chunk = options.alreadyRead ? std::move((*options.alreadyRead)[round]) : cloud.read(chunkIndex, true);
        // The round's chunk sizes give every point its input index.
        const std::vector<std::uint64_t> sizes = allGather(c, std::vector<std::uint64_t>{chunk.size()});
        std::uint64_t first = base;
        for (std::size_t r = 0; r < ranks; ++r) {
            if (round * ranks + r < cloud.chunkCount())
                received.chunkStarts.push_back(base);
            if (r < static_cast<std::size_t>(c.rank()))
                first += sizes[r];
            base += sizes[r];
        }
        // Where each point goes, counted per rank; then the records written
        // straight at their rank's place in one send buffer.
        std::fill(sendCounts.begin(), sendCounts.end(), 0);
        destinationsOf.clear();
        targetCounts.assign(chunk.size(), 0);
        for (std::size_t i = 0; i < chunk.size(); ++i) {
            const Eigen::Vector3d p = chunk.globalPosition(i);
            if (seen)
                seen(p);
            targets.clear();
            destinations(p, targets);
            targetCounts[i] = static_cast<std::uint32_t>(targets.size());
            for (const int r : targets) {
                destinationsOf.push_back(static_cast<std::uint32_t>(r));
                ++sendCounts[static_cast<std::size_t>(r)];
            }
        }
        std::vector<std::size_t> place(ranks, 0);
        for (std::size_t r = 1; r < ranks; ++r)
            place[r] = place[r - 1] + static_cast<std::size_t>(sendCounts[r - 1]) * recordFloats;
        const std::size_t sendFloats = place.back() + static_cast<std::size_t>(sendCounts.back()) * recordFloats;
        for (std::size_t r = 0; r < ranks; ++r)
            sendOffsets[r] = static_cast<int>(place[r] / recordFloats);
        sendBuffer.resize(sendFloats);
        const bool normals = options.withNormals && chunk.hasNormals();
        std::size_t next = 0;
        for (std::size_t i = 0; i < chunk.size(); ++i)
            for (std::uint32_t t = 0; t < targetCounts[i]; ++t) {
                float* record = sendBuffer.data() + place[destinationsOf[next++]];
                place[destinationsOf[next - 1]] += recordFloats;
                std::copy(chunk.positions()[i].data(), chunk.positions()[i].data() + 3, record);
                float* rest = record + 3;
                if (options.withNormals) {
                    if (normals)
                        std::copy(chunk.normals()[i].data(), chunk.normals()[i].data() + 3, rest);
                    else
                        rest[0] = std::numeric_limits<float>::quiet_NaN(); // no normal
                    rest += 3;
                }
                if (options.withIndex) {
                    const std::uint64_t index = first + i;
                    std::memcpy(rest, &index, sizeof index);
                }
            }
        exchangeRecords(c, sendBuffer, sendCounts, sendOffsets, recordFloats, receiveBuffer);
        // Rank s sent chunk qN + s: in rank order, the records are in input order.
        for (std::size_t at = 0; at < receiveBuffer.size(); at += recordFloats) {
            const float* record = receiveBuffer.data() + at;
            received.positions.emplace_back(record[0], record[1], record[2]);
            const float* rest = record + 3;
            if (options.withNormals) {
                if (!std::isnan(rest[0]))
                    received.normals.emplace_back(rest[0], rest[1], rest[2]);
                rest += 3;
            }
            if (options.withIndex) {
                std::uint64_t index = 0;
                std::memcpy(&index, rest, sizeof index);
                received.index.push_back(index);
            }
        }
    }
    received.chunkStarts.push_back(base);
    // Normals only when every point received has one (a file has them or not).
    if (received.normals.size() != received.positions.size())
        received.normals.clear();
    return received;
}

std::uint64_t countInTiles(const std::vector<Eigen::Vector3f>& positions, const Eigen::Vector3d& origin, const TileGrid& grid,
                           const std::vector<TileKey>& tiles)
{
    const HaloRegion own(grid, tiles, 0.0);
    std::uint64_t count = 0;
    for (const Eigen::Vector3f& q : positions) {
        const Eigen::Vector3d p = origin + q.cast<double>();
        count += own.owns(grid.tileOf(p.x(), p.y()));
    }
    return count;
}

RegionRouter::RegionRouter(const TileGrid& grid, const std::map<TileKey, int>& owners, int ranks, double halo)
    : grid_(grid), owner_(owners.begin(), owners.end()), halo_(halo),
      reach_(static_cast<std::int64_t>(std::ceil(halo / grid.size())))
{
    std::vector<std::vector<TileKey>> tiles(static_cast<std::size_t>(ranks));
    for (const auto& [key, rank] : owners)
        tiles[static_cast<std::size_t>(rank)].push_back(key);
    for (const std::vector<TileKey>& own : tiles)
        regions_.emplace_back(grid, own, halo);
}

const std::vector<int>& RegionRouter::candidatesOf(const TileKey& key) const
{
    const auto found = candidates_.find(key);
    if (found != candidates_.end())
        return found->second;
    std::vector<int> ranks;
    for (std::int64_t dx = -reach_; dx <= reach_; ++dx)
        for (std::int64_t dy = -reach_; dy <= reach_; ++dy) {
            const auto near = owner_.find({key.x + dx, key.y + dy});
            if (near != owner_.end() && std::find(ranks.begin(), ranks.end(), near->second) == ranks.end())
                ranks.push_back(near->second);
        }
    std::sort(ranks.begin(), ranks.end());
    return candidates_.emplace(key, std::move(ranks)).first->second;
}

void RegionRouter::operator()(const Eigen::Vector3d& world, std::vector<int>& ranks) const
{
    const TileKey key = grid_.tileOf(world.x(), world.y());
    const int owner = lastOwner_.of(key, [&](const TileKey& k) {
        const auto found = owner_.find(k);
        return found != owner_.end() ? found->second : -1;
    });
    // Most points lie deeper than the halo inside their tile: only its rank's.
    if (owner >= 0 && grid_.depthInGrownTile(key, -halo_, world.x(), world.y()) > 0) {
        ranks.push_back(owner);
        return;
    }
    for (const int r : candidatesOf(key))
        if (regions_[static_cast<std::size_t>(r)].contains(world.x(), world.y()))
            ranks.push_back(r);
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

namespace {

//! The values this rank owns in the chunk [begin, end) of input indices, from
//! `next` on (owned indices increase): its offset in the chunk, then one float
//! per plane, each as 4 bytes.
void packChunkValues(const OwnedPoints& owned, const std::vector<const std::vector<float>*>& planes, std::uint64_t begin,
                     std::uint64_t end, std::size_t& next, std::vector<std::uint32_t>& words)
{
    for (; next < owned.index.size() && owned.index[next] < end; ++next) {
        words.push_back(static_cast<std::uint32_t>(owned.index[next] - begin));
        for (const std::vector<float>* plane : planes) {
            std::uint32_t bits = 0;
            std::memcpy(&bits, &(*plane)[next], sizeof bits);
            words.push_back(bits);
        }
    }
}

//! One chunk's planes from the packed values every rank sent for it; throws
//! unless every point of the chunk got its values.
std::vector<std::vector<float>> unpackChunkValues(const std::vector<std::uint32_t>& words, std::size_t planeCount,
                                                  std::size_t points, const ChunkedCloud& cloud, std::size_t k)
{
    const std::size_t stride = 1 + planeCount;
    if (words.size() != points * stride)
        throw Error(ErrorCode::Internal, "chunk " + std::to_string(k) + " of " + cloud.path().string() + ": " +
                                             std::to_string(words.size() / stride) + " values for " + std::to_string(points) +
                                             " points");
    std::vector<std::vector<float>> chunkPlanes(planeCount, std::vector<float>(points, std::numeric_limits<float>::quiet_NaN()));
    for (std::size_t at = 0; at < words.size(); at += stride) {
        const std::uint32_t offset = words[at];
        if (offset >= points)
            throw Error(ErrorCode::Internal, "chunk " + std::to_string(k) + ": a value beyond its points");
        for (std::size_t f = 0; f < planeCount; ++f)
            std::memcpy(&chunkPlanes[f][offset], &words[at + 1 + f], sizeof(float));
    }
    return chunkPlanes;
}

//! Collective. Every rank writes the chunks it decodes in distributePoints's
//! rounds (chunk qN + r on rank r) at their place in one file, its values
//! sent to it by their owners (MPI_Alltoallv): the output is written on every
//! rank at once. False, with nothing written, where the output's format or
//! encoding cannot be written so (text).
bool writeInPlace(const Communicator& c, const io::FormatRegistry& formats, const ChunkedCloud& cloud, const OwnedPoints& owned,
                  const std::vector<const std::vector<float>*>& planes, const AttachValues& attach,
                  const std::filesystem::path& output, const io::WriteOptions& write)
{
    const std::size_t chunks = owned.chunkStarts.size() - 1, planeCount = planes.size();
    const auto ranks = static_cast<std::size_t>(c.size()), rank = static_cast<std::size_t>(c.rank());
    // A record: an offset and a value per plane. A round sends up to N
    // chunks of them, which is why the exchange counts records, not bytes.
    const std::size_t stride = 1 + planeCount;
    std::unique_ptr<io::PlacedChunkWriter> writer;
    std::vector<int> sendCounts(ranks), sendOffsets(ranks);
    std::vector<std::uint32_t> sendWords, receiveWords;
    std::size_t next = 0;
    std::uint64_t written = 0;
    for (std::size_t round = 0; round * ranks < chunks; ++round) {
        // Every rank's values for chunk qN + s, to rank s.
        sendWords.clear();
        for (std::size_t s = 0; s < ranks; ++s) {
            const std::size_t k = round * ranks + s;
            const std::size_t before = sendWords.size();
            if (k < chunks)
                packChunkValues(owned, planes, owned.chunkStarts[k], owned.chunkStarts[k + 1], next, sendWords);
            sendOffsets[s] = static_cast<int>(before / stride);
            sendCounts[s] = static_cast<int>((sendWords.size() - before) / stride);
        }
        exchangeRecords(c, sendWords, sendCounts, sendOffsets, stride, receiveWords);

        const std::size_t k = round * ranks + rank;
        PointCloud chunk = k < chunks ? cloud.read(k, false) : PointCloud();
        if (k < chunks)
            attach(chunk, unpackChunkValues(receiveWords, planeCount, chunk.size(), cloud, k));
        if (round == 0) {
            // Rank 0 creates the file (or finds its encoding cannot be placed) and tells the others where it is.
            std::string path;
            if (rank == 0) {
                try {
                    writer = io::openPlacedChunkWriter(formats, output, {}, chunk, owned.total(), write);
                    path = writer->temporaryPath().string();
                } catch (const Error& e) {
                    if (e.code() != ErrorCode::Unsupported)
                        throw;
                }
            }
            auto length = static_cast<std::uint64_t>(path.size());
            MPI_Bcast(&length, 1, MPI_UINT64_T, 0, c.comm);
            if (length == 0)
                return false;
            path.resize(static_cast<std::size_t>(length));
            MPI_Bcast(path.data(), static_cast<int>(length), MPI_CHAR, 0, c.comm);
            // Every range of a file reads with the same attributes: a rank's
            // own chunk lays its writer out as rank 0's. A rank that cannot
            // reach the file (not on a file system the ranks share) sends
            // every rank back to rank 0 writing alone; rank 0's temporary goes.
            int joined = 1;
            if (rank != 0 && k < chunks) {
                try {
                    writer = io::openPlacedChunkWriter(formats, output, path, chunk, owned.total(), write);
                } catch (const Error& e) {
                    std::cerr << "warning: (rank " << rank << ") " << e.what() << "; rank 0 writes the output alone\n";
                    joined = 0;
                }
            }
            MPI_Allreduce(MPI_IN_PLACE, &joined, 1, MPI_INT, MPI_MIN, c.comm);
            if (!joined)
                return false;
        }
        if (k < chunks) {
            writer->write(owned.chunkStarts[k], chunk);
            written += chunk.size();
        }
    }
    if (writer)
        writer->close();
    // Every rank's records are in the file; their count, not the file's size
    // (which a shared file system may show late), says it is whole.
    const std::uint64_t all = sumOverRanks(c, written);
    if (rank == 0)
        writer->commit(all);
    return true;
}

} // namespace

void writeInInputOrder(const Communicator& c, const io::FormatRegistry& formats, const ChunkedCloud& cloud,
                       const OwnedPoints& owned, const std::vector<const std::vector<float>*>& planes,
                       const AttachValues& attach, const std::filesystem::path& output, const io::WriteOptions& write,
                       std::ostream& out)
{
    if (owned.total() > 0 && writeInPlace(c, formats, cloud, owned, planes, attach, output, write)) {
        if (c.rank() == 0)
            out << "wrote " << output.string() << '\n';
        return;
    }

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

void finishRun(const Communicator& c, Clock::time_point start, std::ostream& out)
{
    if (c.rank() == 0)
        out << std::fixed << std::setprecision(3) << std::chrono::duration<double>(Clock::now() - start).count() << " s\n"
            << std::defaultfloat;
    memoryNote("done");
    c.barrier();
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
