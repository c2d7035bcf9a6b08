// SPDX-License-Identifier: GPL-3.0-or-later
//! The layered item encoders of LAZ, version 3 (LAS 1.4 point formats 6-8):
//! the mirrors of LayeredItems.cpp, after LASzip's
//! laswriteitemcompressed_v3.cpp. Every point's attributes are coded into
//! their layers; a layer whose attribute never changed in the chunk is left
//! out (the decoder then keeps the first point's value), except the x, y and
//! z layers, always written.

#include "LayeredState.h"

namespace scandiff::io::detail::laz {

namespace {

using namespace layered;

//! The encoders' counterpart of LayerStream: a layer's encoder and whether
//! its attribute changed in the chunk.
struct LayerSink
{
    ArithmeticEncoder encoder;
    bool changed = false;

    std::vector<unsigned char> finish() { return changed ? encoder.done() : std::vector<unsigned char>(); }
};

class Point14Encoder final : public LayeredItemEncoder
{
public:
    Point14Encoder(const unsigned char* first, std::uint32_t& context)
    {
        const Point14 p = Point14::parse(first);
        current_ = p.scannerChannel;
        context = current_;
        contexts_[current_] = std::make_unique<Point14Context>(p);
        sinks_[kReturnsXY].changed = sinks_[kZ].changed = true;
    }

