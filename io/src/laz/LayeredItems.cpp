// SPDX-License-Identifier: GPL-3.0-or-later
//! The layered item coders of LAZ, version 3 (LAS 1.4 point formats 6-10):
//! point14, rgb14, rgbnir14 and byte14, after LASzip's
//! lasreaditemcompressed_v3.cpp. Each attribute has a stream ("layer") of its
//! own in a chunk, empty when the attribute never changes there; the state is
//! kept per scanner channel (four contexts), a new context starting from the
//! last point of the one before it.

#include "LayeredState.h"

#include <optional>
#include <vector>

namespace scandiff::io::detail::laz {

namespace {

using namespace layered;

//! A layer's decoder, when the layer has bytes.
class LayerStream
{
public:
    void open(const Layer& layer)
    {
        decoder_.reset();
        if (layer.size > 0)
            decoder_.emplace(layer.data, layer.data + layer.size);
    }
    bool changes() const { return decoder_.has_value(); }
    ArithmeticDecoder& operator*() { return *decoder_; }
    bool corrupt() const { return decoder_ && decoder_->corrupt(); }
    bool endedExactly() const { return !decoder_ || decoder_->endedExactly(); }

private:
    std::optional<ArithmeticDecoder> decoder_;
};

//! The 30 bytes of a LAS 1.4 point, in nine layers: returns and x, y; z;
//! classification; flags; intensity; scan angle; user data; point source;
//! GPS time.
class Point14Decoder final : public LayeredItem
{
public:
    explicit Point14Decoder(const unsigned char* first) : first_(Point14::parse(first)) {}

    std::size_t layerCount() const override { return kLayers; }

    void start(const Layer* layers, std::uint32_t& context) override
    {
        for (std::size_t i = 0; i < kLayers; ++i)
            streams_[i].open(layers[i]);
        xyChannel_ = first_.scannerChannel;
        context = xyChannel_;
        contexts_[xyChannel_] = std::make_unique<Point14Context>(first_);
    }

    bool corrupt() const override
    {
        return std::any_of(streams_.begin(), streams_.end(), [](const LayerStream& s) { return s.corrupt(); });
    }
    bool endedExactly() const override
    {
        return std::all_of(streams_.begin(), streams_.end(), [](const LayerStream& s) { return s.endedExactly(); });
    }

    //! Two passes over the run: the returns and x, y first, then the other
    //! layers from what the first left per point. The layers are streams of
    //! their own; in one pass each, a layer's decoding does not wait behind
    //! the x, y layer's mispredicted branches.
    void decodeRun(unsigned char* item, std::size_t stride, std::size_t count, std::uint8_t* contexts) override
    {
        steps_.resize(count);
        for (std::size_t k = 0; k < count; ++k) {
            steps_[k] = decodeReturnsXY(item + k * stride);
            // The items after this one see the channel where it changed, 0 elsewhere (Items.h).
            contexts[k] = steps_[k].channelChanged ? steps_[k].channel : 0;
        }
        for (std::size_t k = 0; k < count; ++k)
            decodeOthers(item + k * stride, steps_[k]);
    }

private:
    enum : std::size_t { kReturnsXY, kZ, kClassification, kFlags, kIntensity, kScanAngle, kUserData, kPointSource, kGpsTime, kLayers };

    //! What the x, y layer tells the others about a point.
    struct Step
    {
        std::uint8_t channel = 0;
        std::uint8_t startedFrom = kNone; //!< a channel used for the first time starts from this one's last point
        std::uint8_t position = 0;        //!< single 3, first 2, last 1, intermediate 0
        std::uint8_t level = 0;           //!< |n - r|, at most 7: the height's context
        std::uint8_t zSize = 0;           //!< the mean size of the x and y corrections
        bool channelChanged = false, single = false, gpsTimeChanged = false, scanAngleChanged = false,
             pointSourceChanged = false;
    };
    static constexpr std::uint8_t kNone = 0xFF;

