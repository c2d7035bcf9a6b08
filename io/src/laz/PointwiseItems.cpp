// SPDX-License-Identifier: GPL-3.0-or-later
//! The pointwise item coders of LAZ, version 2 (what LASzip has written for
//! LAS 1.0-1.3 records since 2011): point10, gpstime11, rgb12 and extra bytes,
//! after LASzip's lasreaditemcompressed_v2.cpp. Also what the layered coders
//! share with them: the streaming median and the colour coder.

#include "Items.h"

#include <algorithm>

namespace scandiff::io::detail::laz {

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

void StreamingMedian5::add(std::int32_t x)
{
    // LASzip's rule: while `high`, the largest of the five goes, else the
    // smallest, and x takes its place in order; `high` then stays or becomes
    // true if x fell below the old median (or, after the smallest went, at
    // it). Written with min and max rather than LASzip's branches: which way
    // each goes is the coded data, and they were mispredicted. Equal values
    // are interchangeable, so the order among them does not matter.
    const bool dropSmallest = !high;
    const std::int32_t a0 = dropSmallest ? v[1] : v[0], a1 = dropSmallest ? v[2] : v[1];
    const std::int32_t a2 = dropSmallest ? v[3] : v[2], a3 = dropSmallest ? v[4] : v[3];
    high = high ? x < v[2] : !(v[2] < x);
    v[0] = std::min(a0, x);
    v[1] = std::min(a1, std::max(a0, x));
    v[2] = std::min(a2, std::max(a1, x));
    v[3] = std::min(a3, std::max(a2, x));
    v[4] = std::max(a3, x);
}

std::array<std::uint16_t, 3> decodeRgb(ArithmeticDecoder& d, RgbModels& models, const std::array<std::uint16_t, 3>& last)
{
    std::array<std::uint16_t, 3> rgb{};
    const std::uint32_t used = d.decodeSymbol(models.byteUsed);
    auto low = [](std::uint32_t v) { return static_cast<std::int32_t>(v & 0xFF); };
    auto high = [](std::uint32_t v) { return static_cast<std::int32_t>(v >> 8); };
    rgb[0] = (used & 1) ? fold(static_cast<std::int32_t>(d.decodeSymbol(models.diff[0])) + low(last[0])) : low(last[0]);
    rgb[0] |= static_cast<std::uint16_t>(((used & 2) ? fold(static_cast<std::int32_t>(d.decodeSymbol(models.diff[1])) + high(last[0]))
                                                     : high(last[0]))
                                         << 8);
    if (used & 64) {
        std::int32_t diff = low(rgb[0]) - low(last[0]);
        rgb[1] = (used & 4) ? fold(static_cast<std::int32_t>(d.decodeSymbol(models.diff[2])) + clampByte(diff + low(last[1])))
                            : low(last[1]);
        if (used & 16) {
            diff = (diff + (low(rgb[1]) - low(last[1]))) / 2;
            rgb[2] = fold(static_cast<std::int32_t>(d.decodeSymbol(models.diff[4])) + clampByte(diff + low(last[2])));
        } else {
            rgb[2] = low(last[2]);
        }
        diff = high(rgb[0]) - high(last[0]);
        if (used & 8)
            rgb[1] |= static_cast<std::uint16_t>(fold(static_cast<std::int32_t>(d.decodeSymbol(models.diff[3])) + clampByte(diff + high(last[1]))) << 8);
        else
            rgb[1] |= last[1] & 0xFF00;
        if (used & 32) {
            diff = (diff + (high(rgb[1]) - high(last[1]))) / 2;
            rgb[2] |= static_cast<std::uint16_t>(fold(static_cast<std::int32_t>(d.decodeSymbol(models.diff[5])) + clampByte(diff + high(last[2]))) << 8);
        } else {
            rgb[2] |= last[2] & 0xFF00;
        }
    } else {
        // Grey: one value for the three channels.
        rgb[1] = rgb[2] = rgb[0];
    }
    return rgb;
}

void encodeRgb(ArithmeticEncoder& e, RgbModels& models, const std::array<std::uint16_t, 3>& last,
               const std::array<std::uint16_t, 3>& rgb)
{
    auto low = [](std::uint32_t v) { return static_cast<std::int32_t>(v & 0xFF); };
    auto high = [](std::uint32_t v) { return static_cast<std::int32_t>(v >> 8); };
    std::uint32_t used = 0;
    for (std::size_t c = 0; c < 3; ++c) {
        used |= (low(last[c]) != low(rgb[c]) ? 1u : 0u) << (2 * c);
        used |= (high(last[c]) != high(rgb[c]) ? 1u : 0u) << (2 * c + 1);
    }
    if (rgb[0] != rgb[1] || rgb[0] != rgb[2])
        used |= 64;
    e.encodeSymbol(models.byteUsed, used);
    if (used & 1)
        e.encodeSymbol(models.diff[0], fold(low(rgb[0]) - low(last[0])));
    if (used & 2)
        e.encodeSymbol(models.diff[1], fold(high(rgb[0]) - high(last[0])));
    if (!(used & 64))
        return;
    std::int32_t diff = low(rgb[0]) - low(last[0]);
    if (used & 4)
        e.encodeSymbol(models.diff[2], fold(low(rgb[1]) - clampByte(diff + low(last[1]))));
    if (used & 16) {
        diff = (diff + (low(rgb[1]) - low(last[1]))) / 2;
        e.encodeSymbol(models.diff[4], fold(low(rgb[2]) - clampByte(diff + low(last[2]))));
    }
    diff = high(rgb[0]) - high(last[0]);
    if (used & 8)
        e.encodeSymbol(models.diff[3], fold(high(rgb[1]) - clampByte(diff + high(last[1]))));
    if (used & 32) {
        diff = (diff + (high(rgb[1]) - high(last[1]))) / 2;
        e.encodeSymbol(models.diff[5], fold(high(rgb[2]) - clampByte(diff + high(last[2]))));
    }
}

void GpsTimeSequences::decodeMultiple(ArithmeticDecoder& d, std::int32_t multi)
{
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
    last_[current_] = addWrapping(last_[current_], diff);
}

void GpsTimeSequences::decodeFullTime(ArithmeticDecoder& d)
{
    next_ = (next_ + 1) & 3;
    const auto high = static_cast<std::uint32_t>(
        diff_.decompress(d, static_cast<std::int32_t>(static_cast<std::uint64_t>(last_[current_]) >> 32), 8));
    last_[next_] = static_cast<std::int64_t>((std::uint64_t(high) << 32) | d.readInt());
    current_ = next_;
    lastDiff_[current_] = 0;
    extremeCount_[current_] = 0;
}

void GpsTimeSequences::countExtreme(std::int32_t diff)
{
    if (++extremeCount_[current_] > 3) {
        lastDiff_[current_] = diff;
        extremeCount_[current_] = 0;
    }
}

namespace {

// The context of a return r of n (3-bit fields): the coordinates' medians and
// the last intensity are kept per "return map" class, the last height per level.
constexpr std::uint8_t kReturnMap[8][8] = {
    {15, 14, 13, 12, 11, 10, 9, 8}, {14, 0, 1, 3, 6, 10, 10, 9},   {13, 1, 2, 4, 7, 11, 11, 10},
    {12, 3, 4, 5, 8, 12, 12, 11},   {11, 6, 7, 8, 9, 13, 13, 12},  {10, 10, 11, 12, 13, 14, 14, 13},
    {9, 10, 11, 12, 13, 14, 15, 14}, {8, 9, 10, 11, 12, 13, 14, 15}};
constexpr std::uint8_t returnLevel(std::uint32_t n, std::uint32_t r) { return static_cast<std::uint8_t>(n > r ? n - r : r - n); }

//! The 20 bytes of a LAS 1.0-1.3 point: x, y, z (int32), intensity (uint16),
//! return byte, classification, scan angle rank, user data, point source id.
class Point10Decoder final : public PointwiseItem
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
    IntegerCoder intensity_{16, 4};
    std::array<SymbolModel, 2> scanAngle_{SymbolModel(256), SymbolModel(256)};
    IntegerCoder pointSource_{16};
    std::array<std::unique_ptr<SymbolModel>, 256> returnByte_, classification_, userData_;
    IntegerCoder dx_{32, 2}, dy_{32, 22}, z_{32, 20};
};

//! The GPS time (a double), coded on its 64-bit pattern: as a multiple of
//! the last difference, a new difference, or a jump to one of four sequences
//! (returns of several pulses interleave in time).
class GpsTime11Decoder final : public PointwiseItem, private GpsTimeSequences
{
public:
    explicit GpsTime11Decoder(const unsigned char* first) : GpsTimeSequences(load<std::int64_t>(first)) {}

