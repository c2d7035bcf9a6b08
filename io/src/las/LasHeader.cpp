// SPDX-License-Identifier: GPL-3.0-or-later
//! The LAS header and its records (las/LasHeader.h).

#include "las/LasHeader.h"

#include <scandiff/io/CoordinateSystem.h>

#include <optional>

namespace scandiff::io::detail::las {

namespace fs = std::filesystem;

std::string fixedString(const char* p, std::size_t maxLength)
{
    std::size_t n = 0;
    while (n < maxLength && p[n] != '\0')
        ++n;
    return std::string(p, n);
}

[[noreturn]] void invalid(const fs::path& path, const std::string& what)
{
    throw Error(ErrorCode::InvalidData, path.string() + ": " + what);
}

LasHeader parseHeader(const MappedFile& file)
{
    const fs::path& path = file.path();
    const char* data = file.data();
    const std::size_t size = file.size();
    if (size == 0)
        invalid(path, "empty file (0 bytes), not a LAS file");
    if (size < 4 || std::memcmp(data, "LASF", 4) != 0)
        invalid(path, "not a LAS file (the signature at byte 0 is not 'LASF')");
    if (size < kHeaderSize12)
        invalid(path, "LAS header too short: the file has " + std::to_string(size) +
                          " bytes, a header needs at least " + std::to_string(kHeaderSize12));

    LasHeader h;
    h.versionMajor = static_cast<unsigned char>(data[hdr::versionMajor]);
    h.versionMinor = static_cast<unsigned char>(data[hdr::versionMinor]);
    if (h.versionMajor != 1 || h.versionMinor > 4)
        invalid(path, "unknown LAS version " + std::to_string(h.versionMajor) + "." + std::to_string(h.versionMinor) +
                          " at byte 24 (1.0 to 1.4 are supported)");

    h.globalEncoding = load<std::uint16_t>(data + hdr::globalEncoding);
    h.headerSize = load<std::uint16_t>(data + hdr::headerSize);
    // 1.3 headers written with the 1.2 size exist in the wild; only 1.4 needs the
    // longer header, for the 64-bit point count.
    const std::size_t minimumHeader = h.versionMinor >= 4 ? kHeaderSize14 : kHeaderSize12;
    if (h.headerSize < minimumHeader)
        invalid(path, "LAS header too short: header size (byte 94) is " + std::to_string(h.headerSize) + ", LAS 1." +
                          std::to_string(h.versionMinor) + " needs at least " + std::to_string(minimumHeader));
    if (h.headerSize > size)
        invalid(path, "LAS header too short: header size (byte 94) is " + std::to_string(h.headerSize) +
                          " but the file has only " + std::to_string(size) + " bytes");

    const auto formatByte = static_cast<unsigned char>(data[hdr::pointFormat]);
    // LASzip marks compressed points by setting bit 7 of the format id (bit 6 in
    // some older writers).
    h.compressed = (formatByte & 0xC0) != 0;
    h.pointFormat = formatByte & 0x3F;
    if (h.pointFormat > 10)
        invalid(path, "unknown point data record format " + std::to_string(h.pointFormat) +
                          " at byte 104 (0 to 10 are defined)");

    h.recordLength = load<std::uint16_t>(data + hdr::recordLength);
    if (h.recordLength < kBaseRecordSize[static_cast<std::size_t>(h.pointFormat)])
        invalid(path, "point record length (byte 105) is " + std::to_string(h.recordLength) +
                          " bytes, smaller than the " +
                          std::to_string(kBaseRecordSize[static_cast<std::size_t>(h.pointFormat)]) +
                          " bytes of point format " + std::to_string(h.pointFormat));

    h.offsetToPoints = load<std::uint32_t>(data + hdr::offsetToPoints);
    if (h.offsetToPoints > size)
        invalid(path, "offset to point data (byte 96) is " + std::to_string(h.offsetToPoints) +
                          ", beyond the end of the file (" + std::to_string(size) + " bytes)");
    if (h.offsetToPoints < h.headerSize)
        invalid(path, "offset to point data (byte 96) is " + std::to_string(h.offsetToPoints) +
                          ", inside the " + std::to_string(h.headerSize) + "-byte header");
    h.vlrCount = load<std::uint32_t>(data + hdr::vlrCount);

    for (int a = 0; a < 3; ++a) {
        h.scale[a] = load<double>(data + hdr::scale + 8 * static_cast<std::size_t>(a));
        h.offset[a] = load<double>(data + hdr::offset + 8 * static_cast<std::size_t>(a));
        h.max[a] = load<double>(data + hdr::bounds + 16 * static_cast<std::size_t>(a));
        h.min[a] = load<double>(data + hdr::bounds + 16 * static_cast<std::size_t>(a) + 8);
    }
    static const char* const axisName[3] = {"X", "Y", "Z"};
    for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(h.scale[a]) || h.scale[a] == 0.0)
            invalid(path, std::string(axisName[a]) + " scale factor (byte " + std::to_string(hdr::scale + 8 * a) +
                              ") is " + std::to_string(h.scale[a]) + "; it must be a finite non-zero number");
        if (!std::isfinite(h.offset[a]))
            invalid(path, std::string(axisName[a]) + " offset (byte " + std::to_string(hdr::offset + 8 * a) +
                              ") is not a finite number");
    }

    // LAS 1.4 R15: the 64-bit "Number of Point Records" must always be filled;
    // the legacy 32-bit one is zero for formats 6-10 or beyond 2^32 points.
    const std::uint64_t legacyCount = load<std::uint32_t>(data + hdr::legacyPointCount);
    h.pointCount = legacyCount;
    if (h.versionMinor >= 4) {
        h.evlrStart = load<std::uint64_t>(data + hdr::evlrStart);
        h.evlrCount = load<std::uint32_t>(data + hdr::evlrCount);
        const std::uint64_t count64 = load<std::uint64_t>(data + hdr::pointCount);
        // A few writers fill only the legacy count of a 1.4 file.
        if (count64 != 0)
            h.pointCount = count64;
    }

    const std::uint64_t available = size - h.offsetToPoints;
    // A LAZ file's count is checked against its chunk table (LazDecoder.cpp).
    if (!h.compressed && h.pointCount > available / h.recordLength)
        invalid(path, "truncated: " + std::to_string(h.pointCount) + " points of " + std::to_string(h.recordLength) +
                          " bytes need " +
                          (h.pointCount > std::numeric_limits<std::uint64_t>::max() / h.recordLength
                               ? std::string("more than 2^64")
                               : std::to_string(h.pointCount * h.recordLength)) +
                          " bytes from byte " + std::to_string(h.offsetToPoints) + ", but only " +
                          std::to_string(available) + " bytes follow");
    return h;
}


