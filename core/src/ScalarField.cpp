// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/ScalarField.h>

#include <algorithm>

namespace scandiff {

void ScalarField::resize(std::size_t n)
{
    values_.resize(n, std::numeric_limits<float>::quiet_NaN());
    if (keepsDoubles_)
        doubles_.resize(n, std::numeric_limits<double>::quiet_NaN());
}

void ScalarField::keepDoubles()
{
    if (keepsDoubles_ && doubles_.size() == values_.size())
        return;
    std::vector<double> exact(values_.size());
    for (std::size_t i = 0; i < values_.size(); ++i)
        exact[i] = value(i);
    doubles_ = std::move(exact);
    keepsDoubles_ = true;
}

void ScalarField::dropDoubles()
{
    keepsDoubles_ = false;
    doubles_ = {};
}

bool ScalarField::dropDoublesIfExactInFloat()
{
    for (std::size_t i = 0; i < doubles_.size(); ++i) {
        const double exact = doubles_[i];
        if (std::isnan(exact) && std::isnan(values_[i]))
            continue;
        if (offset_ + static_cast<double>(values_[i]) != exact)
            return false;
    }
    dropDoubles();
    return true;
}

ValueRange ScalarField::range() const
{
    ValueRange r;
    if (keepsDoubles_) {
        // The doubles' own extremes, not their float roundings.
        double lo = std::numeric_limits<double>::infinity();
        double hi = -lo;
        for (std::size_t i = 0; i < values_.size(); ++i) {
            if (std::isnan(values_[i]))
                continue;
            const double v = value(i);
            lo = std::min(lo, v);
            hi = std::max(hi, v);
            ++r.validCount;
        }
        if (r.validCount > 0) {
            r.min = lo;
            r.max = hi;
        }
        return r;
    }
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
