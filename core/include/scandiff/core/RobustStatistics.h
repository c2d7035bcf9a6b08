// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Order statistics the tools share: the median, a percentile and the robust
//! standard deviation (the median absolute deviation, scaled), each by
//! selection (std::nth_element, linear time) rather than a full sort. One
//! definition so every tool means the same thing by "the median": the upper
//! one, the element at size/2 once ordered, never an average of two.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace scandiff {

//! The median absolute deviation of normal data is 0.6745 sigma (the
//! normal's third quartile): times this it estimates sigma.
inline constexpr double kMadToSigma = 1.4826;

//! The upper median of `values` (0 for none); reorders them.
inline double medianInPlace(std::vector<double>& values)
{
    if (values.empty())
        return 0.0;
    const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    return *middle;
}

//! The upper median of `values` (0 for none).
inline double medianOf(std::vector<double> values)
{
    return medianInPlace(values);
}

//! The median of |values| (0 for none).
inline double medianAbsolute(std::vector<double> values)
{
    for (double& v : values)
        v = std::abs(v);
    return medianInPlace(values);
}

//! The value at rank round(p (n - 1)) once ordered (NaN for none), p in [0, 1].
inline double percentileOf(std::vector<double> values, double p)
{
    if (values.empty())
        return std::numeric_limits<double>::quiet_NaN();
    const auto rank = std::min(values.size() - 1, static_cast<std::size_t>(p * static_cast<double>(values.size() - 1) + 0.5));
    const auto at = values.begin() + static_cast<std::ptrdiff_t>(rank);
    std::nth_element(values.begin(), at, values.end());
    return *at;
}

//! kMadToSigma x the median absolute deviation from `centre`: a standard
//! deviation that a minority of outliers does not inflate.
inline double robustSigma(const std::vector<double>& values, double centre)
{
    std::vector<double> deviations(values.size());
    for (std::size_t i = 0; i < values.size(); ++i)
        deviations[i] = std::abs(values[i] - centre);
    return kMadToSigma * medianInPlace(deviations);
}

} // namespace scandiff
