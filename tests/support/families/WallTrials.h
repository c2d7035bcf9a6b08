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

#include <algorithm>
#include <cstdio>
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
    std::vector<wallsurvey::Ring3> rings; //!< every closed ring the contours gave
    facade::FacadeScore score;
    std::size_t points = 0;
    std::size_t largestRingVertices = 0; //!< over the openings' matched rings
    //! Rectangular windows (not arched, not doors) whose ring has other than 4 vertices.
    std::size_t rectanglesNotFourCorners = 0;
};

inline void countCorners(const facade::FacadeScene& scene, FacadeTrial& trial)
{
    for (std::size_t k = 0; k < trial.score.openings.size(); ++k) {
        const auto& o = scene.params.openings[k];
        const auto& s = trial.score.openings[k];
        if (s.ring >= 0)
            trial.largestRingVertices = std::max(trial.largestRingVertices, s.vertices);
        if (!o.arched && !o.door && s.ring >= 0 && s.vertices != 4)
            ++trial.rectanglesNotFourCorners;
    }
}

//! `contours --vectorise` with `options` on `cloud` (the scene's points, or
//! some of them, with or without a segment field), scored.
inline FacadeTrial outlineFacade(const facade::FacadeScene& scene, const PointCloud& cloud, std::map<std::string, std::string> options)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& contours = *registry.tools.find("contours");
    options.emplace("vectorise", "true");
    ToolResult outlines = contours.execute(ToolInputs().add("input", cloud), contours.resolve(options), nullptr);
    FacadeTrial trial;
    trial.points = cloud.size();
    trial.rings = closedRings(std::get<Drawing>(outlines.find("contours")->data));
    trial.score = facade::score(scene, trial.rings);
    countCorners(scene, trial);
    return trial;
}

//! The façade workflow: planes by `segmentation` (the primitives tool), then
//! `contours --vectorise` on every plane.
inline FacadeTrial runFacade(const facade::FacadeScene& scene, const std::map<std::string, std::string>& primitiveOptions,
                             const std::map<std::string, std::string>& contourOptions)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& primitives = *registry.tools.find("primitives");
    ToolResult planes = primitives.execute(ToolInputs().add("input", scene.cloud), primitives.resolve(primitiveOptions), nullptr);
    const PointCloud& labelled = std::get<PointCloud>(planes.find("primitives")->data);
    return outlineFacade(scene, labelled, contourOptions);
}

//! The wall's own points (its face and the relief on it), as a user who
//! segmented the façade well would give them to `contours --vectorise`: the
//! outlines and their vectorisation, apart from the segmentation.
inline FacadeTrial runFacadeContours(const facade::FacadeScene& scene, const std::map<std::string, std::string>& contourOptions)
{
    std::vector<std::size_t> wall;
    for (std::size_t i = 0; i < scene.surface.size(); ++i)
        if (scene.surface[i] == facade::Surface::WallFace || scene.surface[i] == facade::Surface::Relief)
            wall.push_back(i);
    return outlineFacade(scene, scene.cloud.subset(wall), contourOptions);
}

struct StoneTrial
{
    std::vector<wallsurvey::Ring3> rings;
    stonewall::StoneWallScore score;
    std::size_t points = 0;
    std::size_t polygons = 0;
    //! The tool's stone_class against the truth, per kind of point (face,
    //! arris, joint): how many of each it called stone.
    std::size_t truthParts[3] = {0, 0, 0}, calledStone[3] = {0, 0, 0}, calledParting[3] = {0, 0, 0}, calledJoint[3] = {0, 0, 0};
    std::string report; //!< the tool's summary
    std::vector<int> stoneOfPoint; //!< the tool's stone_id per point (-1: none)
    std::vector<int> jointOfPoint; //!< the tool's stone_joint per point
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
    trial.report = result.summary;
    trial.rings = drawing ? closedRings(*drawing) : std::vector<wallsurvey::Ring3>{};
    trial.polygons = trial.rings.size();
    trial.score = stonewall::scorePolygons(scene, trial.rings);
    if (const PointCloud* labelled = std::get_if<PointCloud>(&result.find("stones")->data))
        if (const ScalarField* stoneClass = labelled->field("stone_class")) {
            if (const ScalarField* id = labelled->field("stone_id"))
                for (std::size_t i = 0; i < labelled->size(); ++i)
                    trial.stoneOfPoint.push_back(static_cast<int>(id->value(i)));
            for (std::size_t i = 0; i < scene.part.size() && i < labelled->size(); ++i) {
                const auto part = static_cast<std::size_t>(scene.part[i]);
                ++trial.truthParts[part];
                trial.calledStone[part] += stoneClass->value(i) > 0.5;
                if (const ScalarField* joint = labelled->field("stone_joint")) {
                    trial.calledParting[part] += joint->value(i) == 1.0;
                    trial.calledJoint[part] += joint->value(i) == 2.0;
                    trial.jointOfPoint.push_back(static_cast<int>(joint->value(i)));
                }
            }
        }
    return trial;
}

