// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The histogram of a scalar field, as the workbench draws it and the
//! "field histogram" tool exports it.

#include <cstddef>
#include <vector>

namespace scandiff {

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

} // namespace scandiff
