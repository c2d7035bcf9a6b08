// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Histogram.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace scandiff {

namespace {

//! The values' extent and how many are finite, over [begin, end).
struct Extent
{
    double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
    std::size_t finite = 0;
};

} // namespace

// Both passes split over the cores (a 20 M-value field is read after every
// tool that adds one, on the workbench's thread): minima, maxima and counts
// are exact whatever the split, so the histogram is the same on any number
// of threads.
Histogram computeHistogram(const float* values, std::size_t count, double offset, int bins)
{
    bins = std::max(bins, 1);
    Histogram h;
    h.counts.assign(static_cast<std::size_t>(bins), 0);
    constexpr std::size_t kGrain = 1 << 16;
    const Extent extent = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, count, kGrain), Extent{},
        [&](const tbb::blocked_range<std::size_t>& r, Extent e) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const double v = static_cast<double>(values[i]) + offset;
                if (!std::isfinite(v))
                    continue;
                e.lo = std::min(e.lo, v);
                e.hi = std::max(e.hi, v);
                ++e.finite;
            }
            return e;
        },
        [](Extent a, const Extent& b) {
            a.lo = std::min(a.lo, b.lo);
            a.hi = std::max(a.hi, b.hi);
            a.finite += b.finite;
            return a;
        });
    h.finiteCount = extent.finite;
    if (h.finiteCount == 0)
        return h;
    const double lo = extent.lo, hi = extent.hi;
    h.min = lo;
    h.max = hi;
    const double span = hi - lo;
    if (!(span > 0.0)) {
        h.counts[0] = h.finiteCount;
        return h;
    }
    const double toBin = bins / span;
    const int lastBin = bins - 1;
    using Counts = std::vector<std::size_t>;
    h.counts = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, count, kGrain), Counts(static_cast<std::size_t>(bins), 0),
        [&](const tbb::blocked_range<std::size_t>& r, Counts counts) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const double v = static_cast<double>(values[i]) + offset;
                if (!std::isfinite(v))
                    continue;
                const double x = (v - lo) * toBin;
                const int bin = x >= lastBin ? lastBin : static_cast<int>(x);
                ++counts[static_cast<std::size_t>(bin)];
            }
            return counts;
        },
        [](Counts a, const Counts& b) {
            for (std::size_t k = 0; k < a.size(); ++k)
                a[k] += b[k];
            return a;
        });
    return h;
}

} // namespace scandiff
