// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/FieldRange.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <functional>

namespace scandiff {

namespace {

const ScalarField& checkedField(const PointCloud& cloud, const std::string& fieldName, double low, double high)
{
    const ScalarField* field = cloud.field(fieldName);
    if (!field)
        throw Error(ErrorCode::InvalidArgument, "the cloud has no scalar field '" + fieldName + "'");
    if (std::isnan(low) || std::isnan(high) || low > high)
        throw Error(ErrorCode::InvalidArgument, "invalid range for '" + fieldName + "': the lower bound must not exceed the upper");
    return *field;
}

// The comparison is made on the stored value's double form, exactly as ScalarField::value() gives it.
bool inRange(const ScalarField& field, std::size_t i, double low, double high)
{
    const double v = field.value(i);
    return v >= low && v <= high; // false for NaN
}

} // namespace

FieldRangeSplit splitByFieldRange(const PointCloud& cloud, const std::string& fieldName, double low, double high)
{
    const ScalarField& field = checkedField(cloud, fieldName, low, high);
    std::vector<std::size_t> inside, outside;
    inside.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i)
        (inRange(field, i, low, high) ? inside : outside).push_back(i);
    FieldRangeSplit split{cloud.subset(inside), cloud.subset(outside)};
    split.inside.name = cloud.name;
    split.outside.name = cloud.name;
    return split;
}

std::size_t countInRange(const ScalarField& field, double low, double high)
{
    // On every core: the workbench counts at each step of a threshold drag.
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, field.size(), 1 << 16), std::size_t(0),
        [&](const tbb::blocked_range<std::size_t>& r, std::size_t n) {
            for (std::size_t i = r.begin(); i != r.end(); ++i)
                n += inRange(field, i, low, high) ? 1 : 0;
            return n;
        },
        std::plus<>());
}

} // namespace scandiff