    void decode(ArithmeticDecoder& d, unsigned char* item) override
    {
        read(d);
        store<std::int64_t>(item, last_[current_]);
    }

private:
    static constexpr std::int32_t kMultiUnchanged = kMulti - kMultiMinus + 1;
    static constexpr std::int32_t kMultiCodeFull = kMulti - kMultiMinus + 2;
    static constexpr std::uint32_t kMultiTotal = kMulti - kMultiMinus + 6;

    void read(ArithmeticDecoder& d)
    {
        // A switch to another sequence is followed by that sequence's own code.
        // An encoder switches sequence at most once per time (the time fits
        // the sequence it switches to); a damaged stream could switch forever.
        for (int switches = 0;; ++switches) {
            if (switches > 1) {
                d.markCorrupt();
                return;
            }
            if (lastDiff_[current_] == 0) {
                const auto multi = static_cast<std::int32_t>(d.decodeSymbol(zeroDiff_));
                if (multi == 1) {
                    lastDiff_[current_] = diff_.decompress(d, 0, 0);
                    last_[current_] = addWrapping(last_[current_], lastDiff_[current_]);
                    extremeCount_[current_] = 0;
                } else if (multi == 2) {
                    decodeFullTime(d);
                } else if (multi > 2) {
                    current_ = (current_ + static_cast<std::uint32_t>(multi) - 2) & 3;
                    continue;
                }
                return;
            }
            const auto multi = static_cast<std::int32_t>(d.decodeSymbol(multiple_));
            if (multi == 1) {
                last_[current_] = addWrapping(last_[current_], diff_.decompress(d, lastDiff_[current_], 1));
                extremeCount_[current_] = 0;
            } else if (multi < kMultiUnchanged) {
                decodeMultiple(d, multi);
            } else if (multi == kMultiCodeFull) {
                decodeFullTime(d);
            } else if (multi > kMultiCodeFull) {
                current_ = (current_ + static_cast<std::uint32_t>(multi - kMultiCodeFull)) & 3;
                continue;
            }
            // kMultiUnchanged: the same time again.
            return;
        }
    }

