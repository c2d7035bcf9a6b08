// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A named per-point scalar field: float32 values around a double offset.
//! value(i) = offset + values[i]; NaN in `values` means "no value".
//! The offset keeps large values (GPS time ~1e9 s) precise in float32.

#include <cmath>
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

    double value(std::size_t i) const { return offset_ + static_cast<double>(values_[i]); }
    void setValue(std::size_t i, double v) { values_[i] = static_cast<float>(v - offset_); }
    bool hasValue(std::size_t i) const { return !std::isnan(values_[i]); }

    //! Min/max of the valid values (NaN when there is none).
    ValueRange range() const;

private:
    std::string name_;
    double offset_ = 0.0;
    std::vector<float> values_;
};

} // namespace scandiff
