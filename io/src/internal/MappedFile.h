// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Read-only memory map of a whole file (internal to io/). Readers parse straight
//! from the mapping: no copy of a 300 MB scan into a buffer first.

#include <cstddef>
#include <filesystem>
#include <string_view>

namespace scandiff::io::detail {

class MappedFile
{
public:
    //! Throws Error(Io) "<file>: cannot open: <reason>" when missing or unreadable.
    explicit MappedFile(const std::filesystem::path& path);
    ~MappedFile();
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;

    const char* data() const { return data_; }
    std::size_t size() const { return size_; }
    std::string_view view() const { return {data_, size_}; }
    const std::filesystem::path& path() const { return path_; }

    //! Tells the kernel the bytes [begin, end) were consumed: their pages leave
    //! this process's memory (they stay in the page cache, and a later read of
    //! them simply maps them again). Keeps the peak memory of reading a 400 MB
    //! file near the size of the cloud instead of cloud + file.
    static void releaseConsumed(const char* begin, const char* end);

private:
    std::filesystem::path path_;
    const char* data_ = nullptr;
    std::size_t size_ = 0;
};

} // namespace scandiff::io::detail
