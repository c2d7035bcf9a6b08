// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Write-to-temporary-then-rename. A writer opens an AtomicFile on the final path,
//! writes to tempPath() (or stream()), and calls commit(), which flushes and
//! renames over the destination. If commit() is never reached (an exception,
//! cancellation), the temporary file is removed and the destination is untouched.

#include <filesystem>
#include <fstream>
#include <memory>

namespace scandiff::io {

class AtomicFile
{
public:
    //! Throws Error(Io) if the destination's folder does not exist.
    explicit AtomicFile(std::filesystem::path destination);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    const std::filesystem::path& destination() const { return destination_; }
    //! The temporary file, in the destination's folder (same file system).
    const std::filesystem::path& tempPath() const { return temp_; }
    //! A binary output stream on tempPath(), opened on first use.
    std::ofstream& stream();
    //! Flushes, checks for write errors and renames into place. Throws Error(Io).
    void commit();

private:
    std::filesystem::path destination_;
    std::filesystem::path temp_;
    std::unique_ptr<std::ofstream> stream_;
    bool committed_ = false;
};

} // namespace scandiff::io