    SymbolModel multiple_{kMultiTotal};
    SymbolModel zeroDiff_{6};
};

//! Red, green, blue (uint16 each).
class Rgb12Decoder final : public PointwiseItem
{
public:
    explicit Rgb12Decoder(const unsigned char* first)
    {
        for (int c = 0; c < 3; ++c)
            last_[static_cast<std::size_t>(c)] = load<std::uint16_t>(first + 2 * c);
    }

    void decode(ArithmeticDecoder& d, unsigned char* item) override
    {
        last_ = decodeRgb(d, models_, last_);
        for (int c = 0; c < 3; ++c)
            store<std::uint16_t>(item + 2 * c, last_[static_cast<std::size_t>(c)]);
    }

private:
    std::array<std::uint16_t, 3> last_{};
    RgbModels models_;
};

//! Extra bytes: each byte's change, a model per byte position.
class ByteDecoder final : public PointwiseItem
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

} // namespace

std::unique_ptr<PointwiseItem> makePointwiseItem(std::uint16_t type, std::size_t size, const unsigned char* first)
{
    switch (type) {
    case kPoint10: return std::make_unique<Point10Decoder>(first);
    case kGpsTime11: return std::make_unique<GpsTime11Decoder>(first);
    case kRgb12: return std::make_unique<Rgb12Decoder>(first);
    default: return std::make_unique<ByteDecoder>(first, size);
    }
}

} // namespace scandiff::io::detail::laz
