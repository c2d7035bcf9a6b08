// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The offset a scalar field is stored around (internal to io/), shared by the
//! readers that meet double or wide integer values.

#include <algorithm>
#include <cmath>

namespace scandiff::io::detail {

//! Keeps float precision for large values (GPS time ~1e9 s, 32-bit ids): values
//! are stored relative to their rounded-down minimum.
inline double chooseFieldOffset(double lo, double hi)
{
    if (!(lo <= hi))
        return 0.0;
    if (std::max(std::abs(lo), std::abs(hi)) < 1e5)
        return 0.0;
    return std::floor(lo);
}

} // namespace scandiff::io::detail
