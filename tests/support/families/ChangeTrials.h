// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The distance families run as `scandiff-cli c2c` (then `scandiff-cli
//! segment`) run them, through the same parameter declarations and run
//! functions, scored against their truth: the terrain-change family and the
//! visibility at grazing incidence. Shared by the family tests and
//! bench/FamilyTrials.cpp.

#include "GrazingVisibilityFamily.h"
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

//! C2C with the visibility test from the reference's stored scanner pose
//! (`--visibility`), `options` on top; the visibility labels scored.
inline grazing::VisibilityScore runVisibility(const grazing::GrazingScene& scene, std::map<std::string, std::string> options)
{
    options.emplace("visibility", "true");
    CloudToCloudRun run =
        runCloudToCloud(scene.compared, scene.reference, resolveParameters(cloudToCloudParameters(), options, "c2c"), nullptr);
    const std::vector<float> labels = run.forward.visibility ? run.forward.visibility->values() : std::vector<float>{};
    return grazing::scoreLabels(scene, labels);
}

} // namespace scandiff::test::family
