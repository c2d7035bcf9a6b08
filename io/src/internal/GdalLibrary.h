// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! GDAL, loaded the first time a GeoTIFF, a PNG preview or a coordinate
//! reference system needs it, instead of when the program starts.
//!
//! Why: linked the usual way, libgdal makes every process map and relocate
//! about 110 libraries before main() (its drivers' dependencies: curl, HDF5,
//! NetCDF, Poppler, PostgreSQL, ...): 75 ms of every run on the 2-core
//! machine of docs/benchmarks.md, against 3 ms for an empty program, and a
//! registration or a C2C run takes 0.5 s. Most runs never touch GDAL.
//! The functions are GDAL's own C API (their types from its headers, so a
//! signature that changes breaks the build, not a run), looked up once by
//! dlopen/dlsym in the library the build found.

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal.h>
#include <ogr_srs_api.h>

namespace scandiff::io::detail {

// Every GDAL function io calls, by its own name: a real function, not one of
// GDAL's macros (CPLFree is VSIFree), since each is looked up by its name.
#define SCANDIFF_GDAL_FUNCTIONS(X)                                                                                     \
    X(CPLGetLastErrorMsg)                                                                                              \
    X(CPLPopErrorHandler)                                                                                              \
    X(CPLPushErrorHandler)                                                                                             \
    X(CPLQuietErrorHandler)                                                                                            \
    X(GDALAllRegister)                                                                                                 \
    X(GDALClose)                                                                                                       \
    X(GDALCreate)                                                                                                      \
    X(GDALCreateCopy)                                                                                                  \
    X(GDALGetDriverByName)                                                                                             \
    X(GDALGetRasterBand)                                                                                               \
    X(GDALRasterIO)                                                                                                    \
    X(GDALSetDescription)                                                                                              \
    X(GDALSetGeoTransform)                                                                                             \
    X(GDALSetProjection)                                                                                               \
    X(GDALSetRasterNoDataValue)                                                                                        \
    X(OSRDestroySpatialReference)                                                                                      \
    X(OSRExportToWkt)                                                                                                  \
    X(OSRGetName)                                                                                                      \
    X(OSRImportFromWkt)                                                                                                \
    X(OSRNewSpatialReference)                                                                                          \
    X(OSRSetFromUserInput)                                                                                             \
    X(VSIFree)

struct GdalLibrary
{
#define SCANDIFF_GDAL_POINTER(name) decltype(&::name) name = nullptr;
    SCANDIFF_GDAL_FUNCTIONS(SCANDIFF_GDAL_POINTER)
#undef SCANDIFF_GDAL_POINTER
};

//! GDAL's functions, loaded on the first call (thread-safe). Throws
//! Error(Unsupported), with the loader's message, when the library or one of
//! the functions cannot be found; every later call throws the same.
const GdalLibrary& gdal();

} // namespace scandiff::io::detail
