// SPDX-License-Identifier: GPL-3.0-or-later
#include "ChunkedCloud.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>

#include <cmath>
#include <exception>
#include <limits>
#include <numeric>

namespace scandiff::mpi {

ChunkedCloud::ChunkedCloud(const Communicator& c, const io::FormatRegistry& formats, std::filesystem::path path,
                           std::uint64_t chunkPoints, io::ReadOptions options)
    : formats_(formats), path_(std::move(path)), chunkPoints_(std::max<std::uint64_t>(chunkPoints, 1)),
      options_(std::move(options))
{
    options_.progress = nullptr;
    if (io::canReadRecordRanges(formats_, path_)) {
        try {
            records_ = io::pointRecordCount(formats_, path_);
            // The first record, in any frame, tells the attributes (sensor
            // poses, CRS) and whether the geometry has normals, which kept
            // coordinates cannot give: then, or when it tells nothing (no
            // record, or one dropped as non-finite), none are kept.
            io::ReadOptions probe = options_;
            probe.geometryOnly = true;
            if (!probe.origin)
                probe.origin = Eigen::Vector3d::Zero();
            const PointCloud first = io::readPointRecords(formats_, path_, {0, 1}, probe);
            layout_ = first.subset({});
            keepCoordinates_ = !first.empty() && !first.hasNormals();
            // Every range is read in the frame a whole read would choose.
            origin_ = chooseOrigin(c);
            options_.origin = origin_;
            return;
        } catch (const Error& e) {
            if (e.code() != ErrorCode::Unsupported)
                throw;
        }
    }
    kept_.clear();
    whole_ = io::readPointCloud(formats_, path_, options_);
    records_ = whole_->size();
    origin_ = whole_->origin();
    layout_ = whole_->subset({});
}

void ChunkedCloud::readShareTogether(const Communicator& c, const std::function<void()>& readShare) const
{
    // A failure on some ranks only (their share unreadable) must not leave
    // the others waiting in the reduction that follows: every rank learns of it.
    std::exception_ptr failure;
    try {
        readShare();
    } catch (...) {
        failure = std::current_exception();
    }
    int failed = failure ? 1 : 0;
    MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MAX, c.comm);
    if (failure)
        std::rethrow_exception(failure);
    if (failed)
        throw Error(ErrorCode::Io, path_.string() + ": another rank could not read its share of the points");
}

namespace {

//! Each axis's range of finite values as a box, +inf and -inf kept on an
//! axis without any (FormatHandler::recordBounds's box): empty when an axis
//! has none.
BoundingBox boxOfAxisRanges(const double lo[3], const double hi[3])
{
    BoundingBox box;
    box.min = Eigen::Vector3d(lo[0], lo[1], lo[2]);
    box.max = Eigen::Vector3d(hi[0], hi[1], hi[2]);
    box.empty = !(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]);
    return box;
}

} // namespace

std::optional<BoundingBox> ChunkedCloud::shareBounds(const Communicator& c)
{
    const auto ranks = static_cast<std::size_t>(c.size()), rank = static_cast<std::size_t>(c.rank());
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
        lo[a] = std::numeric_limits<double>::infinity();
        hi[a] = -lo[a];
    }
    // Whether the format reads coordinates in double depends on its header
    // alone: every rank, with chunks or without, answers alike.
    if (!keepCoordinates_ || !io::pointRecordPositions(formats_, path_, {0, 0})) {
        // Its contiguous share of the records, for the box only.
        const std::uint64_t begin = records_ * rank / ranks, end = records_ * (rank + 1) / ranks;
        return io::pointRecordBounds(formats_, path_, {begin, end - begin});
    }
    for (std::size_t k = rank; k < chunkCount(); k += ranks) {
        std::optional<std::vector<Eigen::Vector3d>> coordinates =
            io::pointRecordPositions(formats_, path_, {static_cast<std::uint64_t>(k) * chunkPoints_, chunkPoints_});
        if (!coordinates)
            throw Error(ErrorCode::Internal, path_.string() + ": the coordinates of a range could not be read in double");
        // Each axis's range of finite values, as the readers' box is.
        for (const Eigen::Vector3d& p : *coordinates)
            for (int a = 0; a < 3; ++a)
                if (std::isfinite(p[a])) {
                    lo[a] = std::min(lo[a], p[a]);
                    hi[a] = std::max(hi[a], p[a]);
                }
        kept_[k] = std::move(*coordinates);
    }
    // A rank without a chunk gives an empty box: the others' chunks cover the file.
    return boxOfAxisRanges(lo, hi);
}

