// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Histogram.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace scandiff {

Histogram computeHistogram(const float* values, std::size_t count, double offset, int bins)
{
    bins = std::max(bins, 1);
    Histogram h;
    h.counts.assign(static_cast<std::size_t>(bins), 0);
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    for (std::size_t i = 0; i < count; ++i) {
        const double v = static_cast<double>(values[i]) + offset;
        if (!std::isfinite(v))
            continue;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
        ++h.finiteCount;
    }
    if (h.finiteCount == 0)
        return h;
    h.min = lo;
    h.max = hi;
    const double span = hi - lo;
    if (!(span > 0.0)) {
        h.counts[0] = h.finiteCount;
        return h;
    }
    const double toBin = bins / span;
    const int lastBin = bins - 1;
    for (std::size_t i = 0; i < count; ++i) {
        const double v = static_cast<double>(values[i]) + offset;
        if (!std::isfinite(v))
            continue;
        const double x = (v - lo) * toBin;
        const int bin = x >= lastBin ? lastBin : static_cast<int>(x);
        ++h.counts[static_cast<std::size_t>(bin)];
    }
    return h;
}

} // namespace scandiff
