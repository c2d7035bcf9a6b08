// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The LAS reader's first step: the public header block, the variable length
//! records (Extra Bytes, coordinate reference system) of LAS 1.0-1.4, checked
//! against the file. Layout facts from the ASPRS LAS 1.4 specification, R15.

#include "internal/MappedFile.h"
#include "las/LasLayout.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace scandiff::io::detail::las {

//! A string field of at most `maxLength` bytes, ended early by a NUL.
std::string fixedString(const char* p, std::size_t maxLength);

// ---------------------------------------------------------------------------
// Public Header Block (LAS 1.4 R15; offsets in LasLayout.h).

struct LasHeader
{
    int versionMajor = 0;
    int versionMinor = 0;
    std::uint16_t globalEncoding = 0;
    std::size_t headerSize = 0;
    std::uint64_t offsetToPoints = 0;
    std::uint32_t vlrCount = 0;
    int pointFormat = 0;
    std::size_t recordLength = 0;
    std::uint64_t pointCount = 0;
    std::uint64_t evlrStart = 0;
    std::uint32_t evlrCount = 0;
    Eigen::Vector3d scale = Eigen::Vector3d::Ones();
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    Eigen::Vector3d min = Eigen::Vector3d::Zero();
    Eigen::Vector3d max = Eigen::Vector3d::Zero();
    bool compressed = false; //!< LAZ: the points are LASzip's
};

[[noreturn]] void invalid(const std::filesystem::path& path, const std::string& what);

//! The public header block, every size and offset checked against the file.
LasHeader parseHeader(const MappedFile& file);

// ---------------------------------------------------------------------------
// Extra Bytes (LAS 1.4 R15, "Extra Bytes" VLR; the descriptor's layout in LasLayout.h).

struct ExtraDimension
{
    std::string name;
    unsigned char type = 0; // 1..10: the scalar types this reader decodes
    std::size_t recordOffset = 0;
    bool hasNoData = false;
    std::uint64_t noDataBits = 0; // upcast no_data, compared with the upcast raw value
    double scale = 1.0;
    double offset = 0.0;
};

// Visits the variable length records, then (1.4) the extended ones, in file
// order: visit(userId, recordId, payload, length) returns true to stop. A
// record running out of its section ends the walk (with a warning when
// `warn`: the first walk of a file says it, not every walk).
template <class Visit>
void forEachRecord(const MappedFile& file, const LasHeader& h, bool warn, Visit visit)
{
    const std::filesystem::path& path = file.path();
    const char* data = file.data();
    std::size_t position = h.headerSize;
    for (std::uint32_t v = 0; v < h.vlrCount; ++v) {
        const bool headerFits = position + kVlrHeaderSize <= h.offsetToPoints;
        const std::size_t length = headerFits ? load<std::uint16_t>(data + position + 20) : 0;
        if (!headerFits || position + kVlrHeaderSize + length > h.offsetToPoints) {
            if (warn)
                logWarning(path.string() + ": variable length record " + std::to_string(v) + " at byte " +
                           std::to_string(position) + " runs into the point data; the remaining records are ignored");
            break;
        }
        if (visit(fixedString(data + position + 2, 16), load<std::uint16_t>(data + position + 18), data + position + kVlrHeaderSize,
                  length))
            return;
        position += kVlrHeaderSize + length;
    }

    std::uint64_t evlr = h.evlrStart;
    for (std::uint32_t v = 0; v < h.evlrCount && evlr != 0; ++v) {
        if (evlr > file.size() || file.size() - evlr < kEvlrHeaderSize)
            break;
        const std::uint64_t length = load<std::uint64_t>(data + evlr + 20);
        if (length > file.size() - evlr - kEvlrHeaderSize)
            break;
        if (visit(fixedString(data + evlr + 2, 16), load<std::uint16_t>(data + evlr + 18), data + evlr + kEvlrHeaderSize,
                  static_cast<std::size_t>(length)))
            return;
        evlr += kEvlrHeaderSize + length;
    }
}

// Finds the Extra Bytes record among the VLRs (and, in 1.4, the EVLRs).
std::vector<ExtraDimension> findExtraDimensions(const MappedFile& file, const LasHeader& h);

// The coordinate reference system (LAS 1.4 R15, "Coordinate Reference System
// Representation"): the OGC WKT record (user "LASF_Projection", id 2112) when
// there is one, else the EPSG codes of the GeoTIFF GeoKeyDirectoryTag record
// (id 34735: a header of four uint16, the last the key count, then per key
// id, location, count, value; location 0 means the value is the key's own).
// Systems the keys define piece by piece (code 32767, "user-defined") are not
// rebuilt: the cloud gets none, with a warning.
std::string findCrs(const MappedFile& file, const LasHeader& h);

} // namespace scandiff::io::detail::las
