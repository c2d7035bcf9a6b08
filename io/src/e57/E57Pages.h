// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The paged binary layer of an E57 file (ASTM E2807 §8): a 48-byte header,
//! then pages of `pageSize` bytes whose last 4 are the CRC-32C of the rest,
//! stored big-endian. Offsets in the XML are physical (in the file); lengths
//! are logical (the bytes without the checksums). Every page is checked the
//! first time it is read: a bad checksum is an error naming the page.

#include "internal/MappedFile.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace scandiff::io::e57 {

//! CRC-32C (Castagnoli), as E57 pages carry it; hardware-assisted when the CPU has SSE 4.2.
std::uint32_t crc32c(const void* data, std::size_t length);

struct FileHeader
{
    std::uint32_t versionMajor = 0, versionMinor = 0;
    std::uint64_t physicalLength = 0;
    std::uint64_t xmlPhysicalOffset = 0;
    std::uint64_t xmlLogicalLength = 0;
    std::uint64_t pageSize = 0;
};

class PagedReader
{
public:
    //! Maps the file and checks its header against the file's length.
    explicit PagedReader(const std::filesystem::path& path);

    const FileHeader& header() const { return header_; }
    const std::filesystem::path& path() const { return file_.path(); }

    //! Copies `length` logical bytes starting at physical offset `physical`.
    //! Throws Error(InvalidData) naming the file when they leave it or a page's checksum is wrong.
    void read(std::uint64_t physical, void* out, std::uint64_t length);
    std::vector<char> read(std::uint64_t physical, std::uint64_t length);

    //! The physical offset `logicalBytes` further on than `physical`.
    std::uint64_t advance(std::uint64_t physical, std::uint64_t logicalBytes) const;
    std::uint64_t logicalLength() const { return pageCount_ * (header_.pageSize - 4); }
    //! Logical offset of a physical one (which must not point into a checksum).
    std::uint64_t toLogical(std::uint64_t physical) const;
    std::uint64_t toPhysical(std::uint64_t logical) const;

    [[noreturn]] void fail(const std::string& what) const;

private:
    void checkPage(std::uint64_t page);

    detail::MappedFile file_;
    FileHeader header_;
    std::uint64_t pageCount_ = 0;
    std::vector<bool> checked_;
};

} // namespace scandiff::io::e57
