// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The terrain-change family run as `scandiff-cli c2c` then `scandiff-cli
//! segment` run it (the same parameter declarations and run functions),
//! scored against its truth. Shared by the family tests and
//! bench/FamilyTrials.cpp.

#include "TerrainChangeFamily.h"

#include <scandiff/core/distance/DistanceParameters.h>
#include <scandiff/core/segmentation/SegmentationParameters.h>

#include <map>
#include <string>

namespace scandiff::test::family {

struct ChangeTrial
{
    terrainchange::SegmentationScore score;
    std::string summary; //!< the segmentation's own line
    bool met = false;
};

//! C2C with `c2cOptions` (defaults otherwise), then the segmentation with
//! `segmentOptions` on its distance field.
inline ChangeTrial runChangeSegmentation(const terrainchange::TerrainChangeScene& scene,
                                         const std::map<std::string, std::string>& c2cOptions,
                                         std::map<std::string, std::string> segmentOptions)
{
    PointCloud compared = scene.compared.clone();
    CloudToCloudRun distances =
        runCloudToCloud(compared, scene.reference, resolveParameters(cloudToCloudParameters(), c2cOptions, "c2c"), nullptr);
    attachFields(compared, std::move(distances.forward));
    segmentOptions.emplace("field", "c2c_distance");
    const SegmentationRun run = runSegmentation(compared, resolveParameters(segmentationParameters(), segmentOptions, "segment"), nullptr);
    const ScalarField* region = nullptr;
    for (const ScalarField& f : run.fields)
        if (f.name() == "region_id")
            region = &f;
    std::vector<double> ids(compared.size(), 0.0);
    for (std::size_t i = 0; region && i < ids.size(); ++i)
        ids[i] = region->hasValue(i) ? region->value(i) : 0.0;
    ChangeTrial trial;
    trial.score = terrainchange::scoreSegmentation(scene, ids);
    trial.summary = run.summary;
    trial.met = terrainchange::meetsIssueTargets(trial.score);
    return trial;
}

} // namespace scandiff::test::family
