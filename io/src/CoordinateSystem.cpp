// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/io/CoordinateSystem.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>

#include "internal/GdalLibrary.h"

#include <memory>
#include <string>

namespace scandiff::io {

namespace {

using detail::gdal;

struct SpatialReference
{
    OGRSpatialReferenceH handle = gdal().OSRNewSpatialReference(nullptr);
    ~SpatialReference() { gdal().OSRDestroySpatialReference(handle); }
};

//! GDAL reports failures through its error handler (stderr by default): they
//! become our messages instead.
struct QuietGdalErrors
{
    QuietGdalErrors() { gdal().CPLPushErrorHandler(gdal().CPLQuietErrorHandler); }
    ~QuietGdalErrors() { gdal().CPLPopErrorHandler(); }
};

std::string exportWkt(OGRSpatialReferenceH srs)
{
    char* text = nullptr;
    // WKT1 (OGC 01-009) is what LAS 1.4 R15 asks for in its WKT record.
    if (gdal().OSRExportToWkt(srs, &text) != OGRERR_NONE || !text) {
        gdal().VSIFree(text);
        return {};
    }
    std::string wkt(text);
    gdal().VSIFree(text);
    return wkt;
}

} // namespace

std::string crsFromUserInput(const std::string& definition)
{
    const QuietGdalErrors quiet;
    SpatialReference srs;
    if (definition.empty() || gdal().OSRSetFromUserInput(srs.handle, definition.c_str()) != OGRERR_NONE)
        throw Error(ErrorCode::InvalidArgument, "unknown coordinate reference system '" + definition +
                                                    "' (give EPSG:CODE, EPSG:CODE+VERTICALCODE, a WKT or a PROJ string)");
    std::string wkt = exportWkt(srs.handle);
    if (wkt.empty())
        throw Error(ErrorCode::InvalidArgument, "coordinate reference system '" + definition + "' has no WKT form");
    return wkt;
}

std::string crsFromEpsg(int horizontalEpsg, int verticalEpsg, const std::string& where)
{
    const std::string code = "EPSG:" + std::to_string(horizontalEpsg) + (verticalEpsg > 0 ? "+" + std::to_string(verticalEpsg) : "");
    try {
        return crsFromUserInput(code);
    } catch (const Error& e) {
        if (e.code() == ErrorCode::Unsupported) { // no GDAL: say so, rather than blame the code
            logWarning(where + ": " + e.what() + "; the coordinate reference system " + code + " is not read, the cloud gets none");
            return {};
        }
    }
    if (verticalEpsg > 0) { // keep the horizontal system when only the vertical one is unknown
        try {
            std::string wkt = crsFromUserInput("EPSG:" + std::to_string(horizontalEpsg));
            logWarning(where + ": the vertical system EPSG:" + std::to_string(verticalEpsg) +
                       " is unknown to PROJ; the cloud keeps the horizontal one only");
            return wkt;
        } catch (const Error&) {
        }
    }
    logWarning(where + ": the coordinate reference system " + code + " is unknown to PROJ; the cloud gets none");
    return {};
}

std::string crsName(const std::string& wkt)
{
    if (wkt.empty())
        return {};
    try {
        const QuietGdalErrors quiet;
        SpatialReference srs;
        // Imported as WKT only: text from a file must not make GDAL open a path or a URL.
        char* text = const_cast<char*>(wkt.c_str());
        if (gdal().OSRImportFromWkt(srs.handle, &text) == OGRERR_NONE) {
            if (const char* name = gdal().OSRGetName(srs.handle))
                return name;
        }
    } catch (const Error&) { // no GDAL: the name is the text's start
    }
    return wkt.substr(0, 60) + (wkt.size() > 60 ? "..." : "");
}

} // namespace scandiff::io
