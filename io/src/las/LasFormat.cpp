// SPDX-License-Identifier: GPL-3.0-or-later
//! LAS: reads LAS 1.0-1.4 (point data record formats 0-10) straight from a
//! memory map, or, when the points are LAZ, from each chunk's records as
//! LazDecoder.cpp's workers decompress them (LasWriter.cpp writes them).
//!
//! Layout facts quoted below come from the ASPRS LAS 1.4 specification, R15
//! ("LAS 1.4 R15"), which also describes the older versions this reader accepts.

#include "internal/Formats.h"
#include "las/LasHeader.h"
#include "las/LasLayout.h"
#include "laz/LazDecoder.h"
#include "internal/MappedFile.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/Progress.h>
#include <scandiff/io/CoordinateSystem.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

namespace scandiff::io::detail {

namespace {

namespace fs = std::filesystem;
using namespace las;

// ---------------------------------------------------------------------------
// Point decoding.

//! Where the decoder puts each attribute; null when the format lacks it.
struct PointOutputs
{
    Eigen::Vector3f* positions = nullptr;
    //! What the floats miss of the grid's coordinates, when the cloud keeps it.
    Eigen::Vector3f* positionResiduals = nullptr;
    Rgb8* colors = nullptr;
    float* intensity = nullptr;
    float* returnNumber = nullptr;
    float* numberOfReturns = nullptr;
    float* classification = nullptr;
    float* classificationFlags = nullptr;
    float* scannerChannel = nullptr;
    float* scanDirectionFlag = nullptr;
    float* edgeOfFlightLine = nullptr;
    float* scanAngle = nullptr;
    float* userData = nullptr;
    float* pointSourceId = nullptr;
    float* gpsTime = nullptr;
    //! The times' exact form: float residuals beside the floats.
    float* gpsTimeResidual = nullptr;
    double gpsTimeOffset = 0.0;
    float* nir = nullptr;
};

//! What a run of records tells about the whole file.
struct DecodedFacts
{
    //! Bitwise OR of every colour channel: tells whether any exceeds 255.
    unsigned colorBits = 0;
    //! A time the residuals cannot give back (the reader then reads the times as doubles).
    bool gpsTimeResidualFailed = false;
};

struct CoordinateTransform
{
    Eigen::Vector3d scale;
    Eigen::Vector3d shift; // header offset - cloud origin
};

// One instantiation per family of formats, so the per-point loop has no
// branches on the format and all field offsets are constants.
//   Extended: formats 6-10; otherwise the legacy formats 0-5 (LAS 1.4 R15,
//   "Point Data Record Format 0" to "10").
//! Decodes `count` records into the outputs' points [at, at + count).
template <bool Extended, bool HasGpsTime, bool HasRgb, bool HasNir>
DecodedFacts decodeRange(const char* records, std::size_t recordLength, std::size_t count, std::size_t at,
                         const CoordinateTransform& transform, const PointOutputs& out)
{
    constexpr std::size_t gpsOffset = Extended ? 22 : 20;
    constexpr std::size_t rgbOffset = Extended ? 30 : (HasGpsTime ? 28 : 20);
    constexpr std::size_t nirOffset = 36;
    const double sx = transform.scale.x(), sy = transform.scale.y(), sz = transform.scale.z();
    const double tx = transform.shift.x(), ty = transform.shift.y(), tz = transform.shift.z();
    DecodedFacts facts;
    unsigned colorBits = 0;
    const char* p = records;
    for (std::size_t i = at; i < at + count; ++i, p += recordLength) {
        // A field the reader left out (known to be 0 everywhere, see readLas)
        // has no array: the branch goes the same way at every point.
        auto put = [i](float* field, float value) {
            if (field)
                field[i] = value;
        };
        const Eigen::Vector3d local(load<std::int32_t>(p) * sx + tx, load<std::int32_t>(p + 4) * sy + ty,
                                    load<std::int32_t>(p + 8) * sz + tz);
        out.positions[i] = local.cast<float>();
        if (out.positionResiduals)
            out.positionResiduals[i] = (local - out.positions[i].cast<double>()).cast<float>();
        put(out.intensity, load<std::uint16_t>(p + 12));
        const auto returns = static_cast<unsigned char>(p[14]);
        if constexpr (Extended) {
            // Byte 14: return number (bits 0-3), number of returns (4-7).
            // Byte 15: classification flags (0-3: synthetic, key-point, withheld,
            // overlap), scanner channel (4-5), scan direction (6), edge of flight line (7).
            const auto flags = static_cast<unsigned char>(p[15]);
            put(out.returnNumber, returns & 0x0F);
            put(out.numberOfReturns, returns >> 4);
            put(out.classificationFlags, flags & 0x0F);
            put(out.scannerChannel, (flags >> 4) & 0x03);
            put(out.scanDirectionFlag, (flags >> 6) & 0x01);
            put(out.edgeOfFlightLine, flags >> 7);
            put(out.classification, static_cast<unsigned char>(p[16]));
            put(out.userData, static_cast<unsigned char>(p[17]));
            // Scan angle: int16 in units of 0.006 degree.
            put(out.scanAngle, static_cast<float>(load<std::int16_t>(p + 18) * 0.006));
            put(out.pointSourceId, load<std::uint16_t>(p + 20));
        } else {
            // Byte 14: return number (bits 0-2), number of returns (3-5), scan
            // direction (6), edge of flight line (7). Byte 15: classification
            // (bits 0-4), synthetic (5), key-point (6), withheld (7); the flags are
            // stored as bits 0-2 of classification_flags, as in formats 6-10.
            const auto classByte = static_cast<unsigned char>(p[15]);
            put(out.returnNumber, returns & 0x07);
            put(out.numberOfReturns, (returns >> 3) & 0x07);
            put(out.scanDirectionFlag, (returns >> 6) & 0x01);
            put(out.edgeOfFlightLine, returns >> 7);
            put(out.classification, classByte & 0x1F);
            put(out.classificationFlags, classByte >> 5);
            // Scan angle rank: int8, whole degrees.
            put(out.scanAngle, static_cast<signed char>(p[16]));
            put(out.userData, static_cast<unsigned char>(p[17]));
            put(out.pointSourceId, load<std::uint16_t>(p + 18));
        }
        if constexpr (HasGpsTime) {
            if (out.gpsTime) {
                const double time = load<double>(p + gpsOffset);
                const auto f = static_cast<float>(time - out.gpsTimeOffset);
                out.gpsTime[i] = f;
                out.gpsTimeResidual[i] = ScalarField::residualOf(time, out.gpsTimeOffset, f);
                if (!ScalarField::residualHolds(time, out.gpsTimeOffset))
                    facts.gpsTimeResidualFailed = true;
            }
        }
        if constexpr (HasRgb) {
            const unsigned r = load<std::uint16_t>(p + rgbOffset);
            const unsigned g = load<std::uint16_t>(p + rgbOffset + 2);
            const unsigned b = load<std::uint16_t>(p + rgbOffset + 4);
            colorBits |= r | g | b;
            // 65535 / 257 = 255: the exact inverse of the x257 scaling of the writer.
            out.colors[i] = Rgb8{static_cast<std::uint8_t>((r + 128) / 257), static_cast<std::uint8_t>((g + 128) / 257),
                                 static_cast<std::uint8_t>((b + 128) / 257)};
        }
        if constexpr (HasNir)
            put(out.nir, load<std::uint16_t>(p + nirOffset));
    }
    facts.colorBits = colorBits;
    return facts;
}

using DecodeFunction = DecodedFacts (*)(const char*, std::size_t, std::size_t, std::size_t, const CoordinateTransform&,
                                        const PointOutputs&);

DecodeFunction decoderFor(int format)
{
    switch (format) {
    case 0: return &decodeRange<false, false, false, false>;
    case 1: case 4: return &decodeRange<false, true, false, false>;
    case 2: return &decodeRange<false, false, true, false>;
    case 3: case 5: return &decodeRange<false, true, true, false>;
    case 6: case 9: return &decodeRange<true, true, false, false>;
    case 7: return &decodeRange<true, true, true, false>;
    case 8: case 10: return &decodeRange<true, true, true, true>;
    default: return nullptr;
    }
}

bool formatHasGpsTime(int format) { return format != 0 && format != 2; }
bool formatHasRgb(int format)
{
    return format == 2 || format == 3 || format == 5 || format == 7 || format == 8 || format == 10;
}
bool formatHasNir(int format) { return format == 8 || format == 10; }
std::size_t rgbOffsetOf(int format) { return format >= 6 ? 30 : (formatHasGpsTime(format) ? 28 : 20); }

// A field offset that keeps float32 precision for values far from zero (large
// integers, times, anything scaled): the first finite value, rounded down.
double offsetForValues(double firstValue)
{
    if (!std::isfinite(firstValue) || std::abs(firstValue) < 1e4)
        return 0.0;
    return std::floor(firstValue);
}

//! One Extra Bytes value of each of `count` records, as a double (NaN for
//! the dimension's no_data), or as a float where a float holds each exactly.
template <class T, class Out>
void extractExtra(const char* records, std::size_t recordLength, std::size_t count, const ExtraDimension& dim, Out* out)
{
    // The no_data value is stored upcast to 8 bytes: double for floats, 64-bit
    // integers otherwise (LAS 1.4 R15, Extra Bytes).
    using Upcast = std::conditional_t<std::is_floating_point_v<T>, double,
                                      std::conditional_t<std::is_signed_v<T>, std::int64_t, std::uint64_t>>;
    Upcast noData{};
    std::memcpy(&noData, &dim.noDataBits, sizeof noData);
    const char* p = records + dim.recordOffset;
    for (std::size_t i = 0; i < count; ++i, p += recordLength) {
        const auto raw = load<T>(p);
        out[i] = static_cast<Out>(dim.hasNoData && static_cast<Upcast>(raw) == noData
                                      ? std::numeric_limits<double>::quiet_NaN()
                                      : static_cast<double>(raw) * dim.scale + dim.offset);
    }
}

template <class Out>
void extractExtraOfType(const char* records, std::size_t recordLength, std::size_t count, const ExtraDimension& dim, Out* out)
{
    switch (dim.type) {
    case 1: extractExtra<std::uint8_t>(records, recordLength, count, dim, out); break;
    case 2: extractExtra<std::int8_t>(records, recordLength, count, dim, out); break;
    case 3: extractExtra<std::uint16_t>(records, recordLength, count, dim, out); break;
    case 4: extractExtra<std::int16_t>(records, recordLength, count, dim, out); break;
    case 5: extractExtra<std::uint32_t>(records, recordLength, count, dim, out); break;
    case 6: extractExtra<std::int32_t>(records, recordLength, count, dim, out); break;
    case 7: extractExtra<std::uint64_t>(records, recordLength, count, dim, out); break;
    case 8: extractExtra<std::int64_t>(records, recordLength, count, dim, out); break;
    case eb::typeFloat: extractExtra<float>(records, recordLength, count, dim, out); break;
    case eb::typeDouble: extractExtra<double>(records, recordLength, count, dim, out); break;
    default: break;
    }
}

//! Fills the field of one Extra Bytes dimension from runs of records taken in
//! any order (a LAZ file's chunks as the workers decode them), each run
//! once. A value a float holds exactly (a plain integer of up to 16 bits, a
//! plain float) goes straight to the float view; any other is kept as a
//! double until finish() has every value: the field's offset comes from the
//! first value of the read, so that a float around it keeps large values
//! (times, identifiers) precisely, and the doubles stay only where the floats
//! do not give every value back.
class ExtraFieldFiller
{
public:
    ExtraFieldFiller(const ExtraDimension& dim, ScalarField& field) : dim_(dim), field_(field)
    {
        const bool plain = dim.scale == 1.0 && dim.offset == 0.0;
        const bool fitsFloat = plain && (dim.type <= 4 || dim.type == eb::typeFloat);
        floats_ = field.values().data();
        if (!fitsFloat) {
            field.keepDoubles();
            doubles_ = field.doubles().data();
        }
    }

