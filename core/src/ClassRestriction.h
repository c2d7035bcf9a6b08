// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Any tool on some classes only (`--classes 2,6`, `--exclude-classes 7,18`):
//! the registry gives every tool that takes point clouds these two optional
//! parameters once, and runs the tool on its cloud inputs restricted to the
//! points whose ASPRS `classification` the user chose, so that each tool
//! answers exactly as on clouds filtered beforehand. What the tool gives in
//! place of its first input (UpdatesInput) is laid back over the whole input,
//! so the workbench, which replaces that entity, loses no point:
//! - the fields the tool added are empty (NaN) on the points left out, the
//!   fields they had keep their values there; normals likewise;
//! - points the tool moved (a registration) are all moved, by the tool's
//!   matrix output, the points left out with them.

#include <scandiff/core/ClassSelection.h>
#include <scandiff/core/ToolRegistry.h>

namespace scandiff::detail {

//! Adds the two parameters to `tool` when it takes point clouds, has neither
//! already, and gives no repeated in-place output (the stations of a
//! multi-station registration: their poses are not one matrix to move the
//! points left out by).
void addClassParameters(ToolSpec& tool);

//! Runs `tool` on its cloud inputs restricted by class (see above). Throws
//! Error(InvalidArgument) for a bad class list, a cloud without the field
//! `classification`, or no point left in a cloud.
ToolResult runOnClasses(const ToolSpec& tool, const ToolInputs& given, const ParameterValues& values,
                        ProgressObserver* progress);

} // namespace scandiff::detail
