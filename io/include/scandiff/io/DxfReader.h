// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The lines of an ASCII DXF drawing, for comparing a vector model with a
//! reference drawing: LWPOLYLINEs, 2D and 3D POLYLINEs (not the mesh kinds,
//! which readPointCloud/readMesh read as surfaces), LINEs and TEXTs of the
//! ENTITIES section, in world coordinates (object coordinate systems applied).
//! Arc segments keep their bulges (DrawingPolyline::bulges, with the plane's
//! normal); polylineVertices() gives points along them.

#include <scandiff/core/Drawing.h>
#include <scandiff/core/Progress.h>

#include <filesystem>

namespace scandiff::io {

//! Throws Error(Io) when the file cannot be read, Error(InvalidData) naming
//! the line of a malformed group, Error(Unsupported) for binary DXF.
Drawing readDrawingDxf(const std::filesystem::path& path, ProgressObserver* progress = nullptr);

} // namespace scandiff::io
