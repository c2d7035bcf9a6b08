// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The primitives family run through `scandiff-cli primitives` (the registry's
//! ToolSpec, default parameters unless given), scored against its truth.
//! Used by bench/FamilyTrials.cpp.

#include "PrimitivesFamily.h"

#include <scandiff/core/ToolRegistry.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <cmath>
#include <map>
#include <string>

namespace scandiff::test::family {

struct PrimitivesTrial
{
    primitives::DetectionScore score;
    std::string report;
};

inline PrimitivesTrial runPrimitives(const primitives::PrimitivesScene& scene, const std::map<std::string, std::string>& options)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("primitives");
    ToolResult result = tool.execute(ToolInputs().add("input", scene.cloud), tool.resolve(options), nullptr);
    const PointCloud& labelled = std::get<PointCloud>(result.find("primitives")->data);
    const ScalarField* id = labelled.field("primitive_id");
    const ScalarField* type = labelled.field("primitive_type");
    std::vector<int> assignment(labelled.size(), -1);
    std::vector<Primitive> detected;
    for (std::size_t i = 0; id && i < labelled.size(); ++i) {
        const double v = id->value(i);
        if (!std::isfinite(v) || v < 0)
            continue;
        const auto k = static_cast<std::size_t>(std::lround(v));
        if (detected.size() <= k)
            detected.resize(k + 1);
        if (type)
            detected[k].kind = static_cast<PrimitiveKind>(std::lround(type->value(i)));
        assignment[i] = static_cast<int>(k);
    }
    PrimitivesTrial trial;
    trial.score = primitives::score(scene, detected, assignment);
    trial.report = result.summary;
    return trial;
}

} // namespace scandiff::test::family