//! An SVG of rings over the truth in a wall's frame (truth green, rings red,
//! the wall's points grey when given): to look at a trial that failed.
inline void writeWallSvg(const std::string& path, const wallsurvey::WallFrame& frame, const std::vector<wallsurvey::Polygon2>& truth,
                         const std::vector<wallsurvey::Ring3>& rings, const PointCloud* points = nullptr, double pixelsPerMetre = 100,
                         const std::vector<int>* pointLabels = nullptr)
{
    double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
    for (const auto& p : truth)
        for (const auto& q : p)
            x0 = std::min(x0, q.x()), y0 = std::min(y0, q.y()), x1 = std::max(x1, q.x()), y1 = std::max(y1, q.y());
    x0 -= 0.5, y0 -= 0.5, x1 += 0.5, y1 += 0.5;
    std::FILE* f = std::fopen(path.c_str(), "w");
    if (!f)
        return;
    const auto px = [&](double x) { return (x - x0) * pixelsPerMetre; };
    const auto py = [&](double y) { return (y1 - y) * pixelsPerMetre; };
    std::fprintf(f, "<svg xmlns='http://www.w3.org/2000/svg' width='%.0f' height='%.0f'><rect width='100%%' height='100%%' fill='white'/>\n",
                 px(x1), py(y0));
    if (points)
        for (std::size_t i = 0; i < points->size(); ++i) {
            const Eigen::Vector3d w = frame.toWall(points->globalPosition(i));
            static const char* palette[] = {"#e6194b", "#3cb44b", "#ffe119", "#4363d8", "#f58231", "#911eb4", "#46f0f0", "#f032e6"};
            const char* colour = !pointLabels ? "#bbb" : (*pointLabels)[i] < 0 ? "#000" : palette[(*pointLabels)[i] % 8];
            if (std::abs(w.z()) < 0.05 && w.x() > x0 && w.x() < x1 && w.y() > y0 && w.y() < y1)
                std::fprintf(f, "<circle cx='%.1f' cy='%.1f' r='0.6' fill='%s'/>\n", px(w.x()), py(w.y()), colour);
        }
    const auto path2 = [&](const wallsurvey::Polygon2& p, const char* colour, double width) {
        std::fprintf(f, "<polygon fill='none' stroke='%s' stroke-width='%.1f' points='", colour, width);
        for (const auto& q : p)
            std::fprintf(f, "%.1f,%.1f ", px(q.x()), py(q.y()));
        std::fprintf(f, "'/>\n");
    };
    for (const auto& p : truth)
        path2(p, "green", 1.5);
    for (const auto& r : rings) {
        wallsurvey::Polygon2 flat;
        for (const auto& q : r) {
            const Eigen::Vector3d w = frame.toWall(q);
            flat.emplace_back(w.x(), w.y());
        }
        path2(flat, "red", 0.8);
        for (const auto& q : flat)
            std::fprintf(f, "<circle cx='%.1f' cy='%.1f' r='1.5' fill='red'/>\n", px(q.x()), py(q.y()));
    }
    std::fprintf(f, "</svg>\n");
    std::fclose(f);
}

} // namespace scandiff::test::family
