// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The coders of the parts ("items") of a LAZ point record (internal to io/):
//! pointwise ones (LAS 1.0-1.3 records, one arithmetic stream for the whole
//! record) in PointwiseItems.cpp, layered ones (LAS 1.4 records, a stream per
//! attribute so a reader may skip some) in LayeredItems.cpp. Each item coder
//! keeps the last item it produced and writes the next straight into the
//! output record.

#include "ArithmeticCoder.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace scandiff::io::detail::laz {

//! Item types of the LASzip record (LASzip's laszip.hpp).
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

std::string itemName(std::uint16_t type);

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

//! A GPS time's bit pattern plus a difference, wrapping as LASzip's integers
//! do (a damaged stream may add anything).
inline std::int64_t addWrapping(std::int64_t pattern, std::int32_t diff)
{
    return static_cast<std::int64_t>(static_cast<std::uint64_t>(pattern) + static_cast<std::uint64_t>(std::int64_t(diff)));
}

//! A byte plus a change, modulo 256 (LASzip's U8_FOLD).
inline std::uint8_t fold(std::int32_t v) { return static_cast<std::uint8_t>(v & 0xFF); }
inline std::int32_t clampByte(std::int32_t v) { return std::clamp(v, 0, 255); }

//! The median of the last five values (of a coordinate's differences).
struct StreamingMedian5
{
    std::array<std::int32_t, 5> v{};
    bool high = true;

    std::int32_t median() const { return v[2]; }
    void add(std::int32_t x);
};

//! The six byte models of a colour and the decoding both RGB coders share:
//! which bytes changed, then each byte's change, green and blue predicted
//! from red's change.
struct RgbModels
{
    SymbolModel byteUsed{128};
    std::array<SymbolModel, 6> diff{SymbolModel(256), SymbolModel(256), SymbolModel(256),
                                    SymbolModel(256), SymbolModel(256), SymbolModel(256)};
};
std::array<std::uint16_t, 3> decodeRgb(ArithmeticDecoder& d, RgbModels& models, const std::array<std::uint16_t, 3>& last);
//! The mirror of decodeRgb(): codes `rgb` after `last`.
void encodeRgb(ArithmeticEncoder& e, RgbModels& models, const std::array<std::uint16_t, 3>& last,
               const std::array<std::uint16_t, 3>& rgb);

//! The GPS times of both GPS coders (gpstime11 and the layered point14's):
//! four sequences of 64-bit patterns (returns of interleaved pulses), each
//! with its last time and last difference. A time is coded as a multiple of
//! the last difference plus a correction, as a new 32-bit difference, as a
//! switch to another sequence, or in full as a new sequence; the two coders
//! differ only in how they number those codes.
class GpsTimeSequences
{
protected:
    static constexpr std::int32_t kMulti = 500;
    static constexpr std::int32_t kMultiMinus = -10;

    explicit GpsTimeSequences(std::int64_t first) { last_[0] = first; }

    //! Decodes the time of multiplier code `multi`: 0 (no relation to the
    //! last difference), 2..kMulti (a multiple), kMulti + 1..kMulti - kMultiMinus
    //! (a negative multiple).
    void decodeMultiple(ArithmeticDecoder& d, std::int32_t multi);
    //! A time too far from the last for 32 bits: its high word as a
    //! correction, its low word raw, in a new sequence.
    void decodeFullTime(ArithmeticDecoder& d);
    //! After more than three extreme differences in a row the last one becomes the reference.
    void countExtreme(std::int32_t diff);
    static std::int32_t wrapMul(std::int32_t a, std::int32_t b)
    {
        return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) * static_cast<std::uint32_t>(b));
    }

    std::array<std::int64_t, 4> last_{};
    std::array<std::int32_t, 4> lastDiff_{}, extremeCount_{};
    std::uint32_t current_ = 0, next_ = 0;
    IntegerCoder diff_{32, 9};
};

//! A pointwise item: decoded from the record's single stream.
class PointwiseItem
{
public:
    virtual ~PointwiseItem() = default;
    virtual void decode(ArithmeticDecoder& decoder, unsigned char* item) = 0;
};

//! The coder of a pointwise item (point10, gpstime11, rgb12 or bytes,
//! version 2), starting from the chunk's first item.
std::unique_ptr<PointwiseItem> makePointwiseItem(std::uint16_t type, std::size_t size, const unsigned char* first);

//! The bytes of one layer of a chunk (possibly none: the attribute never changes in it).
struct Layer
{
    const unsigned char* data = nullptr;
    std::size_t size = 0;
};

//! A layered item: each of its attributes in a stream of its own. The
//! point14 item chooses the context (0-3) the others follow: each context
//! keeps its own last values and models. That context is not simply the
//! point's scanner channel: LASzip hands the items after point14 a context
//! that starts at 0 for every point and that point14 sets to the new
//! channel only at a point whose channel changed (LASreadPoint::read and
//! LASwritePoint::write, LASzip 3.x). Files with one channel do not tell the
//! difference; files with several are coded that way by every LASzip
//! writer, and laz-perf reads them so.
class LayeredItem
{
public:
    virtual ~LayeredItem() = default;
    virtual std::size_t layerCount() const = 0;
    //! Gives the chunk's layers (layerCount() of them) and the context of the
    //! first point; the point14 item sets it from that point.
    virtual void start(const Layer* layers, std::uint32_t& context) = 0;
    //! Decodes the items of `count` consecutive points, the first at `item`,
    //! one every `stride` bytes. `contexts` holds each point's context for
    //! the items after point14 (see above): the point14 item writes it, the
    //! others read it.
    virtual void decodeRun(unsigned char* item, std::size_t stride, std::size_t count, std::uint8_t* contexts) = 0;
    //! Whether a layer's stream cannot come from an encoder (see ArithmeticDecoder::corrupt).
    virtual bool corrupt() const = 0;
    //! Once the chunk is decoded: whether every layer was read to its last
    //! byte (see ArithmeticDecoder::endedExactly).
    virtual bool endedExactly() const = 0;
};

//! The coder of a layered item (point14, rgb14, rgbnir14 or byte14, version
//! 3), starting from the chunk's first item.
std::unique_ptr<LayeredItem> makeLayeredItem(std::uint16_t type, std::size_t size, const unsigned char* first);

//! The bits of a layered item (point14, rgb14, rgbnir14 or byte14) each of its
//! layers codes, in the order of the layers: a mask over the item's `size`
//! bytes per layer. A layer empty in a chunk means those bits are the chunk's
//! first item's at every point of it.
std::vector<std::vector<std::uint8_t>> layerBits(std::uint16_t type, std::size_t size);

//! The encoder of a layered item, the mirror of LayeredItem: each item of a
//! chunk after the first goes to encode(), then finish() gives its layers
//! (empty for an attribute that never changed in the chunk).
class LayeredItemEncoder
{
public:
    virtual ~LayeredItemEncoder() = default;
    virtual void encode(const unsigned char* item, std::uint32_t& context) = 0;
    virtual void finish(std::vector<std::vector<unsigned char>>& layers) = 0;
};

//! The encoder of a layered item (point14, rgb14, rgbnir14 or byte14,
//! version 3), starting from the chunk's first item; the point14 one sets
//! `context` from it.
std::unique_ptr<LayeredItemEncoder> makeLayeredItemEncoder(std::uint16_t type, std::size_t size, const unsigned char* first,
                                                           std::uint32_t& context);

} // namespace scandiff::io::detail::laz
