// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/io/AtomicFile.h>

#include <scandiff/core/Error.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <unistd.h>

namespace scandiff::io {

namespace fs = std::filesystem;

AtomicFile::AtomicFile(fs::path destination) : destination_(std::move(destination))
{
    const fs::path folder = destination_.has_parent_path() ? destination_.parent_path() : fs::path(".");
    std::error_code ec;
    if (!fs::is_directory(folder, ec))
        throw Error(ErrorCode::Io, destination_.string() + ": cannot write: folder '" + folder.string() + "' does not exist");
    if (fs::is_directory(destination_, ec))
        throw Error(ErrorCode::Io, destination_.string() + ": cannot write: it is a folder");
    static std::atomic<unsigned> counter{0};
    // A leading dot hides the partial file; pid + counter keep concurrent writers apart.
    temp_ = folder / ("." + destination_.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                      std::to_string(counter++));
}

AtomicFile::~AtomicFile()
{
    if (!committed_) {
        stream_.reset();
        std::error_code ec;
        fs::remove(temp_, ec);
    }
}

std::ofstream& AtomicFile::stream()
{
    if (!stream_) {
        stream_ = std::make_unique<std::ofstream>(temp_, std::ios::binary | std::ios::trunc);
        if (!*stream_)
            throw Error(ErrorCode::Io, destination_.string() + ": cannot create temporary file '" + temp_.string() +
                                           "': " + std::strerror(errno));
    }
    return *stream_;
}

void AtomicFile::commit()
{
    if (stream_) {
        stream_->flush();
        const bool ok = static_cast<bool>(*stream_);
        stream_->close();
        if (!ok || stream_->fail())
            throw Error(ErrorCode::Io, destination_.string() + ": write failed (disk full?)");
        stream_.reset();
    }
    std::error_code ec;
    if (!fs::exists(temp_, ec))
        throw Error(ErrorCode::Internal, destination_.string() + ": nothing was written to the temporary file");
    fs::rename(temp_, destination_, ec);
    if (ec)
        throw Error(ErrorCode::Io, destination_.string() + ": cannot rename the temporary file into place: " + ec.message());
    committed_ = true;
}

} // namespace scandiff::io