    //! The values of `count` records, for the points from `at`.
    void fill(const char* records, std::size_t recordLength, std::size_t count, std::size_t at) const
    {
        if (doubles_)
            extractExtraOfType(records, recordLength, count, dim_, doubles_ + at);
        else
            extractExtraOfType(records, recordLength, count, dim_, floats_ + at);
    }

    void finish()
    {
        if (!doubles_)
            return;
        const std::size_t count = field_.size();
        const double* first = std::find_if(doubles_, doubles_ + count, [](double v) { return std::isfinite(v); });
        const double offset = offsetForValues(first == doubles_ + count ? std::numeric_limits<double>::quiet_NaN() : *first);
        field_.setOffset(offset);
        for (std::size_t i = 0; i < count; ++i)
            floats_[i] = static_cast<float>(doubles_[i] - offset);
        field_.compact(dim_.type == eb::typeDouble);
    }

private:
    const ExtraDimension& dim_;
    ScalarField& field_;
    float* floats_ = nullptr;
    double* doubles_ = nullptr;
};

// The cloud origin: the caller's, else the header offset (the "global shift"
// the producer chose) unless the data lie far from it, where float32 would
// lose millimetres (e.g. an offset of 0 for UTM coordinates).
Eigen::Vector3d chooseOrigin(const LasHeader& h, const char* firstRecord, const ReadOptions& options)
{
    if (options.origin)
        return *options.origin;
    BoundingBox box;
    const bool headerBoundsUsable = h.min.allFinite() && h.max.allFinite() && (h.min.array() <= h.max.array()).all() &&
                                    !(h.min.isZero() && h.max.isZero());
    if (headerBoundsUsable) {
        box.min = h.min;
        box.max = h.max;
        box.empty = false;
    } else if (h.pointCount > 0 && firstRecord) {
        // Bounds missing: the first point stands for the data.
        Eigen::Vector3d first;
        for (int a = 0; a < 3; ++a)
            first[a] = load<std::int32_t>(firstRecord + 4 * a) * h.scale[a] + h.offset[a];
        box.min = box.max = first;
        box.empty = false;
    }
    if (box.empty)
        return h.offset;
    const double reach =
        std::max((box.min - h.offset).cwiseAbs().maxCoeff(), (box.max - h.offset).cwiseAbs().maxCoeff());
    // Same threshold as suggestOrigin(): below 1e4 m float32 keeps sub-millimetre steps.
    if (reach < 1e4)
        return h.offset;
    return suggestOrigin(box);
}

//! An Extra Bytes dimension's field name: its own unless the cloud has that
//! field or it is one of the format's standard attributes (`standard`), made
//! or not. Then a suffix: the name does not depend on which standard fields
//! the points leave at 0, and a field made later (the LAZ scanner channel)
//! never meets it.
std::string uniqueFieldName(const PointCloud& cloud, std::string name, const std::vector<std::string>& standard)
{
    if (name.empty())
        name = "extra";
    if (!cloud.field(name) && std::find(standard.begin(), standard.end(), name) == standard.end())
        return name;
    for (int k = 2;; ++k) {
        std::string candidate = name + "_" + std::to_string(k);
        if (!cloud.field(candidate))
            return candidate;
    }
}

//! The fields of a point format's standard attributes, in the cloud's order.
std::vector<std::string> standardFieldNames(int format)
{
    std::vector<std::string> names = {"intensity",           "return_number", "number_of_returns", "classification",
                                      "classification_flags", "scan_direction_flag", "edge_of_flight_line", "scan_angle",
                                      "user_data",           "point_source_id"};
    if (format >= 6)
        names.emplace_back("scanner_channel");
    if (formatHasGpsTime(format))
        names.emplace_back("gps_time");
    if (formatHasNir(format))
        names.emplace_back("nir");
    return names;
}

//! Whether the bits of standard field `name` of a record of `format` are all
//! set in `zeroBits` (a mask over the record: set where the bit is 0 in every
//! record).
bool fieldIsZeroIn(const std::vector<std::uint8_t>& zeroBits, int format, const std::string& name)
{
    struct Bits
    {
        const char* name;
        std::size_t first, last; // bytes
        std::uint8_t mask;
    };
    // LAS 1.4 R15, "Point Data Record Format 0" to "10" (as decodeRange reads them).
    static const Bits kExtended[] = {
        {"intensity", 12, 13, 0xFF},          {"return_number", 14, 14, 0x0F},     {"number_of_returns", 14, 14, 0xF0},
        {"classification_flags", 15, 15, 0x0F}, {"scanner_channel", 15, 15, 0x30}, {"scan_direction_flag", 15, 15, 0x40},
        {"edge_of_flight_line", 15, 15, 0x80}, {"classification", 16, 16, 0xFF},  {"user_data", 17, 17, 0xFF},
        {"scan_angle", 18, 19, 0xFF},         {"point_source_id", 20, 21, 0xFF},  {"gps_time", 22, 29, 0xFF},
        {"nir", 36, 37, 0xFF}};
    static const Bits kLegacy[] = {
        {"intensity", 12, 13, 0xFF},        {"return_number", 14, 14, 0x07},        {"number_of_returns", 14, 14, 0x38},
        {"scan_direction_flag", 14, 14, 0x40}, {"edge_of_flight_line", 14, 14, 0x80}, {"classification", 15, 15, 0x1F},
        {"classification_flags", 15, 15, 0xE0}, {"scan_angle", 16, 16, 0xFF},       {"user_data", 17, 17, 0xFF},
        {"point_source_id", 18, 19, 0xFF},  {"gps_time", 20, 27, 0xFF}};
    auto zeroIn = [&](const auto& fields) {
        for (const Bits& field : fields) {
            if (name != field.name)
                continue;
            for (std::size_t b = field.first; b <= field.last; ++b)
                if (b >= zeroBits.size() || (zeroBits[b] & field.mask) != field.mask)
                    return false;
            return true;
        }
        return false;
    };
    return format >= 6 ? zeroIn(kExtended) : zeroIn(kLegacy);
}

//! The bits that are 0 in every one of `count` uncompressed records (a mask
//! over the record, as lazBitsZeroInEveryRecord gives for LAZ), read in
//! blocks on every core. Stops early once none of `names` can be 0
//! everywhere any more, as in most files after the first block; throws
//! Error(Cancelled) between blocks if the ticker's observer asks.
std::vector<std::uint8_t> lasBitsZeroInEveryRecord(const char* records, std::size_t count, std::size_t recordLength,
                                                   int format, const std::vector<std::string>& names,
                                                   const ProgressTicker& ticker)
{
    if (count == 0)
        return std::vector<std::uint8_t>(recordLength, 0); // no record tells anything: every field is kept, empty
    std::vector<std::uint8_t> seen(recordLength, 0); // bits set in some record
    std::mutex seenMutex;
    std::atomic<bool> settled{false};
    auto zeroBits = [&] {
        std::vector<std::uint8_t> zero(recordLength);
        for (std::size_t b = 0; b < recordLength; ++b)
            zero[b] = static_cast<std::uint8_t>(~seen[b]);
        return zero;
    };
    const std::size_t blocks = (count + kChunkPoints - 1) / kChunkPoints;
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t block) {
        if (settled.load(std::memory_order_relaxed))
            return;
        ticker.checkCancel(); // a file of 100 M points takes seconds
        const std::size_t begin = block * kChunkPoints, end = std::min(count, begin + kChunkPoints);
        // The standard fields lie in bytes 12 to 37 (every record has 20
        // bytes at least): 8-byte words while the record holds them, then
        // single bytes, ORed over the block.
        const std::size_t wordsEnd = recordLength >= 28 ? 28 : 20, end38 = std::min<std::size_t>(recordLength, 38);
        std::uint64_t words[2] = {};
        std::uint8_t tail[18] = {};
        const char* const stop = records + end * recordLength;
        for (const char* p = records + begin * recordLength; p < stop; p += recordLength) {
            words[0] |= load<std::uint64_t>(p + 12);
            if (wordsEnd == 28)
                words[1] |= load<std::uint64_t>(p + 20);
            for (std::size_t b = wordsEnd; b < end38; ++b)
                tail[b - wordsEnd] |= static_cast<std::uint8_t>(p[b]);
        }
        // The pages stay mapped for the parse, which releases them as it
        // goes: giving them back here and mapping them again cost 0.17 s of
        // 0.59 on 10 M points (page faults are dear on this virtual machine),
        // for a peak of 350 MiB instead of 687 (655 before the fields 0
        // everywhere were left out).
        const std::lock_guard<std::mutex> lock(seenMutex);
        for (std::size_t b = 0; b < 8; ++b) {
            seen[12 + b] |= static_cast<std::uint8_t>(words[0] >> (8 * b));
            if (wordsEnd == 28)
                seen[20 + b] |= static_cast<std::uint8_t>(words[1] >> (8 * b));
        }
        for (std::size_t b = wordsEnd; b < end38; ++b)
            seen[b] |= tail[b - wordsEnd];
        const std::vector<std::uint8_t> zero = zeroBits();
        if (std::none_of(names.begin(), names.end(), [&](const std::string& name) { return fieldIsZeroIn(zero, format, name); }))
            settled = true;
    });
    // Bytes 0 to 11 (the coordinates) and past 37 are not looked at: no field
    // is left out for them.
    std::vector<std::uint8_t> zero = zeroBits();
    std::fill(zero.begin(), zero.begin() + 12, 0);
    if (recordLength > 38)
        std::fill(zero.begin() + 38, zero.end(), 0);
    return zero;
}

