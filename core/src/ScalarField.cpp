// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/ScalarField.h>

#include <algorithm>

namespace scandiff {

ValueRange ScalarField::range() const
{
    ValueRange r;
    float lo = std::numeric_limits<float>::infinity();
    float hi = -std::numeric_limits<float>::infinity();
    for (float v : values_) {
        if (std::isnan(v))
            continue;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
        ++r.validCount;
    }
    if (r.validCount > 0) {
        r.min = offset_ + static_cast<double>(lo);
        r.max = offset_ + static_cast<double>(hi);
    }
    return r;
}

} // namespace scandiff
