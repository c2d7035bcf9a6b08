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

//! Receives decoded records: `count` records of the layout's length, the
//! first of them record `firstPoint` of the file. Called on worker threads,
//! for several chunks at once; `records` lives only during the call.
using LazRecordsConsumer = std::function<void(std::uint64_t firstPoint, const char* records, std::size_t count)>;

//! Where the first record of the compressed points lies (stored as is, the
//! first record of the first chunk), or 0 when the file is too short for it.
std::uint64_t lazFirstRecordOffset(const LazLayout& layout, std::uint64_t pointsStart, std::size_t recordLength,
                                   std::size_t fileSize);

//! A chunk of compressed points: each is decoded on its own.
struct LazChunk
{
    std::uint64_t offset = 0; //!< of its first byte in the file
    std::uint64_t bytes = 0;  //!< 0 when unknown (no chunk table)
    std::uint64_t firstPoint = 0;
    std::uint64_t points = 0;
};

//! The chunks of the `count` records of `recordLength` bytes whose compressed
//! data starts at byte `pointsStart` of the file (`data`, `size` bytes), from
//! the chunk table: what vouches for the header's count before anything is
//! allocated for it. Throws Error(InvalidData) naming the file for a chunk
//! table that does not fit the file or the count.
std::vector<LazChunk> readLazChunks(const std::filesystem::path& path, const char* data, std::size_t size,
                                    std::uint64_t pointsStart, const LazLayout& layout, std::size_t recordLength,
                                    std::uint64_t count);

//! Decompresses the records [first, first + wanted) of `chunks` (of the file
//! `data`, `size` bytes) chunk by chunk: only the chunks holding those
//! records are decoded, each into a buffer of its worker, and handed to
//! `consume` clipped to the range. Chunks are decoded in parallel;
//! `progress(points)` is called between batches of chunks with the records
//! handed over since the last call (it may throw to cancel). Throws
//! Error(InvalidData) naming the file for a chunk that does not decode (a
//! damaged stream is given up within a thousand points or so).
void decompressLazRecords(const std::filesystem::path& path, const char* data, std::size_t size,
                          const std::vector<LazChunk>& chunks, const LazLayout& layout, std::size_t recordLength,
                          std::uint64_t first, std::uint64_t wanted, const LazRecordsConsumer& consume,
                          const std::function<void(std::size_t)>& progress);

//! The bits that are 0 in every record of a layered file, as its chunks tell
//! without decoding: a layer empty in a chunk holds an attribute that never
//! changes there, so its bits are the chunk's first record's (stored as is).
//! A mask over `recordLength` bytes, a bit set where that bit is 0 in every
//! record; every bit clear for a pointwise file or chunks that do not parse
//! (the decoder reports those). The reader leaves out the standard fields
//! that would be 0 everywhere, before allocating them.
std::vector<std::uint8_t> lazBitsZeroInEveryRecord(const char* data, std::size_t size, const std::vector<LazChunk>& chunks,
                                                   const LazLayout& layout, std::size_t recordLength);

//! Every record decompressed into one buffer (count × recordLength bytes),
//! allocated once the chunk table has vouched for the count. The readers
//! parse chunk by chunk (decompressLazRecords); this is for the tests that
//! compare every record with its uncompressed twin.
std::unique_ptr<char[]> decompressLaz(const std::filesystem::path& path, const char* data, std::size_t size,
                                      std::uint64_t pointsStart, const LazLayout& layout, std::size_t recordLength,
                                      std::uint64_t count, const std::function<void(std::size_t)>& progress);

} // namespace scandiff::io::detail
