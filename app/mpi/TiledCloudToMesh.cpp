// SPDX-License-Identifier: GPL-3.0-or-later
#include "TiledCloudToMesh.h"

#include "ChunkedCloud.h"
#include "Tiling.h"

#include "CliSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToMesh.h>
#include <scandiff/core/distance/DistanceParameters.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace scandiff::mpi {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

//! The mesh as scandiff-cli reads it, with the errors cloudToMesh would give
//! on the whole of it (a rank's part might not hold the faulty triangle).
Mesh readCheckedMesh(const io::FormatRegistry& formats, const std::filesystem::path& path)
{
    Mesh mesh = io::readMesh(formats, path);
    mesh.checkConsistency();
    if (mesh.triangles.empty())
        throw Error(ErrorCode::InvalidData, "cloud-to-mesh: the reference mesh '" + mesh.name + "' has no triangle");
    const auto& vertices = mesh.vertices.positions();
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        for (const std::uint32_t v : mesh.triangles[t])
            if (!vertices[v].allFinite())
                throw Error(ErrorCode::InvalidData, "cloud-to-mesh: triangle " + std::to_string(t) + " of the reference mesh '" +
                                                        mesh.name + "' has a vertex with a non-finite coordinate");
    return mesh;
}

//! A triangle's XY bounding box in world coordinates.
std::pair<Eigen::Vector2d, Eigen::Vector2d> worldBox(const Mesh& mesh, const Triangle& triangle)
{
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(kInfinity), hi = -lo;
    for (const std::uint32_t v : triangle) {
        const Eigen::Vector3d p = mesh.vertices.globalPosition(v);
        lo = lo.cwiseMin(p.head<2>());
        hi = hi.cwiseMax(p.head<2>());
    }
    return {lo, hi};
}

//! The triangles `keep` accepts, in their order, with the vertices they use
//! (same float coordinates, same origin): cloudToMesh gives every point whose
//! nearest triangles are among them the distance and the sign it gives on the
//! whole mesh, ties between triangles broken by their order as there.
template <class Keep>
Mesh partOf(const Mesh& whole, Keep&& keep)
{
    Mesh part;
    part.name = whole.name;
    part.vertices.setOrigin(whole.vertices.origin());
    std::vector<std::uint32_t> renumbered(whole.vertices.size(), std::numeric_limits<std::uint32_t>::max());
    std::vector<Eigen::Vector3f> vertices;
    for (const Triangle& triangle : whole.triangles) {
        if (!keep(triangle))
            continue;
        Triangle t;
        for (std::size_t k = 0; k < 3; ++k) {
            std::uint32_t& mapped = renumbered[triangle[k]];
            if (mapped == std::numeric_limits<std::uint32_t>::max()) {
                mapped = static_cast<std::uint32_t>(vertices.size());
                vertices.push_back(whole.vertices.positions()[triangle[k]]);
            }
            t[k] = mapped;
        }
        part.triangles.push_back(t);
    }
    part.vertices.resize(vertices.size());
    part.vertices.positions() = std::move(vertices);
    return part;
}

class CloudToMeshRun
{
public:
    CloudToMeshRun(const Communicator& c, const io::FormatRegistry& formats, const CloudToMeshJob& job)
        : c_(c), formats_(formats), job_(job),
          // scandiff-cli's order: the settings, the mesh, the cloud (so its errors come first alike).
          params_(cloudToMeshSettings(job.values)), mesh_(readCheckedMesh(formats, job.reference)),
          compared_(c, formats, job.compared, job.tiling.chunkPoints, job.read), grid_(job.tiling.tileSize)
    {
        halo_ = job.tiling.halo ? *job.tiling.halo : params_.maxDistance ? *params_.maxDistance : job.tiling.tileSize / 10;
        checkChunkedOutput(formats, job.output);
    }

    void run(std::ostream& out)
    {
        const auto start = Clock::now();
        compared_.settleFieldsLeftOut(c_);
        owned_ = collectOwnedPoints(c_, compared_, grid_);
        if (owned_.total() == 0)
            throw Error(ErrorCode::InvalidData, "cloud-to-mesh: the compared cloud '" + job_.compared.stem().string() + "' is empty");
        report_.tiles = owned_.tiles.size();
        report_.points = owned_.index.size();
        const HaloRegion region(grid_, owned_.tiles, halo_);
        Mesh part = partOf(mesh_, [&](const Triangle& t) {
            const auto [lo, hi] = worldBox(mesh_, t);
            return region.intersects(lo, hi);
        });
        report_.held = part.triangles.size();
        report_.heldInTiles = countInOwnTiles(part);
        mesh_ = Mesh(); // read again only if a point needs a wider search
        memoryNote("mesh part cut");
        computeOwnTiles(part);
        memoryNote("computed");
        widen();
        report_.seconds = std::chrono::duration<double>(Clock::now() - start).count();

        const DistanceStatistics statistics = statisticsOverRanks(c_, distance_);
        comparedCloud_ = PointCloud();
        if (c_.rank() == 0)
            cli::printStatistics(out, std::string("c2m ") + (params_.signedDistances ? "signed" : "unsigned") + " (compared -> mesh)",
                                 statistics);
        reportRanks(c_, report_, {"c2m", "compared points", "triangles"}, grid_.size(), halo_, compared_.streamed(), out);
        if (!job_.output.empty())
            writeInInputOrder(
                c_, formats_, compared_, owned_, {&distance_},
                [](PointCloud& chunk, std::vector<std::vector<float>>&& values) {
                    ScalarField distance("c2m_distance", chunk.size());
                    if (values[0].size() == chunk.size())
                        distance.values() = std::move(values[0]);
                    chunk.addField(std::move(distance));
                },
                job_.output, job_.write, out);
        finishRun(c_, start, out);
    }

private:
    //! Triangles whose box lies within the rank's own tiles (for the halo overhead).
    std::uint64_t countInOwnTiles(const Mesh& part) const
    {
        const HaloRegion own(grid_, owned_.tiles, 0.0);
        std::uint64_t count = 0;
        for (const Triangle& t : part.triangles) {
            const auto [lo, hi] = worldBox(part, t);
            count += own.owns(grid_.tileOf(lo.x(), lo.y())) && own.owns(grid_.tileOf(hi.x(), hi.y()));
        }
        return count;
    }

