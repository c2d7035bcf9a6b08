// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What the layered (LAS 1.4) decoders and encoders of LAZ share (internal to
//! io/): the return tables, the point's fields, the per-scanner-channel state
//! and its context switch, the GPS time coder.

#include "Items.h"

#include <vector>

namespace scandiff::io::detail::laz::layered {

// The context of a return r of n (4-bit fields): the coordinates' medians are
// kept per class of this map (6 classes), the last heights per level.
constexpr std::uint8_t kReturnMap6[16][16] = {
    {0, 1, 2, 3, 4, 5, 3, 4, 4, 5, 5, 5, 5, 5, 5, 5}, {1, 0, 1, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3},
    {2, 1, 2, 4, 4, 4, 4, 4, 4, 4, 4, 3, 3, 3, 3, 3}, {3, 3, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4}, {5, 3, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {3, 3, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4}, {4, 3, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4}, {5, 3, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4},
    {5, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 4, 4, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4, 4}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5}};
//! |n - r|, at most 7.
constexpr std::uint32_t returnLevel8(std::uint32_t n, std::uint32_t r) { return std::min<std::uint32_t>(n > r ? n - r : r - n, 7); }

//! The fields of a LAS 1.4 point (formats 6-10, the first 30 bytes).
struct Point14
{
    std::int32_t x = 0, y = 0, z = 0;
    std::uint16_t intensity = 0;
    std::uint32_t returnNumber = 0, numberOfReturns = 0;
    std::uint32_t classificationFlags = 0, scannerChannel = 0, scanDirection = 0, edgeOfFlightLine = 0;
    std::uint32_t classification = 0, userData = 0;
    std::int16_t scanAngle = 0;
    std::uint16_t pointSource = 0;
    std::int64_t gpsTime = 0; //!< the double's bit pattern
    bool gpsTimeChanged = false; //!< of this point, a context of the next one

    static Point14 parse(const unsigned char* p)
    {
        Point14 q;
        q.x = load<std::int32_t>(p);
        q.y = load<std::int32_t>(p + 4);
        q.z = load<std::int32_t>(p + 8);
        q.intensity = load<std::uint16_t>(p + 12);
        q.returnNumber = p[14] & 15u;
        q.numberOfReturns = p[14] >> 4;
        q.classificationFlags = p[15] & 15u;
        q.scannerChannel = (p[15] >> 4) & 3u;
        q.scanDirection = (p[15] >> 6) & 1u;
        q.edgeOfFlightLine = p[15] >> 7;
        q.classification = p[16];
        q.userData = p[17];
        q.scanAngle = load<std::int16_t>(p + 18);
        q.pointSource = load<std::uint16_t>(p + 20);
        q.gpsTime = load<std::int64_t>(p + 22);
        return q;
    }

    //! All but x, y and the returns (what the layers after the first give;
    //! the decoder writes those in its first pass).
    void writeOthers(unsigned char* p) const
    {
        store(p + 8, z);
        store(p + 12, intensity);
        p[15] = static_cast<unsigned char>(classificationFlags | (scannerChannel << 4) | (scanDirection << 6) | (edgeOfFlightLine << 7));
        p[16] = static_cast<unsigned char>(classification);
        p[17] = static_cast<unsigned char>(userData);
        store(p + 18, scanAngle);
        store(p + 20, pointSource);
        store(p + 22, gpsTime);
    }
};

//! Models made on first use, keyed by a small value.
template <std::size_t N>
class LazyModels
{
public:
    explicit LazyModels(std::uint32_t symbols) : symbols_(symbols) {}
    SymbolModel& operator[](std::size_t key)
    {
        std::unique_ptr<SymbolModel>& m = models_[key];
        if (!m)
            m = std::make_unique<SymbolModel>(symbols_);
        return *m;
    }

private:
    std::uint32_t symbols_;
    std::array<std::unique_ptr<SymbolModel>, N> models_;
};

//! The context switch of the items that follow point14's context (rgb14,
//! rgbnir14, byte14): a context used for the first time starts from the last
//! item of the one before it. Returns the last item to predict from and
//! update. In version 3 a switch to a context already used keeps predicting
//! from (and updating) the previous context's last item, with the new
//! context's models: LASzip's encoder does the same, so the format is that
//! (version 4 corrected it). NIR included: the current LASzip reader and
//! writer, and laz-perf, keep it in that same last item; an earlier LASzip
//! reader (seen in older copies of its source) kept it in the new context's,
//! and so decodes the NIR of files with several channels differently.
template <typename Context>
auto& switchContext(std::array<std::unique_ptr<Context>, 4>& contexts, std::uint32_t& current, std::uint32_t context)
{
    Context* holder = contexts[current].get();
    if (context != current) {
        current = context;
        if (!contexts[context]) {
            contexts[context] = std::make_unique<Context>(holder->last);
            holder = contexts[context].get();
        }
    }
    return holder->last;
}

//! The GPS time of the layered coder: as in gpstime11, with the codes
//! renumbered (no "unchanged" code: whether the time changed is in the
//! point's changed-values symbol). Decodes or encodes, not both.
class GpsTime14 : private GpsTimeSequences
{
public:
    explicit GpsTime14(std::int64_t first) : GpsTimeSequences(first) {}

