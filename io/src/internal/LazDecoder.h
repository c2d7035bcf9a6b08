// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! LAZ: LAS point records compressed by LASzip, decompressed back into the
//! uncompressed records the LAS reader parses (internal to io/).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <vector>

namespace scandiff::io::detail {

//! One item of a LASzip record description: what part of a point record it
//! compresses (type), its size in bytes, and the version of its coder.
struct LazItem
{
    std::uint16_t type = 0;
    std::uint16_t size = 0;
    std::uint16_t version = 0;
};

//! The LASzip record (user "laszip encoded", record 22204) of a file.
struct LazLayout
{
    //! 1: pointwise, one stream; 2: pointwise in chunks; 3: layered in chunks (LAS 1.4 formats).
    std::uint16_t compressor = 0;
    //! Points per chunk; UINT32_MAX: each chunk's count is in the chunk table.
    std::uint32_t chunkSize = 0;
    std::vector<LazItem> items;
};

constexpr const char* kLaszipUserId = "laszip encoded";
constexpr std::uint16_t kLaszipRecordId = 22204;

//! Parses the LASzip record's payload and checks it against the header's
//! record length. Throws Error(InvalidData) for a record that contradicts
//! itself or the header, Error(Unsupported) for a coder this reader does not
//! have, each naming the file.
LazLayout parseLazLayout(const std::filesystem::path& path, const char* payload, std::size_t length, std::size_t recordLength);

//! Decompresses the `count` records of `recordLength` bytes whose compressed
//! data starts at byte `pointsStart` of the file (`data`, `size` bytes), into
//! memory allocated once the chunk table has vouched for the count. Chunks are
//! decoded in parallel; `progress(points)` is called between batches of
//! chunks with the points decoded since the last call (it may throw to
//! cancel). Throws Error(InvalidData) naming the file for a chunk table or
//! chunk that does not fit the file or the header's count, or that does not
//! decode (a damaged stream is given up within a thousand points or so).
std::unique_ptr<char[]> decompressLaz(const std::filesystem::path& path, const char* data, std::size_t size,
                                      std::uint64_t pointsStart, const LazLayout& layout, std::size_t recordLength,
                                      std::uint64_t count, const std::function<void(std::size_t)>& progress);

} // namespace scandiff::io::detail
