// SPDX-License-Identifier: GPL-3.0-or-later
//! LAZ decompression: the LASzip record, the chunk table, and the coders of the
//! items of LAS 1.0-1.3 point records (point10, gpstime11, rgb12 and extra
//! bytes, version 2: what LASzip has written since 2011). Each chunk starts with
//! one uncompressed record and is decoded on its own, so chunks are decoded in
//! parallel. How LASzip lays these out is described in its documentation and
//! source (github.com/LASzip/LASzip: laszip.hpp, lasreadpoint.cpp,
//! lasreaditemcompressed_v2.cpp); this file follows that description.

#include "internal/LazDecoder.h"
#include "internal/LazArithmeticDecoder.h"

#include <scandiff/core/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <memory>
#include <string>

namespace scandiff::io::detail {

namespace {

namespace fs = std::filesystem;
using laz::ArithmeticDecoder;
using laz::IntegerDecompressor;
using laz::SymbolModel;

template <typename T>
T load(const void* p)
{
    T value;
    std::memcpy(&value, p, sizeof(T));
    return value;
}

template <typename T>
void store(void* p, T value)
{
    std::memcpy(p, &value, sizeof(T));
}

[[noreturn]] void invalid(const fs::path& path, const std::string& what)
{
    throw Error(ErrorCode::InvalidData, path.string() + ": " + what);
}

// Item types of the LASzip record (laszip.hpp).
enum ItemType : std::uint16_t {
    kByte = 0,
    kPoint10 = 6,
    kGpsTime11 = 7,
    kRgb12 = 8,
    kWavePacket13 = 9,
    kPoint14 = 10,
    kRgb14 = 11,
    kRgbNir14 = 12,
    kWavePacket14 = 13,
    kByte14 = 14,
};

std::string itemName(std::uint16_t type)
{
    switch (type) {
    case kByte: return "extra bytes";
    case kPoint10: return "point10";
    case kGpsTime11: return "gpstime11";
    case kRgb12: return "rgb12";
    case kWavePacket13: return "wavepacket13";
    case kPoint14: return "point14";
    case kRgb14: return "rgb14";
    case kRgbNir14: return "rgbnir14";
    case kWavePacket14: return "wavepacket14";
    case kByte14: return "byte14";
    default: return "type " + std::to_string(type);
    }
}

std::uint8_t fold(std::int32_t v) { return static_cast<std::uint8_t>(v & 0xFF); }
std::int32_t clampByte(std::int32_t v) { return std::clamp(v, 0, 255); }

// ---------------------------------------------------------------------------
// The item coders. Each keeps the last item it produced and writes the next
// one straight into the output record.

class ItemDecoder
{
public:
    virtual ~ItemDecoder() = default;
    virtual void decode(ArithmeticDecoder& decoder, unsigned char* item) = 0;
};

//! The median of the last five values (of a coordinate's differences).
struct StreamingMedian5
{
    std::array<std::int32_t, 5> v{};
    bool high = true;

