// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What the LAS reader (LasFormat.cpp) and writer (LasWriter.cpp) share
//! (internal to io/): the byte layout of the public header block, the
//! variable length records and the Extra Bytes descriptors, after the ASPRS
//! LAS 1.4 specification, R15 ("LAS 1.4 R15"), and the writer's entry point.

#include <scandiff/core/PointCloud.h>
#include <scandiff/io/FileIO.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>

// LAS is little endian (LAS 1.4 R15, "LAS Format Definition"): fields are loaded with
// memcpy, which is only right on a little-endian host.
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the LAS reader and writer assume a little-endian host"
#endif

namespace scandiff::io::detail::las {

// Points decoded between two progress steps: large enough that the ticker costs
// nothing, small enough for a responsive Cancel.
constexpr std::size_t kChunkPoints = 1u << 16;

template <class T>
T load(const char* p)
{
    T value;
    std::memcpy(&value, p, sizeof value);
    return value;
}

template <class T>
void store(char* p, T value)
{
    std::memcpy(p, &value, sizeof value);
}

// ---------------------------------------------------------------------------
// Public Header Block (LAS 1.4 R15). Offsets are the same in every version:
// 1.0-1.2 have 227 bytes, 1.3 appends the waveform start (235 bytes), 1.4 the
// EVLR fields and the 64-bit counts (375 bytes).

constexpr std::size_t kHeaderSize12 = 227;
constexpr std::size_t kHeaderSize14 = 375;

namespace hdr {
constexpr std::size_t globalEncoding = 6;
constexpr std::size_t versionMajor = 24;
constexpr std::size_t versionMinor = 25;
constexpr std::size_t systemIdentifier = 26;
constexpr std::size_t generatingSoftware = 58;
constexpr std::size_t creationDay = 90;
constexpr std::size_t creationYear = 92;
constexpr std::size_t headerSize = 94;
constexpr std::size_t offsetToPoints = 96;
constexpr std::size_t vlrCount = 100;
constexpr std::size_t pointFormat = 104;
constexpr std::size_t recordLength = 105;
constexpr std::size_t legacyPointCount = 107;
constexpr std::size_t scale = 131;      // x, y, z doubles
constexpr std::size_t offset = 155;     // x, y, z doubles
constexpr std::size_t bounds = 179;     // max x, min x, max y, min y, max z, min z
constexpr std::size_t evlrStart = 235;  // 1.4
constexpr std::size_t evlrCount = 243;  // 1.4
constexpr std::size_t pointCount = 247; // 1.4, uint64
constexpr std::size_t pointsByReturn = 255; // 1.4, uint64[15]
} // namespace hdr

// Variable length record header: 54 bytes; the extended one (EVLR, 1.4) has a
// 64-bit payload length and is 60 bytes (LAS 1.4 R15, "Variable Length Records"
// and "Extended Variable Length Records").
constexpr std::size_t kVlrHeaderSize = 54;
constexpr std::size_t kEvlrHeaderSize = 60;

// Size of the standard part of each point data record format (LAS 1.4 R15,
// "Point Data Record Format 0" to "10"). Formats 4, 5, 9 and 10 end with 29
// bytes of wave packet descriptor, which this reader skips.
constexpr std::array<std::size_t, 11> kBaseRecordSize = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};

// ---------------------------------------------------------------------------
// Extra Bytes (LAS 1.4 R15, "Extra Bytes" VLR): user id "LASF_Spec",
// record id 4, an array of 192-byte descriptors, one per extra dimension, in
// the order the dimensions follow the standard part of each point record.

constexpr std::size_t kExtraBytesDescriptorSize = 192;

namespace eb {
constexpr std::size_t dataType = 2;
constexpr std::size_t options = 3;
constexpr std::size_t name = 4;
constexpr std::size_t noData = 40;
constexpr std::size_t scale = 112;
constexpr std::size_t offset = 136;
constexpr std::size_t description = 160;
constexpr unsigned optNoData = 1u << 0;
constexpr unsigned optScale = 1u << 3;
constexpr unsigned optOffset = 1u << 4;
constexpr unsigned char typeFloat = 9;
constexpr unsigned char typeDouble = 10;
} // namespace eb

//! Writes LAS 1.4 with point format 6, 7 or 8, or LAZ 1.4 (LASzip's layered
//! chunks) when `compressed`.
void writeLas(const PointCloud& cloud, const std::filesystem::path& path, const WriteOptions& options, bool compressed);

} // namespace scandiff::io::detail::las
