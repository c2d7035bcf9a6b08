// SPDX-License-Identifier: GPL-3.0-or-later
#include "TiledM3c2.h"

#include "ChunkedCloud.h"
#include "Tiling.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/DistanceParameters.h>
#include <scandiff/core/distance/M3C2.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace scandiff::mpi {

namespace {

const char* const kFieldNames[] = {fields::kM3c2Distance, fields::kM3c2Uncertainty, fields::kM3c2Significant,
                                   fields::kM3c2N1,       fields::kM3c2N2,          fields::kM3c2Std1,
                                   fields::kM3c2Std2,     fields::kM3c2NormalScale};
constexpr std::size_t kFieldCount = sizeof kFieldNames / sizeof kFieldNames[0];

//! How far from a core point M3C2 looks: half the largest normal scale, and
//! the cylinder's half-diagonal.
double searchReach(const M3c2Params& params)
{
    const double normal = *std::max_element(params.normalScales.begin(), params.normalScales.end()) / 2;
    return std::max(normal, std::hypot(params.projectionScale / 2, params.maxDepth));
}

//! One epoch's points within a rank's region, read once across the ranks.
struct EpochPart
{
    std::vector<Eigen::Vector3f> positions;
    std::uint64_t inOwnTiles = 0, total = 0;
};

EpochPart collectEpoch(const Communicator& c, const ChunkedCloud& epoch, const TileGrid& grid, const RegionRouter& router,
                       const std::vector<TileKey>& ownTiles)
{
    ReceivedPoints received = distributePoints(c, epoch, {}, router);
    EpochPart part;
    part.total = received.chunkStarts.back();
    part.inOwnTiles = countInTiles(received.positions, epoch.origin(), grid, ownTiles);
    part.positions = std::move(received.positions);
    return part;
}

class M3c2Run
{
public:
    M3c2Run(const Communicator& c, const io::FormatRegistry& formats, const M3c2Job& job)
        : c_(c), formats_(formats), job_(job), params_(m3c2Settings(job.values)),
          reference_(c, formats, job.reference, job.tiling.chunkPoints, job.read),
          compared_(c, formats, job.compared, job.tiling.chunkPoints, job.read),
          cores_(c, formats, job.corePoints.empty() ? job.reference : job.corePoints, job.tiling.chunkPoints, job.read),
          grid_(job.tiling.tileSize)
    {
        if (job.values.has("core-spacing"))
            throw Error(ErrorCode::Unsupported, "scandiff-mpi m3c2: --core-spacing subsamples the whole reference, which no "
                                                "rank holds; give --core-points (a subsampled file) or none (every reference point)");
        if (job.values.has("raster-cell"))
            throw Error(ErrorCode::Unsupported, "scandiff-mpi m3c2: --raster-cell is not supported on tiles; rasterise the "
                                                "output with scandiff-cli rasterize");
        if (params_.projectionScale == 0.0 || std::find(params_.normalScales.begin(), params_.normalScales.end(), 0.0) != params_.normalScales.end())
            throw Error(ErrorCode::Unsupported, "scandiff-mpi m3c2: give --normal-scale and --projection-scale; guessing them "
                                                "(0) reads both whole epochs, which no rank holds: scandiff-cli m3c2-scales "
                                                "--reference R --compared C guesses them");
        using Kind = NormalOrientation::Kind;
        if (params_.orientation.kind == Kind::MinimumSpanningTree || params_.orientation.kind == Kind::None)
            throw Error(ErrorCode::InvalidArgument, "m3c2: orient the normals by a direction, the sensor or the centroid");
        referenceLayout_ = reference_.layout().subset({});
        reach_ = searchReach(params_);
        if (job.tiling.halo && *job.tiling.halo < reach_)
        {
            std::ostringstream message;
            message << "--halo " << *job.tiling.halo << " is shorter than M3C2's search (" << reach_
                    << " m: half the largest normal scale, or the cylinder's half-diagonal sqrt((d/2)^2 + H^2)); leave it "
                       "out or give at least that";
            throw Error(ErrorCode::InvalidArgument, message.str());
        }
        halo_ = job.tiling.halo ? *job.tiling.halo : reach_;
        checkChunkedOutput(formats, job.output);
    }