// Byte size of an extra-bytes data type; 0 for an unknown type. Types 11-30 are
// the deprecated 2- and 3-element arrays of types 1-10 (LAS 1.4 R15, Extra Bytes data_type).
std::size_t extraTypeSize(unsigned char type, unsigned char options)
{
    static constexpr std::size_t scalarSize[11] = {0, 1, 1, 2, 2, 4, 4, 8, 8, 4, 8};
    if (type == 0)
        return options; // "undocumented extra bytes": options holds the byte count
    if (type <= 10)
        return scalarSize[type];
    if (type <= 20)
        return 2 * scalarSize[type - 10];
    if (type <= 30)
        return 3 * scalarSize[type - 20];
    return 0;
}

std::vector<ExtraDimension> parseExtraBytes(const fs::path& path, const char* payload, std::size_t length,
                                            std::size_t baseSize, std::size_t recordLength)
{
    std::vector<ExtraDimension> dims;
    std::size_t position = baseSize;
    for (std::size_t d = 0; d + kExtraBytesDescriptorSize <= length; d += kExtraBytesDescriptorSize) {
        const char* p = payload + d;
        const auto type = static_cast<unsigned char>(p[eb::dataType]);
        const auto options = static_cast<unsigned char>(p[eb::options]);
        std::string name = fixedString(p + eb::name, 32);
        const std::size_t size = extraTypeSize(type, options);
        if (size == 0 && type != 0) {
            logWarning(path.string() + ": extra bytes dimension '" + name + "' has unknown data type " +
                       std::to_string(type) + "; it and the extra dimensions after it are skipped");
            break;
        }
        if (position + size > recordLength) {
            logWarning(path.string() + ": extra bytes dimension '" + name + "' does not fit in the " +
                       std::to_string(recordLength) + "-byte point record; it and the ones after it are skipped");
            break;
        }
        if (type != 0) {
            // Types 11-20 and 21-30, deprecated since LAS 1.4 R14 but still
            // written (laspy's samples have them), are arrays of 2 and 3 values
            // of type 1-10, each element with its own no_data, scale and offset
            // (the descriptor's three slots): one field per element, named as
            // PDAL names them (name0, name1, name2).
            const std::size_t elements = type <= 10 ? 1 : type <= 20 ? 2 : 3;
            const auto elementType = static_cast<unsigned char>(type - 10 * (elements - 1));
            for (std::size_t e = 0; e < elements; ++e) {
                ExtraDimension dim;
                dim.name = elements == 1 ? name : name + std::to_string(e);
                dim.type = elementType;
                dim.recordOffset = position + e * (size / elements);
                dim.hasNoData = (options & eb::optNoData) != 0;
                dim.noDataBits = load<std::uint64_t>(p + eb::noData + 8 * e);
                if (options & eb::optScale)
                    dim.scale = load<double>(p + eb::scale + 8 * e);
                if (options & eb::optOffset)
                    dim.offset = load<double>(p + eb::offset + 8 * e);
                dims.push_back(std::move(dim));
            }
        }
        position += size;
    }
    return dims;
}
// Finds the Extra Bytes record among the VLRs (and, in 1.4, the EVLRs).
std::vector<ExtraDimension> findExtraDimensions(const MappedFile& file, const LasHeader& h)
{
    const fs::path& path = file.path();
    const std::size_t baseSize = kBaseRecordSize[static_cast<std::size_t>(h.pointFormat)];
    if (h.recordLength == baseSize)
        return {};
    std::optional<std::vector<ExtraDimension>> dims;
    forEachRecord(file, h, false, [&](const std::string& user, std::uint16_t id, const char* payload, std::size_t length) {
        if (user != "LASF_Spec" || id != 4)
            return false;
        dims = parseExtraBytes(path, payload, length, baseSize, h.recordLength);
        return true;
    });
    if (dims)
        return std::move(*dims);
    logInfo(path.string() + ": " + std::to_string(h.recordLength - baseSize) +
            " undescribed extra bytes per point were ignored");
    return {};
}