    std::int32_t median() const { return v[2]; }
    void add(std::int32_t x)
    {
        if (high) {
            if (x < v[2]) {
                v[4] = v[3];
                v[3] = v[2];
                if (x < v[0]) {
                    v[2] = v[1];
                    v[1] = v[0];
                    v[0] = x;
                } else if (x < v[1]) {
                    v[2] = v[1];
                    v[1] = x;
                } else {
                    v[2] = x;
                }
            } else {
                if (x < v[3]) {
                    v[4] = v[3];
                    v[3] = x;
                } else {
                    v[4] = x;
                }
                high = false;
            }
        } else {
            if (v[2] < x) {
                v[0] = v[1];
                v[1] = v[2];
                if (v[4] < x) {
                    v[2] = v[3];
                    v[3] = v[4];
                    v[4] = x;
                } else if (v[3] < x) {
                    v[2] = v[3];
                    v[3] = x;
                } else {
                    v[2] = x;
                }
            } else {
                if (v[1] < x) {
                    v[0] = v[1];
                    v[1] = x;
                } else {
                    v[0] = x;
                }
                high = true;
            }
        }
    }
};

// The context of a return r of n (3-bit fields): the coordinates' medians and
// the last intensity are kept per "return map" class, the last height per level.
constexpr std::uint8_t kReturnMap[8][8] = {
    {15, 14, 13, 12, 11, 10, 9, 8}, {14, 0, 1, 3, 6, 10, 10, 9},   {13, 1, 2, 4, 7, 11, 11, 10},
    {12, 3, 4, 5, 8, 12, 12, 11},   {11, 6, 7, 8, 9, 13, 13, 12},  {10, 10, 11, 12, 13, 14, 14, 13},
    {9, 10, 11, 12, 13, 14, 15, 14}, {8, 9, 10, 11, 12, 13, 14, 15}};
constexpr std::uint8_t returnLevel(std::uint32_t n, std::uint32_t r) { return static_cast<std::uint8_t>(n > r ? n - r : r - n); }

//! The 20 bytes of a LAS 1.0-1.3 point: x, y, z (int32), intensity (uint16),
//! return byte, classification, scan angle rank, user data, point source id.
class Point10Decoder final : public ItemDecoder
{
public:
    explicit Point10Decoder(const unsigned char* first)
    {
        std::memcpy(last_, first, 20);
        // The first intensity is not a prediction: the coder starts from zero.
        last_[12] = last_[13] = 0;
    }

    void decode(ArithmeticDecoder& d, unsigned char* item) override
    {
        const std::uint32_t changed = d.decodeSymbol(changedValues_);
        if (changed & 32)
            last_[14] = static_cast<unsigned char>(d.decodeSymbol(model(returnByte_, last_[14])));
        const std::uint32_t r = last_[14] & 7, n = (last_[14] >> 3) & 7;
        const std::uint32_t m = kReturnMap[n][r], l = returnLevel(n, r);
        // Unchanged values keep the last point's intensity, changed ones the
        // last of this return class.
        if (changed & 16)
            lastIntensity_[m] = static_cast<std::uint16_t>(intensity_.decompress(d, lastIntensity_[m], m < 3 ? m : 3));
        if (changed != 0)
            store<std::uint16_t>(last_ + 12, lastIntensity_[m]);
        if (changed & 8)
            last_[15] = static_cast<unsigned char>(d.decodeSymbol(model(classification_, last_[15])));
        if (changed & 4) {
            const std::uint32_t direction = (last_[14] >> 6) & 1;
            last_[16] = fold(static_cast<std::int32_t>(d.decodeSymbol(scanAngle_[direction])) + last_[16]);
        }
        if (changed & 2)
            last_[17] = static_cast<unsigned char>(d.decodeSymbol(model(userData_, last_[17])));
        if (changed & 1)
            store<std::uint16_t>(last_ + 18, static_cast<std::uint16_t>(pointSource_.decompress(d, load<std::uint16_t>(last_ + 18))));

        const std::int32_t dx = dx_.decompress(d, xMedian_[m].median(), n == 1);
        store<std::int32_t>(last_, static_cast<std::int32_t>(static_cast<std::uint32_t>(load<std::int32_t>(last_)) + static_cast<std::uint32_t>(dx)));
        xMedian_[m].add(dx);
        std::uint32_t k = dx_.lastSize();
        const std::int32_t dy = dy_.decompress(d, yMedian_[m].median(), (n == 1) + (k < 20 ? k & ~1u : 20));
        store<std::int32_t>(last_ + 4, static_cast<std::int32_t>(static_cast<std::uint32_t>(load<std::int32_t>(last_ + 4)) + static_cast<std::uint32_t>(dy)));
        yMedian_[m].add(dy);
        k = (dx_.lastSize() + dy_.lastSize()) / 2;
        lastHeight_[l] = z_.decompress(d, lastHeight_[l], (n == 1) + (k < 18 ? k & ~1u : 18));
        store<std::int32_t>(last_ + 8, lastHeight_[l]);
        std::memcpy(item, last_, 20);
    }

private:
    //! The model of a byte given its previous value, made on first use.
    static SymbolModel& model(std::array<std::unique_ptr<SymbolModel>, 256>& models, unsigned char previous)
    {
        std::unique_ptr<SymbolModel>& m = models[previous];
        if (!m)
            m = std::make_unique<SymbolModel>(256);
        return *m;
    }

