// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The running moments of the values of a region that grows one point at a
//! time: its mean and variance, and what they would be if a candidate joined.
//! Growing on a scalar value (thesis 003 §II.2, stones on intensity; the
//! primitives plugin's regions of a field) accepts a candidate on those.

#include <cstddef>

namespace scandiff {

struct RunningMoments
{
    double sum = 0.0, sumSquares = 0.0;
    std::size_t count = 0;

    void add(double value)
    {
        sum += value;
        sumSquares += value * value;
        ++count;
    }
    double mean() const { return sum / static_cast<double>(count); }
    //! The population variance, from the sums (rounding may leave it a little below 0).
    double variance() const
    {
        const double m = mean();
        return sumSquares / static_cast<double>(count) - m * m;
    }
    //! The mean and the variance with `value` added.
    double meanWith(double value) const { return (sum + value) / static_cast<double>(count + 1); }
    double varianceWith(double value) const
    {
        const double m = meanWith(value);
        return (sumSquares + value * value) / static_cast<double>(count + 1) - m * m;
    }
};

} // namespace scandiff
