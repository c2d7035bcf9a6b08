// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The everyday processing tools of core (normals, features, subsampling,
//! editing, scalar fields, primitives and unrolling, mesh sampling, M3C2), declared
//! once as ToolSpecs: scandiff-cli makes a subcommand of each, the workbench a
//! dialog and a menu entry.

#include <scandiff/core/ToolRegistry.h>

namespace scandiff {

void registerProcessingTools(ToolRegistry& registry);

} // namespace scandiff
