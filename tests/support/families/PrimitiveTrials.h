// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The primitives family run through `scandiff-cli primitives` (the registry's
//! ToolSpec, default parameters unless given), scored against its truth.
//! Used by bench/FamilyTrials.cpp.

#include "PrimitivesFamily.h"

#include <scandiff/core/ToolRegistry.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <algorithm>
#include <map>
#include <string>

namespace scandiff::test::family {

struct PrimitivesTrial
{
    primitives::DetectionScore score;
    std::string report;
    std::vector<Primitive> detected;
    std::vector<int> assignment; //!< per point: detected shape, -1 none
    std::vector<double> rms;     //!< per detected shape, its fit's (m)
};

//! Per true shape, the detected shapes holding its points, largest first
//! (at most `most`): how a shape was split or shared. For diagnosis.
inline std::string spread(const primitives::PrimitivesScene& scene, const PrimitivesTrial& trial, std::size_t most = 6)
{
    std::string out;
    for (std::size_t t = 0; t < scene.shapes.size(); ++t) {
        std::map<int, std::size_t> counts;
        for (std::size_t i = 0; i < scene.labels.size(); ++i)
            if (scene.labels[i] == int(t))
                ++counts[trial.assignment[i]];
        std::vector<std::pair<std::size_t, int>> sorted;
        for (const auto& [d, n] : counts)
            sorted.emplace_back(n, d);
        std::sort(sorted.rbegin(), sorted.rend());
        out += scene.shapes[t].name + ":";
        for (std::size_t k = 0; k < sorted.size() && k < most; ++k)
            out += " #" + std::to_string(sorted[k].second) + "(" +
                   (sorted[k].second >= 0 ? primitives::DetectionScore::primitiveKindLabel(trial.detected[std::size_t(sorted[k].second)].kind) : "none") +
                   ") " + std::to_string(sorted[k].first);
        out += "\n";
    }
    // Each detected shape's make-up, by true shape (-1: clutter).
    std::map<int, std::map<int, std::size_t>> makeUp;
    for (std::size_t i = 0; i < scene.labels.size(); ++i)
        if (trial.assignment[i] >= 0)
            ++makeUp[trial.assignment[i]][scene.labels[i] >= 0 ? scene.labels[i] : -1 - int(scene.kinds[i])];
    for (const auto& [d, parts] : makeUp) {
        out += "#" + std::to_string(d) + " " + primitives::DetectionScore::primitiveKindLabel(trial.detected[std::size_t(d)].kind) +
               (std::size_t(d) < trial.rms.size() ? " rms " + std::to_string(trial.rms[std::size_t(d)]) : std::string()) + ":";
        for (const auto& [t, n] : parts)
            out += " " + (t >= 0 ? scene.shapes[std::size_t(t)].name : "clutter kind " + std::to_string(-1 - t)) + " " + std::to_string(n) + ";";
        out += "\n";
    }
    return out;
}

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
    // The shapes' parameters, from the tool's JSON document (ids are the labels' values).
    std::vector<double> rmsOf;
    if (const ToolOutput* document = result.find("document")) {
        const nlohmann::json json = nlohmann::json::parse(std::get<TextDocument>(document->data).text);
        const auto vector = [](const nlohmann::json& v) { return Eigen::Vector3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>()); };
        for (const nlohmann::json& shape : json.at("primitives")) {
            const auto k = shape.at("id").get<std::size_t>();
            if (k >= detected.size())
                continue;
            Primitive& p = detected[k];
            if (shape.contains("normal")) {
                p.direction = vector(shape["normal"]);
                p.point = vector(shape["point"]);
            }
            for (const char* key : {"center", "axis_point", "apex"})
                if (shape.contains(key))
                    p.point = vector(shape[key]);
            if (shape.contains("axis_direction"))
                p.direction = vector(shape["axis_direction"]);
            for (const char* key : {"radius", "major_radius"})
                if (shape.contains(key))
                    p.radius = shape[key].get<double>();
            if (shape.contains("minor_radius"))
                p.minorRadius = shape["minor_radius"].get<double>();
            if (rmsOf.size() <= k)
                rmsOf.resize(k + 1, 0.0);
            rmsOf[k] = shape.value("rms", 0.0);
            if (shape.contains("half_angle_deg"))
                p.halfAngle = shape["half_angle_deg"].get<double>() * 3.14159265358979323846 / 180.0;
        }
    }
    PrimitivesTrial trial;
    trial.score = primitives::score(scene, detected, assignment);
    trial.report = result.summary;
    trial.detected = std::move(detected);
    trial.assignment = std::move(assignment);
    trial.rms = std::move(rmsOf);
    return trial;
}

} // namespace scandiff::test::family
