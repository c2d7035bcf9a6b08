// SPDX-License-Identifier: GPL-3.0-or-later
#include "ChunkedCloud.h"

#include <scandiff/core/Error.h>

#include <numeric>

namespace scandiff::mpi {

ChunkedCloud::ChunkedCloud(const io::FormatRegistry& formats, std::filesystem::path path, std::uint64_t chunkPoints,
                           io::ReadOptions options)
    : formats_(formats), path_(std::move(path)), chunkPoints_(std::max<std::uint64_t>(chunkPoints, 1)),
      options_(std::move(options))
{
    options_.progress = nullptr;
    if (io::canReadRecordRanges(formats_, path_)) {
        try {
            records_ = io::pointRecordCount(formats_, path_);
            // The first range fixes the origin a whole read would choose; every
            // later range is read in that frame.
            io::ReadOptions firstOptions = options_;
            firstOptions.geometryOnly = true;
            const PointCloud first = io::readPointRecords(formats_, path_, {0, 1}, firstOptions);
            origin_ = first.origin();
            options_.origin = origin_;
            return;
        } catch (const Error& e) {
            if (e.code() != ErrorCode::Unsupported)
                throw;
        }
    }
    whole_ = io::readPointCloud(formats_, path_, options_);
    records_ = whole_->size();
    origin_ = whole_->origin();
}

std::size_t ChunkedCloud::chunkCount() const
{
    return static_cast<std::size_t>((records_ + chunkPoints_ - 1) / chunkPoints_);
}

PointCloud ChunkedCloud::read(std::size_t chunk, bool geometryOnly) const
{
    const io::RecordRange range{static_cast<std::uint64_t>(chunk) * chunkPoints_, chunkPoints_};
    if (whole_) {
        const std::uint64_t end = std::min(records_, range.first + range.count);
        std::vector<std::size_t> indices(static_cast<std::size_t>(end - std::min(end, range.first)));
        std::iota(indices.begin(), indices.end(), static_cast<std::size_t>(range.first));
        return whole_->subset(indices);
    }
    io::ReadOptions options = options_;
    options.geometryOnly = geometryOnly;
    return io::readPointRecords(formats_, path_, range, options);
}

} // namespace scandiff::mpi
