// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A point file read chunk by chunk, so that a rank holds one chunk of it at a
//! time plus what it keeps. Formats that can read a range of records (binary
//! PLY, LAS) are streamed; any other is read whole once and served from memory
//! (said by streamed(), and in the run's report).

#include "Mpi.h"

#include <scandiff/core/PointCloud.h>
#include <scandiff/io/FileIO.h>

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace scandiff::mpi {

class ChunkedCloud
{
public:
    //! Collective. Reads the header and, when the origin must be chosen from
    //! every point's coordinates, their box (each rank a share of the records).
    //! Throws Error like the readers, on every rank alike.
    ChunkedCloud(const Communicator& c, const io::FormatRegistry& formats, std::filesystem::path path,
                 std::uint64_t chunkPoints, io::ReadOptions options);

    const std::filesystem::path& path() const { return path_; }
    std::size_t chunkCount() const;
    //! The records of the file (points, non-finite ones included).
    std::uint64_t recordCount() const { return records_; }
    //! The points of one chunk, in file order, in the frame a whole read gives
    //! (same origin); non-finite points dropped as a whole read drops them.
    //! Geometry only: positions and normals. A chunk whose coordinates the
    //! origin's pass kept is served from them the first time, and they go.
    PointCloud read(std::size_t chunk, bool geometryOnly) const;
    //! The file's attributes without its points (sensor poses, CRS), from
    //! its first record.
    const PointCloud& layout() const { return layout_; }
    const Eigen::Vector3d& origin() const { return origin_; }
    //! Collective, for the cloud whose attributes go to the output. Finds the
    //! fields a whole read leaves out because they are 0 in the whole file
    //! (LAS's standard attributes), which every range keeps: each rank reads
    //! its share of the chunks, the ranks agree, and read() leaves them out
    //! too, so that the output has scandiff-cli's fields.
    void settleFieldsLeftOut(const Communicator& c);
    bool streamed() const { return !whole_; }

private:
    Eigen::Vector3d chooseOrigin(const Communicator& c);
    //! This rank's part of the box of the whole file, std::nullopt where the
    //! header fixes the origin. Where the format gives the coordinates in
    //! double and the geometry has no normals, this rank's chunks are read so
    //! and kept for their first geometry read (one thread: read() is not
    //! safe to call from several).
    std::optional<BoundingBox> shareBounds(const Communicator& c);
    PointCloud fromKeptCoordinates(std::vector<Eigen::Vector3d>&& coordinates) const;
    //! Collective: runs `readShare` (this rank's share of the file), then
    //! rethrows its failure on this rank and fails the others too.
    void readShareTogether(const Communicator& c, const std::function<void()>& readShare) const;

    const io::FormatRegistry& formats_;
    std::filesystem::path path_;
    std::uint64_t chunkPoints_;
    io::ReadOptions options_;
    std::uint64_t records_ = 0;
    Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
    std::optional<PointCloud> whole_;
    std::vector<std::string> leftOut_; //!< fields read() removes (settleFieldsLeftOut)
    PointCloud layout_;
    bool keepCoordinates_ = false; //!< the file's geometry is positions only (see the constructor)
    //! Per chunk of this rank, its coordinates as the file holds them, read
    //! while choosing the origin: the geometry pass that follows needs them
    //! and reading the chunk again cost a third of the time before counting.
    mutable std::map<std::size_t, std::vector<Eigen::Vector3d>> kept_;
};

} // namespace scandiff::mpi
