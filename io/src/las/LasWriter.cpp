// SPDX-License-Identifier: GPL-3.0-or-later
//! LAS: writes LAS 1.4 with point format 6, 7 or 8, or LAZ 1.4 through
//! LazEncoder.cpp's chunks (the reader is LasFormat.cpp).
//!
//! Layout facts quoted below come from the ASPRS LAS 1.4 specification, R15
//! ("LAS 1.4 R15").

#include "las/LasLayout.h"
#include "laz/LazEncoder.h"

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

//! How the cloud's attributes go into the records: the standard ones into
//! their slots of the point format, everything else as extra bytes.
struct RecordPlan
{
    std::array<SlotSource, static_cast<std::size_t>(Slot::Count)> slots{};
    int format = 6;
    std::size_t baseSize = 0, recordLength = 0;
    std::vector<ExtraOutput> extras;
    const SlotSource& slot(Slot s) const { return slots[static_cast<std::size_t>(s)]; }
};

RecordPlan planRecords(const PointCloud& cloud, const fs::path& path)
{
    RecordPlan plan;
    std::vector<const ScalarField*> others;
    for (const ScalarField& f : cloud.fields()) {
        const auto it =
            std::find_if(kSlotNames.begin(), kSlotNames.end(), [&](const char* s) { return f.name() == s; });
        if (it == kSlotNames.end()) {
            others.push_back(&f);
            continue;
        }
        plan.slots[static_cast<std::size_t>(it - kSlotNames.begin())] = SlotSource{&f};
    }
    const SlotSource& nirSlot = plan.slot(Slot::Nir);
    // Format 8 adds near infrared to the colours of format 7; without colours a
    // "nir" field goes to the extra bytes rather than forcing black colours.
    plan.format = cloud.hasColors() ? (nirSlot.field ? 8 : 7) : 6;
    if (plan.format != 8 && nirSlot.field) {
        others.push_back(cloud.field("nir"));
        plan.slots[static_cast<std::size_t>(Slot::Nir)] = SlotSource{};
    }
    plan.baseSize = kBaseRecordSize[static_cast<std::size_t>(plan.format)];

    // Extra bytes: float (type 9) keeps a field exactly; a field with an offset
    // (times, large values) or kept in double needs double (type 10).
    plan.recordLength = plan.baseSize;
    for (const ScalarField* f : others) {
        ExtraOutput e;
        e.field = f;
        e.asDouble = f->offset() != 0.0 || f->isDouble();
        e.recordOffset = plan.recordLength;
        // The descriptor's name is char[32]: longer names are cut to 32 bytes,
        // and a cut name that repeats an earlier one ends with "~2", "~3"...
        e.lasName = f->name().substr(0, 32);
        if (e.lasName.empty())
            e.lasName = "field";
        auto taken = [&](const std::string& name) {
            return std::any_of(plan.extras.begin(), plan.extras.end(), [&](const ExtraOutput& x) { return x.lasName == name; });
        };
        for (int k = 2; taken(e.lasName); ++k) {
            const std::string suffix = "~" + std::to_string(k);
            e.lasName = f->name().substr(0, 32 - suffix.size()) + suffix;
        }
        if (e.lasName != f->name())
            logWarning(path.string() + ": scalar field '" + f->name() + "' is stored as '" + e.lasName +
                       "' (LAS extra dimension names are limited to 32 characters)");
        plan.recordLength += e.asDouble ? 8 : 4;
        plan.extras.push_back(std::move(e));
    }
    // Both the point record length and the VLR payload (192 bytes per extra
    // dimension) are 16-bit numbers.
    if (plan.recordLength > std::numeric_limits<std::uint16_t>::max() ||
        plan.extras.size() * kExtraBytesDescriptorSize > std::numeric_limits<std::uint16_t>::max())
        throw Error(ErrorCode::InvalidArgument, path.string() + ": too many scalar fields for LAS (" +
                                                    std::to_string(plan.extras.size()) +
                                                    " extra dimensions; at most 341 fit in the Extra Bytes record)");
    return plan;
}

//! The Extra Bytes VLR describing the extra dimensions.
std::string extraBytesRecord(const std::vector<ExtraOutput>& extras)
{
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
    return variableLengthRecord("LASF_Spec", 4, "Extra Bytes Record", descriptors, false);
}

