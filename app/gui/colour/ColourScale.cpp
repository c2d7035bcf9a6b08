// SPDX-License-Identifier: GPL-3.0-or-later
#include "colour/ColourScale.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace scandiff::gui {

ColourTable colourTable(const ColourScale& scale)
{
    constexpr int lastEntry = kColourLutSize - 1;
    ColourTable table;
    for (int i = 0; i < kColourLutSize; ++i)
        table[static_cast<std::size_t>(i)] = scale.colourAt(static_cast<double>(i) / lastEntry);
    return table;
}

void colourise(const float* values, std::size_t count, double offset, const ColourScale& scale,
               const FieldColouring& how, std::uint8_t* rgba)
{
    colourise(values, count, offset, colourTable(scale), how, rgba);
}

void colourise(const float* values, std::size_t count, double offset, const ColourTable& lut,
               const FieldColouring& how, std::uint8_t* rgba, std::size_t stride, std::size_t first)
{
    constexpr int lastEntry = kColourLutSize - 1;

    const double cmin = how.colourMin;
    const double cmax = how.colourMax;
    const bool degenerate = !(cmax > cmin);
    const double toIndex = degenerate ? 0.0 : lastEntry / (cmax - cmin);
    const double vmin = how.visibleMin;
    const double vmax = how.visibleMax;
    const bool hideOutside = how.outside == FieldColouring::Outside::Hide;

    // Over the k-th values taken, k in [begin, end): value first + k * stride.
    auto colourRange = [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const std::size_t i = first + k * stride;
            std::uint8_t* out = rgba + 4 * i;
            const double v = static_cast<double>(values[i]) + offset;
            const std::array<std::uint8_t, 3>* colour;
            if (std::isnan(v)) {
                if (!how.showNaN) {
                    out[0] = out[1] = out[2] = out[3] = 0;
                    continue;
                }
                colour = &how.nanColour;
            } else if (v < vmin || v > vmax) {
                if (hideOutside) {
                    out[0] = out[1] = out[2] = out[3] = 0;
                    continue;
                }
                colour = &how.greyColour;
            } else {
                int index;
                if (degenerate) {
                    index = v < cmin ? 0 : v > cmax ? lastEntry : lastEntry / 2;
                } else {
                    // Comparisons before the cast keep infinities and huge values
                    // away from the float-to-int conversion.
                    const double x = (v - cmin) * toIndex;
                    index = x <= 0.0 ? 0 : x >= lastEntry ? lastEntry : static_cast<int>(x + 0.5);
                }
                colour = &lut[index];
            }
            out[0] = (*colour)[0];
            out[1] = (*colour)[1];
            out[2] = (*colour)[2];
            out[3] = 255;
        }
    };

    // Below this the thread start-up costs more than the loop.
    constexpr std::size_t parallelThreshold = 1 << 16;
    const std::size_t taken = first < count ? (count - first + stride - 1) / stride : 0;
    if (taken < parallelThreshold) {
        colourRange(0, taken);
        return;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, taken, 1 << 14),
                      [&](const tbb::blocked_range<std::size_t>& r) { colourRange(r.begin(), r.end()); });
}

} // namespace scandiff::gui