    std::int64_t decode(ArithmeticDecoder& d)
    {
        // An encoder switches sequence at most once per time (the time fits
        // the sequence it switches to); a damaged stream could switch forever.
        for (int switches = 0;; ++switches) {
            if (switches > 1) {
                d.markCorrupt();
                return last_[current_];
            }
            if (lastDiff_[current_] == 0) {
                const auto multi = static_cast<std::int32_t>(d.decodeSymbol(zeroDiff_));
                if (multi == 0) {
                    lastDiff_[current_] = diff_.decompress(d, 0, 0);
                    last_[current_] = addWrapping(last_[current_], lastDiff_[current_]);
                    extremeCount_[current_] = 0;
                } else if (multi == 1) {
                    decodeFullTime(d);
                } else {
                    current_ = (current_ + static_cast<std::uint32_t>(multi) - 1) & 3;
                    continue;
                }
                return last_[current_];
            }
            const auto multi = static_cast<std::int32_t>(d.decodeSymbol(multiple_));
            if (multi == 1) {
                last_[current_] = addWrapping(last_[current_], diff_.decompress(d, lastDiff_[current_], 1));
                extremeCount_[current_] = 0;
            } else if (multi < kMultiCodeFull) {
                decodeMultiple(d, multi);
            } else if (multi == kMultiCodeFull) {
                decodeFullTime(d);
            } else {
                current_ = (current_ + static_cast<std::uint32_t>(multi - kMultiCodeFull)) & 3;
                continue;
            }
            return last_[current_];
        }
    }

    //! The mirror of decode(): `time` (a double's bit pattern) as a
    //! multiple of the last difference, a new difference, a switch to
    //! another of the four sequences, or a new sequence.
    void encode(ArithmeticEncoder& e, std::int64_t time)
    {
        for (;;) {
            const std::int64_t diff64 = wrapSub(time, last_[current_]);
            const auto diff = static_cast<std::int32_t>(diff64);
            const bool fits = diff64 == std::int64_t(diff);
            if (lastDiff_[current_] == 0) {
                if (fits) {
                    e.encodeSymbol(zeroDiff_, 0);
                    diff_.compress(e, 0, diff, 0);
                    lastDiff_[current_] = diff;
                    extremeCount_[current_] = 0;
                    last_[current_] = time;
                    return;
                }
                if (const int other = otherSequence(time)) {
                    e.encodeSymbol(zeroDiff_, static_cast<std::uint32_t>(other + 1));
                    current_ = (current_ + static_cast<std::uint32_t>(other)) & 3;
                    continue;
                }
                e.encodeSymbol(zeroDiff_, 1);
                newSequence(e, time);
                return;
            }
            if (!fits) {
                if (const int other = otherSequence(time)) {
                    e.encodeSymbol(multiple_, static_cast<std::uint32_t>(kMultiCodeFull + other));
                    current_ = (current_ + static_cast<std::uint32_t>(other)) & 3;
                    continue;
                }
                e.encodeSymbol(multiple_, kMultiCodeFull);
                newSequence(e, time);
                return;
            }
            const std::int32_t previous = lastDiff_[current_];
            // LASzip's choice of multiplier: a float ratio rounded half away from zero.
            // Clamped first: every multiplier beyond the coded ones is coded as the extreme one.
            const float ratio = std::clamp(static_cast<float>(diff) / static_cast<float>(previous), float(kMultiMinus - 1), float(kMulti + 1));
            const auto multi = static_cast<std::int32_t>(ratio >= 0 ? ratio + 0.5f : ratio - 0.5f);
            if (multi == 1) {
                e.encodeSymbol(multiple_, 1);
                diff_.compress(e, previous, diff, 1);
                extremeCount_[current_] = 0;
            } else if (multi > 0) {
                if (multi < kMulti) {
                    e.encodeSymbol(multiple_, static_cast<std::uint32_t>(multi));
                    diff_.compress(e, wrapMul(multi, previous), diff, multi < 10 ? 2 : 3);
                } else {
                    e.encodeSymbol(multiple_, kMulti);
                    diff_.compress(e, wrapMul(kMulti, previous), diff, 4);
                    countExtreme(diff);
                }
            } else if (multi < 0) {
                if (multi > kMultiMinus) {
                    e.encodeSymbol(multiple_, static_cast<std::uint32_t>(kMulti - multi));
                    diff_.compress(e, wrapMul(multi, previous), diff, 5);
                } else {
                    e.encodeSymbol(multiple_, kMulti - kMultiMinus);
                    diff_.compress(e, wrapMul(kMultiMinus, previous), diff, 6);
                    countExtreme(diff);
                }
            } else {
                e.encodeSymbol(multiple_, 0);
                diff_.compress(e, 0, diff, 7);
                countExtreme(diff);
            }
            last_[current_] = time;
            return;
        }
    }

private:
    static constexpr std::int32_t kMultiCodeFull = kMulti - kMultiMinus + 1;
    static constexpr std::uint32_t kMultiTotal = kMulti - kMultiMinus + 5;