    unsigned char last_[20];
    std::array<std::uint16_t, 16> lastIntensity_{};
    std::array<StreamingMedian5, 16> xMedian_{}, yMedian_{};
    std::array<std::int32_t, 8> lastHeight_{};
    SymbolModel changedValues_{64};
    IntegerDecompressor intensity_{16, 4};
    std::array<SymbolModel, 2> scanAngle_{SymbolModel(256), SymbolModel(256)};
    IntegerDecompressor pointSource_{16};
    std::array<std::unique_ptr<SymbolModel>, 256> returnByte_, classification_, userData_;
    IntegerDecompressor dx_{32, 2}, dy_{32, 22}, z_{32, 20};
};

//! The GPS time (a double), coded on its 64-bit pattern: as a multiple of
//! the last difference, a new difference, or a jump to one of four sequences
//! (returns of several pulses interleave in time).
class GpsTime11Decoder final : public ItemDecoder
{
public:
    explicit GpsTime11Decoder(const unsigned char* first) { last_[0] = load<std::int64_t>(first); }

    void decode(ArithmeticDecoder& d, unsigned char* item) override
    {
        read(d);
        store<std::int64_t>(item, last_[current_]);
    }

private:
    static constexpr std::int32_t kMulti = 500;
    static constexpr std::int32_t kMultiMinus = -10;
    static constexpr std::int32_t kMultiUnchanged = kMulti - kMultiMinus + 1;
    static constexpr std::int32_t kMultiCodeFull = kMulti - kMultiMinus + 2;
    static constexpr std::uint32_t kMultiTotal = kMulti - kMultiMinus + 6;

    void read(ArithmeticDecoder& d)
    {
        // A switch to another sequence is followed by that sequence's own code.
        for (;;) {
            if (lastDiff_[current_] == 0) {
                const auto multi = static_cast<std::int32_t>(d.decodeSymbol(zeroDiff_));
                if (multi == 1) {
                    lastDiff_[current_] = diff_.decompress(d, 0, 0);
                    last_[current_] += lastDiff_[current_];
                    extremeCount_[current_] = 0;
                } else if (multi == 2) {
                    fullTime(d);
                } else if (multi > 2) {
                    current_ = (current_ + static_cast<std::uint32_t>(multi) - 2) & 3;
                    continue;
                }
                return;
            }
            auto multi = static_cast<std::int32_t>(d.decodeSymbol(multiple_));
            if (multi == 1) {
                last_[current_] += diff_.decompress(d, lastDiff_[current_], 1);
                extremeCount_[current_] = 0;
            } else if (multi < kMultiUnchanged) {
                std::int32_t diff;
                const std::int32_t previous = lastDiff_[current_];
                if (multi == 0) {
                    diff = diff_.decompress(d, 0, 7);
                    countExtreme(diff);
                } else if (multi < kMulti) {
                    diff = diff_.decompress(d, wrapMul(multi, previous), multi < 10 ? 2 : 3);
                } else if (multi == kMulti) {
                    diff = diff_.decompress(d, wrapMul(kMulti, previous), 4);
                    countExtreme(diff);
                } else {
                    multi = kMulti - multi;
                    if (multi > kMultiMinus) {
                        diff = diff_.decompress(d, wrapMul(multi, previous), 5);
                    } else {
                        diff = diff_.decompress(d, wrapMul(kMultiMinus, previous), 6);
                        countExtreme(diff);
                    }
                }
                last_[current_] += diff;
            } else if (multi == kMultiCodeFull) {
                fullTime(d);
            } else if (multi > kMultiCodeFull) {
                current_ = (current_ + static_cast<std::uint32_t>(multi - kMultiCodeFull)) & 3;
                continue;
            }
            // kMultiUnchanged: the same time again.
            return;
        }
    }

