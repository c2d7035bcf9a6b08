// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/ScalarField.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cstdint>

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

namespace {

//! The extremes and the count of the values that are not NaN, over part of a field.
struct Extremes
{
    double lo = std::numeric_limits<double>::infinity();
    double hi = -std::numeric_limits<double>::infinity();
    std::size_t count = 0;

    void merge(const Extremes& other)
    {
        lo = std::min(lo, other.lo);
        hi = std::max(hi, other.hi);
        count += other.count;
    }
};

//! The floats of [begin, end): eight lanes with no branch, so that the
//! compiler keeps them in vector registers (`v < lo ? v : lo` is the
//! processors' min instruction, which keeps `lo` when v is NaN).
Extremes floatExtremes(const float* begin, const float* end)
{
    constexpr std::size_t kLanes = 8;
    float lo[kLanes], hi[kLanes];
    std::uint32_t count[kLanes] = {};
    std::fill(lo, lo + kLanes, std::numeric_limits<float>::infinity());
    std::fill(hi, hi + kLanes, -std::numeric_limits<float>::infinity());
    const float* v = begin;
    for (; end - v >= static_cast<std::ptrdiff_t>(kLanes); v += kLanes) {
        for (std::size_t l = 0; l < kLanes; ++l) {
            lo[l] = v[l] < lo[l] ? v[l] : lo[l];
            hi[l] = v[l] > hi[l] ? v[l] : hi[l];
            count[l] += v[l] == v[l];
        }
    }
    Extremes e;
    for (std::size_t l = 0; l < kLanes; ++l) {
        e.lo = std::min(e.lo, static_cast<double>(lo[l]));
        e.hi = std::max(e.hi, static_cast<double>(hi[l]));
        e.count += count[l];
    }
    for (; v < end; ++v) {
        if (std::isnan(*v))
            continue;
        e.lo = std::min(e.lo, static_cast<double>(*v));
        e.hi = std::max(e.hi, static_cast<double>(*v));
        ++e.count;
    }
    return e;
}

} // namespace

ValueRange ScalarField::range() const
{
    // In blocks on every core: a field of a large cloud is read whole, and
    // `info` asks for every field's range.
    constexpr std::size_t kBlock = 1 << 16; // (the lane counts hold up to 2^32 each)
    const bool exact = exact_ != Exact::None;
    const Extremes e = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, values_.size(), kBlock), Extremes{},
        [&](const tbb::blocked_range<std::size_t>& block, Extremes part) {
            if (!exact) {
                // Floats first, the offset once per block.
                Extremes f = floatExtremes(values_.data() + block.begin(), values_.data() + block.end());
                if (f.count > 0) {
                    f.lo = offset_ + f.lo;
                    f.hi = offset_ + f.hi;
                }
                part.merge(f);
                return part;
            }
            // The exact values' own extremes, not their float roundings.
            for (std::size_t i = block.begin(); i < block.end(); ++i) {
                if (std::isnan(values_[i]))
                    continue;
                const double v = value(i);
                part.lo = std::min(part.lo, v);
                part.hi = std::max(part.hi, v);
                ++part.count;
            }
            return part;
        },
        [](Extremes a, const Extremes& b) {
            a.merge(b);
            return a;
        });
    ValueRange r;
    r.validCount = e.count;
    if (e.count > 0) {
        r.min = e.lo;
        r.max = e.hi;
    }
    return r;
}

} // namespace scandiff