    //! How far around a point its value looked: its distance, or the search's bound.
    double reachOf(float value) const
    {
        if (std::isnan(value))
            return params_.maxDistance ? *params_.maxDistance : kInfinity;
        return std::abs(static_cast<double>(value));
    }

    double margin(std::size_t j, double reach) const
    {
        return roundingMargin(static_cast<double>(comparedCloud_.positions()[j].cwiseAbs().maxCoeff()), reach);
    }

    //! Distances of this rank's points on its part of the mesh; a point whose
    //! distance reaches out of its tile's halo is left for widen().
    void computeOwnTiles(const Mesh& part)
    {
        const std::size_t n = owned_.positions.size();
        comparedCloud_ = makeCloud(compared_.origin(), std::move(owned_.positions));
        distance_.assign(n, std::numeric_limits<float>::quiet_NaN());
        if (n == 0)
            return;
        if (part.triangles.empty()) {
            for (std::size_t j = 0; j < n; ++j)
                pending_.push_back({j, kInfinity});
            return;
        }
        const CloudToMeshResult result = cloudToMesh(comparedCloud_, part, params_);
        for (std::size_t j = 0; j < n; ++j) {
            const Eigen::Vector3d p = comparedCloud_.globalPosition(j);
            const double depth = grid_.depthInGrownTile(grid_.tileOf(p.x(), p.y()), halo_, p.x(), p.y());
            const float value = result.distance.values()[j];
            const double reach = reachOf(value);
            if (reach + margin(j, reach) <= depth)
                distance_[j] = value;
            else
                pending_.push_back({j, reach});
        }
    }

    //! The points whose nearest triangle may lie outside the halo, on every
    //! triangle within their distance on the part (never shorter than the
    //! whole mesh's): one pass settles them.
    void widen()
    {
        report_.widened = pending_.size();
        if (pending_.empty())
            return;
        report_.widenings = 1;
        const Mesh whole = readCheckedMesh(formats_, job_.reference);
        std::vector<Eigen::Vector2d> centres;
        std::vector<double> radii;
        for (Pending& w : pending_) {
            w.radius += margin(w.index, w.radius);
            centres.push_back(comparedCloud_.globalPosition(w.index).head<2>());
            radii.push_back(w.radius);
        }
        const ReachIndex reach(std::move(centres), std::move(radii), grid_.size());
        const Mesh part = partOf(whole, [&](const Triangle& t) {
            const auto [lo, hi] = worldBox(whole, t);
            return reach.touches(lo, hi);
        });
        std::vector<Eigen::Vector3f> queries;
        for (const Pending& w : pending_)
            queries.push_back(comparedCloud_.positions()[w.index]);
        const PointCloud compared = makeCloud(compared_.origin(), std::move(queries));
        if (part.triangles.empty()) { // every triangle beyond the maximum distance: what cloudToMesh gives there
            const float beyond = params_.clampBeyondMax ? static_cast<float>(*params_.maxDistance)
                                                        : std::numeric_limits<float>::quiet_NaN();
            for (const Pending& w : pending_)
                distance_[w.index] = beyond;
            pending_.clear();
            return;
        }
        const CloudToMeshResult result = cloudToMesh(compared, part, params_);
        for (std::size_t m = 0; m < pending_.size(); ++m)
            distance_[pending_[m].index] = result.distance.values()[m];
        pending_.clear();
    }

    struct Pending
    {
        std::size_t index; //!< in this rank's compared points
        double radius;     //!< the reach to fetch (+inf: unknown)
    };

    const Communicator& c_;
    const io::FormatRegistry& formats_;
    const CloudToMeshJob& job_;
    CloudToMeshParams params_;
    Mesh mesh_;
    ChunkedCloud compared_;
    TileGrid grid_;
    double halo_ = 0;
    OwnedPoints owned_;
    PointCloud comparedCloud_;
    std::vector<float> distance_;
    std::vector<Pending> pending_;
    RankReport report_;
};

} // namespace

void runTiledCloudToMesh(const Communicator& c, const io::FormatRegistry& formats, const CloudToMeshJob& job, std::ostream& out)
{
    checkTilingOptions(job.tiling);
    CloudToMeshRun run(c, formats, job);
    runCollectively(c, [&] { run.run(out); });
}

} // namespace scandiff::mpi
