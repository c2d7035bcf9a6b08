// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The conversion of a scalar field into per-point RGBA for the view, through a
//! colour scale (core/ColourScale.h). Plain C++ on purpose: the view, sessions
//! and tests use it without Qt.

#include <scandiff/core/ColourScale.h>
#include <scandiff/core/Histogram.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace scandiff::gui {

using scandiff::ColourScale;
using scandiff::ColourStop;
using scandiff::computeHistogram;
using scandiff::Histogram;

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

//! A scale's colours at kColourLutSize evenly spaced points of [0, 1]:
//! built once per colouring, looked up per value.
using ColourTable = std::array<std::array<std::uint8_t, 3>, kColourLutSize>;
ColourTable colourTable(const ColourScale& scale);

//! Colours `count` values into rgba[4*count]; a point's value is
//! values[i] + offset, computed in double. Hidden points get (0,0,0,0).
//! Values in the visible range are looked up in a table of kColourLutSize
//! colours spanning [colourMin, colourMax] (nearest entry), saturating outside.
//! When colourMax <= colourMin, values below colourMin get the scale's first
//! colour, values above colourMax its last, and values in between (if any) the
//! middle colour. Large inputs are split over TBB's threads.
void colourise(const float* values, std::size_t count, double offset, const ColourScale& scale,
               const FieldColouring& how, std::uint8_t* rgba);
//! The same with the scale's table built already, for every stride-th value
//! from `first` only (i = first, first + stride, ... < count): the view
//! colours the part of a large cloud a frame draws.
void colourise(const float* values, std::size_t count, double offset, const ColourTable& table,
               const FieldColouring& how, std::uint8_t* rgba, std::size_t stride = 1, std::size_t first = 0);

} // namespace scandiff::gui
