// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The entropy coder of LAZ (internal to io/): the adaptive arithmetic coder
//! LASzip uses (A. Said, "Introduction to Arithmetic Coding - Theory and
//! Practice", HP Labs HPL-2004-76, in the variant M. Isenburg published with
//! LASzip, "LASzip: lossless compression of LiDAR data", PE&RS 79(2), 2013),
//! its adaptive symbol and bit models, and the integer coder that codes a value
//! as a correction to a prediction, in both directions. Every constant and update rule
//! must match the encoder bit for bit, or the stream decodes into garbage:
//! they are LASzip's, from its published description and source.
//!
//! Written by hand because Debian 12 packages no LAZ library (no LASzip, no
//! laz-perf, no PDAL).

#include <algorithm>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <vector>

namespace scandiff::io::detail::laz {

constexpr std::uint32_t kMinLength = 0x01000000u; //!< renormalise below this interval length
constexpr std::uint32_t kMaxLength = 0xFFFFFFFFu;
constexpr std::uint32_t kBitLengthShift = 13;     //!< bit models: probability precision
constexpr std::uint32_t kBitMaxCount = 1u << kBitLengthShift;
constexpr std::uint32_t kSymbolLengthShift = 15;  //!< symbol models: distribution precision
constexpr std::uint32_t kSymbolMaxCount = 1u << kSymbolLengthShift;

//! An adaptive model of one binary decision.
struct BitModel
{
    std::uint32_t updateCycle = 4, bitsUntilUpdate = 4;
    std::uint32_t bit0Probability = 1u << (kBitLengthShift - 1);
    std::uint32_t bit0Count = 1, bitCount = 2;

    [[gnu::noinline, gnu::cold]] void update()
    {
        // Halve the counts when they reach the maximum, then rescale.
        if ((bitCount += updateCycle) > kBitMaxCount) {
            bitCount = (bitCount + 1) >> 1;
            bit0Count = (bit0Count + 1) >> 1;
            if (bit0Count == bitCount)
                ++bitCount;
        }
        const std::uint32_t scale = 0x80000000u / bitCount;
        bit0Probability = (bit0Count * scale) >> (31 - kBitLengthShift);
        updateCycle = (5 * updateCycle) >> 2;
        if (updateCycle > 64)
            updateCycle = 64;
        bitsUntilUpdate = updateCycle;
    }
};

//! An adaptive model of an alphabet of 2..2048 symbols, with the lookup table
//! that speeds decoding of alphabets larger than 4.
class SymbolModel
{
public:
    //! The table is only the decoder's search aid: the stream does not depend
    //! on it. LASzip's has a quarter as many entries as symbols, and the
    //! bisection that ends each search then took a third of the integer
    //! decoding's time (its branches follow the coded data, so they are
    //! mispredicted); this one has four entries per symbol, so a search mostly
    //! ends at the table. Once a model has settled (an update every
    //! (symbols + 6) × 8 symbols), rebuilding the table costs under one store
    //! per symbol decoded.
    static constexpr std::uint32_t kTableFinerBits = 2;
    static constexpr std::uint32_t kTableFrom = 4;

    explicit SymbolModel(std::uint32_t symbols) : symbols_(symbols), lastSymbol_(symbols - 1)
    {
        assert(symbols >= 2 && symbols <= 2048); // LAZ's alphabets; the 16-bit counts need under 4,000
        if (symbols > kTableFrom) {
            std::uint32_t tableBits = 3;
            while (symbols > (1u << (tableBits - kTableFinerBits)))
                ++tableBits;
            tableSize_ = 1u << tableBits;
            tableShift_ = kSymbolLengthShift - tableBits;
            // value / (length >> 15) reaches 2^15 + 2^15 / (length >> 15)
            // at most, and length >= 2^24: 64 past the end, rounded up to
            // entries, and one more for the end of the last search.
            tableEnd_ = tableSize_ + ((64u + (1u << tableShift_) - 1) >> tableShift_);
            // Eight entries of room past the end for fillDecoderTable()'s stores.
            decoderTable_.resize(tableEnd_ + 2 + 8);
        }
        distribution_.resize(symbols);
        counts_.assign(symbols, 1);
        updateCycle_ = symbols;
        update();
        updateCycle_ = symbolsUntilUpdate_ = (symbols + 6) >> 1;
    }

