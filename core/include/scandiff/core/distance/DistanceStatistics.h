// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Summary statistics of a distance field (cloud-to-mesh, cloud-to-cloud).

#include <scandiff/core/ScalarField.h>

#include <cstddef>
#include <limits>

namespace scandiff {

//! Statistics over the valid (non-NaN) values of a field, in the field's unit.
//! With no valid value, count is 0 and every other member is NaN.
struct DistanceStatistics
{
    std::size_t count = 0; //!< number of non-NaN values
    double mean = std::numeric_limits<double>::quiet_NaN();
    //! Population standard deviation: sqrt(sum (v - mean)^2 / count), as CloudCompare shows it.
    double standardDeviation = std::numeric_limits<double>::quiet_NaN();
    double min = std::numeric_limits<double>::quiet_NaN();
    double max = std::numeric_limits<double>::quiet_NaN();
    double rms = std::numeric_limits<double>::quiet_NaN(); //!< sqrt(sum v^2 / count)
};

//! Statistics of field.value(i) over the valid entries, accumulated in double
//! (two passes: the mean, then the deviations).
DistanceStatistics computeStatistics(const ScalarField& field);

} // namespace scandiff
