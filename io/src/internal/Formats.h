// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The built-in format handlers, one per format folder of io/src/.

#include <scandiff/io/FileIO.h>

namespace scandiff::io::detail {

FormatHandler plyFormat();        // ply/PlyFormat.cpp
FormatHandler asciiFormat();      // ascii/AsciiFormat.cpp
FormatHandler lasFormat();        // las/LasFormat.cpp
FormatHandler lazFormat();        // las/LasFormat.cpp (reading; laz/LazDecoder.cpp decompresses)
FormatHandler pcdFormat();        // pcd/PcdFormat.cpp
FormatHandler meshFormat();       // mesh/MeshFormats.cpp (readers in mesh/MeshReaders.cpp)
FormatHandler dxfFormat();        // dxf/DxfWriter.cpp (export only)
FormatHandler geoTiffFormat();    // raster/GeoTiffFormat.cpp (export of gridded clouds, GDAL)
FormatHandler pngPreviewFormat();  // raster/RasterPreview.cpp (picture of a gridded cloud, GDAL)
FormatHandler e57Format();        // e57/E57Format.cpp (reader, writer and paged layer in e57/)

} // namespace scandiff::io::detail