    [[gnu::noinline, gnu::cold]] void update()
    {
        if ((totalCount_ += updateCycle_) > kSymbolMaxCount) {
            totalCount_ = 0;
            for (std::uint16_t& c : counts_)
                totalCount_ += (c = static_cast<std::uint16_t>((c + 1) >> 1));
        }
        std::uint32_t sum = 0;
        const std::uint32_t scale = 0x80000000u / totalCount_;
        for (std::uint32_t k = 0; k < symbols_; ++k) {
            distribution_[k] = static_cast<std::uint16_t>((scale * sum) >> (31 - kSymbolLengthShift));
            sum += counts_[k];
        }
        if (tableSize_ != 0)
            fillDecoderTable();
        updateCycle_ = (5 * updateCycle_) >> 2;
        const std::uint32_t maxCycle = (symbols_ + 6) << 3;
        if (updateCycle_ > maxCycle)
            updateCycle_ = maxCycle;
        symbolsUntilUpdate_ = updateCycle_;
    }

private:
    //! Entry t holds the last symbol whose distribution is below t's share
    //! of the interval: entries (dist[k - 1] >> shift, dist[k] >> shift]
    //! are symbol k - 1, the ones past the last symbol's start the last.
    void fillDecoderTable()
    {
        std::uint16_t* table = decoderTable_.data();
        std::uint32_t s = 0;
        for (std::uint32_t k = 1; k < symbols_; ++k) {
            const std::uint32_t w = distribution_[k] >> tableShift_;
            // Eight entries at once whether the symbol spans that many or
            // none; the next symbol's overwrite the ones past its own. A
            // loop entry by entry stopped on a branch mispredicted at every
            // symbol (the spans follow the counts), and the models of a
            // chunk are rebuilt often while their update cycle is short.
            const std::uint64_t pattern = (k - 1) * 0x0001000100010001ull;
            std::memcpy(table + s + 1, &pattern, sizeof pattern);
            std::memcpy(table + s + 5, &pattern, sizeof pattern);
            for (std::uint32_t t = s + 9; t <= w; ++t)
                table[t] = static_cast<std::uint16_t>(k - 1);
            s = w;
        }
        table[0] = 0;
        std::fill(table + s + 1, table + tableEnd_ + 2, static_cast<std::uint16_t>(symbols_ - 1));
    }

    friend class ArithmeticDecoder;
    friend class ArithmeticEncoder;
    std::uint32_t symbols_, lastSymbol_;
    std::uint32_t tableSize_ = 0, tableShift_ = 0, tableEnd_ = 0;
    std::uint32_t totalCount_ = 0, updateCycle_ = 0, symbolsUntilUpdate_ = 0;
    // 16 bits suffice and halve the models' share of the cache: the
    // distribution is below 2^15, a symbol below 2^11, and a count at most
    // 2^15 plus one update cycle ((516 + 6) × 8 for the largest alphabet LAZ
    // uses, gpstime11's; under 2^16 up to 4,000 symbols). They also cannot
    // alias the decoder's 32-bit state.
    std::vector<std::uint16_t> distribution_, counts_, decoderTable_;
};

//! Decodes from the bytes [begin, end); beyond `end` it reads zeros and counts
//! them, so a corrupt stream can be told from a whole one.
class ArithmeticDecoder
{
public:
    ArithmeticDecoder(const unsigned char* begin, const unsigned char* end) : next_(begin), end_(end)
    {
        for (int i = 0; i < 4; ++i)
            value_ = (value_ << 8) | byte();
    }

    //! Where the next byte would be read (past `end` when it ran out).
    const unsigned char* position() const { return next_; }
    std::size_t bytesPastEnd() const { return pastEnd_; }
    //! Whether the stream was read to its last byte exactly, as every stream
    //! an encoder finished is (it writes the bytes the decoder reads ahead).
    bool endedExactly() const { return next_ == end_; }
    //! Whether the stream cannot come from an encoder: it ran past its end,
    //! left the coding interval, or a coder saw an impossible sequence.
    bool corrupt() const { return pastEnd_ > 0 || corrupt_ || value_ >= length_; }
    void markCorrupt() { corrupt_ = true; }

    std::uint32_t decodeBit(BitModel& m)
    {
        const std::uint32_t x = m.bit0Probability * (length_ >> kBitLengthShift);
        const std::uint32_t bit = value_ >= x;
        if (bit == 0) {
            length_ = x;
            ++m.bit0Count;
        } else {
            value_ -= x;
            length_ -= x;
        }
        renormalise();
        if (--m.bitsUntilUpdate == 0)
            m.update();
        return bit;
    }