//! The LASzip record of a LAZ file.
LazLayout findLazLayout(const MappedFile& file, const LasHeader& h)
{
    const fs::path& path = file.path();
    std::optional<LazLayout> layout;
    forEachRecord(file, h, false, [&](const std::string& user, std::uint16_t id, const char* payload, std::size_t length) {
        if (user != kLaszipUserId || id != kLaszipRecordId)
            return false;
        layout = parseLazLayout(path, payload, length, h.recordLength);
        return true;
    });
    if (!layout)
        invalid(path, "the point format (byte 104) says the points are compressed (LAZ), but there is no LASzip record "
                      "(user id 'laszip encoded', record 22204)");
    return *layout;
}

//! Offset of a format's GPS time in its records.
std::size_t gpsTimeOffsetOf(int format) { return format >= 6 ? 22 : 20; }

//! Colours of 8-bit files: LAS 1.4 R15 says colours are normalised to 16
//! bits, but several tools write 8-bit values unscaled. If no channel exceeds
//! 255 the file is of that kind (genuine 16-bit colours that low would all be
//! black), so its colours are taken as they are.
void takeColorsUnscaled(const char* records, std::size_t recordLength, int format, std::size_t count, Rgb8* colors)
{
    const char* p = records + rgbOffsetOf(format);
    for (std::size_t i = 0; i < count; ++i, p += recordLength)
        colors[i] = Rgb8{static_cast<std::uint8_t>(p[0]), static_cast<std::uint8_t>(p[2]), static_cast<std::uint8_t>(p[4])};
}

