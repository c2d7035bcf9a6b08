// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A named per-point scalar field: float32 values around a double offset.
//! value(i) = offset + values[i]; NaN in `values` means "no value".
//! The offset keeps large values (GPS time ~1e9 s) precise in float32.
//!
//! A field read from a double-valued source (LAS GPS time, a PLY or PCD double
//! property, text with more digits than a float holds) also keeps every value
//! as a double, so that writing it back gives the same bits. The float view
//! stays the working copy that display and algorithms read. Code that writes
//! through the float view (values()) does not need to know about the doubles:
//! value(i) returns the double only while the float view still holds that
//! double's rounding, so a value changed through the float view wins.

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
    double offset() const { return offset_; }
    void setOffset(double offset) { offset_ = offset; }

    //! Stored float values (relative to offset()).
    const std::vector<float>& values() const { return values_; }
    std::vector<float>& values() { return values_; }

    double value(std::size_t i) const
    {
        if (i < doubles_.size()) {
            const double exact = doubles_[i];
            if (static_cast<float>(exact - offset_) == values_[i])
                return exact;
        }
        return offset_ + static_cast<double>(values_[i]);
    }
    void setValue(std::size_t i, double v)
    {
        values_[i] = static_cast<float>(v - offset_);
        if (i < doubles_.size())
            doubles_[i] = v;
    }
    bool hasValue(std::size_t i) const { return !std::isnan(values_[i]); }

    //! Resizes the float view and, for a double field, the doubles; new values are NaN.
    void resize(std::size_t n);

    //! True when the field keeps its values as doubles too.
    bool isDouble() const { return keepsDoubles_; }
    //! Starts keeping doubles: every current value becomes its double.
    void keepDoubles();
    //! Back to float only (frees the doubles).
    void dropDoubles();
    //! Drops the doubles when the float view around the offset already gives
    //! every one of them back exactly; returns whether it did.
    bool dropDoublesIfExactInFloat();
    //! The doubles (empty unless isDouble()). Writing one does not update the
    //! float view: use setValue() for that.
    const std::vector<double>& doubles() const { return doubles_; }
    std::vector<double>& doubles() { return doubles_; }

    //! Min/max of the valid values (NaN when there is none).
    ValueRange range() const;

private:
    std::string name_;
    double offset_ = 0.0;
    std::vector<float> values_;
    bool keepsDoubles_ = false;
    std::vector<double> doubles_; //!< empty, or one per value when keepsDoubles_
};

} // namespace scandiff