    std::uint32_t decodeSymbol(SymbolModel& m)
    {
        std::uint32_t symbol, x, y = length_;
        if (!m.decoderTable_.empty()) {
            // The table narrows the search to a few symbols, bisection ends it.
            length_ >>= kSymbolLengthShift;
            const std::uint32_t dv = value_ / length_;
            std::uint32_t t = dv >> m.tableShift_;
            // The table has entries beyond its size for the rounding of
            // `length`; only a damaged stream, out of its interval, goes further.
            if (t > m.tableEnd_) {
                corrupt_ = true;
                t = m.tableEnd_;
            }
            symbol = m.decoderTable_[t];
            std::uint32_t n = m.decoderTable_[t + 1] + 1;
            // Without branches: which half holds the symbol is the coded
            // data itself, so a branch on it would be mispredicted half the
            // time. Masks, because GCC turns the plain selections into a branch.
            const std::uint16_t* distribution = m.distribution_.data();
            while (n > symbol + 1) {
                const std::uint32_t k = (symbol + n) >> 1;
                const std::uint32_t above = 0u - static_cast<std::uint32_t>(distribution[k] > dv);
                n = (k & above) | (n & ~above);
                symbol = (symbol & above) | (k & ~above);
            }
            x = m.distribution_[symbol] * length_;
            if (symbol != m.lastSymbol_)
                y = m.distribution_[symbol + 1] * length_;
        } else {
            x = symbol = 0;
            length_ >>= kSymbolLengthShift;
            std::uint32_t n = m.symbols_;
            std::uint32_t k = n >> 1;
            do {
                const std::uint32_t z = length_ * m.distribution_[k];
                if (z > value_) {
                    n = k;
                    y = z;
                } else {
                    symbol = k;
                    x = z;
                }
            } while ((k = (symbol + n) >> 1) != symbol);
        }
        value_ -= x;
        length_ = y - x;
        renormalise();
        ++m.counts_[symbol];
        if (--m.symbolsUntilUpdate_ == 0)
            m.update();
        return symbol;
    }

    //! `bits` raw bits (1..32), not modelled.
    std::uint32_t readBits(std::uint32_t bits)
    {
        if (bits > 19) {
            const std::uint32_t low = readShort();
            const std::uint32_t high = readBits(bits - 16) << 16;
            return high | low;
        }
        length_ >>= bits;
        const std::uint32_t value = value_ / length_;
        value_ -= length_ * value;
        renormalise();
        return value;
    }

    std::uint32_t readShort() { return readBits(16); }
    //! Low 16 bits first.
    std::uint32_t readInt()
    {
        const std::uint32_t low = readShort();
        const std::uint32_t high = readShort();
        return (high << 16) | low;
    }

private:
    std::uint32_t byte()
    {
        if (next_ < end_)
            return *next_++;
        ++next_;
        ++pastEnd_;
        return 0;
    }
    //! Shifts `length` back to at least kMinLength, a byte of the stream
    //! into `value` for each 8 bits. Whether it is needed after a symbol is
    //! the coded data itself: a branch on it was mispredicted often, so the
    //! shift (0, 8, 16 or 24 bits: `length` is never 0) is computed and
    //! applied without one, up to 4 bytes before the end of the stream.
    void renormalise()
    {
        if (end_ - next_ < 4) {
            while (length_ < kMinLength) {
                value_ = (value_ << 8) | byte();
                length_ <<= 8;
            }
            return;
        }
        const unsigned shift = static_cast<unsigned>(__builtin_clz(length_)) & ~7u;
        std::uint32_t word;
        std::memcpy(&word, next_, sizeof word);
        word = __builtin_bswap32(word); // the stream is big-endian
        value_ = static_cast<std::uint32_t>(((std::uint64_t(value_) << 32) | word) >> (32 - shift));
        length_ <<= shift;
        next_ += shift >> 3;
    }

    const unsigned char* next_;
    const unsigned char* end_;
    std::size_t pastEnd_ = 0;
    bool corrupt_ = false;
    std::uint32_t value_ = 0, length_ = kMaxLength;
};

//! Encodes into a byte vector, the mirror of ArithmeticDecoder. done() ends
//! the stream with the bytes the decoder reads ahead, no more.
class ArithmeticEncoder
{
public:
    void encodeBit(BitModel& m, std::uint32_t bit)
    {
        const std::uint32_t x = m.bit0Probability * (length_ >> kBitLengthShift);
        if (bit == 0) {
            length_ = x;
            ++m.bit0Count;
        } else {
            add(x);
            length_ -= x;
        }
        if (length_ < kMinLength)
            renormalise();
        if (--m.bitsUntilUpdate == 0)
            m.update();
    }