Eigen::Vector3d ChunkedCloud::chooseOrigin(const Communicator& c)
{
    // The whole file's box is its shares' boxes joined axis by axis; whether
    // one is needed depends on the header alone, so every rank agrees.
    std::optional<BoundingBox> box;
    if (!options_.origin)
        readShareTogether(c, [&] { box = shareBounds(c); });
    if (!box) { // given, or fixed by the header: the first record tells it
        io::ReadOptions firstOptions = options_;
        firstOptions.geometryOnly = true;
        return io::readPointRecords(formats_, path_, {0, 1}, firstOptions).origin();
    }
    // Each axis's range, +inf/-inf where the share has none.
    double lo[3] = {box->min.x(), box->min.y(), box->min.z()}, hi[3] = {box->max.x(), box->max.y(), box->max.z()};
    MPI_Allreduce(MPI_IN_PLACE, lo, 3, MPI_DOUBLE, MPI_MIN, c.comm);
    MPI_Allreduce(MPI_IN_PLACE, hi, 3, MPI_DOUBLE, MPI_MAX, c.comm);
    return suggestOrigin(boxOfAxisRanges(lo, hi));
}

std::size_t ChunkedCloud::chunkCount() const
{
    return static_cast<std::size_t>((records_ + chunkPoints_ - 1) / chunkPoints_);
}

void ChunkedCloud::settleFieldsLeftOut(const Communicator& c)
{
    if (whole_) // the whole read has left them out already
        return;
    const std::vector<std::string> candidates = io::fieldsLeftOutWhenZero(formats_, path_);
    if (candidates.empty())
        return;
    // 1 where a field has a value other than 0 in this rank's share, or is missing.
    std::vector<int> kept(candidates.size(), 0);
    const auto ranks = static_cast<std::size_t>(c.size());
    readShareTogether(c, [&] {
        for (std::size_t k = static_cast<std::size_t>(c.rank()); k < chunkCount(); k += ranks) {
            const PointCloud chunk = read(k, false);
            for (std::size_t f = 0; f < candidates.size(); ++f) {
                const ScalarField* field = chunk.field(candidates[f]);
                if (!field || !field->isZeroEverywhere())
                    kept[f] = 1;
            }
        }
    });
    MPI_Allreduce(MPI_IN_PLACE, kept.data(), static_cast<int>(kept.size()), MPI_INT, MPI_MAX, c.comm);
    for (std::size_t f = 0; f < candidates.size(); ++f)
        if (!kept[f])
            leftOut_.push_back(candidates[f]);
}

PointCloud ChunkedCloud::fromKeptCoordinates(std::vector<Eigen::Vector3d>&& coordinates) const
{
    // As a geometry read of the range makes it: the same conversion to the
    // origin's frame, the same points dropped.
    PointCloud cloud = layout_.subset({});
    cloud.setOrigin(origin_);
    cloud.resize(coordinates.size());
    std::vector<Eigen::Vector3f>& positions = cloud.positions();
    for (std::size_t i = 0; i < coordinates.size(); ++i)
        for (int a = 0; a < 3; ++a)
            positions[i][a] = static_cast<float>(coordinates[i][a] - origin_[a]);
    coordinates = {};
    if (const std::size_t dropped = cloud.removeNonFinitePoints(); dropped > 0)
        logWarning(path_.string() + ": " + std::to_string(dropped) + " points with non-finite coordinates were skipped");
    return cloud;
}

PointCloud ChunkedCloud::read(std::size_t chunk, bool geometryOnly) const
{
    if (const auto found = kept_.find(chunk); geometryOnly && found != kept_.end()) {
        std::vector<Eigen::Vector3d> coordinates = std::move(found->second);
        kept_.erase(found);
        return fromKeptCoordinates(std::move(coordinates));
    }
    const io::RecordRange range{static_cast<std::uint64_t>(chunk) * chunkPoints_, chunkPoints_};
    if (whole_) {
        const std::uint64_t end = std::min(records_, range.first + range.count);
        std::vector<std::size_t> indices(static_cast<std::size_t>(end - std::min(end, range.first)));
        std::iota(indices.begin(), indices.end(), static_cast<std::size_t>(range.first));
        return whole_->subset(indices);
    }
    io::ReadOptions options = options_;
    options.geometryOnly = geometryOnly;
    PointCloud cloud = io::readPointRecords(formats_, path_, range, options);
    for (const std::string& name : leftOut_)
        cloud.removeField(name);
    return cloud;
}

} // namespace scandiff::mpi
