// SPDX-License-Identifier: GPL-3.0-or-later
//! LAS: writes LAS 1.4 with point format 6, 7 or 8, or LAZ 1.4 through
//! LazEncoder.cpp's chunks (the reader is LasFormat.cpp).
//!
//! Layout facts quoted below come from the ASPRS LAS 1.4 specification, R15
//! ("LAS 1.4 R15").

#include "internal/LasLayout.h"
#include "internal/LazEncoder.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/Progress.h>
#include <scandiff/io/AtomicFile.h>
#include <scandiff/io/CoordinateSystem.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <ctime>
#include <limits>
#include <string>
#include <vector>

namespace scandiff::io::detail::las {

namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------
// Writing: LAS 1.4, point format 6 (no colour), 7 (colour) or 8 (colour and a
// "nir" field), so every standard attribute has its full 1.4 range.

// Where a standard scalar field goes in a format 6-8 record.
enum class Slot {
    Intensity,
    ReturnNumber,
    NumberOfReturns,
    ClassificationFlags,
    ScannerChannel,
    ScanDirectionFlag,
    EdgeOfFlightLine,
    Classification,
    UserData,
    ScanAngle,
    PointSourceId,
    GpsTime,
    Nir,
    Count
};

// The field names of the slots, in the order of Slot; the reader uses the same names.
constexpr std::array<const char*, static_cast<std::size_t>(Slot::Count)> kSlotNames = {
    "intensity",           "return_number",       "number_of_returns", "classification_flags",
    "scanner_channel",     "scan_direction_flag", "edge_of_flight_line", "classification",
    "user_data",           "scan_angle",          "point_source_id",   "gps_time",
    "nir"};

struct SlotSource
{
    const ScalarField* field = nullptr;

    // The field value of point i, or `fallback` when there is no field; NaN -> 0.
    double get(std::size_t i, double fallback) const
    {
        if (!field)
            return fallback;
        return field->hasValue(i) ? field->value(i) : 0.0;
    }
};

template <class T>
T clampRound(double v)
{
    const double r = std::round(v);
    if (!(r >= static_cast<double>(std::numeric_limits<T>::lowest())))
        return std::numeric_limits<T>::lowest();
    if (r > static_cast<double>(std::numeric_limits<T>::max()))
        return std::numeric_limits<T>::max();
    return static_cast<T>(r);
}

unsigned clampBits(double v, unsigned maxValue)
{
    const double r = std::round(v);
    if (!(r >= 0.0))
        return 0;
    return r > maxValue ? maxValue : static_cast<unsigned>(r);
}

struct ExtraOutput
{
    const ScalarField* field = nullptr;
    std::string lasName;
    bool asDouble = false;
    std::size_t recordOffset = 0;
};

// Quantisation of one axis. LAS stores int32 = (coordinate - offset) / scale.
// 0.1 mm is a usual scanner resolution and close to the step of a float32 local
// coordinate 1-2 km from the origin (61 µm at 1 km, 122 µm at 2 km), so it
// changes a coordinate by at most 50 µm. It overflows int32 only beyond ±214 km
// from the offset; there the scale is coarsened by decades (1 mm: ±2147 km)
// rather than losing points.
void chooseQuantization(const fs::path& path, double origin, double lo, double hi, bool empty, double& offset,
                        double& scale)
{
    static constexpr double kScales[] = {1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0, 1000.0};
    // Keep a margin below 2^31 for the rounding of the extreme points.
    constexpr double kLimit = 2147483000.0;
    offset = std::isfinite(origin) ? std::round(origin) : 0.0;
    scale = kScales[0];
    if (empty)
        return;
    auto reach = [&](double o) { return std::max(std::abs(lo - o), std::abs(hi - o)); };
    if (reach(offset) / kScales[0] > kLimit) {
        const double centre = std::round(0.5 * (lo + hi));
        if (reach(centre) < reach(offset))
            offset = centre;
    }
    for (double s : kScales) {
        scale = s;
        if (reach(offset) / s <= kLimit)
            return;
    }
    throw Error(ErrorCode::InvalidData, path.string() + ": coordinates span " + std::to_string(hi - lo) +
                                            " m, too large for LAS even at a 1 km resolution");
}

// A variable length record (54-byte header, 16-bit length) or an extended
// one (60-byte header, 64-bit length, LAS 1.4), its payload after the header:
// reserved u16, user id char[16] at 2, record id u16 at 18, the length at 20,
// the description char[32] after it (LAS 1.4 R15, tables 16 and 24).
std::string variableLengthRecord(const char* userId, std::uint16_t recordId, const char* description, const std::string& payload,
                                 bool extended)
{
    std::string record((extended ? kEvlrHeaderSize : kVlrHeaderSize) + payload.size(), '\0');
    std::memcpy(&record[2], userId, std::min<std::size_t>(16, std::strlen(userId)));
    store<std::uint16_t>(&record[18], recordId);
    if (extended)
        store<std::uint64_t>(&record[20], payload.size());
    else
        store<std::uint16_t>(&record[20], static_cast<std::uint16_t>(payload.size()));
    std::memcpy(&record[extended ? 28 : 22], description, std::min<std::size_t>(32, std::strlen(description)));
    std::memcpy(&record[extended ? kEvlrHeaderSize : kVlrHeaderSize], payload.data(), payload.size());
    return record;
}

} // namespace