    void run(std::ostream& out)
    {
        const auto start = Clock::now();
        cores_.settleFieldsLeftOut(c_);
        owned_ = collectOwnedPoints(c_, cores_, grid_);
        report_.tiles = owned_.tiles.size();
        report_.points = owned_.index.size();
        orientTowardsTheWholeCentroid();
        // Every point within the search reach is held, whatever the rounding:
        // the halo grows by the margin of the largest coordinate of a core point.
        const Eigen::Vector3d shift = cores_.origin() - reference_.origin();
        double magnitude = 0;
        for (const Eigen::Vector3f& p : owned_.positions)
            magnitude = std::max(magnitude, (shift + p.cast<double>()).cwiseAbs().maxCoeff());
        MPI_Allreduce(MPI_IN_PLACE, &magnitude, 1, MPI_DOUBLE, MPI_MAX, c_.comm);
        const RegionRouter router(grid_, owned_.owners, c_.size(), halo_ + roundingMargin(magnitude + reach_, reach_));
        EpochPart reference = collectEpoch(c_, reference_, grid_, router, owned_.tiles);
        EpochPart compared = collectEpoch(c_, compared_, grid_, router, owned_.tiles);
        if (reference.total == 0 || compared.total == 0)
            throw Error(ErrorCode::InvalidData, std::string("m3c2: the ") + (reference.total == 0 ? "reference" : "compared") +
                                                    " cloud '" +
                                                    (reference.total == 0 ? job_.reference : job_.compared).stem().string() +
                                                    "' is empty");
        report_.held = reference.positions.size() + compared.positions.size();
        report_.heldInTiles = reference.inOwnTiles + compared.inOwnTiles;
        memoryNote("epochs collected");
        compute(std::move(reference.positions), std::move(compared.positions));
        memoryNote("computed");
        report_.seconds = std::chrono::duration<double>(Clock::now() - start).count();

        std::uint64_t counts[4] = {owned_.total(), measured_, significant_, withoutNormal_};
        MPI_Allreduce(MPI_IN_PLACE, counts + 1, 3, MPI_UINT64_T, MPI_SUM, c_.comm);
        if (c_.rank() == 0)
            out << "m3c2: M3C2 at " << counts[0] << " core points: " << counts[1] << " measured, " << counts[2]
                << " significant changes" << (counts[3] ? ", " + std::to_string(counts[3]) + " without a normal" : std::string())
                << '\n';
        reportRanks(c_, report_, {"m3c2", "core points", "points of both epochs"}, grid_.size(), halo_,
                    reference_.streamed() && compared_.streamed() && cores_.streamed(), out);
        if (!job_.output.empty())
            writeOutput(out);
        finishRun(c_, start, out);
    }

private:
    //! The centroid rule looks at every core point: rank 0 sums them in input
    //! order, as m3c2 does on the whole set (in the reference's frame, through
    //! float), and every rank orients by that sum.
    void orientTowardsTheWholeCentroid()
    {
        using Kind = NormalOrientation::Kind;
        if (params_.orientation.kind != Kind::AwayFromCentroid && params_.orientation.kind != Kind::TowardsCentroid)
            return;
        double centroid[3] = {0, 0, 0};
        if (c_.rank() == 0) {
            const Eigen::Vector3d shift = cores_.origin() - reference_.origin();
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            std::uint64_t count = 0;
            for (std::size_t k = 0; k < cores_.chunkCount(); ++k) {
                const PointCloud chunk = cores_.read(k, true);
                for (const Eigen::Vector3f& p : chunk.positions())
                    sum += (p.cast<double>() + shift).cast<float>().cast<double>();
                count += chunk.size();
            }
            sum /= static_cast<double>(count);
            std::copy(sum.data(), sum.data() + 3, centroid);
        }
        MPI_Bcast(centroid, 3, MPI_DOUBLE, 0, c_.comm);
        params_.orientation.centroid = Eigen::Vector3d(centroid[0], centroid[1], centroid[2]);
    }

