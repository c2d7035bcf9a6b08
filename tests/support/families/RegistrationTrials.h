// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The registration families run through the tools as the command line runs
//! them (the registry's ToolSpecs), scored against their truth: airborne
//! epochs with grown vegetation (`register --exclude-changes`) and the
//! stations of a hall in any heading (`register-stations`). Shared by the
//! family tests and bench/FamilyTrials.cpp.

#include "AirborneEpochsFamily.h"
#include "StationsFamily.h"

#include <scandiff/core/ToolRegistry.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <map>
#include <string>

namespace scandiff::test::family {

struct AirborneTrial
{
    airborne::AlignmentError error;
    Eigen::Matrix4d matrix = Eigen::Matrix4d::Identity(); //!< later -> earlier, global
    std::string report;                                   //!< the tool's summary line
};

//! `register --reference EARLIER --moving LATER --exclude-changes` and `options`.
inline AirborneTrial runAirborneRegistration(const airborne::AirborneEpochsScene& scene, std::map<std::string, std::string> options)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("register");
    options.emplace("exclude-changes", "true");
    ToolResult result =
        tool.execute(ToolInputs().add("reference", scene.earlier).add("moving", scene.later), tool.resolve(options), nullptr);
    AirborneTrial trial;
    trial.matrix = result.transform("matrix");
    trial.report = result.summary;
    trial.error = airborne::scoreAlignment(scene.later, scene.laterKind, trial.matrix, scene.trueLaterToEarlier);
    return trial;
}

struct StationsTrial
{
    std::vector<stations::PoseError> errors;
    std::vector<Eigen::Matrix4d> poses; //!< station -> station 0, as the tool gave them
    std::string report;
    Table pairs;
};

//! `register-stations S0 S1 ...` with `options`.
inline StationsTrial runStations(const stations::StationsScene& scene, const std::map<std::string, std::string>& options)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("register-stations");
    ToolInputs inputs;
    for (const PointCloud& cloud : scene.clouds)
        inputs.add("input", cloud);
    ToolResult result = tool.execute(inputs, tool.resolve(options), nullptr);
    StationsTrial trial;
    const Table& poses = std::get<Table>(result.find("poses")->data);
    for (const auto& row : poses.rows) {
        Eigen::Matrix4d m;
        for (int k = 0; k < 16; ++k)
            m(k / 4, k % 4) = std::get<double>(row[static_cast<std::size_t>(k)]);
        trial.poses.push_back(m);
    }
    trial.errors = stations::scorePoses(scene, trial.poses);
    trial.report = result.summary;
    trial.pairs = std::get<Table>(result.find("pairs")->data);
    return trial;
}

} // namespace scandiff::test::family