// The coordinate reference system (LAS 1.4 R15, "Coordinate Reference System
// Representation"): the OGC WKT record (user "LASF_Projection", id 2112) when
// there is one, else the EPSG codes of the GeoTIFF GeoKeyDirectoryTag record
// (id 34735: a header of four uint16, the last the key count, then per key
// id, location, count, value; location 0 means the value is the key's own).
// Systems the keys define piece by piece (code 32767, "user-defined") are not
// rebuilt: the cloud gets none, with a warning.
std::string findCrs(const MappedFile& file, const LasHeader& h)
{
    const std::string where = file.path().string();
    std::string wkt;
    int horizontal = -1, geographic = -1, vertical = -1; // -1: key absent
    forEachRecord(file, h, true, [&](const std::string& user, std::uint16_t id, const char* payload, std::size_t length) {
        if (user != "LASF_Projection")
            return false;
        if (id == 2112) {
            wkt.assign(payload, std::find(payload, payload + length, '\0'));
            while (!wkt.empty() && std::isspace(static_cast<unsigned char>(wkt.back())))
                wkt.pop_back();
            return !wkt.empty();
        }
        if (id == 34735 && length >= 8) {
            const std::size_t keys = std::min<std::size_t>(load<std::uint16_t>(payload + 6), (length - 8) / 8);
            for (std::size_t k = 0; k < keys; ++k) {
                const char* key = payload + 8 + 8 * k;
                if (load<std::uint16_t>(key + 2) != 0)
                    continue; // a value stored elsewhere: not a code
                const int value = load<std::uint16_t>(key + 6);
                switch (load<std::uint16_t>(key)) {
                case 3072: horizontal = value; break; // ProjectedCSTypeGeoKey
                case 2048: geographic = value; break; // GeographicTypeGeoKey
                case 4096: vertical = value; break;   // VerticalCSTypeGeoKey
                default: break;
                }
            }
        }
        return false;
    });
    if (!wkt.empty())
        return wkt;
    auto known = [](int code) { return code > 0 && code != 32767; };
    // A projected system's key decides alone: its geographic key is only its
    // base, and projected metres must not be labelled as degrees.
    const int base = horizontal >= 0 ? horizontal : geographic;
    if (known(base))
        return crsFromEpsg(base, known(vertical) ? vertical : 0, where);
    if (base == 32767)
        logWarning(where + ": the coordinate reference system is user-defined GeoTIFF keys, which are not read; the cloud gets none");
    return {};
}

} // namespace scandiff::io::detail::las