//! The file's scale and offset: chosen for the cloud's extent, or the grid
//! it was read on (the same integers back) when its points still fit it.
struct Quantization
{
    Eigen::Vector3d offset, scale;
};

Quantization chooseGrid(const PointCloud& cloud, const fs::path& path)
{
    Quantization q;
    const BoundingBox bounds = cloud.bounds();
    for (int a = 0; a < 3; ++a)
        chooseQuantization(path, cloud.origin()[a], bounds.min[a], bounds.max[a], bounds.empty, q.offset[a], q.scale[a]);
    if (const auto& grid = cloud.sourceGrid(); grid && !bounds.empty) {
        bool fits = true;
        for (int a = 0; a < 3; ++a) {
            const double reach = std::max(std::abs(bounds.min[a] - grid->offset[a]), std::abs(bounds.max[a] - grid->offset[a]));
            fits = fits && grid->scale[a] > 0 && reach / grid->scale[a] <= 2147483000.0;
        }
        if (fits) {
            q.offset = grid->offset;
            q.scale = grid->scale;
        }
    }
    return q;
}

//! What the header sums up of the records written.
struct RecordTotals
{
    std::array<std::uint64_t, 15> pointsByReturn{};
    std::array<std::int32_t, 3> rawMin{std::numeric_limits<std::int32_t>::max(), std::numeric_limits<std::int32_t>::max(),
                                       std::numeric_limits<std::int32_t>::max()};
    std::array<std::int32_t, 3> rawMax{std::numeric_limits<std::int32_t>::lowest(), std::numeric_limits<std::int32_t>::lowest(),
                                       std::numeric_limits<std::int32_t>::lowest()};
    double gpsMax = -std::numeric_limits<double>::infinity();
};

//! One point's record at p (zeroed); returns its return number.
unsigned fillRecord(char* p, const PointCloud& cloud, std::size_t i, const RecordPlan& plan, const Eigen::Vector3d& shift,
                    const Eigen::Vector3d& inverseScale, RecordTotals& totals)
{
    // With the file's exact coordinates where a float misses its grid.
    const Eigen::Vector3d local = cloud.exactLocalPosition(i);
    for (int a = 0; a < 3; ++a) {
        const std::int32_t raw = clampRound<std::int32_t>((shift[a] + local[a]) * inverseScale[a]);
        store<std::int32_t>(p + 4 * a, raw);
        totals.rawMin[a] = std::min(totals.rawMin[a], raw);
        totals.rawMax[a] = std::max(totals.rawMax[a], raw);
    }
    store<std::uint16_t>(p + 12, clampRound<std::uint16_t>(plan.slot(Slot::Intensity).get(i, 0.0)));
    // Return number and count default to 1: "1 of 1" is what a single-return
    // scanner produces, and 0 is not a valid return number.
    const unsigned returnNumber = clampBits(plan.slot(Slot::ReturnNumber).get(i, 1.0), 15);
    const unsigned numberOfReturns = clampBits(plan.slot(Slot::NumberOfReturns).get(i, 1.0), 15);
    p[14] = static_cast<char>(returnNumber | (numberOfReturns << 4));
    p[15] = static_cast<char>(clampBits(plan.slot(Slot::ClassificationFlags).get(i, 0.0), 15) |
                              (clampBits(plan.slot(Slot::ScannerChannel).get(i, 0.0), 3) << 4) |
                              (clampBits(plan.slot(Slot::ScanDirectionFlag).get(i, 0.0), 1) << 6) |
                              (clampBits(plan.slot(Slot::EdgeOfFlightLine).get(i, 0.0), 1) << 7));
    p[16] = static_cast<char>(clampRound<std::uint8_t>(plan.slot(Slot::Classification).get(i, 0.0)));
    p[17] = static_cast<char>(clampRound<std::uint8_t>(plan.slot(Slot::UserData).get(i, 0.0)));
    // Scan angle in 0.006 degree units; LAS 1.4 R15 limits it to ±30000 (±180°).
    const double angle = std::clamp(plan.slot(Slot::ScanAngle).get(i, 0.0) / 0.006, -30000.0, 30000.0);
    store<std::int16_t>(p + 18, clampRound<std::int16_t>(angle));
    store<std::uint16_t>(p + 20, clampRound<std::uint16_t>(plan.slot(Slot::PointSourceId).get(i, 0.0)));
    const double gps = plan.slot(Slot::GpsTime).get(i, 0.0);
    totals.gpsMax = std::max(totals.gpsMax, gps);
    store<double>(p + 22, gps);
    if (plan.format >= 7) {
        // 8-bit to 16-bit: x257 maps 0..255 onto the full 0..65535 range.
        const Rgb8& c = cloud.colors()[i];
        store<std::uint16_t>(p + 30, static_cast<std::uint16_t>(c.r * 257));
        store<std::uint16_t>(p + 32, static_cast<std::uint16_t>(c.g * 257));
        store<std::uint16_t>(p + 34, static_cast<std::uint16_t>(c.b * 257));
    }
    if (plan.format == 8)
        store<std::uint16_t>(p + 36, clampRound<std::uint16_t>(plan.slot(Slot::Nir).get(i, 0.0)));
    for (const ExtraOutput& e : plan.extras) {
        if (e.asDouble)
            store<double>(p + e.recordOffset, e.field->value(i));
        else
            store<float>(p + e.recordOffset, e.field->values()[i]);
    }
    return returnNumber;
}

