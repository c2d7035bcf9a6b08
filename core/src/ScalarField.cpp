// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/ScalarField.h>

#include <algorithm>

namespace scandiff {

namespace {
constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
} // namespace

bool ScalarField::residualHolds(double v, double offset)
{
    if (std::isnan(v))
        return true;
    const auto f = static_cast<float>(v - offset);
    const float r = residualOf(v, offset, f);
    return f + r == f && offset + (static_cast<double>(f) + static_cast<double>(r)) == v;
}

void ScalarField::setValue(std::size_t i, double v)
{
    const auto f = static_cast<float>(v - offset_);
    if (exact_ == Exact::Residuals && !residualHolds(v, offset_))
        keepDoubles(); // a value the residuals cannot give back: doubles from here on
    values_[i] = f;
    if (exact_ == Exact::Doubles && i < doubles_.size())
        doubles_[i] = v;
    else if (exact_ == Exact::Residuals && i < residuals_.size())
        residuals_[i] = std::isnan(v) ? 0.0f : residualOf(v, offset_, f);
}

void ScalarField::resize(std::size_t n)
{
    values_.resize(n, kNaNf);
    if (exact_ == Exact::Doubles)
        doubles_.resize(n, kNaN);
    else if (exact_ == Exact::Residuals)
        residuals_.resize(n, 0.0f);
}

void ScalarField::moveValue(std::size_t from, std::size_t to)
{
    values_[to] = values_[from];
    if (exact_ == Exact::Doubles)
        doubles_[to] = doubles_[from];
    else if (exact_ == Exact::Residuals)
        residuals_[to] = residuals_[from];
}

ScalarField ScalarField::subset(const std::vector<std::size_t>& indices) const
{
    ScalarField out(name_, 0);
    out.offset_ = offset_;
    out.exact_ = exact_;
    out.values_.reserve(indices.size());
    for (std::size_t i : indices)
        out.values_.push_back(values_[i]);
    if (exact_ == Exact::Doubles) {
        out.doubles_.reserve(indices.size());
        for (std::size_t i : indices)
            out.doubles_.push_back(value(i));
    } else if (exact_ == Exact::Residuals) {
        out.residuals_.reserve(indices.size());
        for (std::size_t i : indices)
            out.residuals_.push_back(residuals_[i]);
    }
    return out;
}

void ScalarField::keepDoubles()
{
    if (exact_ == Exact::Doubles && doubles_.size() == values_.size())
        return;
    std::vector<double> exact(values_.size());
    for (std::size_t i = 0; i < values_.size(); ++i)
        exact[i] = value(i);
    doubles_ = std::move(exact);
    residuals_ = {};
    exact_ = Exact::Doubles;
}

void ScalarField::keepResiduals()
{
    if (exact_ == Exact::Residuals && residuals_.size() == values_.size())
        return;
    if (exact_ == Exact::Doubles) {
        compact();
        if (exact_ != Exact::None)
            return;
    }
    residuals_.assign(values_.size(), 0.0f);
    exact_ = Exact::Residuals;
}

void ScalarField::dropExact()
{
    exact_ = Exact::None;
    doubles_ = {};
    residuals_ = {};
}

bool ScalarField::compact(bool stayExact)
{
    if (exact_ == Exact::None)
        return false;
    bool floatHolds = true, residualsHold = true;
    for (std::size_t i = 0; i < values_.size() && (floatHolds || residualsHold); ++i) {
        const double v = value(i);
        if (std::isnan(v))
            continue;
        floatHolds = floatHolds && offset_ + static_cast<double>(values_[i]) == v;
        residualsHold = residualsHold && residualHolds(v, offset_);
    }
    if (floatHolds && !stayExact) {
        dropExact();
        return false;
    }
    if (residualsHold && exact_ == Exact::Doubles) {
        std::vector<float> residuals(values_.size(), 0.0f);
        for (std::size_t i = 0; i < values_.size(); ++i) {
            const double v = value(i);
            if (!std::isnan(v)) {
                values_[i] = static_cast<float>(v - offset_);
                residuals[i] = residualOf(v, offset_, values_[i]);
            }
        }
        doubles_ = {};
        residuals_ = std::move(residuals);
        exact_ = Exact::Residuals;
    }
    return true;
}

bool ScalarField::isZeroEverywhere() const
{
    if (offset_ == 0.0 && std::any_of(values_.begin(), values_.end(), [](float v) { return v != 0.0f; }))
        return false;
    const ValueRange r = range();
    return r.validCount == size() && r.min == 0.0 && r.max == 0.0;
}

ValueRange ScalarField::range() const
{
    ValueRange r;
    if (exact_ != Exact::None) {
        // The exact values' own extremes, not their float roundings.
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
