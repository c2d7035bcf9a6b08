// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The façade and stone-wall families run through the tools as the command
//! line runs them (the registry's ToolSpecs, default parameters unless the
//! trial says otherwise) and scored against their truth. Shared by the family
//! tests and bench/FamilyTrials.cpp, so the figures in docs/benchmarks.md are
//! those the tests assert.

#include "FacadeFamily.h"
#include "StoneWallFamily.h"

#include <scandiff/core/Drawing.h>
#include <scandiff/core/ToolRegistry.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace scandiff::test::family {

//! Every closed polyline of a drawing, its arcs as points (the rings the
//! scoring compares with the truth).
inline std::vector<wallsurvey::Ring3> closedRings(const Drawing& drawing, const std::string& layerPrefix = "")
{
    std::vector<wallsurvey::Ring3> rings;
    for (const DrawingPolyline& polyline : drawing.polylines)
        if (polyline.closed && polyline.layer.compare(0, layerPrefix.size(), layerPrefix) == 0)
            rings.push_back(polylineVertices(polyline, 2.0));
    return rings;
}

struct FacadeTrial
{
    facade::FacadeScore score;
    std::size_t points = 0;
    std::size_t rings = 0;
    std::size_t largestRingVertices = 0; //!< over the openings' matched rings
};

//! The façade workflow: planes by `segmentation` (the primitives tool), then
//! `contours --vectorise` on every plane.
inline FacadeTrial runFacade(const facade::FacadeScene& scene, const std::map<std::string, std::string>& primitiveOptions,
                             const std::map<std::string, std::string>& contourOptions)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& primitives = *registry.tools.find("primitives");
    ToolResult planes = primitives.execute(ToolInputs().add("input", scene.cloud), primitives.resolve(primitiveOptions), nullptr);
    const PointCloud& labelled = std::get<PointCloud>(planes.find("primitives")->data);
    const ToolSpec& contours = *registry.tools.find("contours");
    std::map<std::string, std::string> options = contourOptions;
    options.emplace("vectorise", "true");
    ToolResult outlines = contours.execute(ToolInputs().add("input", labelled), contours.resolve(options), nullptr);
    FacadeTrial trial;
    trial.points = scene.cloud.size();
    const std::vector<wallsurvey::Ring3> rings = closedRings(std::get<Drawing>(outlines.find("contours")->data));
    trial.rings = rings.size();
    trial.score = facade::score(scene, rings);
    for (const auto& opening : trial.score.openings)
        if (opening.ring >= 0 && !scene.params.openings.empty())
            trial.largestRingVertices = std::max(trial.largestRingVertices, opening.vertices);
    return trial;
}

struct StoneTrial
{
    stonewall::StoneWallScore score;
    std::size_t points = 0;
    std::size_t polygons = 0;
};

inline StoneTrial runStones(const stonewall::StoneWallScene& scene, const std::map<std::string, std::string>& options)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& stones = *registry.tools.find("stones");
    ToolResult result = stones.execute(ToolInputs().add("input", scene.cloud), stones.resolve(options), nullptr);
    const Drawing* drawing = nullptr;
    for (const ToolOutput& output : result.outputs)
        if (std::holds_alternative<Drawing>(output.data))
            drawing = &std::get<Drawing>(output.data);
    StoneTrial trial;
    trial.points = scene.cloud.size();
    const std::vector<wallsurvey::Ring3> rings = drawing ? closedRings(*drawing) : std::vector<wallsurvey::Ring3>{};
    trial.polygons = rings.size();
    trial.score = stonewall::scorePolygons(scene, rings);
    return trial;
}

} // namespace scandiff::test::family