//! The points of a LAS file's records, mapped in memory.
void parseRecordsInMemory(const LasHeader& h, const char* records, std::size_t count,
                          const CoordinateTransform& transform, const PointOutputs& out,
                          const std::vector<ExtraFieldFiller>& extras, PointCloud& cloud, ProgressTicker& ticker)
{
    const DecodeFunction decode = decoderFor(h.pointFormat);
    // Blocks of records on every core, as the LAZ workers parse their chunks.
    std::atomic<unsigned> colorBits{0};
    std::atomic<bool> gpsTimeResidualFailed{false};
    const std::size_t blocks = (count + kChunkPoints - 1) / kChunkPoints;
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t block) {
        const std::size_t begin = block * kChunkPoints, end = std::min(count, begin + kChunkPoints);
        const DecodedFacts some = decode(records + begin * h.recordLength, h.recordLength, end - begin, begin, transform, out);
        colorBits.fetch_or(some.colorBits, std::memory_order_relaxed);
        if (some.gpsTimeResidualFailed)
            gpsTimeResidualFailed = true;
        for (const ExtraFieldFiller& extra : extras)
            extra.fill(records + begin * h.recordLength, h.recordLength, end - begin, begin);
        MappedFile::releaseConsumed(records + begin * h.recordLength, records + end * h.recordLength);
        ticker.step(end - begin);
    });
    DecodedFacts facts;
    facts.colorBits = colorBits.load();
    facts.gpsTimeResidualFailed = gpsTimeResidualFailed.load();
    if (facts.gpsTimeResidualFailed) {
        // Times the residuals cannot hold (far from the offset, or not times at
        // all): read again as doubles.
        ScalarField& time = *cloud.field("gps_time");
        time.keepDoubles();
        const char* p = records + gpsTimeOffsetOf(h.pointFormat);
        for (std::size_t i = 0; i < count; ++i, p += h.recordLength)
            time.doubles()[i] = load<double>(p);
    }
    if (out.colors && facts.colorBits <= 255)
        takeColorsUnscaled(records, h.recordLength, h.pointFormat, count, out.colors);
}

