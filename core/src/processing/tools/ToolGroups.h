// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The processing tools' declarations, one file per menu group (internal to core).

#include <scandiff/core/ToolRegistry.h>

#include <sstream>
#include <string>

namespace scandiff::detail {

void registerNormalTools(ToolRegistry& registry);
void registerSubsamplingTools(ToolRegistry& registry);
void registerEditTools(ToolRegistry& registry);
void registerFieldTools(ToolRegistry& registry);
void registerSurfaceTools(ToolRegistry& registry);
void registerDistanceTools(ToolRegistry& registry); // M3C2, then the raster tools
void registerRasterTools(ToolRegistry& registry);
void registerGroundTools(ToolRegistry& registry);

//! The declaration of a tool taking one cloud, with its first output.
inline ToolSpec oneCloudTool(std::string name, std::string title, std::string category, std::string description,
                             OutputSpec output)
{
    ToolSpec tool;
    tool.name = std::move(name);
    tool.title = std::move(title);
    tool.category = std::move(category);
    tool.description = std::move(description);
    tool.outputs = {std::move(output)};
    return tool;
}

//! An output that is the input changed in place (normals, fields, moved points).
inline OutputSpec updatedCloud(std::string label)
{
    return OutputSpec{"output", std::move(label), DataKind::Cloud, true};
}

//! An output that is a new cloud, shown under its input.
inline OutputSpec newCloud(std::string label)
{
    return OutputSpec{"output", std::move(label), DataKind::Cloud, false};
}

//! Numbers in a summary: six significant digits, as a person reads them.
template <typename... Parts>
std::string describe(const Parts&... parts)
{
    std::ostringstream s;
    s.precision(6);
    (s << ... << parts);
    return s.str();
}

} // namespace scandiff::detail
