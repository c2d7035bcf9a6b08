// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Choosing points by their ASPRS class (the field `classification`) for a
//! run: the two parameters every tool on clouds takes (`--classes 2,6`,
//! `--exclude-classes 7,18`), the points they keep, and a result computed on
//! those points spread back over the whole cloud. The registry applies them
//! to its tools (core/src/ClassRestriction.h); the distances declared outside
//! it (c2c) use them directly.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/ToolRegistry.h>

#include <optional>
#include <vector>

namespace scandiff {

inline constexpr const char* kClassesParameter = "classes";
inline constexpr const char* kExcludeClassesParameter = "exclude-classes";

//! ASPRS classes from a list ("2,6", "2 8"): integers in 0..255. Throws
//! Error(InvalidArgument) naming `what` for another number, or for none.
std::vector<int> parseClassList(const std::string& text, const std::string& what);

//! The optional parameters `classes` and `exclude-classes`.
std::vector<ParameterSpec> classParameters();

//! True when `values` restricts the run to some classes.
bool restrictsClasses(const ParameterValues& values);

//! The points of `cloud` the values keep, in order: those whose class is in
//! `classes` (when given) and not in `exclude-classes`; a point without a
//! class (NaN) is in no class. Nothing when the values restrict nothing.
//! Throws Error(InvalidArgument) for a bad class list (not integers in
//! 0..255, empty), a cloud without `classification`, or no point kept.
std::optional<std::vector<std::size_t>> pointsOfClasses(const PointCloud& cloud, const ParameterValues& values);

//! A field of the points `kept` (one value each, in their order) as a field of
//! `size` points: NaN on the others.
ScalarField spreadOver(const ScalarField& part, const std::vector<std::size_t>& kept, std::size_t size);

} // namespace scandiff