    void compute(std::vector<Eigen::Vector3f>&& referencePositions, std::vector<Eigen::Vector3f>&& comparedPositions)
    {
        const std::size_t n = owned_.positions.size();
        for (std::vector<float>& plane : planes_)
            plane.assign(n, std::numeric_limits<float>::quiet_NaN());
        if (n == 0)
            return;
        PointCloud reference = makeCloud(reference_.origin(), std::move(referencePositions), {}, referenceLayout_.sensors());
        reference.setCrsWkt(referenceLayout_.crsWkt());
        const PointCloud compared = makeCloud(compared_.origin(), std::move(comparedPositions));
        const PointCloud cores = makeCloud(cores_.origin(), std::move(owned_.positions));
        const M3c2Result result = m3c2OnParts(reference, compared, cores, params_);
        measured_ = result.measuredCount;
        significant_ = result.significantCount;
        withoutNormal_ = result.withoutNormal;
        const auto& normals = result.corePoints.normals();
        for (std::size_t j = 0; j < n; ++j)
            for (int a = 0; a < 3; ++a)
                planes_[static_cast<std::size_t>(a)][j] = normals[j][a];
        for (std::size_t f = 0; f < kFieldCount; ++f)
            planes_[3 + f] = result.corePoints.field(kFieldNames[f])->values();
    }

    //! Rank 0 writes the core points with their normals and fields in input
    //! order, as m3c2 gives them (every field of the core points' file kept).
    void writeOutput(std::ostream& out)
    {
        std::vector<const std::vector<float>*> planes;
        for (const std::vector<float>& plane : planes_)
            planes.push_back(&plane);
        const std::string crs = referenceLayout_.crsWkt();
        writeInInputOrder(
            c_, formats_, cores_, owned_, planes,
            [&crs](PointCloud& chunk, std::vector<std::vector<float>>&& values) {
                const std::size_t n = chunk.size();
                if (chunk.crsWkt().empty())
                    chunk.setCrsWkt(crs);
                std::vector<Eigen::Vector3f>& normals = chunk.enableNormals();
                for (std::size_t j = 0; j < n && values[0].size() == n; ++j)
                    normals[j] = Eigen::Vector3f(values[0][j], values[1][j], values[2][j]);
                for (std::size_t f = 0; f < kFieldCount; ++f) {
                    ScalarField field(kFieldNames[f], n);
                    if (values[3 + f].size() == n)
                        field.values() = std::move(values[3 + f]);
                    chunk.addField(std::move(field));
                }
            },
            job_.output, job_.write, out);
    }

    const Communicator& c_;
    const io::FormatRegistry& formats_;
    const M3c2Job& job_;
    M3c2Params params_;
    ChunkedCloud reference_, compared_, cores_;
    TileGrid grid_;
    PointCloud referenceLayout_;
    double reach_ = 0, halo_ = 0;
    OwnedPoints owned_;
    std::vector<float> planes_[3 + kFieldCount]; //!< normal x, y, z, then the fields, per owned core point
    std::uint64_t measured_ = 0, significant_ = 0, withoutNormal_ = 0;
    RankReport report_;
};

} // namespace

void runTiledM3c2(const Communicator& c, const io::FormatRegistry& formats, const M3c2Job& job, std::ostream& out)
{
    checkTilingOptions(job.tiling);
    M3c2Run run(c, formats, job);
    runCollectively(c, [&] { run.run(out); });
}

} // namespace scandiff::mpi