    void encodeSymbol(SymbolModel& m, std::uint32_t symbol)
    {
        std::uint32_t x;
        if (symbol == m.lastSymbol_) {
            x = m.distribution_[symbol] * (length_ >> kSymbolLengthShift);
            add(x);
            length_ -= x;
        } else {
            length_ >>= kSymbolLengthShift;
            x = m.distribution_[symbol] * length_;
            add(x);
            length_ = m.distribution_[symbol + 1] * length_ - x;
        }
        if (length_ < kMinLength)
            renormalise();
        ++m.counts_[symbol];
        if (--m.symbolsUntilUpdate_ == 0)
            m.update();
    }

    //! `bits` raw bits (1..32) of `value`.
    void writeBits(std::uint32_t bits, std::uint32_t value)
    {
        if (bits > 19) {
            writeBits(16, value & 0xFFFF);
            value >>= 16;
            bits -= 16;
        }
        length_ >>= bits;
        add(value * length_);
        if (length_ < kMinLength)
            renormalise();
    }
    //! Low 16 bits first.
    void writeInt(std::uint32_t value)
    {
        writeBits(16, value & 0xFFFF);
        writeBits(16, value >> 16);
    }

    //! The finished stream.
    std::vector<unsigned char> done()
    {
        const std::uint32_t before = base_;
        bool anotherByte = true;
        if (length_ > 2 * kMinLength) {
            base_ += kMinLength;
            length_ = kMinLength >> 1;
        } else {
            base_ += kMinLength >> 1;
            length_ = kMinLength >> 9;
            anotherByte = false;
        }
        if (before > base_)
            propagateCarry();
        renormalise();
        // Zeros for the decoder's read-ahead, so that it ends on the last byte.
        out_.push_back(0);
        out_.push_back(0);
        if (anotherByte)
            out_.push_back(0);
        return std::move(out_);
    }

private:
    void add(std::uint32_t x)
    {
        const std::uint32_t before = base_;
        base_ += x;
        if (before > base_)
            propagateCarry();
    }
    void propagateCarry()
    {
        std::size_t i = out_.size();
        while (i > 0 && out_[i - 1] == 0xFF)
            out_[--i] = 0;
        if (i > 0)
            ++out_[i - 1];
    }
    void renormalise()
    {
        do {
            out_.push_back(static_cast<unsigned char>(base_ >> 24));
            base_ <<= 8;
        } while ((length_ <<= 8) < kMinLength);
    }

    std::uint32_t base_ = 0, length_ = kMaxLength;
    std::vector<unsigned char> out_;
};

//! Integers of `bits` bits (32: any int32) coded as the correction to a
//! prediction: first the number k of significant bits of the correction (a
//! symbol model per context), then its value among the 2^k of that size (a
//! model per k for the high `bitsHigh` bits, raw bits below). Sums wrap
//! modulo 2^bits, as the encoder folded them. One class for both directions:
//! the per-scanner-channel states that hold these are shared by the decoders
//! and the encoders.
class IntegerCoder
{
public:
    explicit IntegerCoder(std::uint32_t bits, std::uint32_t contexts = 1, std::uint32_t bitsHigh = 8) : bitsHigh_(bitsHigh)
    {
        if (bits > 0 && bits < 32) {
            correctionBits_ = bits;
            range_ = 1u << bits;
            minCorrection_ = -static_cast<std::int32_t>(range_ / 2);
            maxCorrection_ = minCorrection_ + static_cast<std::int32_t>(range_ - 1);
        }
        sizeModels_.reserve(contexts);
        for (std::uint32_t c = 0; c < contexts; ++c)
            sizeModels_.emplace_back(correctionBits_ + 1);
        valueModels_.resize(correctionBits_);
    }

    //! The size k of the last correction: the point coders use it as context.
    std::uint32_t lastSize() const { return k_; }

    std::int32_t decompress(ArithmeticDecoder& decoder, std::int32_t prediction, std::uint32_t context = 0)
    {
        const std::int32_t correction = readCorrection(decoder, sizeModels_[context]);
        if (range_ == 0)
            return static_cast<std::int32_t>(static_cast<std::uint32_t>(prediction) + static_cast<std::uint32_t>(correction));
        std::int64_t value = std::int64_t(prediction) + correction;
        if (value < 0)
            value += range_;
        else if (value >= std::int64_t(range_))
            value -= range_;
        return static_cast<std::int32_t>(value);
    }