    void encode(const unsigned char* item, std::uint32_t& context) override
    {
        const Point14 p = Point14::parse(item);
        Point14Context* c = contexts_[current_].get();
        const Point14* last = &c->last;
        ArithmeticEncoder& xy = sinks_[kReturnsXY].encoder;
        const std::uint32_t lastPosition = (last->returnNumber == 1 ? 1u : 0u) +
                                           (last->returnNumber >= last->numberOfReturns ? 2u : 0u) +
                                           (last->gpsTimeChanged ? 4u : 0u);
        const std::uint32_t channel = p.scannerChannel;
        // Changes are counted from the last point of the same channel.
        if (channel != current_ && contexts_[channel])
            last = &contexts_[channel]->last;
        const bool pointSourceChanged = p.pointSource != last->pointSource;
        // On the bits: a -0 after a 0 is a change (LASzip compares the doubles and would lose the sign).
        const bool gpsTimeChanged = p.gpsTime != last->gpsTime;
        const bool scanAngleChanged = p.scanAngle != last->scanAngle;
        const std::uint32_t lastN = last->numberOfReturns, lastR = last->returnNumber;
        const std::uint32_t n = p.numberOfReturns, r = p.returnNumber;
        std::uint32_t changed = (channel != current_ ? 1u << 6 : 0u) | (pointSourceChanged ? 1u << 5 : 0u) |
                                (gpsTimeChanged ? 1u << 4 : 0u) | (scanAngleChanged ? 1u << 3 : 0u) |
                                (n != lastN ? 1u << 2 : 0u);
        if (r != lastR)
            changed |= r == (lastR + 1) % 16 ? 1u : r == (lastR + 15) % 16 ? 2u : 3u;
        xy.encodeSymbol(c->changedValues[lastPosition], changed);
        if (changed & (1u << 6)) {
            xy.encodeSymbol(c->scannerChannel, (channel + 4 - current_ - 1) % 4);
            if (!contexts_[channel]) {
                contexts_[channel] = std::make_unique<Point14Context>(c->last);
                last = &contexts_[channel]->last;
            }
            current_ = channel;
            context = current_;
            c = contexts_[current_].get();
        }
        if (changed & (1u << 2))
            xy.encodeSymbol(c->numberOfReturns[lastN], n);
        if ((changed & 3u) == 3u) {
            if (gpsTimeChanged)
                xy.encodeSymbol(c->returnNumber[lastR], r);
            else
                xy.encodeSymbol(c->returnNumberGpsSame, (r + 16 - lastR - 2) % 16);
        }
        const std::uint32_t m = kReturnMap6[n][r], l = returnLevel8(n, r);
        const std::uint32_t position = (r == 1 ? 2u : 0u) + (r >= n ? 1u : 0u); // as the decoder's
        const std::uint32_t medianSlot = (m << 1) | (gpsTimeChanged ? 1u : 0u);

        const auto dx = static_cast<std::int32_t>(static_cast<std::uint32_t>(p.x) - static_cast<std::uint32_t>(last->x));
        c->dx.compress(xy, c->xMedian[medianSlot].median(), dx, n == 1);
        c->xMedian[medianSlot].add(dx);
        std::uint32_t k = c->dx.lastSize();
        const auto dy = static_cast<std::int32_t>(static_cast<std::uint32_t>(p.y) - static_cast<std::uint32_t>(last->y));
        c->dy.compress(xy, c->yMedian[medianSlot].median(), dy, (n == 1) + (k < 20 ? k & ~1u : 20));
        c->yMedian[medianSlot].add(dy);

        k = (c->dx.lastSize() + c->dy.lastSize()) / 2;
        c->z.compress(sinks_[kZ].encoder, c->lastZ[l], p.z, (n == 1) + (k < 18 ? k & ~1u : 18));
        c->lastZ[l] = p.z;

        sinks_[kClassification].changed |= p.classification != last->classification;
        const std::uint32_t classKey = ((last->classification & 0x1F) << 1) + (position == 3 ? 1 : 0);
        sinks_[kClassification].encoder.encodeSymbol(c->classification[classKey], p.classification);

        const std::uint32_t lastFlags = (last->edgeOfFlightLine << 5) | (last->scanDirection << 4) | last->classificationFlags;
        const std::uint32_t flags = (p.edgeOfFlightLine << 5) | (p.scanDirection << 4) | p.classificationFlags;
        sinks_[kFlags].changed |= flags != lastFlags;
        sinks_[kFlags].encoder.encodeSymbol(c->flags[lastFlags], flags);

        sinks_[kIntensity].changed |= p.intensity != last->intensity;
        const std::uint32_t intensitySlot = (position << 1) | (gpsTimeChanged ? 1u : 0u);
        c->intensity.compress(sinks_[kIntensity].encoder, c->lastIntensity[intensitySlot], p.intensity, position);
        c->lastIntensity[intensitySlot] = p.intensity;

        if (scanAngleChanged) {
            sinks_[kScanAngle].changed = true;
            c->scanAngle.compress(sinks_[kScanAngle].encoder, last->scanAngle, p.scanAngle, gpsTimeChanged);
        }
        sinks_[kUserData].changed |= p.userData != last->userData;
        sinks_[kUserData].encoder.encodeSymbol(c->userData[last->userData / 4], p.userData);
        if (pointSourceChanged) {
            sinks_[kPointSource].changed = true;
            c->pointSource.compress(sinks_[kPointSource].encoder, last->pointSource, p.pointSource);
        }
        if (gpsTimeChanged) {
            sinks_[kGpsTime].changed = true;
            c->gpsTime.encode(sinks_[kGpsTime].encoder, p.gpsTime);
        }
        c->last = p;
        c->last.gpsTimeChanged = gpsTimeChanged;
    }

    void finish(std::vector<std::vector<unsigned char>>& layers) override
    {
        for (LayerSink& sink : sinks_)
            layers.push_back(sink.finish());
    }

private:
    enum : std::size_t { kReturnsXY, kZ, kClassification, kFlags, kIntensity, kScanAngle, kUserData, kPointSource, kGpsTime, kLayers };

    std::array<LayerSink, kLayers> sinks_;
    std::array<std::unique_ptr<Point14Context>, 4> contexts_;
    std::uint32_t current_ = 0;
};

class Rgb14Encoder final : public LayeredItemEncoder
{
public:
    Rgb14Encoder(const unsigned char* first, bool withNir, std::uint32_t context) : withNir_(withNir), current_(context)
    {
        std::array<std::uint16_t, 4> values{};
        for (std::size_t k = 0; k < (withNir ? 4u : 3u); ++k)
            values[k] = load<std::uint16_t>(first + 2 * k);
        contexts_[current_] = std::make_unique<RgbContext>(values);
    }

