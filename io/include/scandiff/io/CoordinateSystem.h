// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Coordinate reference systems of clouds (PointCloud::crsWkt), through
//! GDAL's OGR spatial references (PROJ's database underneath): what a user
//! types, what LAS GeoTIFF keys give, and a name to show.

#include <string>

namespace scandiff::io {

//! OGC WKT of what a user gives: "EPSG:2154", "EPSG:2056+5728" (horizontal +
//! vertical), a WKT, a PROJ string. Throws Error(InvalidArgument) naming the
//! input when PROJ does not know it.
std::string crsFromUserInput(const std::string& definition);

//! OGC WKT of an EPSG horizontal system, with an EPSG vertical system when
//! `verticalEpsg` > 0 (a compound system). Empty, with a warning naming
//! `where`, when a code is unknown.
std::string crsFromEpsg(int horizontalEpsg, int verticalEpsg, const std::string& where);

//! The name of the system ("RGF93 v1 / Lambert-93"), for display; the start
//! of the text when it cannot be parsed; empty for an empty input.
std::string crsName(const std::string& wkt);

} // namespace scandiff::io