    void compress(ArithmeticEncoder& encoder, std::int32_t prediction, std::int32_t value, std::uint32_t context = 0)
    {
        std::int32_t correction;
        if (range_ == 0) {
            correction = static_cast<std::int32_t>(static_cast<std::uint32_t>(value) - static_cast<std::uint32_t>(prediction));
        } else {
            std::int64_t c = std::int64_t(value) - prediction;
            if (c < minCorrection_)
                c += range_;
            else if (c > maxCorrection_)
                c -= range_;
            correction = static_cast<std::int32_t>(c);
        }
        writeCorrection(encoder, correction, sizeModels_[context]);
    }

private:
    SymbolModel& valueModel(std::uint32_t k)
    {
        std::optional<SymbolModel>& model = valueModels_[k - 1];
        if (!model)
            model.emplace(k <= bitsHigh_ ? 1u << k : 1u << bitsHigh_);
        return *model;
    }
    std::int32_t readCorrection(ArithmeticDecoder& decoder, SymbolModel& sizeModel)
    {
        k_ = decoder.decodeSymbol(sizeModel);
        if (k_ == 0)
            return static_cast<std::int32_t>(decoder.decodeBit(zeroOrOne_));
        if (k_ >= 32)
            return minCorrection_;
        std::int64_t c = decoder.decodeSymbol(valueModel(k_));
        if (k_ > bitsHigh_) {
            const std::uint32_t lowBits = k_ - bitsHigh_;
            c = (c << lowBits) | decoder.readBits(lowBits);
        }
        // [0, 2^(k-1)) stands for [-(2^k - 1), -2^(k-1)], [2^(k-1), 2^k) for
        // [2^(k-1) + 1, 2^k]. Without a branch: the sign is the data itself.
        const std::int64_t below = -static_cast<std::int64_t>(c < (std::int64_t(1) << (k_ - 1)));
        c += 1 - (below & (std::int64_t(1) << k_));
        return static_cast<std::int32_t>(static_cast<std::uint32_t>(c));
    }
    void writeCorrection(ArithmeticEncoder& encoder, std::int32_t c, SymbolModel& sizeModel)
    {
        // k: the smallest with c in [-(2^k - 1), 2^k].
        std::uint32_t magnitude = c <= 0 ? static_cast<std::uint32_t>(-std::int64_t(c)) : static_cast<std::uint32_t>(c) - 1;
        k_ = 0;
        while (magnitude) {
            magnitude >>= 1;
            ++k_;
        }
        encoder.encodeSymbol(sizeModel, k_);
        if (k_ == 0) {
            encoder.encodeBit(zeroOrOne_, static_cast<std::uint32_t>(c));
            return;
        }
        if (k_ >= 32)
            return; // INT32_MIN: the decoder knows it from k alone
        std::int64_t v = c < 0 ? std::int64_t(c) + ((std::int64_t(1) << k_) - 1) : std::int64_t(c) - 1;
        if (k_ <= bitsHigh_) {
            encoder.encodeSymbol(valueModel(k_), static_cast<std::uint32_t>(v));
        } else {
            const std::uint32_t lowBits = k_ - bitsHigh_;
            const auto low = static_cast<std::uint32_t>(v & ((std::int64_t(1) << lowBits) - 1));
            encoder.encodeSymbol(valueModel(k_), static_cast<std::uint32_t>(v >> lowBits));
            encoder.writeBits(lowBits, low);
        }
    }

    std::uint32_t bitsHigh_;
    std::uint32_t correctionBits_ = 32;
    std::uint32_t range_ = 0; //!< 0: 32-bit values, wrapping as uint32
    std::int32_t minCorrection_ = INT32_MIN;
    std::int32_t maxCorrection_ = INT32_MAX;
    std::uint32_t k_ = 0;
    std::vector<SymbolModel> sizeModels_;
    BitModel zeroOrOne_;
    //! The model of corrections of k bits, index k - 1, made on first use:
    //! a chunk of a few dozen thousand points seldom sees more than half of
    //! the 32 sizes, and a model of 256 symbols takes 3 KB to make (its
    //! first state does not depend on when it is made).
    std::vector<std::optional<SymbolModel>> valueModels_;
};

} // namespace scandiff::io::detail::laz
