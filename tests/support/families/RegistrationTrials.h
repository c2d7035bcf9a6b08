// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The registration families run through the tools as the command line runs
//! them (the registry's ToolSpecs), scored against their truth: airborne
//! epochs with grown vegetation (`register --exclude-changes`). Shared by the
//! family tests and bench/FamilyTrials.cpp.

#include "AirborneEpochsFamily.h"

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

} // namespace scandiff::test::family