    Step decodeReturnsXY(unsigned char* item)
    {
        Step step;
        Point14Context* c = contexts_[xyChannel_].get();
        ArithmeticDecoder& xy = *streams_[kReturnsXY];
        // The last point's return (single, first, last or intermediate) and
        // whether its time changed choose the model of what changed now.
        const std::uint32_t lastPosition = (c->last.returnNumber == 1 ? 1u : 0u) +
                                           (c->last.returnNumber >= c->last.numberOfReturns ? 2u : 0u) +
                                           (c->last.gpsTimeChanged ? 4u : 0u);
        const std::uint32_t changed = xy.decodeSymbol(c->changedValues[lastPosition]);
        if (changed & (1u << 6)) {
            const std::uint32_t channel = (xyChannel_ + xy.decodeSymbol(c->scannerChannel) + 1) % 4;
            if (!contexts_[channel]) {
                // Only the returns and x, y of the last point are known yet:
                // the second pass sets the rest when it reaches this point.
                contexts_[channel] = std::make_unique<Point14Context>(c->last);
                step.startedFrom = static_cast<std::uint8_t>(xyChannel_);
            }
            xyChannel_ = channel;
            c = contexts_[xyChannel_].get();
            step.channelChanged = true;
        }
        step.channel = static_cast<std::uint8_t>(xyChannel_);
        Point14& p = c->last;
        step.pointSourceChanged = changed & (1u << 5);
        step.gpsTimeChanged = changed & (1u << 4);
        step.scanAngleChanged = changed & (1u << 3);

        const std::uint32_t lastN = p.numberOfReturns, lastR = p.returnNumber;
        const std::uint32_t n = (changed & (1u << 2)) ? xy.decodeSymbol(c->numberOfReturns[lastN]) : lastN;
        p.numberOfReturns = n;
        std::uint32_t r = lastR;
        switch (changed & 3u) {
        case 1: r = (lastR + 1) % 16; break;
        case 2: r = (lastR + 15) % 16; break;
        case 3:
            r = step.gpsTimeChanged ? xy.decodeSymbol(c->returnNumber[lastR])
                                    : (lastR + xy.decodeSymbol(c->returnNumberGpsSame) + 2) % 16;
            break;
        default: break;
        }
        p.returnNumber = r;
        step.single = n == 1;
        step.level = static_cast<std::uint8_t>(returnLevel8(n, r));
        // The return of this point: single 3, first 2, last 1, intermediate 0
        // (the last point's above counts first as 1 and last as 2).
        step.position = static_cast<std::uint8_t>((r == 1 ? 2u : 0u) + (r >= n ? 1u : 0u));
        const std::uint32_t medianSlot = (std::uint32_t(kReturnMap6[n][r]) << 1) | (step.gpsTimeChanged ? 1u : 0u);

        const std::int32_t dx = c->dx.decompress(xy, c->xMedian[medianSlot].median(), n == 1);
        p.x = static_cast<std::int32_t>(static_cast<std::uint32_t>(p.x) + static_cast<std::uint32_t>(dx));
        c->xMedian[medianSlot].add(dx);
        const std::uint32_t k = c->dx.lastSize();
        const std::int32_t dy = c->dy.decompress(xy, c->yMedian[medianSlot].median(), (n == 1) + (k < 20 ? k & ~1u : 20));
        p.y = static_cast<std::int32_t>(static_cast<std::uint32_t>(p.y) + static_cast<std::uint32_t>(dy));
        c->yMedian[medianSlot].add(dy);
        step.zSize = static_cast<std::uint8_t>((c->dx.lastSize() + c->dy.lastSize()) / 2);
        p.gpsTimeChanged = step.gpsTimeChanged;
        p.scannerChannel = xyChannel_;
        store(item, p.x);
        store(item + 4, p.y);
        item[14] = static_cast<unsigned char>(r | (n << 4));
        return step;
    }

