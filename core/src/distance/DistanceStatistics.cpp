// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/distance/DistanceStatistics.h>

#include <algorithm>
#include <cmath>

namespace scandiff {

DistanceStatistics computeStatistics(const ScalarField& field)
{
    DistanceStatistics s;
    double sum = 0.0, sumSquares = 0.0;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t i = 0; i < field.size(); ++i) {
        if (!field.hasValue(i))
            continue;
        const double v = field.value(i);
        ++s.count;
        sum += v;
        sumSquares += v * v;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    if (s.count == 0)
        return s;
    const double n = static_cast<double>(s.count);
    s.mean = sum / n;
    double deviations = 0.0;
    for (std::size_t i = 0; i < field.size(); ++i) {
        if (!field.hasValue(i))
            continue;
        const double d = field.value(i) - s.mean;
        deviations += d * d;
    }
    s.standardDeviation = std::sqrt(deviations / n);
    s.min = lo;
    s.max = hi;
    s.rms = std::sqrt(sumSquares / n);
    return s;
}

} // namespace scandiff
