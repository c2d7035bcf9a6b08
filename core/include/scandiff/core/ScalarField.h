// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A named per-point scalar field: float32 values around a double offset.
//! value(i) = offset + values[i]; NaN in `values` means "no value".
//! The offset keeps large values (GPS time ~1e9 s) precise in float32.
//!
//! A field read from a double-valued source (LAS GPS time, a PLY or PCD double
//! property, text with more digits than a float holds) also keeps every value
//! exactly, so that writing it back gives the same bits. The float view stays
//! the working copy that display and algorithms read. The exact values are
//! kept in the smallest form that gives every one back:
//! - residuals: per value, the float r that the float view f misses,
//!   value = offset + (f + r), 4 bytes more per value. Exact whenever the
//!   value's bits below the float's fit in another float: GPS times (a span of
//!   hours from the offset and microseconds need ~40 bits) and any 32-bit
//!   integer;
//! - doubles, 8 bytes more per value, for anything else.
//! Code that writes through the float view (values()) does not need to know
//! about them: value(i) uses the exact form only while the float view still
//! holds that value's rounding (a residual only while it is below half the
//! float's last digit), so a value changed through the float view wins.

#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace scandiff {

struct ValueRange
{
    double min = std::numeric_limits<double>::quiet_NaN();
    double max = std::numeric_limits<double>::quiet_NaN();
    std::size_t validCount = 0; //!< number of non-NaN values
};

class ScalarField
{
public:
    ScalarField() = default;
    explicit ScalarField(std::string name, std::size_t size = 0)
        : name_(std::move(name)), values_(size, std::numeric_limits<float>::quiet_NaN())
    {
    }

    const std::string& name() const { return name_; }
    void rename(std::string name) { name_ = std::move(name); }

    std::size_t size() const { return values_.size(); }
    //! Bytes its per-value arrays hold (their capacities): the float view and
    //! the exact form when kept.
    std::size_t heldBytes() const
    {
        return values_.capacity() * sizeof(float) + residuals_.capacity() * sizeof(float) + doubles_.capacity() * sizeof(double);
    }
    double offset() const { return offset_; }
    void setOffset(double offset) { offset_ = offset; }

    //! Stored float values (relative to offset()).
    const std::vector<float>& values() const { return values_; }
    std::vector<float>& values() { return values_; }

    double value(std::size_t i) const
    {
        if (exact_ == Exact::Doubles && i < doubles_.size()) {
            const double exact = doubles_[i];
            if (static_cast<float>(exact - offset_) == values_[i])
                return exact;
        } else if (exact_ == Exact::Residuals && i < residuals_.size()) {
            const float f = values_[i], r = residuals_[i];
            if (f + r == f)
                return offset_ + (static_cast<double>(f) + static_cast<double>(r));
        }
        return offset_ + static_cast<double>(values_[i]);
    }
    //! Sets value i (its exact form too, for a field that keeps one).
    void setValue(std::size_t i, double v);
    bool hasValue(std::size_t i) const { return !std::isnan(values_[i]); }

    //! Resizes the float view and the exact form; new values are NaN.
    void resize(std::size_t n);
    //! Value `from` copied onto value `to`, exact form included.
    void moveValue(std::size_t from, std::size_t to);
    //! The values at `indices`, in that order, exact form included.
    ScalarField subset(const std::vector<std::size_t>& indices) const;

    //! True when the field keeps its values exactly (residuals or doubles).
    bool isDouble() const { return exact_ != Exact::None; }
    //! Keeps every value as a double from now on (the current values, exactly).
    void keepDoubles();
    //! Keeps float residuals (all 0: the current float view is taken as exact).
    //! For readers that fill them with setValue() or through residuals().
    void keepResiduals();
    //! Back to the float view only.
    void dropExact();
    //! The smallest exact form that gives every current value back: none when
    //! the float view does (residuals of 0 with `stayExact`, for a field whose
    //! type is double in its file and must be written back as one), residuals
    //! when they do, else doubles. Returns whether an exact form is kept.
    bool compact(bool stayExact = false);
    //! Whether offset + (f + r) gives v back, f and r floats (see residualOf).
    static bool residualHolds(double v, double offset);
    //! The float residual of v around `offset` beside its float f = float(v - offset).
    static float residualOf(double v, double offset, float f)
    {
        return static_cast<float>((v - offset) - static_cast<double>(f));
    }
    //! The exact forms (empty unless kept). Writing one does not update the
    //! float view: use setValue() for that.
    const std::vector<double>& doubles() const { return doubles_; }
    std::vector<double>& doubles() { return doubles_; }
    const std::vector<float>& residuals() const { return residuals_; }
    std::vector<float>& residuals() { return residuals_; }

    //! Min/max of the valid values (NaN when there is none).
    ValueRange range() const;
    //! Whether every value is valid and 0 (what LAS readers leave out). A
    //! value other than 0 is usually among the first: only a field of zeros
    //! is scanned to its end.
    bool isZeroEverywhere() const;

private:
    std::string name_;
    double offset_ = 0.0;
    std::vector<float> values_;
    enum class Exact : unsigned char { None, Residuals, Doubles };
    Exact exact_ = Exact::None;
    std::vector<float> residuals_; //!< one per value with Exact::Residuals
    std::vector<double> doubles_;  //!< one per value with Exact::Doubles
};

} // namespace scandiff
