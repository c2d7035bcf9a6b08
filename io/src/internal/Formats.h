// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The built-in format handlers, one per source file of io/src/.

#include <scandiff/io/FileIO.h>

namespace scandiff::io::detail {

FormatHandler plyFormat();        // PlyFormat.cpp
FormatHandler asciiFormat();      // AsciiFormat.cpp
FormatHandler lasFormat();        // LasFormat.cpp
FormatHandler lazFormat();        // LasFormat.cpp (reading; LazDecoder.cpp decompresses)
FormatHandler pcdFormat();        // PcdFormat.cpp
FormatHandler meshFormat();       // MeshFormats.cpp (readers in MeshReaders.cpp)
FormatHandler dxfFormat();        // DxfWriter.cpp (export only)
FormatHandler geoTiffFormat();    // GeoTiffFormat.cpp (export of gridded clouds, GDAL)
FormatHandler pngPreviewFormat();  // RasterPreview.cpp (picture of a gridded cloud, GDAL)
FormatHandler e57Format();        // e57/E57Format.cpp (reader, writer and paged layer in e57/)

} // namespace scandiff::io::detail