    //! A time too far from the last for 32 bits: its high word as a
    //! correction, its low word raw, in a new sequence.
    void fullTime(ArithmeticDecoder& d)
    {
        next_ = (next_ + 1) & 3;
        const auto high = static_cast<std::uint32_t>(diff_.decompress(d, static_cast<std::int32_t>(static_cast<std::uint64_t>(last_[current_]) >> 32), 8));
        const std::uint64_t pattern = (std::uint64_t(high) << 32) | d.readInt();
        last_[next_] = static_cast<std::int64_t>(pattern);
        current_ = next_;
        lastDiff_[current_] = 0;
        extremeCount_[current_] = 0;
    }

    //! After more than three extreme differences in a row the last one becomes the reference.
    void countExtreme(std::int32_t diff)
    {
        if (++extremeCount_[current_] > 3) {
            lastDiff_[current_] = diff;
            extremeCount_[current_] = 0;
        }
    }

    static std::int32_t wrapMul(std::int32_t a, std::int32_t b)
    {
        return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) * static_cast<std::uint32_t>(b));
    }

    std::array<std::int64_t, 4> last_{};
    std::array<std::int32_t, 4> lastDiff_{}, extremeCount_{};
    std::uint32_t current_ = 0, next_ = 0;
    SymbolModel multiple_{kMultiTotal};
    SymbolModel zeroDiff_{6};
    IntegerDecompressor diff_{32, 9};
};

//! Red, green, blue (uint16 each): which bytes changed, then each byte's
//! change, green and blue predicted from red's.
class Rgb12Decoder final : public ItemDecoder
{
public:
    explicit Rgb12Decoder(const unsigned char* first)
    {
        for (int c = 0; c < 3; ++c)
            last_[c] = load<std::uint16_t>(first + 2 * c);
    }

    void decode(ArithmeticDecoder& d, unsigned char* item) override
    {
        std::array<std::uint16_t, 3> rgb{};
        const std::uint32_t used = d.decodeSymbol(byteUsed_);
        auto low = [](std::uint32_t v) { return static_cast<std::int32_t>(v & 0xFF); };
        auto high = [](std::uint32_t v) { return static_cast<std::int32_t>(v >> 8); };
        rgb[0] = (used & 1) ? fold(static_cast<std::int32_t>(d.decodeSymbol(diff_[0])) + low(last_[0])) : low(last_[0]);
        rgb[0] |= static_cast<std::uint16_t>(((used & 2) ? fold(static_cast<std::int32_t>(d.decodeSymbol(diff_[1])) + high(last_[0]))
                                                         : high(last_[0]))
                                             << 8);
        if (used & 64) {
            std::int32_t diff = low(rgb[0]) - low(last_[0]);
            rgb[1] = (used & 4) ? fold(static_cast<std::int32_t>(d.decodeSymbol(diff_[2])) + clampByte(diff + low(last_[1])))
                                : low(last_[1]);
            if (used & 16) {
                diff = (diff + (low(rgb[1]) - low(last_[1]))) / 2;
                rgb[2] = fold(static_cast<std::int32_t>(d.decodeSymbol(diff_[4])) + clampByte(diff + low(last_[2])));
            } else {
                rgb[2] = low(last_[2]);
            }
            diff = high(rgb[0]) - high(last_[0]);
            if (used & 8)
                rgb[1] |= static_cast<std::uint16_t>(fold(static_cast<std::int32_t>(d.decodeSymbol(diff_[3])) + clampByte(diff + high(last_[1]))) << 8);
            else
                rgb[1] |= last_[1] & 0xFF00;
            if (used & 32) {
                diff = (diff + (high(rgb[1]) - high(last_[1]))) / 2;
                rgb[2] |= static_cast<std::uint16_t>(fold(static_cast<std::int32_t>(d.decodeSymbol(diff_[5])) + clampByte(diff + high(last_[2]))) << 8);
            } else {
                rgb[2] |= last_[2] & 0xFF00;
            }
        } else {
            // Grey: one value for the three channels.
            rgb[1] = rgb[2] = rgb[0];
        }
        last_ = rgb;
        for (int c = 0; c < 3; ++c)
            store<std::uint16_t>(item + 2 * c, rgb[static_cast<std::size_t>(c)]);
    }

private:
    std::array<std::uint16_t, 3> last_{};
    SymbolModel byteUsed_{128};
    std::array<SymbolModel, 6> diff_{SymbolModel(256), SymbolModel(256), SymbolModel(256),
                                     SymbolModel(256), SymbolModel(256), SymbolModel(256)};
};