//! The points of the LAZ records [first, first + count), parsed by the
//! workers as they decode each chunk, Extra Bytes included: no buffer of
//! every record (a file of 10 M points in format 7 would need 360 MB more)
//! and both cores parse.
//! With `channel`, the scanner channel is made there once a chunk has a
//! point of a channel other than 0 (see readLas), else left out.
void parseLazRecords(const MappedFile& file, const LasHeader& h, const LazLayout& layout,
                     const std::vector<LazChunk>& chunks, std::uint64_t first, std::size_t count,
                     const CoordinateTransform& transform, const PointOutputs& out,
                     const std::vector<ExtraFieldFiller>& extras, PointCloud& cloud, ProgressTicker& ticker,
                     std::optional<ScalarField>* channel)
{
    const DecodeFunction decode = decoderFor(h.pointFormat);
    std::once_flag channelMade;
    std::atomic<unsigned> colorBits{0};
    std::atomic<bool> gpsTimeResidualFailed{false};
    // Runs of points whose colours were taken as 8-bit values because none of
    // their channels exceeds 255; scaled back if another chunk has a channel
    // above 255. Exact: a run's 8-bit value c is its 16-bit value.
    std::mutex runsMutex;
    std::vector<std::pair<std::size_t, std::size_t>> unscaledRuns;
    decompressLazRecords(
        file.path(), file.data(), file.size(), chunks, layout, h.recordLength, first, count,
        [&](std::uint64_t firstPoint, const char* records, std::size_t n) {
            const auto at = static_cast<std::size_t>(firstPoint - first);
            PointOutputs chunkOut = out;
            if (channel) {
                // Bits 4-5 of byte 15 (formats 6-10).
                unsigned bits = 0;
                for (std::size_t i = 0; i < n; ++i)
                    bits |= static_cast<unsigned char>(records[i * h.recordLength + 15]);
                if (bits & 0x30) {
                    std::call_once(channelMade, [&] {
                        // Zeros: the chunks parsed before had channel 0.
                        try {
                            channel->emplace("scanner_channel");
                            (*channel)->values().assign(count, 0.0f);
                        } catch (const std::bad_alloc&) {
                            throw Error(ErrorCode::Io, file.path().string() + ": not enough memory for the scanner channel of " +
                                                           std::to_string(count) + " points");
                        }
                    });
                    chunkOut.scannerChannel = (*channel)->values().data();
                }
            }
            const DecodedFacts facts = decode(records, h.recordLength, n, at, transform, chunkOut);
            for (const ExtraFieldFiller& extra : extras)
                extra.fill(records, h.recordLength, n, at);
            colorBits.fetch_or(facts.colorBits, std::memory_order_relaxed);
            if (facts.gpsTimeResidualFailed)
                gpsTimeResidualFailed = true;
            if (out.colors && facts.colorBits <= 255) {
                takeColorsUnscaled(records, h.recordLength, h.pointFormat, n, out.colors + at);
                const std::lock_guard<std::mutex> lock(runsMutex);
                unscaledRuns.emplace_back(at, n);
            }
        },
        [&](std::size_t points) { ticker.step(points); });
    if (out.colors && colorBits.load() > 255) {
        // 65535 / 257 = 255: the exact inverse of the x257 scaling of the writer.
        auto scaled = [](std::uint8_t c) { return static_cast<std::uint8_t>((c + 128) / 257); };
        for (const auto& [at, n] : unscaledRuns)
            for (std::size_t i = at; i < at + n; ++i)
                out.colors[i] = Rgb8{scaled(out.colors[i].r), scaled(out.colors[i].g), scaled(out.colors[i].b)};
    }
    if (gpsTimeResidualFailed) {
        // Times the residuals cannot hold: decoded again, kept as doubles.
        ScalarField& time = *cloud.field("gps_time");
        time.keepDoubles();
        double* doubles = time.doubles().data();
        const std::size_t offset = gpsTimeOffsetOf(h.pointFormat);
        decompressLazRecords(
            file.path(), file.data(), file.size(), chunks, layout, h.recordLength, first, count,
            [&](std::uint64_t firstPoint, const char* records, std::size_t n) {
                for (std::size_t i = 0; i < n; ++i)
                    doubles[firstPoint - first + i] = load<double>(records + i * h.recordLength + offset);
            },
            [](std::size_t) {});
    }
}