    static std::int64_t wrapSub(std::int64_t a, std::int64_t b)
    {
        return static_cast<std::int64_t>(static_cast<std::uint64_t>(a) - static_cast<std::uint64_t>(b));
    }
    //! 1-3: the sequence, counted from the current one, whose last time is within 32 bits; 0: none.
    int otherSequence(std::int64_t time) const
    {
        for (int i = 1; i < 4; ++i) {
            const std::int64_t d = wrapSub(time, last_[(current_ + static_cast<std::uint32_t>(i)) & 3]);
            if (d == std::int64_t(static_cast<std::int32_t>(d)))
                return i;
        }
        return 0;
    }
    void newSequence(ArithmeticEncoder& e, std::int64_t time)
    {
        diff_.compress(e, static_cast<std::int32_t>(static_cast<std::uint64_t>(last_[current_]) >> 32),
                          static_cast<std::int32_t>(static_cast<std::uint64_t>(time) >> 32), 8);
        e.writeInt(static_cast<std::uint32_t>(static_cast<std::uint64_t>(time)));
        next_ = (next_ + 1) & 3;
        current_ = next_;
        lastDiff_[current_] = 0;
        extremeCount_[current_] = 0;
        last_[current_] = time;
    }

    SymbolModel multiple_{kMultiTotal};
    SymbolModel zeroDiff_{5};
};

//! One scanner channel's state of the point14 coder.
struct Point14Context
{
    explicit Point14Context(const Point14& from) : last(from), gpsTime(from.gpsTime)
    {
        last.gpsTimeChanged = false;
        lastZ.fill(from.z);
        lastIntensity.fill(from.intensity);
    }

    //! A context the decoder's first pass started from `from` when only its
    //! returns and x, y were known: the rest of `from`, once decoded.
    void restartOthers(const Point14& from)
    {
        Point14 restarted = from;
        restarted.x = last.x;
        restarted.y = last.y;
        restarted.returnNumber = last.returnNumber;
        restarted.numberOfReturns = last.numberOfReturns;
        restarted.scannerChannel = last.scannerChannel;
        restarted.gpsTimeChanged = last.gpsTimeChanged;
        last = restarted;
        lastZ.fill(from.z);
        lastIntensity.fill(from.intensity);
        gpsTime = GpsTime14(from.gpsTime);
    }

    Point14 last;
    std::array<SymbolModel, 8> changedValues{SymbolModel(128), SymbolModel(128), SymbolModel(128), SymbolModel(128),
                                             SymbolModel(128), SymbolModel(128), SymbolModel(128), SymbolModel(128)};
    SymbolModel scannerChannel{3};
    LazyModels<16> numberOfReturns{16}, returnNumber{16};
    SymbolModel returnNumberGpsSame{13};
    IntegerCoder dx{32, 2}, dy{32, 22}, z{32, 20};
    std::array<StreamingMedian5, 12> xMedian{}, yMedian{};
    std::array<std::int32_t, 8> lastZ{};
    LazyModels<64> classification{256}, flags{64}, userData{256};
    IntegerCoder intensity{16, 4};
    std::array<std::uint16_t, 8> lastIntensity{};
    IntegerCoder scanAngle{16, 2};
    IntegerCoder pointSource{16};
    GpsTime14 gpsTime;
};

//! One scanner channel's state of the rgb14 and rgbnir14 coders.
struct RgbContext
{
    explicit RgbContext(const std::array<std::uint16_t, 4>& from) : last(from) {}
    std::array<std::uint16_t, 4> last; //!< red, green, blue, near infrared
    RgbModels rgbModels;
    SymbolModel nirUsed{4};
    std::array<SymbolModel, 2> nirDiff{SymbolModel(256), SymbolModel(256)};
};

//! One scanner channel's state of the byte14 coder.
struct BytesContext
{
    explicit BytesContext(const std::vector<unsigned char>& from) : last(from)
    {
        models.reserve(from.size());
        for (std::size_t i = 0; i < from.size(); ++i)
            models.emplace_back(256);
    }
    std::vector<unsigned char> last;
    std::vector<SymbolModel> models;
};

} // namespace scandiff::io::detail::laz::layered
