// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Splitting a cloud by a scalar-field range: the "split at thresholds" of the
//! workbench (and what a user does with CloudCompare's "filter by value").

#include <scandiff/core/PointCloud.h>

#include <string>

namespace scandiff {

struct FieldRangeSplit
{
    PointCloud inside;  //!< points whose value v satisfies low <= v <= high, in input order
    PointCloud outside; //!< the others, NaN ("no value") included, in input order
};

//! Both parts keep every attribute and the origin. Throws Error(InvalidArgument)
//! if the field does not exist or low > high or a bound is NaN.
FieldRangeSplit splitByFieldRange(const PointCloud& cloud, const std::string& fieldName, double low, double high);

//! How many values lie in [low, high] (NaN never does).
std::size_t countInRange(const ScalarField& field, double low, double high);

} // namespace scandiff
