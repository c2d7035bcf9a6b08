// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/processing/ProcessingTools.h>

#include "processing/tools/ToolGroups.h"

namespace scandiff {

void registerProcessingTools(ToolRegistry& registry)
{
    detail::registerNormalTools(registry);
    detail::registerSubsamplingTools(registry);
    detail::registerEditTools(registry);
    detail::registerFieldTools(registry);
    detail::registerSurfaceTools(registry);
    detail::registerDistanceTools(registry);
    detail::registerGroundTools(registry);
}

} // namespace scandiff
