// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What plugins contribute, gathered in one object that front ends and tests own
//! and pass around explicitly (no global registry, no static initialisers that
//! a linker could drop).
//!
//! A plugin is a folder plugins/NAME with its own CMake target (see
//! cmake/ScandiffPlugins.cmake) and one function
//!     void scandiff_register_plugin_NAME(scandiff::PluginRegistry&);
//! which adds its description, tools and file formats.

#include <scandiff/core/ToolRegistry.h>
#include <scandiff/io/FileIO.h>

#include <string>
#include <vector>

namespace scandiff {

struct PluginInfo
{
    std::string name;
    std::string description;
    std::string dependencies; //!< third-party libraries it brings (e.g. "PCL io")
};

struct PluginRegistry
{
    std::vector<PluginInfo> plugins;
    ToolRegistry tools;
    io::FormatRegistry formats;
};

//! The built-in formats of io/ plus every plugin of this build.
PluginRegistry makePluginRegistry();

} // namespace scandiff