//! Extra bytes: each byte's change, a model per byte position.
class ByteDecoder final : public ItemDecoder
{
public:
    ByteDecoder(const unsigned char* first, std::size_t size) : last_(first, first + size)
    {
        models_.reserve(size);
        for (std::size_t i = 0; i < size; ++i)
            models_.emplace_back(256);
    }

    void decode(ArithmeticDecoder& d, unsigned char* item) override
    {
        for (std::size_t i = 0; i < last_.size(); ++i)
            item[i] = last_[i] = fold(static_cast<std::int32_t>(last_[i]) + static_cast<std::int32_t>(d.decodeSymbol(models_[i])));
    }

private:
    std::vector<unsigned char> last_;
    std::vector<SymbolModel> models_;
};

// ---------------------------------------------------------------------------
// Chunks.

struct Chunk
{
    std::uint64_t offset = 0; //!< of its first byte in the file
    std::uint64_t bytes = 0;  //!< 0 when unknown (no chunk table)
    std::uint64_t firstPoint = 0;
    std::uint64_t points = 0;
};

//! Decodes one chunk's records into `out`; returns the bytes its stream used.
std::uint64_t decodeChunk(const fs::path& path, const LazLayout& layout, const unsigned char* file, std::size_t fileSize,
                          const Chunk& chunk, std::size_t recordLength, std::size_t chunkIndex, char* out)
{
    if (chunk.points == 0)
        return 0;
    if (chunk.offset > fileSize || fileSize - chunk.offset < recordLength)
        invalid(path, "LAZ chunk " + std::to_string(chunkIndex) + " starts at byte " + std::to_string(chunk.offset) +
                          ", too close to the end of the file (" + std::to_string(fileSize) + " bytes) for its first record");
    // The first record of a chunk is stored as is; the coders start from it.
    const unsigned char* first = file + chunk.offset;
    std::memcpy(out, first, recordLength);
    std::vector<std::unique_ptr<ItemDecoder>> items;
    std::vector<std::size_t> offsets;
    std::size_t at = 0;
    for (const LazItem& item : layout.items) {
        switch (item.type) {
        case kPoint10: items.push_back(std::make_unique<Point10Decoder>(first + at)); break;
        case kGpsTime11: items.push_back(std::make_unique<GpsTime11Decoder>(first + at)); break;
        case kRgb12: items.push_back(std::make_unique<Rgb12Decoder>(first + at)); break;
        default: items.push_back(std::make_unique<ByteDecoder>(first + at, item.size)); break;
        }
        offsets.push_back(at);
        at += item.size;
    }
    const unsigned char* streamEnd = chunk.bytes ? file + chunk.offset + chunk.bytes : file + fileSize;
    ArithmeticDecoder decoder(first + recordLength, streamEnd);
    for (std::uint64_t p = 1; p < chunk.points; ++p) {
        auto* record = reinterpret_cast<unsigned char*>(out + p * recordLength);
        for (std::size_t i = 0; i < items.size(); ++i)
            items[i]->decode(decoder, record + offsets[i]);
    }
    // The encoder flushes exactly the bytes the decoder reads ahead: a whole
    // chunk is used up to its last byte, never beyond.
    if (decoder.bytesPastEnd() > 0)
        invalid(path, "LAZ chunk " + std::to_string(chunkIndex) + " (from byte " + std::to_string(chunk.offset) +
                          ") is corrupt or truncated: decoding its " + std::to_string(chunk.points) +
                          " points runs past its end");
    return static_cast<std::uint64_t>(decoder.position() - first);
}