void writeLas(const PointCloud& cloud, const fs::path& path, const WriteOptions& options, bool compressed)
{
    const std::size_t n = cloud.size();
    const auto& positions = cloud.positions();

    std::size_t finiteCount = 0;
    for (const auto& p : positions)
        finiteCount += p.allFinite() ? 1 : 0;
    if (finiteCount != n)
        logWarning(path.string() + ": " + std::to_string(n - finiteCount) +
                   " points with non-finite coordinates were not written");

    // Standard attributes into their slots, everything else as extra bytes.
    std::array<SlotSource, static_cast<std::size_t>(Slot::Count)> slots{};
    std::vector<const ScalarField*> others;
    for (const ScalarField& f : cloud.fields()) {
        const auto it =
            std::find_if(kSlotNames.begin(), kSlotNames.end(), [&](const char* s) { return f.name() == s; });
        if (it == kSlotNames.end()) {
            others.push_back(&f);
            continue;
        }
        slots[static_cast<std::size_t>(it - kSlotNames.begin())] = SlotSource{&f};
    }
    const SlotSource& nirSlot = slots[static_cast<std::size_t>(Slot::Nir)];
    // Format 8 adds near infrared to the colours of format 7; without colours a
    // "nir" field goes to the extra bytes rather than forcing black colours.
    const int format = cloud.hasColors() ? (nirSlot.field ? 8 : 7) : 6;
    if (format != 8 && nirSlot.field) {
        others.push_back(cloud.field("nir"));
        slots[static_cast<std::size_t>(Slot::Nir)] = SlotSource{};
    }
    const std::size_t baseSize = kBaseRecordSize[static_cast<std::size_t>(format)];

    // Extra bytes: float (type 9) keeps a field exactly; a field with an offset
    // (times, large values) or kept in double needs double (type 10).
    std::vector<ExtraOutput> extras;
    std::size_t recordLength = baseSize;
    for (const ScalarField* f : others) {
        ExtraOutput e;
        e.field = f;
        e.asDouble = f->offset() != 0.0 || f->isDouble();
        e.recordOffset = recordLength;
        // The descriptor's name is char[32]: longer names are cut to 32 bytes,
        // and a cut name that repeats an earlier one ends with "~2", "~3"...
        e.lasName = f->name().substr(0, 32);
        if (e.lasName.empty())
            e.lasName = "field";
        auto taken = [&](const std::string& name) {
            return std::any_of(extras.begin(), extras.end(), [&](const ExtraOutput& x) { return x.lasName == name; });
        };
        for (int k = 2; taken(e.lasName); ++k) {
            const std::string suffix = "~" + std::to_string(k);
            e.lasName = f->name().substr(0, 32 - suffix.size()) + suffix;
        }
        if (e.lasName != f->name())
            logWarning(path.string() + ": scalar field '" + f->name() + "' is stored as '" + e.lasName +
                       "' (LAS extra dimension names are limited to 32 characters)");
        recordLength += e.asDouble ? 8 : 4;
        extras.push_back(std::move(e));
    }
    // Both the point record length and the VLR payload (192 bytes per extra
    // dimension) are 16-bit numbers.
    if (recordLength > std::numeric_limits<std::uint16_t>::max() ||
        extras.size() * kExtraBytesDescriptorSize > std::numeric_limits<std::uint16_t>::max())
        throw Error(ErrorCode::InvalidArgument, path.string() + ": too many scalar fields for LAS (" +
                                                    std::to_string(extras.size()) +
                                                    " extra dimensions; at most 341 fit in the Extra Bytes record)");

    // Extra Bytes VLR.
    std::string vlr;
    std::uint32_t vlrCount = 0;
    if (!extras.empty()) {
        std::string descriptors(kExtraBytesDescriptorSize * extras.size(), '\0');
        for (std::size_t d = 0; d < extras.size(); ++d) {
            char* p = &descriptors[kExtraBytesDescriptorSize * d];
            p[eb::dataType] = static_cast<char>(extras[d].asDouble ? eb::typeDouble : eb::typeFloat);
            // NaN means "no value" in scandiff; declaring it as no_data tells other
            // readers so (stored as a double, the upcast of float and double).
            p[eb::options] = static_cast<char>(eb::optNoData);
            store<double>(p + eb::noData, std::numeric_limits<double>::quiet_NaN());
            std::memcpy(p + eb::name, extras[d].lasName.data(), extras[d].lasName.size());
            const char description[] = "scandiff scalar field";
            std::memcpy(p + eb::description, description, sizeof description - 1);
        }
        vlr += variableLengthRecord("LASF_Spec", 4, "Extra Bytes Record", descriptors, false);
        ++vlrCount;
    }

    // The coordinate reference system as an OGC WKT record, NUL-terminated;
    // one too long for a VLR's 16-bit length goes into an EVLR after the points.
    std::string crsRecord;
    if (!cloud.crsWkt().empty()) {
        const std::string wkt = cloud.crsWkt() + '\0';
        if (wkt.size() > std::numeric_limits<std::uint16_t>::max()) {
            crsRecord = variableLengthRecord("LASF_Projection", 2112, "OGC coordinate system WKT", wkt, true);
        } else {
            vlr += variableLengthRecord("LASF_Projection", 2112, "OGC coordinate system WKT", wkt, false);
            ++vlrCount;
        }
    }

    // LAZ: the LASzip record describing the compressed records.
    std::optional<LazLayout> lazLayout;
    if (compressed) {
        lazLayout = lazLayoutForFormat(format, recordLength - baseSize);
        vlr += variableLengthRecord(kLaszipUserId, kLaszipRecordId, "by scandiff, LASzip compatible",
                                    lazRecordPayload(*lazLayout), false);
        ++vlrCount;
    }

    const BoundingBox bounds = cloud.bounds();
    Eigen::Vector3d lasOffset, lasScale;
    for (int a = 0; a < 3; ++a)
        chooseQuantization(path, cloud.origin()[a], bounds.min[a], bounds.max[a], bounds.empty, lasOffset[a],
                           lasScale[a]);
    // Points read from a LAS file go back on its grid (the same scale and
    // offset, so the same integers) when they still fit it.
    if (const auto& grid = cloud.sourceGrid(); grid && !bounds.empty) {
        bool fits = true;
        for (int a = 0; a < 3; ++a) {
            const double reach = std::max(std::abs(bounds.min[a] - grid->offset[a]), std::abs(bounds.max[a] - grid->offset[a]));
            fits = fits && grid->scale[a] > 0 && reach / grid->scale[a] <= 2147483000.0;
        }
        if (fits) {
            lasOffset = grid->offset;
            lasScale = grid->scale;
        }
    }
    const Eigen::Vector3d inverseScale = lasScale.cwiseInverse();
    const Eigen::Vector3d shift = cloud.origin() - lasOffset;

    AtomicFile output(path);
    std::ofstream& stream = output.stream();
    const std::uint64_t offsetToPoints = kHeaderSize14 + vlr.size();
    // The header is written again at the end, with the extents and return counts.
    std::array<char, kHeaderSize14> header{};
    stream.write(header.data(), header.size());
    stream.write(vlr.data(), static_cast<std::streamsize>(vlr.size()));

    std::array<std::uint64_t, 15> pointsByReturn{};
    constexpr std::int32_t kInt32Max = std::numeric_limits<std::int32_t>::max();
    constexpr std::int32_t kInt32Min = std::numeric_limits<std::int32_t>::lowest();
    std::array<std::int32_t, 3> rawMin{kInt32Max, kInt32Max, kInt32Max};
    std::array<std::int32_t, 3> rawMax{kInt32Min, kInt32Min, kInt32Min};
    double gpsMax = -std::numeric_limits<double>::infinity();
    auto slot = [&](Slot s) -> const SlotSource& { return slots[static_cast<std::size_t>(s)]; };

    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), n);
    std::optional<LazPointWriter> lazPoints;
    if (lazLayout)
        lazPoints.emplace(stream, *lazLayout, recordLength);
    std::vector<char> buffer(kChunkPoints * recordLength);
    for (std::size_t begin = 0; begin < n; begin += kChunkPoints) {
        const std::size_t end = std::min(n, begin + kChunkPoints);
        std::fill(buffer.begin(), buffer.end(), '\0');
        char* p = buffer.data();
        for (std::size_t i = begin; i < end; ++i) {
            if (!positions[i].allFinite())
                continue;
            // With the file's exact coordinates where a float misses its grid.
            const Eigen::Vector3d local = cloud.exactLocalPosition(i);
            for (int a = 0; a < 3; ++a) {
                const std::int32_t raw = clampRound<std::int32_t>((shift[a] + local[a]) * inverseScale[a]);
                store<std::int32_t>(p + 4 * a, raw);
                rawMin[a] = std::min(rawMin[a], raw);
                rawMax[a] = std::max(rawMax[a], raw);
            }
            store<std::uint16_t>(p + 12, clampRound<std::uint16_t>(slot(Slot::Intensity).get(i, 0.0)));
            // Return number and count default to 1: "1 of 1" is what a single-return
            // scanner produces, and 0 is not a valid return number.
            const unsigned returnNumber = clampBits(slot(Slot::ReturnNumber).get(i, 1.0), 15);
            const unsigned numberOfReturns = clampBits(slot(Slot::NumberOfReturns).get(i, 1.0), 15);
            p[14] = static_cast<char>(returnNumber | (numberOfReturns << 4));
            p[15] = static_cast<char>(clampBits(slot(Slot::ClassificationFlags).get(i, 0.0), 15) |
                                      (clampBits(slot(Slot::ScannerChannel).get(i, 0.0), 3) << 4) |
                                      (clampBits(slot(Slot::ScanDirectionFlag).get(i, 0.0), 1) << 6) |
                                      (clampBits(slot(Slot::EdgeOfFlightLine).get(i, 0.0), 1) << 7));
            p[16] = static_cast<char>(clampRound<std::uint8_t>(slot(Slot::Classification).get(i, 0.0)));
            p[17] = static_cast<char>(clampRound<std::uint8_t>(slot(Slot::UserData).get(i, 0.0)));
            // Scan angle in 0.006 degree units; LAS 1.4 R15 limits it to ±30000 (±180°).
            const double angle = std::clamp(slot(Slot::ScanAngle).get(i, 0.0) / 0.006, -30000.0, 30000.0);
            store<std::int16_t>(p + 18, clampRound<std::int16_t>(angle));
            store<std::uint16_t>(p + 20, clampRound<std::uint16_t>(slot(Slot::PointSourceId).get(i, 0.0)));
            const double gps = slot(Slot::GpsTime).get(i, 0.0);
            gpsMax = std::max(gpsMax, gps);
            store<double>(p + 22, gps);
            if (format >= 7) {
                // 8-bit to 16-bit: x257 maps 0..255 onto the full 0..65535 range.
                const Rgb8& c = cloud.colors()[i];
                store<std::uint16_t>(p + 30, static_cast<std::uint16_t>(c.r * 257));
                store<std::uint16_t>(p + 32, static_cast<std::uint16_t>(c.g * 257));
                store<std::uint16_t>(p + 34, static_cast<std::uint16_t>(c.b * 257));
            }
            if (format == 8)
                store<std::uint16_t>(p + 36, clampRound<std::uint16_t>(slot(Slot::Nir).get(i, 0.0)));
            for (const ExtraOutput& e : extras) {
                if (e.asDouble)
                    store<double>(p + e.recordOffset, e.field->value(i));
                else
                    store<float>(p + e.recordOffset, e.field->values()[i]);
            }
            if (returnNumber >= 1)
                ++pointsByReturn[returnNumber - 1];
            p += recordLength;
        }
        if (lazPoints)
            lazPoints->add(buffer.data(), static_cast<std::size_t>(p - buffer.data()) / recordLength);
        else
            stream.write(buffer.data(), p - buffer.data());
        ticker.step(end - begin);
    }
    if (lazPoints)
        lazPoints->finish();

    const auto evlrStart = static_cast<std::uint64_t>(stream.tellp());
    stream.write(crsRecord.data(), static_cast<std::streamsize>(crsRecord.size()));

    // Public header block, LAS 1.4.
    char* h = header.data();
    std::memcpy(h, "LASF", 4);
    // Global encoding: bit 4 (WKT) is required for point formats 6-10 (LAS 1.4 R15,
    // "Coordinate Reference System Representation": GeoTIFF with them is an error).
    // Bit 0: the cloud does not record the GPS time type, but times beyond one week
    // (604800 s) cannot be GPS week time, so they are adjusted standard GPS time.
    std::uint16_t globalEncoding = 1u << 4;
    if (gpsMax > 604800.0)
        globalEncoding |= 1u;
    store<std::uint16_t>(h + hdr::globalEncoding, globalEncoding);
    h[hdr::versionMajor] = 1;
    h[hdr::versionMinor] = 4;
    const char systemIdentifier[] = "OTHER";
    std::memcpy(h + hdr::systemIdentifier, systemIdentifier, sizeof systemIdentifier - 1);
    const char software[] = "scandiff";
    std::memcpy(h + hdr::generatingSoftware, software, sizeof software - 1);
    const std::time_t now = std::time(nullptr);
    std::tm utc{};
    if (gmtime_r(&now, &utc)) {
        store<std::uint16_t>(h + hdr::creationDay, static_cast<std::uint16_t>(utc.tm_yday + 1));
        store<std::uint16_t>(h + hdr::creationYear, static_cast<std::uint16_t>(utc.tm_year + 1900));
    }
    store<std::uint16_t>(h + hdr::headerSize, static_cast<std::uint16_t>(kHeaderSize14));
    store<std::uint32_t>(h + hdr::offsetToPoints, static_cast<std::uint32_t>(offsetToPoints));
    store<std::uint32_t>(h + hdr::vlrCount, vlrCount);
    if (!crsRecord.empty()) {
        store<std::uint64_t>(h + hdr::evlrStart, evlrStart);
        store<std::uint32_t>(h + hdr::evlrCount, 1u);
    }
    // LASzip marks compressed records with bit 7 of the format.
    h[hdr::pointFormat] = static_cast<char>(format | (compressed ? 0x80 : 0));
    store<std::uint16_t>(h + hdr::recordLength, static_cast<std::uint16_t>(recordLength));
    // Legacy point counts stay 0: LAS 1.4 R15 requires it for point formats 6 and above.
    for (int a = 0; a < 3; ++a) {
        store<double>(h + hdr::scale + 8 * a, lasScale[a]);
        store<double>(h + hdr::offset + 8 * a, lasOffset[a]);
        // The extents of the stored (quantised) coordinates; zero without points.
        const double lo = finiteCount ? rawMin[a] * lasScale[a] + lasOffset[a] : 0.0;
        const double hi = finiteCount ? rawMax[a] * lasScale[a] + lasOffset[a] : 0.0;
        store<double>(h + hdr::bounds + 16 * a, hi);
        store<double>(h + hdr::bounds + 16 * a + 8, lo);
    }
    store<std::uint64_t>(h + hdr::pointCount, finiteCount);
    for (std::size_t r = 0; r < pointsByReturn.size(); ++r)
        store<std::uint64_t>(h + hdr::pointsByReturn + 8 * r, pointsByReturn[r]);
    stream.seekp(0);
    stream.write(header.data(), header.size());
    output.commit();
}

} // namespace scandiff::io::detail::las