//! Every finite point's record, by chunks, plain or through the LAZ coder.
RecordTotals writeRecords(std::ofstream& stream, const PointCloud& cloud, const RecordPlan& plan, const Quantization& grid,
                          const std::optional<LazLayout>& lazLayout, ProgressTicker& ticker)
{
    RecordTotals totals;
    const Eigen::Vector3d inverseScale = grid.scale.cwiseInverse();
    const Eigen::Vector3d shift = cloud.origin() - grid.offset;
    std::optional<LazPointWriter> lazPoints;
    if (lazLayout)
        lazPoints.emplace(stream, *lazLayout, plan.recordLength);
    std::vector<char> buffer(kChunkPoints * plan.recordLength);
    const std::size_t n = cloud.size();
    for (std::size_t begin = 0; begin < n; begin += kChunkPoints) {
        const std::size_t end = std::min(n, begin + kChunkPoints);
        std::fill(buffer.begin(), buffer.end(), '\0');
        char* p = buffer.data();
        for (std::size_t i = begin; i < end; ++i) {
            if (!cloud.positions()[i].allFinite())
                continue;
            const unsigned returnNumber = fillRecord(p, cloud, i, plan, shift, inverseScale, totals);
            if (returnNumber >= 1)
                ++totals.pointsByReturn[returnNumber - 1];
            p += plan.recordLength;
        }
        if (lazPoints)
            lazPoints->add(buffer.data(), static_cast<std::size_t>(p - buffer.data()) / plan.recordLength);
        else
            stream.write(buffer.data(), p - buffer.data());
        ticker.step(end - begin);
    }
    if (lazPoints)
        lazPoints->finish();
    return totals;
}

//! The LAS 1.4 public header block, once the records are written.
struct HeaderFacts
{
    int format = 6;
    bool compressed = false;
    std::size_t recordLength = 0;
    std::uint64_t offsetToPoints = 0, finiteCount = 0, evlrStart = 0;
    std::uint32_t vlrCount = 0;
    bool hasEvlr = false;
};

