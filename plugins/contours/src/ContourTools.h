// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The tools of the contours plugin, registered by ContoursPlugin.cpp.
#include <scandiff/core/ToolRegistry.h>

namespace scandiff::plugins {

ToolSpec comparePolygonsTool();

} // namespace scandiff::plugins