//! The chunks of a chunked file, from its chunk table.
std::vector<Chunk> readChunkTable(const fs::path& path, const unsigned char* file, std::size_t size, std::uint64_t pointsStart,
                                  const LazLayout& layout, std::size_t recordLength, std::uint64_t count)
{
    if (pointsStart > size || size - pointsStart < 8)
        invalid(path, "LAZ point data (from byte " + std::to_string(pointsStart) + ") too short for the chunk table's offset");
    const std::uint64_t chunksStart = pointsStart + 8;
    auto tableOffset = load<std::int64_t>(file + pointsStart);
    if (tableOffset == -1 && size >= 8) // written to a stream: the offset is at the end of the file
        tableOffset = load<std::int64_t>(file + size - 8);
    if (tableOffset < 0 || static_cast<std::uint64_t>(tableOffset) < chunksStart ||
        static_cast<std::uint64_t>(tableOffset) > size || size - static_cast<std::uint64_t>(tableOffset) < 8)
        invalid(path, "the LAZ chunk table's offset (" + std::to_string(tableOffset) + ", at byte " +
                          std::to_string(pointsStart) + ") points outside the file (" + std::to_string(size) + " bytes)");
    const unsigned char* table = file + tableOffset;
    const auto version = load<std::uint32_t>(table);
    if (version != 0)
        invalid(path, "unknown LAZ chunk table version " + std::to_string(version) + " at byte " + std::to_string(tableOffset));
    const auto chunkCount = load<std::uint32_t>(table + 4);
    const std::uint64_t dataBytes = static_cast<std::uint64_t>(tableOffset) - chunksStart;
    // Every chunk holds at least its first record uncompressed.
    if (chunkCount > dataBytes / recordLength + (count == 0 ? 1 : 0))
        invalid(path, "the LAZ chunk table lists " + std::to_string(chunkCount) + " chunks, more than the " +
                          std::to_string(dataBytes) + " bytes of point data can hold");
    const bool variable = layout.chunkSize == UINT32_MAX;
    std::vector<Chunk> chunks(chunkCount);
    ArithmeticDecoder decoder(table + 8, file + size);
    IntegerDecompressor sizes(32, 2);
    for (std::size_t i = 0; i < chunkCount; ++i) {
        if (variable)
            chunks[i].points = static_cast<std::uint32_t>(sizes.decompress(decoder, i ? static_cast<std::int32_t>(chunks[i - 1].points) : 0, 0));
        chunks[i].bytes = static_cast<std::uint32_t>(sizes.decompress(decoder, i ? static_cast<std::int32_t>(chunks[i - 1].bytes) : 0, 1));
    }
    if (decoder.bytesPastEnd() > 0)
        invalid(path, "the LAZ chunk table at byte " + std::to_string(tableOffset) + " is truncated");
    std::uint64_t offset = chunksStart, point = 0;
    for (std::size_t i = 0; i < chunkCount; ++i) {
        Chunk& c = chunks[i];
        c.offset = offset;
        c.firstPoint = point;
        if (!variable)
            c.points = std::min<std::uint64_t>(layout.chunkSize, count - std::min(count, point));
        if (c.bytes > static_cast<std::uint64_t>(tableOffset) - offset)
            invalid(path, "LAZ chunk " + std::to_string(i) + " (" + std::to_string(c.bytes) + " bytes from byte " +
                              std::to_string(offset) + ") runs past the chunk table at byte " + std::to_string(tableOffset));
        offset += c.bytes;
        point += c.points;
    }
    if (point != count)
        invalid(path, "the LAZ chunk table accounts for " + std::to_string(point) + " points, the header says " +
                          std::to_string(count));
    return chunks;
}

} // namespace

