// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Scalar-field operations (thesis 000 annex C: "gradient; Gaussian filter;
//! product of two scalar fields"), generalised: any arithmetic between fields
//! and constants through an expression, Gaussian smoothing in a radius,
//! conversions between fields and colours, the histogram as a table.

#include <scandiff/core/ColourScale.h>
#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/Table.h>

#include <optional>
#include <string>

namespace scandiff {

//! "NAME = EXPRESSION" split at the first '=' that is not part of a comparison
//! (==, !=, <=, >=); both sides trimmed. Throws Error(InvalidArgument).
std::pair<std::string, std::string> parseFieldAssignment(const std::string& text);

//! The name an expression uses for a field: every character other than a
//! letter, a digit or '_' replaced by '_' ("C2C absolute distances" ->
//! C2C_absolute_distances).
std::string expressionName(const std::string& fieldName);

//! The value of `expression` at every point, in double (muparser: + - * / ^,
//! comparisons and && || giving 1 or 0, "c ? a : b", abs sqrt exp ln log
//! (natural) log10 log2 sin cos tan ... min max sum avg, the constants _pi
//! _e). Variables: each field by expressionName(), x y z (global
//! coordinates), nx ny nz and r g b (0-255) when the cloud has them. A point
//! without a value in a field the expression uses gets no value (NaN), even
//! where the expression would not need it. Throws Error(InvalidArgument)
//! naming the position of a syntax error or the unknown variable, Error(Cancelled).
ScalarField evaluateFieldExpression(const PointCloud& cloud, const std::string& expression, const std::string& resultName,
                                    ProgressObserver* progress = nullptr);

//! The Gaussian-weighted mean of the field over the points within 3 sigma
//! (weights exp(-d²/2σ²), thesis eq. 3.10; the point itself included, NaN
//! values left out). A constant field stays that constant. Throws
//! Error(InvalidArgument) for a missing field or sigma not > 0.
ScalarField gaussianSmoothing(const PointCloud& cloud, const std::string& fieldName, double sigma, const std::string& resultName,
                              ProgressObserver* progress = nullptr);

//! Colours from a field through a scale over [low, high] (values outside are
//! saturated); points without a value get `noValue`.
std::vector<Rgb8> coloursFromField(const ScalarField& field, const ColourScale& scale, double low, double high,
                                   Rgb8 noValue = Rgb8{150, 150, 150});

enum class ColourChannel { Luminance, Red, Green, Blue, Mean };
ColourChannel parseColourChannel(const std::string& name);
//! A field from the colours: luminance 0.2126 R + 0.7152 G + 0.0722 B
//! (ITU-R BT.709), one channel, or their mean, in 0..255. Throws
//! Error(InvalidArgument) when the cloud has no colours.
ScalarField fieldFromColours(const PointCloud& cloud, ColourChannel channel, const std::string& resultName);

//! The field's histogram over its range (or [low, high] when given: values
//! outside are not counted) as a table: bin_min, bin_max, count. Throws
//! Error(InvalidArgument) for bins < 1 or low >= high.
Table fieldHistogram(const ScalarField& field, int bins, std::optional<std::pair<double, double>> range = std::nullopt);

//! CloudCompare's "filter by value": which points keep, or with `outside`
//! lose, a value of the field in [low, high] (bounds included, compared on
//! the exact values a double-valued field keeps). A point without a value is
//! in neither set: a filter never invents a value for it.
struct FilterByValueParams
{
    std::string field;
    double low = 0.0, high = 0.0;
    bool outside = false;
};
struct FilterByValueResult
{
    std::vector<std::size_t> kept; //!< in cloud order
    std::size_t withoutValue = 0;  //!< points left out for having no value
};
//! Throws Error(InvalidArgument) for a missing field or low > high.
FilterByValueResult filterByValue(const PointCloud& cloud, const FilterByValueParams& params);

} // namespace scandiff
