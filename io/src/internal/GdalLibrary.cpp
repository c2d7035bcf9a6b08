// SPDX-License-Identifier: GPL-3.0-or-later
#include "internal/GdalLibrary.h"

#include <scandiff/core/Error.h>

#include <dlfcn.h>

#include <string>

namespace scandiff::io::detail {

namespace {

struct Loaded
{
    GdalLibrary functions;
    std::string error; //!< empty once every function is found
};

Loaded load()
{
    Loaded loaded;
    // SCANDIFF_GDAL_SONAME: the library the build linked against (io/CMakeLists.txt).
    // Never closed: GDAL keeps its drivers registered for the process.
    void* handle = dlopen(SCANDIFF_GDAL_SONAME, RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
        const char* why = dlerror();
        loaded.error = std::string("GDAL could not be loaded (") + (why ? why : SCANDIFF_GDAL_SONAME) + ")";
        return loaded;
    }
#define SCANDIFF_GDAL_LOOKUP(name)                                                                                     \
    loaded.functions.name = reinterpret_cast<decltype(&::name)>(dlsym(handle, #name));                                 \
    if (!loaded.functions.name && loaded.error.empty())                                                                \
        loaded.error = std::string("GDAL (" SCANDIFF_GDAL_SONAME ") has no function ") + #name;
    SCANDIFF_GDAL_FUNCTIONS(SCANDIFF_GDAL_LOOKUP)
#undef SCANDIFF_GDAL_LOOKUP
    return loaded;
}

} // namespace

const GdalLibrary& gdal()
{
    static const Loaded loaded = load();
    if (!loaded.error.empty())
        throw Error(ErrorCode::Unsupported, loaded.error);
    return loaded.functions;
}

} // namespace scandiff::io::detail
