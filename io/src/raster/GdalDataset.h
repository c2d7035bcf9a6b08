// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What the writers that go through GDAL (GeoTIFF, PNG preview) share: the
//! drivers registered once, a driver looked up with a clear error, and a
//! dataset closed on every way out.

#include <scandiff/core/Error.h>

#include "internal/GdalLibrary.h"

#include <filesystem>
#include <mutex>
#include <string>

namespace scandiff::io::detail {

//! GDAL's driver `name` (its drivers registered on first use, once for the
//! process); throws Error(Unsupported) naming `path` when this GDAL lacks it.
inline GDALDriverH gdalDriver(const char* name, const std::filesystem::path& path)
{
    static std::once_flag registered;
    std::call_once(registered, [] { gdal().GDALAllRegister(); });
    GDALDriverH driver = gdal().GDALGetDriverByName(name);
    if (!driver)
        throw Error(ErrorCode::Unsupported, path.string() + ": this GDAL has no " + name + " driver");
    return driver;
}

//! A dataset closed when it goes out of scope (a cancellation, an error), or
//! by close() where the caller needs its file complete: GDAL writes a file
//! when it closes the dataset.
class GdalDataset
{
public:
    explicit GdalDataset(GDALDatasetH handle) : handle_(handle) {}
    GdalDataset(const GdalDataset&) = delete;
    GdalDataset& operator=(const GdalDataset&) = delete;
    ~GdalDataset() { close(); }
    GDALDatasetH get() const { return handle_; }
    explicit operator bool() const { return handle_ != nullptr; }
    void close()
    {
        if (handle_)
            gdal().GDALClose(handle_);
        handle_ = nullptr;
    }

private:
    GDALDatasetH handle_;
};

} // namespace scandiff::io::detail
