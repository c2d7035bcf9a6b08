// SPDX-License-Identifier: GPL-3.0-or-later
#include "internal/Formats.h"

namespace scandiff::io {

void registerBuiltinFormats(FormatRegistry& registry)
{
    registry.add(detail::plyFormat());
    registry.add(detail::asciiFormat());
    registry.add(detail::lasFormat());
    registry.add(detail::lazFormat());
    registry.add(detail::pcdFormat());
    registry.add(detail::e57Format());
    registry.add(detail::meshFormat());
    registry.add(detail::dxfFormat());
    registry.add(detail::geoTiffFormat());
    registry.add(detail::pngPreviewFormat());
}

} // namespace scandiff::io