//! Whether a float around `origin` can miss the file's grid by half a step or
//! more somewhere in the file's box (then the reader keeps each point's
//! residual, see PointCloud::positionResiduals): a float's rounding at a
//! distance d from the origin is at most d / 2^24. A box the header does not
//! give (non-finite, inverted) is taken as the worst case.
bool floatsMissTheGrid(const LasHeader& h, const Eigen::Vector3d& origin)
{
    // A box of zeros is one the writer left unset (chooseOrigin reads it so too).
    if (h.min.isZero() && h.max.isZero())
        return true;
    for (int a = 0; a < 3; ++a) {
        if (!(std::isfinite(h.min[a]) && std::isfinite(h.max[a]) && h.min[a] <= h.max[a]))
            return true;
        const double reach = std::max(std::abs(h.min[a] - origin[a]), std::abs(h.max[a] - origin[a]));
        // A quarter step: the header's box may be rounded, the test stays on the safe side.
        if (reach * 0x1p-24 >= 0.25 * std::abs(h.scale[a]))
            return true;
    }
    return false;
}

//! The whole file, or with `range` the records of that range (a LAZ file's
//! chunks that hold them are decoded whole).
//! Where the parse writes each attribute: the cloud's arrays, null for a
//! field not made.
PointOutputs pointOutputs(PointCloud& cloud, double gpsTimeOffset)
{
    auto values = [&](const char* name) {
        ScalarField* f = cloud.field(name);
        return f ? f->values().data() : nullptr;
    };
    PointOutputs out;
    out.positions = cloud.positions().data();
    if (!cloud.positionResiduals().empty())
        out.positionResiduals = cloud.positionResiduals().data();
    out.colors = cloud.hasColors() ? cloud.enableColors().data() : nullptr;
    out.intensity = values("intensity");
    out.returnNumber = values("return_number");
    out.numberOfReturns = values("number_of_returns");
    out.classification = values("classification");
    out.classificationFlags = values("classification_flags");
    out.scannerChannel = values("scanner_channel");
    out.scanDirectionFlag = values("scan_direction_flag");
    out.edgeOfFlightLine = values("edge_of_flight_line");
    out.scanAngle = values("scan_angle");
    out.userData = values("user_data");
    out.pointSourceId = values("point_source_id");
    out.gpsTime = values("gps_time");
    if (ScalarField* time = cloud.field("gps_time"))
        out.gpsTimeResidual = time->residuals().data();
    out.gpsTimeOffset = gpsTimeOffset;
    out.nir = values("nir");
    return out;
}