    void decodeOthers(unsigned char* item, const Step& step)
    {
        if (step.startedFrom != kNone)
            contexts_[step.channel]->restartOthers(contexts_[step.startedFrom]->last);
        Point14Context* c = contexts_[step.channel].get();
        Point14& p = c->last;
        if (streams_[kZ].changes()) {
            const std::uint32_t k = step.zSize;
            p.z = c->z.decompress(*streams_[kZ], c->lastZ[step.level], step.single + (k < 18 ? k & ~1u : 18));
            c->lastZ[step.level] = p.z;
        }
        if (streams_[kClassification].changes()) {
            const std::uint32_t key = ((p.classification & 0x1F) << 1) + (step.position == 3 ? 1 : 0);
            p.classification = (*streams_[kClassification]).decodeSymbol(c->classification[key]);
        }
        if (streams_[kFlags].changes()) {
            const std::uint32_t key = (p.edgeOfFlightLine << 5) | (p.scanDirection << 4) | p.classificationFlags;
            const std::uint32_t f = (*streams_[kFlags]).decodeSymbol(c->flags[key]);
            p.edgeOfFlightLine = (f >> 5) & 1;
            p.scanDirection = (f >> 4) & 1;
            p.classificationFlags = f & 0x0F;
        }
        if (streams_[kIntensity].changes()) {
            const std::uint32_t slot = (std::uint32_t(step.position) << 1) | (step.gpsTimeChanged ? 1u : 0u);
            p.intensity = static_cast<std::uint16_t>(c->intensity.decompress(*streams_[kIntensity], c->lastIntensity[slot], step.position));
            c->lastIntensity[slot] = p.intensity;
        }
        if (streams_[kScanAngle].changes() && step.scanAngleChanged)
            p.scanAngle = static_cast<std::int16_t>(c->scanAngle.decompress(*streams_[kScanAngle], p.scanAngle, step.gpsTimeChanged));
        if (streams_[kUserData].changes())
            p.userData = (*streams_[kUserData]).decodeSymbol(c->userData[p.userData / 4]);
        if (streams_[kPointSource].changes() && step.pointSourceChanged)
            p.pointSource = static_cast<std::uint16_t>(c->pointSource.decompress(*streams_[kPointSource], p.pointSource));
        if (streams_[kGpsTime].changes() && step.gpsTimeChanged)
            p.gpsTime = c->gpsTime.decode(*streams_[kGpsTime]);
        p.writeOthers(item);
    }

    Point14 first_;
    std::array<LayerStream, kLayers> streams_;
    std::array<std::unique_ptr<Point14Context>, 4> contexts_;
    std::uint32_t xyChannel_ = 0; //!< the scanner channel of the first pass
    std::vector<Step> steps_;
};

//! Red, green, blue (uint16 each) in one layer, and near infrared in a
//! second one for rgbnir14.
class Rgb14Decoder final : public LayeredItem
{
public:
    Rgb14Decoder(const unsigned char* first, bool withNir) : withNir_(withNir)
    {
        for (std::size_t c = 0; c < (withNir ? 4u : 3u); ++c)
            first_[c] = load<std::uint16_t>(first + 2 * c);
    }

    std::size_t layerCount() const override { return withNir_ ? 2 : 1; }

    void start(const Layer* layers, std::uint32_t& context) override
    {
        rgb_.open(layers[0]);
        if (withNir_)
            nir_.open(layers[1]);
        current_ = context;
        contexts_[current_] = std::make_unique<Context>(first_);
    }

    bool corrupt() const override { return rgb_.corrupt() || nir_.corrupt(); }
    bool endedExactly() const override { return rgb_.endedExactly() && nir_.endedExactly(); }

    void decodeRun(unsigned char* item, std::size_t stride, std::size_t count, std::uint8_t* contexts) override
    {
        for (std::size_t k = 0; k < count; ++k)
            decode(item + k * stride, contexts[k]);
    }

private:
    void decode(unsigned char* item, std::uint32_t context)
    {
        std::array<std::uint16_t, 4>& last = switchContext(contexts_, current_, context);
        Context& c = *contexts_[current_];
        if (rgb_.changes()) {
            const std::array<std::uint16_t, 3> rgb = decodeRgb(*rgb_, c.rgbModels, {last[0], last[1], last[2]});
            std::copy(rgb.begin(), rgb.end(), last.begin());
        }
        if (nir_.changes()) {
            ArithmeticDecoder& d = *nir_;
            const std::uint32_t used = d.decodeSymbol(c.nirUsed);
            std::uint32_t low = last[3] & 0xFFu, high = last[3] >> 8;
            if (used & 1)
                low = fold(static_cast<std::int32_t>(d.decodeSymbol(c.nirDiff[0]) + low));
            if (used & 2)
                high = fold(static_cast<std::int32_t>(d.decodeSymbol(c.nirDiff[1]) + high));
            last[3] = static_cast<std::uint16_t>(low | (high << 8));
        }
        for (std::size_t k = 0; k < (withNir_ ? 4u : 3u); ++k)
            store(item + 2 * k, last[k]);
    }

    using Context = RgbContext;

    bool withNir_;
    std::array<std::uint16_t, 4> first_{};
    LayerStream rgb_, nir_;
    std::array<std::unique_ptr<Context>, 4> contexts_;
    std::uint32_t current_ = 0;
};

//! Extra bytes: a layer per byte.
class Byte14Decoder final : public LayeredItem
{
public:
    Byte14Decoder(const unsigned char* first, std::size_t size) : first_(first, first + size), streams_(size) {}