    void encode(const unsigned char* item, std::uint32_t& context) override
    {
        std::array<std::uint16_t, 4>& last = switchContext(contexts_, current_, context);
        RgbContext& c = *contexts_[current_];
        const std::array<std::uint16_t, 3> rgb{load<std::uint16_t>(item), load<std::uint16_t>(item + 2), load<std::uint16_t>(item + 4)};
        rgb_.changed |= rgb[0] != last[0] || rgb[1] != last[1] || rgb[2] != last[2];
        encodeRgb(rgb_.encoder, c.rgbModels, {last[0], last[1], last[2]}, rgb);
        std::copy(rgb.begin(), rgb.end(), last.begin());
        if (!withNir_)
            return;
        const std::uint16_t nir = load<std::uint16_t>(item + 6);
        const std::uint32_t used = ((nir & 0xFF) != (last[3] & 0xFF) ? 1u : 0u) | ((nir >> 8) != (last[3] >> 8) ? 2u : 0u);
        nir_.changed |= used != 0;
        nir_.encoder.encodeSymbol(c.nirUsed, used);
        if (used & 1)
            nir_.encoder.encodeSymbol(c.nirDiff[0], fold(static_cast<std::int32_t>(nir & 0xFF) - (last[3] & 0xFF)));
        if (used & 2)
            nir_.encoder.encodeSymbol(c.nirDiff[1], fold(static_cast<std::int32_t>(nir >> 8) - (last[3] >> 8)));
        last[3] = nir;
    }

    void finish(std::vector<std::vector<unsigned char>>& layers) override
    {
        layers.push_back(rgb_.finish());
        if (withNir_)
            layers.push_back(nir_.finish());
    }

private:
    bool withNir_;
    LayerSink rgb_, nir_;
    std::array<std::unique_ptr<RgbContext>, 4> contexts_;
    std::uint32_t current_;
};

class Byte14Encoder final : public LayeredItemEncoder
{
public:
    Byte14Encoder(const unsigned char* first, std::size_t size, std::uint32_t context) : sinks_(size), current_(context)
    {
        contexts_[current_] = std::make_unique<BytesContext>(std::vector<unsigned char>(first, first + size));
    }

    void encode(const unsigned char* item, std::uint32_t& context) override
    {
        std::vector<unsigned char>& last = switchContext(contexts_, current_, context);
        BytesContext& c = *contexts_[current_];
        for (std::size_t i = 0; i < sinks_.size(); ++i) {
            sinks_[i].changed |= item[i] != last[i];
            sinks_[i].encoder.encodeSymbol(c.models[i], fold(static_cast<std::int32_t>(item[i]) - last[i]));
            last[i] = item[i];
        }
    }

    void finish(std::vector<std::vector<unsigned char>>& layers) override
    {
        for (LayerSink& sink : sinks_)
            layers.push_back(sink.finish());
    }

private:
    std::vector<LayerSink> sinks_;
    std::array<std::unique_ptr<BytesContext>, 4> contexts_;
    std::uint32_t current_;
};

} // namespace

std::unique_ptr<LayeredItemEncoder> makeLayeredItemEncoder(std::uint16_t type, std::size_t size, const unsigned char* first,
                                                           std::uint32_t& context)
{
    switch (type) {
    case kPoint14: return std::make_unique<Point14Encoder>(first, context);
    case kRgb14: return std::make_unique<Rgb14Encoder>(first, false, context);
    case kRgbNir14: return std::make_unique<Rgb14Encoder>(first, true, context);
    default: return std::make_unique<Byte14Encoder>(first, size, context);
    }
}

} // namespace scandiff::io::detail::laz
