// SPDX-License-Identifier: GPL-3.0-or-later
#include "view/EntityColouring.h"

#include <algorithm>
#include <cmath>

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
    return legend;
}

ColourLegend colourEntity(const PointCloud& points, const DisplayState& display, std::uint8_t* rgba)
{
    const std::size_t n = points.size();
    ColourLegend legend;
    const ScalarField* field = display.activeField.empty() ? nullptr : points.field(display.activeField);
    if (field) {
        const auto it = display.fields.find(field->name());
        const FieldDisplay fieldDisplay = it == display.fields.end() ? FieldDisplay{} : it->second;
        FieldColouring how;
        std::tie(how.colourMin, how.colourMax) = colourRange(*field, fieldDisplay);
        how.visibleMin = fieldDisplay.low;
        how.visibleMax = fieldDisplay.high;
        how.outside = display.outside;
        colourise(field->values().data(), n, field->offset(), fieldDisplay.scale, how, rgba);
        legend = {true, field->name(), fieldDisplay.scale, how.colourMin, how.colourMax};
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
    const ColourScale scale = *ColourScale::preset("Blue-Green-Yellow-Red");
    colourise(heights.data(), n, 0.0, scale, how, rgba);
    legend = {true, "height", scale, how.colourMin + points.origin().z(), how.colourMax + points.origin().z()};
    return legend;
}

} // namespace scandiff::gui