    std::size_t layerCount() const override { return first_.size(); }

    void start(const Layer* layers, std::uint32_t& context) override
    {
        for (std::size_t i = 0; i < streams_.size(); ++i)
            streams_[i].open(layers[i]);
        current_ = context;
        contexts_[current_] = std::make_unique<Context>(first_);
    }

    bool corrupt() const override
    {
        return std::any_of(streams_.begin(), streams_.end(), [](const LayerStream& s) { return s.corrupt(); });
    }
    bool endedExactly() const override
    {
        return std::all_of(streams_.begin(), streams_.end(), [](const LayerStream& s) { return s.endedExactly(); });
    }

    void decodeRun(unsigned char* item, std::size_t stride, std::size_t count, std::uint8_t* contexts) override
    {
        for (std::size_t k = 0; k < count; ++k)
            decode(item + k * stride, contexts[k]);
    }

private:
    void decode(unsigned char* item, std::uint32_t context)
    {
        std::vector<unsigned char>& last = switchContext(contexts_, current_, context);
        Context& c = *contexts_[current_];
        for (std::size_t i = 0; i < streams_.size(); ++i) {
            if (streams_[i].changes())
                last[i] = fold(static_cast<std::int32_t>(last[i]) + static_cast<std::int32_t>((*streams_[i]).decodeSymbol(c.models[i])));
            item[i] = last[i];
        }
    }

    using Context = BytesContext;

    std::vector<unsigned char> first_;
    std::vector<LayerStream> streams_;
    std::array<std::unique_ptr<Context>, 4> contexts_;
    std::uint32_t current_ = 0;
};

} // namespace

std::unique_ptr<LayeredItem> makeLayeredItem(std::uint16_t type, std::size_t size, const unsigned char* first)
{
    switch (type) {
    case kPoint14: return std::make_unique<Point14Decoder>(first);
    case kRgb14: return std::make_unique<Rgb14Decoder>(first, false);
    case kRgbNir14: return std::make_unique<Rgb14Decoder>(first, true);
    default: return std::make_unique<Byte14Decoder>(first, size);
    }
}

std::vector<std::vector<std::uint8_t>> layerBits(std::uint16_t type, std::size_t size)
{
    // Byte by byte: {layer, byte, bits}, for point14 after the layout of a
    // LAS 1.4 record (Point14::parse) and the layers of Point14Decoder.
    struct Span
    {
        std::size_t layer, byte;
        std::uint8_t bits;
    };
    std::vector<Span> spans;
    std::size_t layers = 0;
    switch (type) {
    case kPoint14: {
        layers = 9;
        for (std::size_t b = 0; b < 8; ++b)
            spans.push_back({0, b, 0xFF}); // x, y
        spans.push_back({0, 14, 0xFF});  // return number, number of returns
        spans.push_back({0, 15, 0x30});  // scanner channel
        for (std::size_t b = 8; b < 12; ++b)
            spans.push_back({1, b, 0xFF}); // z
        spans.push_back({2, 16, 0xFF});  // classification
        spans.push_back({3, 15, 0xCF});  // classification flags, scan direction, edge of flight line
        spans.push_back({4, 12, 0xFF});  // intensity
        spans.push_back({4, 13, 0xFF});
        spans.push_back({5, 18, 0xFF});  // scan angle
        spans.push_back({5, 19, 0xFF});
        spans.push_back({6, 17, 0xFF});  // user data
        spans.push_back({7, 20, 0xFF});  // point source
        spans.push_back({7, 21, 0xFF});
        for (std::size_t b = 22; b < 30; ++b)
            spans.push_back({8, b, 0xFF}); // GPS time
        break;
    }
    case kRgb14:
    case kRgbNir14:
        layers = type == kRgbNir14 ? 2 : 1;
        for (std::size_t b = 0; b < 6; ++b)
            spans.push_back({0, b, 0xFF});
        if (type == kRgbNir14) {
            spans.push_back({1, 6, 0xFF});
            spans.push_back({1, 7, 0xFF});
        }
        break;
    default:
        layers = size;
        for (std::size_t b = 0; b < size; ++b)
            spans.push_back({b, b, 0xFF});
        break;
    }
    std::vector<std::vector<std::uint8_t>> masks(layers, std::vector<std::uint8_t>(size, 0));
    for (const Span& span : spans)
        masks[span.layer][span.byte] |= span.bits;
    return masks;
}

} // namespace scandiff::io::detail::laz