void fillHeader(char* h, const HeaderFacts& facts, const Quantization& grid, const RecordTotals& totals)
{
    std::memcpy(h, "LASF", 4);
    // Global encoding: bit 4 (WKT) is required for point formats 6-10 (LAS 1.4 R15,
    // "Coordinate Reference System Representation": GeoTIFF with them is an error).
    // Bit 0: the cloud does not record the GPS time type, but times beyond one week
    // (604800 s) cannot be GPS week time, so they are adjusted standard GPS time.
    std::uint16_t globalEncoding = 1u << 4;
    if (totals.gpsMax > 604800.0)
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
    store<std::uint32_t>(h + hdr::offsetToPoints, static_cast<std::uint32_t>(facts.offsetToPoints));
    store<std::uint32_t>(h + hdr::vlrCount, facts.vlrCount);
    if (facts.hasEvlr) {
        store<std::uint64_t>(h + hdr::evlrStart, facts.evlrStart);
        store<std::uint32_t>(h + hdr::evlrCount, 1u);
    }
    // LASzip marks compressed records with bit 7 of the format.
    h[hdr::pointFormat] = static_cast<char>(facts.format | (facts.compressed ? 0x80 : 0));
    store<std::uint16_t>(h + hdr::recordLength, static_cast<std::uint16_t>(facts.recordLength));
    // Legacy point counts stay 0: LAS 1.4 R15 requires it for point formats 6 and above.
    for (int a = 0; a < 3; ++a) {
        store<double>(h + hdr::scale + 8 * a, grid.scale[a]);
        store<double>(h + hdr::offset + 8 * a, grid.offset[a]);
        // The extents of the stored (quantised) coordinates; zero without points.
        const double lo = facts.finiteCount ? totals.rawMin[a] * grid.scale[a] + grid.offset[a] : 0.0;
        const double hi = facts.finiteCount ? totals.rawMax[a] * grid.scale[a] + grid.offset[a] : 0.0;
        store<double>(h + hdr::bounds + 16 * a, hi);
        store<double>(h + hdr::bounds + 16 * a + 8, lo);
    }
    store<std::uint64_t>(h + hdr::pointCount, facts.finiteCount);
    for (std::size_t r = 0; r < totals.pointsByReturn.size(); ++r)
        store<std::uint64_t>(h + hdr::pointsByReturn + 8 * r, totals.pointsByReturn[r]);
}

} // namespace

void writeLas(const PointCloud& cloud, const fs::path& path, const WriteOptions& options, bool compressed)
{
    HeaderFacts facts;
    facts.compressed = compressed;
    for (const auto& p : cloud.positions())
        facts.finiteCount += p.allFinite() ? 1 : 0;
    if (facts.finiteCount != cloud.size())
        logWarning(path.string() + ": " + std::to_string(cloud.size() - facts.finiteCount) +
                   " points with non-finite coordinates were not written");
    const RecordPlan plan = planRecords(cloud, path);
    facts.format = plan.format;
    facts.recordLength = plan.recordLength;

    // The variable-length records: the extra dimensions, the coordinate
    // reference system as an OGC WKT record, NUL-terminated (one too long for
    // a VLR's 16-bit length goes into an EVLR after the points), and for LAZ
    // the LASzip record describing the compressed records.
    std::string vlr;
    if (!plan.extras.empty()) {
        vlr += extraBytesRecord(plan.extras);
        ++facts.vlrCount;
    }
    std::string crsRecord;
    if (!cloud.crsWkt().empty()) {
        const std::string wkt = cloud.crsWkt() + '\0';
        if (wkt.size() > std::numeric_limits<std::uint16_t>::max()) {
            crsRecord = variableLengthRecord("LASF_Projection", 2112, "OGC coordinate system WKT", wkt, true);
        } else {
            vlr += variableLengthRecord("LASF_Projection", 2112, "OGC coordinate system WKT", wkt, false);
            ++facts.vlrCount;
        }
    }
    std::optional<LazLayout> lazLayout;
    if (compressed) {
        lazLayout = lazLayoutForFormat(plan.format, plan.recordLength - plan.baseSize);
        vlr += variableLengthRecord(kLaszipUserId, kLaszipRecordId, "by scandiff, LASzip compatible", lazRecordPayload(*lazLayout), false);
        ++facts.vlrCount;
    }
    const Quantization grid = chooseGrid(cloud, path);

    AtomicFile output(path);
    std::ofstream& stream = output.stream();
    facts.offsetToPoints = kHeaderSize14 + vlr.size();
    // The header is written again at the end, with the extents and return counts.
    std::array<char, kHeaderSize14> header{};
    stream.write(header.data(), header.size());
    stream.write(vlr.data(), static_cast<std::streamsize>(vlr.size()));
    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), cloud.size());
    const RecordTotals totals = writeRecords(stream, cloud, plan, grid, lazLayout, ticker);
    facts.evlrStart = static_cast<std::uint64_t>(stream.tellp());
    facts.hasEvlr = !crsRecord.empty();
    stream.write(crsRecord.data(), static_cast<std::streamsize>(crsRecord.size()));
    fillHeader(header.data(), facts, grid, totals);
    stream.seekp(0);
    stream.write(header.data(), header.size());
    output.commit();
}

} // namespace scandiff::io::detail::las
