// SPDX-License-Identifier: GPL-3.0-or-later
#include "ValueFile.h"

#include <scandiff/core/Error.h>

#include <limits>

namespace scandiff::mpi {

namespace {

void check(int status, const std::filesystem::path& file, const char* what)
{
    if (status == MPI_SUCCESS)
        return;
    char message[MPI_MAX_ERROR_STRING];
    int length = 0;
    MPI_Error_string(status, message, &length);
    throw Error(ErrorCode::Io, file.string() + ": " + what + ": " + std::string(message, static_cast<std::size_t>(length)));
}

} // namespace

void writeValuePlanes(const Communicator& c, const std::filesystem::path& file, std::uint64_t total,
                      const std::vector<std::uint64_t>& indices, const std::vector<std::vector<float>>& planes)
{
    if (indices.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
        throw Error(ErrorCode::Unsupported, "more than 2^31 points on one rank: run on more ranks");
    MPI_File handle;
    check(MPI_File_open(c.comm, file.c_str(), MPI_MODE_CREATE | MPI_MODE_WRONLY, MPI_INFO_NULL, &handle), file, "opening");
    MPI_File_set_errhandler(handle, MPI_ERRORS_RETURN);
    check(MPI_File_set_size(handle, static_cast<MPI_Offset>(total * planes.size() * sizeof(float))), file, "sizing");
    std::vector<MPI_Aint> displacements(indices.size());
    for (std::size_t f = 0; f < planes.size(); ++f) {
        for (std::size_t j = 0; j < indices.size(); ++j)
            displacements[j] = static_cast<MPI_Aint>((f * total + indices[j]) * sizeof(float));
        MPI_Datatype scattered;
        MPI_Type_create_hindexed_block(static_cast<int>(indices.size()), 1, displacements.data(), MPI_FLOAT, &scattered);
        MPI_Type_commit(&scattered);
        check(MPI_File_set_view(handle, 0, MPI_FLOAT, scattered, "native", MPI_INFO_NULL), file, "setting the view");
        const int status = MPI_File_write_all(handle, planes[f].data(), static_cast<int>(indices.size()), MPI_FLOAT,
                                              MPI_STATUS_IGNORE);
        MPI_Type_free(&scattered);
        check(status, file, "writing");
    }
    check(MPI_File_close(&handle), file, "closing");
}

ValuePlaneReader::ValuePlaneReader(const std::filesystem::path& file, std::uint64_t total)
    : file_(file), in_(file, std::ios::binary), total_(total)
{
    if (!in_)
        throw Error(ErrorCode::Io, file.string() + ": cannot be opened");
}

void ValuePlaneReader::read(std::size_t plane, std::uint64_t first, std::size_t count, float* out)
{
    in_.seekg(static_cast<std::streamoff>((plane * total_ + first) * sizeof(float)));
    in_.read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(count * sizeof(float)));
    if (!in_)
        throw Error(ErrorCode::Io, file_.string() + ": ends before value " + std::to_string(first + count) + " of plane " +
                                       std::to_string(plane));
}

} // namespace scandiff::mpi
