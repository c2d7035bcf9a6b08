// SPDX-License-Identifier: GPL-3.0-or-later
#include "view/EntityColouring.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <set>

namespace scandiff::gui {

std::pair<double, double> colourRange(const ScalarField& field, const FieldDisplay& display)
{
    const ValueRange r = field.range();
    double lo = std::isfinite(display.colourLow) ? display.colourLow : r.validCount > 0 ? r.min : 0.0;
    double hi = std::isfinite(display.colourHigh) ? display.colourHigh : r.validCount > 0 ? r.max : 1.0;
    if (lo > hi)
        std::swap(lo, hi);
    if (display.symmetric || display.scale.symmetric()) {
        const double m = std::max(std::abs(lo), std::abs(hi));
        lo = -m;
        hi = m;
    }
    if (!(hi > lo)) {
        lo -= 0.5;
        hi += 0.5;
    }
    return {lo, hi};
}

bool isLabelField(const ScalarField& field)
{
    static const char* const kLabelNames[] = {"region_id", "primitive_id", "primitive_type", "classification", "class", "label",
                                              "cluster", "segment"};
    const std::string& name = field.name();
    const bool labelName = std::find(std::begin(kLabelNames), std::end(kLabelNames), name) != std::end(kLabelNames) ||
                           (name.size() > 3 && name.compare(name.size() - 3, 3, "_id") == 0);
    if (!labelName)
        return false;
    for (std::size_t i = 0; i < field.size(); ++i)
        if (field.hasValue(i)) {
            const double v = field.value(i);
            if (v != std::floor(v) || std::abs(v) > 1e9)
                return false;
        }
    return true;
}

bool isFlagField(const ScalarField& field)
{
    bool any = false;
    for (std::size_t i = 0; i < field.size(); ++i)
        if (field.hasValue(i)) {
            const double v = field.value(i);
            if (v != 0.0 && v != 1.0)
                return false;
            any = true;
        }
    return any;
}

bool isCategoricalField(const ScalarField& field) { return isLabelField(field) || isFlagField(field); }

std::array<std::uint8_t, 3> categoryColour(bool isLabel, long value)
{
    // Two of Kelly's colours, the farthest apart for most colour visions.
    static constexpr std::array<std::uint8_t, 3> kNo{0, 103, 165}, kYes{190, 0, 50};
    if (!isLabel && (value == 0 || value == 1))
        return value == 1 ? kYes : kNo;
    return labelColour(value);
}

std::array<std::uint8_t, 3> labelColour(long value)
{
    static constexpr std::array<std::uint8_t, 3> kKelly[] = {
        {243, 195, 0},   {135, 86, 146}, {243, 132, 0},  {161, 202, 241}, {190, 0, 50},   {194, 178, 128}, {0, 136, 86},
        {230, 143, 172}, {0, 103, 165},  {249, 147, 121}, {96, 78, 151},  {246, 166, 0},  {179, 68, 108},  {220, 211, 0},
        {136, 45, 23},   {141, 182, 0},  {101, 69, 34},  {226, 88, 34},   {43, 61, 38}};
    constexpr long kCount = static_cast<long>(std::size(kKelly));
    return kKelly[((value % kCount) + kCount) % kCount];
}

namespace {

//! The values of a label field present, ascending (at most `limit`, for the legend).
std::vector<long> labelsPresent(const ScalarField& field, std::size_t limit)
{
    std::set<long> values;
    for (std::size_t i = 0; i < field.size() && values.size() <= limit; ++i)
        if (field.hasValue(i))
            values.insert(std::lround(field.value(i)));
    return {values.begin(), values.end()};
}

//! Colours a categorical field: each value its categoryColour, the thresholds as for any field.
void colourLabels(const ScalarField& field, const FieldDisplay& display, FieldColouring::Outside outside, std::uint8_t* rgba)
{
    const FieldColouring how;
    const bool label = isLabelField(field);
    for (std::size_t i = 0; i < field.size(); ++i) {
        std::uint8_t* c = rgba + 4 * i;
        if (!field.hasValue(i)) {
            c[0] = how.nanColour[0], c[1] = how.nanColour[1], c[2] = how.nanColour[2], c[3] = 255;
            continue;
        }
        const double v = field.value(i);
        if (v < display.low || v > display.high) {
            if (outside == FieldColouring::Outside::Hide)
                c[0] = c[1] = c[2] = c[3] = 0;
            else
                c[0] = how.greyColour[0], c[1] = how.greyColour[1], c[2] = how.greyColour[2], c[3] = 255;
            continue;
        }
        const long value = std::lround(v);
        const auto colour = categoryColour(label, value);
        c[0] = colour[0], c[1] = colour[1], c[2] = colour[2], c[3] = 255;
    }
}

constexpr std::size_t kLegendCategories = 24;

} // namespace

ColourLegend legendOf(const PointCloud& points, const DisplayState& display)
{
    ColourLegend legend;
    const ScalarField* field = display.activeField.empty() ? nullptr : points.field(display.activeField);
    if (!field)
        return legend;
    const auto it = display.fields.find(field->name());
    legend.shown = true;
    legend.title = field->name();
    const FieldDisplay fieldDisplay = it == display.fields.end() ? FieldDisplay{} : it->second;
    legend.scale = fieldDisplay.scale;
    std::tie(legend.min, legend.max) = colourRange(*field, fieldDisplay);
    if (isCategoricalField(*field))
        for (long value : labelsPresent(*field, kLegendCategories))
            legend.categories.emplace_back(value, categoryColour(*field, value));
    return legend;
}

void blendWithOwnColours(const PointCloud& points, std::uint8_t* rgba)
{
    if (!points.hasColors())
        return;
    const std::vector<Rgb8>& own = points.colors();
    for (std::size_t i = 0; i < own.size(); ++i) {
        std::uint8_t* c = rgba + 4 * i;
        if (c[3] == 0)
            continue;
        const double lightness = (0.2126 * own[i].r + 0.7152 * own[i].g + 0.0722 * own[i].b) / 255.0;
        const double shade = 0.35 + 0.65 * lightness;
        for (int k = 0; k < 3; ++k)
            c[k] = static_cast<std::uint8_t>(std::lround(c[k] * shade));
    }
}

ColourLegend colourEntity(const PointCloud& points, const DisplayState& display, std::uint8_t* rgba)
{
    const std::size_t n = points.size();
    ColourLegend legend;
    const ScalarField* field = display.activeField.empty() ? nullptr : points.field(display.activeField);
    if (field) {
        const auto it = display.fields.find(field->name());
        const FieldDisplay fieldDisplay = it == display.fields.end() ? FieldDisplay{} : it->second;
        if (isCategoricalField(*field)) {
            colourLabels(*field, fieldDisplay, display.outside, rgba);
            if (display.blendColours)
                blendWithOwnColours(points, rgba);
            return legendOf(points, display);
        }
        FieldColouring how;
        std::tie(how.colourMin, how.colourMax) = colourRange(*field, fieldDisplay);
        how.visibleMin = fieldDisplay.low;
        how.visibleMax = fieldDisplay.high;
        how.outside = display.outside;
        colourise(field->values().data(), n, field->offset(), fieldDisplay.scale, how, rgba);
        if (display.blendColours)
            blendWithOwnColours(points, rgba);
        legend = {true, field->name(), fieldDisplay.scale, how.colourMin, how.colourMax, {}};
        return legend;
    }
    if (display.neutral) {
        for (std::size_t i = 0; i < n; ++i) {
            rgba[4 * i] = kNeutralGrey[0];
            rgba[4 * i + 1] = kNeutralGrey[1];
            rgba[4 * i + 2] = kNeutralGrey[2];
            rgba[4 * i + 3] = 255;
        }
        return legend;
    }
    if (points.hasColors()) {
        for (std::size_t i = 0; i < n; ++i) {
            const Rgb8 c = points.colors()[i];
            rgba[4 * i] = c.r;
            rgba[4 * i + 1] = c.g;
            rgba[4 * i + 2] = c.b;
            rgba[4 * i + 3] = 255;
        }
        return legend;
    }
    // Height: what a user expects of a cloud with nothing else to show.
    std::vector<float> heights(n);
    for (std::size_t i = 0; i < n; ++i)
        heights[i] = points.positions()[i].z();
    float zmin = std::numeric_limits<float>::max(), zmax = -zmin;
    for (float z : heights)
        if (std::isfinite(z)) {
            zmin = std::min(zmin, z);
            zmax = std::max(zmax, z);
        }
    FieldColouring how;
    how.colourMin = zmin <= zmax ? zmin : 0.0;
    how.colourMax = zmin < zmax ? zmax : how.colourMin + 1.0;
    const ColourScale scale = ColourScale::defaultScale();
    colourise(heights.data(), n, 0.0, scale, how, rgba);
    legend = {true, "height", scale, how.colourMin + points.origin().z(), how.colourMax + points.origin().z(), {}};
    return legend;
}

} // namespace scandiff::gui