//! A standard field made late (the scanner channel of a LAZ file) at its
//! place among the others, as the LAS reader has it.
void insertAmongStandardFields(PointCloud& cloud, ScalarField field, const std::vector<std::string>& standardNames)
{
    const auto rank = std::find(standardNames.begin(), standardNames.end(), field.name()) - standardNames.begin();
    std::size_t position = 0;
    while (position < cloud.fields().size()) {
        const auto other = std::find(standardNames.begin(), standardNames.end(), cloud.fields()[position].name());
        if (other == standardNames.end() || other - standardNames.begin() > rank)
            break;
        ++position;
    }
    cloud.addField(std::move(field), position);
}

//! A standard attribute that is 0 for every point (user_data, scanner_channel,
//! flags... in most files) carries nothing: dropping it saves 4 bytes per point
//! each, and writing LAS again puts 0 in its slot all the same. Extra Bytes
//! are the user's own dimensions and always kept.
void dropEmptyStandardFields(PointCloud& cloud, const std::vector<std::string>& extraNames)
{
    std::vector<std::string> empty;
    for (const ScalarField& f : cloud.fields())
        if (std::find(extraNames.begin(), extraNames.end(), f.name()) == extraNames.end() && f.isZeroEverywhere())
            empty.push_back(f.name());
    for (const std::string& name : empty)
        cloud.removeField(name);
}