LazLayout parseLazLayout(const fs::path& path, const char* payload, std::size_t length, std::size_t recordLength)
{
    constexpr std::size_t kFixedPart = 34, kItemSize = 6;
    if (length < kFixedPart)
        invalid(path, "the LASzip record is " + std::to_string(length) + " bytes, shorter than its fixed " +
                          std::to_string(kFixedPart));
    LazLayout layout;
    layout.compressor = load<std::uint16_t>(payload);
    const auto coder = load<std::uint16_t>(payload + 2);
    layout.chunkSize = load<std::uint32_t>(payload + 12);
    const auto itemCount = load<std::uint16_t>(payload + 32);
    if (kFixedPart + kItemSize * itemCount > length)
        invalid(path, "the LASzip record lists " + std::to_string(itemCount) + " items, more than its " +
                          std::to_string(length) + " bytes hold");
    if (coder != 0)
        throw Error(ErrorCode::Unsupported, path.string() + ": LAZ entropy coder " + std::to_string(coder) +
                                                " is not known (0, arithmetic, is the only one LASzip defines)");
    std::size_t total = 0;
    for (std::size_t i = 0; i < itemCount; ++i) {
        const char* p = payload + kFixedPart + kItemSize * i;
        LazItem item{load<std::uint16_t>(p), load<std::uint16_t>(p + 2), load<std::uint16_t>(p + 4)};
        total += item.size;
        layout.items.push_back(item);
    }
    if (total != recordLength)
        invalid(path, "the LASzip items add up to " + std::to_string(total) + " bytes per point, the header's record length is " +
                          std::to_string(recordLength));
    if (layout.compressor == 3)
        throw Error(ErrorCode::Unsupported, path.string() +
                                                ": LAZ with layered chunks (LAS 1.4 point formats 6-10) cannot be read yet; "
                                                "decompress it to .las first (e.g. with laszip or pdal translate)");
    if (layout.compressor != 1 && layout.compressor != 2)
        invalid(path, "unknown LAZ compressor " + std::to_string(layout.compressor) + " in the LASzip record");
    if (layout.compressor == 2 && layout.chunkSize == 0)
        layout.chunkSize = UINT32_MAX; // LASzip reads a chunk size of 0 as "given per chunk"
    for (const LazItem& item : layout.items) {
        const bool known = (item.type == kPoint10 && item.size == 20) || (item.type == kGpsTime11 && item.size == 8) ||
                           (item.type == kRgb12 && item.size == 6) || (item.type == kByte && item.size > 0);
        if (!known)
            throw Error(ErrorCode::Unsupported, path.string() + ": LAZ item " + itemName(item.type) + " of " +
                                                    std::to_string(item.size) + " bytes cannot be read");
        if (item.version != 2)
            throw Error(ErrorCode::Unsupported, path.string() + ": LAZ item " + itemName(item.type) + " version " +
                                                    std::to_string(item.version) +
                                                    " cannot be read (version 2, what LASzip writes since 2011, can)");
    }
    return layout;
}

void decompressLaz(const fs::path& path, const char* data, std::size_t size, std::uint64_t pointsStart, const LazLayout& layout,
                   std::size_t recordLength, std::uint64_t count, char* out, const std::function<void(std::size_t)>& progress)
{
    if (count == 0)
        return;
    const auto* file = reinterpret_cast<const unsigned char*>(data);
    std::vector<Chunk> chunks;
    if (layout.compressor == 1) {
        chunks.push_back(Chunk{pointsStart, 0, 0, count});
    } else {
        chunks = readChunkTable(path, file, size, pointsStart, layout, recordLength, count);
    }
    // A few chunks per worker between two calls of `progress`: Cancel is heard
    // within a few chunks' time (about 10 ms each for 50,000 points).
    const std::size_t batch = 8;
    for (std::size_t begin = 0; begin < chunks.size(); begin += batch) {
        const std::size_t end = std::min(chunks.size(), begin + batch);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, 1), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const Chunk& chunk = chunks[i];
                const std::uint64_t used =
                    decodeChunk(path, layout, file, size, chunk, recordLength, i, out + chunk.firstPoint * recordLength);
                if (chunk.bytes != 0 && chunk.points > 1 && used != chunk.bytes)
                    invalid(path, "LAZ chunk " + std::to_string(i) + " (from byte " + std::to_string(chunk.offset) +
                                      ") is corrupt: its " + std::to_string(chunk.points) + " points use " +
                                      std::to_string(used) + " of its " + std::to_string(chunk.bytes) + " bytes");
            }
        });
        std::size_t points = 0;
        for (std::size_t i = begin; i < end; ++i)
            points += chunks[i].points;
        progress(points);
    }
}

} // namespace scandiff::io::detail
