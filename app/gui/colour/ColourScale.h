// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Colour scales for scalar fields and the conversion of a field into per-point
//! RGBA. Plain C++ on purpose: the view, sessions and tests use it without Qt.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace scandiff::gui {

struct ColourStop
{
    double position; // in [0,1]
    std::uint8_t r, g, b;
};

//! A named gradient through two or more colour stops, from position 0 to 1.
class ColourScale
{
public:
    //! Sorts the stops by position (stable, so equal positions make a hard edge
    //! in the given order). Throws std::invalid_argument when there are fewer
    //! than two stops, a position is outside [0,1] or not finite, or the first
    //! and last positions are not exactly 0 and 1.
    ColourScale(std::string name, std::vector<ColourStop> stops, bool symmetric = false);

    //! "Blue-Green-Yellow-Red" (the first one, CloudCompare's default look),
    //! "Grey", "Diverging Blue-White-Red" (symmetric) and "Viridis".
    static const std::vector<ColourScale>& presets();
    static std::optional<ColourScale> preset(const std::string& name);

    const std::string& name() const { return name_; }
    const std::vector<ColourStop>& stops() const { return stops_; }
    //! A symmetric scale is meant to be centred on 0: its users pick a colour
    //! range [-a, a]. The scale itself does not enforce it.
    bool symmetric() const { return symmetric_; }

    //! Linear interpolation between the stops around t; t is clamped to [0,1]
    //! and NaN is treated as 0. Channels are rounded to the nearest integer.
    std::array<std::uint8_t, 3> colourAt(double t) const;

    //! One line of text (no newline) that fromText turns back into an equal
    //! scale; positions keep every bit. Meant for sessions and QSettings.
    std::string toText() const;
    //! Empty if the text is not something toText wrote, or describes an invalid scale.
    static std::optional<ColourScale> fromText(const std::string& text);

    friend bool operator==(const ColourScale& a, const ColourScale& b);
    friend bool operator!=(const ColourScale& a, const ColourScale& b) { return !(a == b); }

private:
    std::string name_;
    std::vector<ColourStop> stops_;
    bool symmetric_ = false;
};

//! How a scalar field is turned into per-point RGBA for the view.
struct FieldColouring
{
    double colourMin = 0, colourMax = 1; // the scale's 0..1 maps to this value range (values outside are saturated)
    double visibleMin = -std::numeric_limits<double>::infinity();
    double visibleMax = std::numeric_limits<double>::infinity(); // threshold range, inclusive
    enum class Outside { Hide, Grey } outside = Outside::Hide;    // Hide: alpha 0; Grey: greyColour, alpha 255
    bool showNaN = true; // NaN ("no value") points: nanColour if true, else hidden (alpha 0)
    std::array<std::uint8_t, 3> greyColour{90, 90, 90}, nanColour{150, 150, 150};
};

//! Number of entries in colourise's lookup table. 3072 intervals put the
//! quarters, thirds and the middle of the colour range exactly on entries.
inline constexpr int kColourLutSize = 3073;

//! Colours `count` values into rgba[4*count]; a point's value is
//! values[i] + offset, computed in double. Hidden points get (0,0,0,0).
//! Values in the visible range are looked up in a table of kColourLutSize
//! colours spanning [colourMin, colourMax] (nearest entry), saturating outside.
//! When colourMax <= colourMin, values below colourMin get the scale's first
//! colour, values above colourMax its last, and values in between (if any) the
//! middle colour. Large inputs are split over TBB's threads.
void colourise(const float* values, std::size_t count, double offset, const ColourScale& scale,
               const FieldColouring& how, std::uint8_t* rgba);

//! Histogram of the finite values (value = v + offset) over [min, max] of those values.
//! Bin i covers [min + i*w, min + (i+1)*w) with w = (max-min)/bins; max falls in
//! the last bin. With no finite value, min = max = 0 and all counts are 0; when
//! all finite values are equal, min = max and they all count in bin 0.
struct Histogram
{
    double min = 0, max = 0;
    std::vector<std::size_t> counts;
    std::size_t finiteCount = 0;
};
//! `bins` below 1 is treated as 1.
Histogram computeHistogram(const float* values, std::size_t count, double offset, int bins);

} // namespace scandiff::gui