Entity readLas(const fs::path& path, const ReadOptions& options, std::optional<RecordRange> range = std::nullopt)
{
    MappedFile file(path);
    const LasHeader h = parseHeader(file);
    const std::uint64_t first = range ? std::min(range->first, h.pointCount) : 0;
    const std::size_t count = static_cast<std::size_t>(range ? std::min(range->count, h.pointCount - first) : h.pointCount);
    const int format = h.pointFormat;
    std::vector<ExtraDimension> extras = findExtraDimensions(file, h);
    const std::optional<LazLayout> layout = h.compressed ? std::optional<LazLayout>(findLazLayout(file, h)) : std::nullopt;
    // The chunk table vouches for the header's count before anything is allocated for it.
    const std::vector<LazChunk> chunks =
        h.compressed ? readLazChunks(path, file.data(), file.size(), h.offsetToPoints, *layout, h.recordLength, h.pointCount)
                     : std::vector<LazChunk>();
    // LAZ is parsed chunk by chunk as the workers decode the chunks.
    const char* records = h.compressed ? nullptr : file.data() + h.offsetToPoints + first * h.recordLength;
    const char* firstRecordOfFile = file.data() + h.offsetToPoints;
    if (h.compressed) {
        // The first record of the first chunk is stored as is.
        const std::uint64_t at = lazFirstRecordOffset(*layout, h.offsetToPoints, h.recordLength, file.size());
        firstRecordOfFile = at ? file.data() + at : nullptr;
    }

    PointCloud cloud;
    cloud.setOrigin(chooseOrigin(h, firstRecordOfFile, options));
    cloud.setSourceGrid(CoordinateGrid{h.offset, h.scale});
    cloud.setCrsWkt(findCrs(file, h));
    double gpsTimeOffset = 0.0;
    // A LAZ range's own first record is not at hand before decoding: its
    // times are kept relative to the file's first.
    const char* timeRecord = h.compressed ? firstRecordOfFile : records;
    if (formatHasGpsTime(format) && count > 0 && timeRecord) {
        // Relative to the first time, float32 keeps 1 µs over ±8 s and 61 µs over
        // ±17 minutes of a ~1e9 s GPS time, which on its own would keep only 64 s.
        gpsTimeOffset = std::floor(load<double>(timeRecord + gpsTimeOffsetOf(format)));
        if (!std::isfinite(gpsTimeOffset))
            gpsTimeOffset = 0.0;
    }
    // From here on, so that the read of the records that finds the fields
    // 0 everywhere can be cancelled too.
    ProgressTicker ticker(options.progress, "Reading " + path.filename().string(), count);
    std::vector<std::string> extraNames;
    std::vector<ExtraFieldFiller> extraFillers;
    // When the scanner channel is left to the parse to make (LAZ): made or not.
    bool channelDeferred = false;
    std::optional<ScalarField> deferredChannel;
    const std::vector<std::string> standardNames = standardFieldNames(format);
    try {
        // A fresh array's pages are zeroed by the kernel as they are first
        // touched, a fifth to a half of a read's time on this machine: the
        // arrays are made on both cores, the positions beside the fields.
        std::vector<std::string> names = standardNames;
        if (!range) {
            // Fields 0 in every record are not made at all (the reader would
            // drop them once read, below): no pages to zero, fill and write
            // for them. A LAZ file's chunks tell which without decoding; an
            // uncompressed file's records are read once for it.
            const std::vector<std::uint8_t> zeroBits =
                h.compressed ? lazBitsZeroInEveryRecord(file.data(), file.size(), chunks, *layout, h.recordLength)
                             : lasBitsZeroInEveryRecord(records, count, h.recordLength, format, names, ticker);
            names.erase(std::remove_if(names.begin(), names.end(),
                                       [&](const std::string& name) { return fieldIsZeroIn(zeroBits, format, name); }),
                        names.end());
            // LAZ codes the scanner channel in the x, y layer, which no chunk
            // leaves empty: only decoding tells whether it is 0 everywhere,
            // as it is in most files. It is made once a chunk shows another
            // channel (parseLazRecords), not made and then dropped (4 bytes a
            // point).
            const auto channel = std::find(names.begin(), names.end(), "scanner_channel");
            if (h.compressed && channel != names.end()) {
                names.erase(channel);
                channelDeferred = true;
            }
        }
        std::vector<ScalarField> standard(names.size());
        tbb::parallel_invoke(
            [&] {
                cloud.resize(count);
                if (floatsMissTheGrid(h, cloud.origin()))
                    cloud.positionResiduals().resize(count);
                if (formatHasRgb(format))
                    cloud.enableColors();
            },
            [&] {
                tbb::parallel_for(std::size_t(0), names.size(), [&](std::size_t f) {
                    standard[f] = ScalarField(names[f], count);
                    if (names[f] == "gps_time") {
                        standard[f].setOffset(gpsTimeOffset);
                        // A double in the file, given back to the bit: float
                        // residuals beside the float view (4 bytes a point)
                        // hold real GPS times (hours from the offset, in
                        // microseconds); doubles otherwise.
                        standard[f].keepResiduals();
                    }
                });
            });
        for (ScalarField& field : standard)
            cloud.addField(std::move(field));
        for (const ExtraDimension& dim : extras) {
            extraNames.push_back(uniqueFieldName(cloud, dim.name, standardNames));
            cloud.addField(ScalarField(extraNames.back(), count));
        }
        // Once every field exists (adding one moves the others).
        for (std::size_t d = 0; d < extras.size(); ++d)
            extraFillers.emplace_back(extras[d], *cloud.field(extraNames[d]));
    } catch (const std::bad_alloc&) {
        throw Error(ErrorCode::Io, path.string() + ": not enough memory to load " + std::to_string(count) + " points");
    } catch (const std::length_error&) {
        throw Error(ErrorCode::Io, path.string() + ": not enough memory to load " + std::to_string(count) + " points");
    }

    // Pointers are taken once every field exists: adding fields moves them.
    const PointOutputs out = pointOutputs(cloud, gpsTimeOffset);

    const CoordinateTransform transform{h.scale, h.offset - cloud.origin()};
    if (h.compressed)
        parseLazRecords(file, h, *layout, chunks, first, count, transform, out, extraFillers, cloud, ticker,
                        channelDeferred ? &deferredChannel : nullptr);
    else
        parseRecordsInMemory(h, records, count, transform, out, extraFillers, cloud, ticker);
    for (ExtraFieldFiller& extra : extraFillers)
        extra.finish();
    if (deferredChannel)
        insertAmongStandardFields(cloud, std::move(*deferredChannel), standardNames);
    // The ranges of one file keep every field, so that each has the same ones.
    if (!range)
        dropEmptyStandardFields(cloud, extraNames);

    const std::size_t dropped = cloud.removeNonFinitePoints();
    if (dropped > 0)
        logWarning(path.string() + ": " + std::to_string(dropped) + " points with non-finite coordinates were skipped");
    return cloud;
}

} // namespace

namespace {

//! LAS and LAZ alike: the same reader, by ranges too; only the writer's
//! compression differs.
FormatHandler lasFamilyHandler(const char* name, const char* extension, bool compressed)
{
    FormatHandler handler;
    handler.name = name;
    handler.extensions = {extension};
    handler.read = [](const fs::path& path, const ReadOptions& options) { return readLas(path, options); };
    handler.countRecords = [](const fs::path& path) {
        const MappedFile file(path);
        return parseHeader(file).pointCount;
    };
    handler.readRecords = [](const fs::path& path, RecordRange range, const ReadOptions& options) -> PointCloud {
        return std::get<PointCloud>(readLas(path, options, range));
    };
    handler.fieldsLeftOutWhenZero = [](const fs::path& path) {
        const MappedFile file(path);
        return standardFieldNames(parseHeader(file).pointFormat);
    };
    handler.writeCloud = [compressed](const PointCloud& cloud, const fs::path& path, const WriteOptions& options) {
        writeLas(cloud, path, options, compressed);
    };
    return handler;
}

} // namespace

FormatHandler lasFormat() { return lasFamilyHandler("LAS", "las", false); }

FormatHandler lazFormat() { return lasFamilyHandler("LAZ", "laz", true); }

} // namespace scandiff::io::detail
