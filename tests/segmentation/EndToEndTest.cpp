// SPDX-License-Identifier: GPL-3.0-or-later
// The whole change-detection chain on a synthetic pair with three known
// changes (SyntheticScene.h): distances, classification, connected
// components, region report and export, the DXF checked by ezdxf.

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToCloud.h>
#include <scandiff/core/segmentation/Classification.h>
#include <scandiff/core/segmentation/ConnectedComponents.h>
#include <scandiff/core/segmentation/FastMarching.h>
#include <scandiff/core/segmentation/RegionReport.h>
#include <scandiff/core/segmentation/SegmentationParameters.h>
#include <scandiff/core/segmentation/StatisticalTest.h>
#include <scandiff/io/FileIO.h>
#include <scandiff/io/RegionExport.h>

#include "DxfCheck.h"
#include "StageWatcher.h"
#include "SyntheticScene.h"
#include "TestSupport.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>

using namespace scandiff;
using test::checkDxf;
using test::DxfCheck;

namespace {

//! The compared epoch with its distances to the reference (plane model: no
//! sampling bias), computed once for the whole suite.
const PointCloud& comparedWithDistances()
{
    static const PointCloud cloud = [] {
        PointCloud reference = test::referenceEpoch();
        PointCloud compared = test::comparedEpoch();
        CloudToCloudParams params;
        params.model = LocalModel::Plane;
        attachFields(compared, cloudToCloud(compared, reference, params));
        return compared;
    }();
    return cloud;
}

//! Horizontal distance from (x, y) to the footprint of change 1, 2 or 3.
double distanceToChange(int change, double x, double y)
{
    const test::Box2& b = change == 1 ? test::kRaisedBlock : change == 2 ? test::kPit : test::kObject;
    return std::hypot(std::max({b.x0 - x, 0.0, x - b.x1}), std::max({b.y0 - y, 0.0, y - b.y1}));
}

//! Checks the issue's criterion: every change is one region holding >= 95 % of
//! its clearly changed points (true distance above 15 cm), and no other
//! region. Unchanged points of a region count against it unless they lie
//! within `fringe` of the change (propagation keeps the ground the gradient
//! estimate reaches: its radius plus a cell).
//! A point is clearly changed when its true distance exceeds `clearAbove`.
void expectThreeChangesFound(const PointCloud& cloud, const ScalarField& regionId, std::size_t regionCount, double fringe = 0.0,
                             double clearAbove = 0.15)
{
    ASSERT_EQ(regionCount, 3u);
    const ScalarField& truth = *cloud.field("truth");
    // Majority change of each region (the fringe votes for its change).
    std::map<int, std::map<int, std::size_t>> votes;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!regionId.hasValue(i))
            continue;
        int change = static_cast<int>(truth.value(i));
        if (change == 0 && fringe > 0)
            for (int c = 1; c <= 3; ++c)
                if (distanceToChange(c, cloud.positions()[i].x(), cloud.positions()[i].y()) <= fringe)
                    change = c;
        ++votes[static_cast<int>(regionId.value(i))][change];
    }
    std::map<int, int> regionOfChange;
    for (const auto& [region, counts] : votes) {
        int best = -1;
        std::size_t bestCount = 0, total = 0;
        for (const auto& [change, count] : counts) {
            total += count;
            if (count > bestCount) {
                bestCount = count;
                best = change;
            }
        }
        EXPECT_NE(best, 0) << "region " << region << " is mostly unchanged ground";
        EXPECT_GE(static_cast<double>(bestCount), 0.95 * total) << "region " << region;
        EXPECT_EQ(regionOfChange.count(best), 0u) << "change " << best << " split into two regions";
        regionOfChange[best] = region;
    }
    for (int change = 1; change <= 3; ++change) {
        ASSERT_EQ(regionOfChange.count(change), 1u) << "change " << change << " not found";
        std::size_t clear = 0, found = 0;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (static_cast<int>(truth.value(i)) != change)
                continue;
            const double z = cloud.positions()[i].z();
            if (std::abs(z) < clearAbove)
                continue; // its true distance to the ground is below the cut
            ++clear;
            found += regionId.hasValue(i) && static_cast<int>(regionId.value(i)) == regionOfChange[change];
        }
        EXPECT_GE(static_cast<double>(found), 0.95 * clear) << "change " << change;
    }
}

} // namespace

TEST(EndToEnd, ThresholdAndComponentsFindTheThreeChanges)
{
    const PointCloud& cloud = comparedWithDistances();
    const ScalarField changed = classifyByRange(*cloud.field("c2c_distance"), 0.1, std::numeric_limits<double>::infinity());
    ConnectedComponentsParams params;
    params.minPoints = 50;
    const ConnectedComponentsResult r = connectedComponents(cloud, selectionFromLabels(changed), params);
    expectThreeChangesFound(cloud, r.regionId, r.regionCount);
}

TEST(EndToEnd, ChiSquareTestAndComponentsFindTheThreeChanges)
{
    const PointCloud& cloud = comparedWithDistances();
    const ScalarField& distance = *cloud.field("c2c_distance");
    // The noise model from a corner the user knows to be unchanged.
    std::vector<std::size_t> quiet;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (cloud.positions()[i].x() > 16 && cloud.positions()[i].y() > 10)
            quiet.push_back(i);
    LocalChiSquareParams params;
    params.model = NoiseModel::Weibull;
    params.noise = fitNoise(distance, NoiseModel::Weibull, &quiet);
    params.confidence = 0.999;
    const LocalChiSquareResult test = localChiSquareTest(cloud, "c2c_distance", params);
    ConnectedComponentsParams cc;
    cc.minPoints = 50;
    const ConnectedComponentsResult r = connectedComponents(cloud, selectionFromLabels(test.changed), cc);
    expectThreeChangesFound(cloud, r.regionId, r.regionCount);
}

TEST(EndToEnd, KMeansFindsTheChangesOfLargeAmplitude)
{
    const PointCloud& cloud = comparedWithDistances();
    const KMeansResult k = kMeans(*cloud.field("c2c_distance"));
    ConnectedComponentsParams cc;
    cc.minPoints = 50;
    const ConnectedComponentsResult r = connectedComponents(cloud, selectionFromLabels(k.changed), cc);
    // The same criterion as the other methods: each change one region with
    // >= 95 % of its clearly changed points, and no other region; "clearly"
    // is above K-means' own cut (with 5 mm of noise, 3 sigma above it).
    ASSERT_EQ(k.thresholds.size(), 1u);
    EXPECT_GT(k.thresholds.front(), 0.1);
    EXPECT_LT(k.thresholds.front(), 0.35);
    expectThreeChangesFound(cloud, r.regionId, r.regionCount, 0.0, k.thresholds.front() + 0.015);
}

TEST(EndToEnd, PropagationFindsTheThreeChanges)
{
    const PointCloud& cloud = comparedWithDistances();
    PropagationParams params;
    params.minSeedValue = 0.15;
    params.minPoints = 50;
    const PropagationResult r = propagationSegmentation(cloud, "c2c_distance", params);
    GradientParams automatic;
    const double radius = gradientNorm(cloud, "c2c_distance", automatic).radius;
    expectThreeChangesFound(cloud, r.regionId, r.regionCount, radius + r.cellSize);
}

TEST(EndToEnd, ReportAndExportOfTheRegions)
{
    PointCloud cloud = comparedWithDistances().clone();
    const ScalarField changed = classifyByRange(*cloud.field("c2c_distance"), 0.1, std::numeric_limits<double>::infinity());
    ConnectedComponentsParams cc;
    cc.minPoints = 50;
    ConnectedComponentsResult components = connectedComponents(cloud, selectionFromLabels(changed), cc);
    cloud.addField(std::move(components.regionId));
    const PointCloud reference = test::referenceEpoch();
    RegionReportParams params;
    params.distanceField = "c2c_distance";
    params.reference = &reference;
    const std::vector<RegionStatistics> report = regionReport(cloud, params);
    ASSERT_EQ(report.size(), 3u);
    std::map<int, const RegionStatistics*> byChange; // by where the centroid lies
    for (const auto& r : report) {
        const double x = r.centroid.x(), y = r.centroid.y();
        const int change = test::kRaisedBlock.contains(x, y) ? 1 : test::kPit.contains(x, y) ? 2 : test::kObject.contains(x, y) ? 3 : 0;
        byChange[change] = &r;
    }
    ASSERT_EQ(byChange.count(1) + byChange.count(2) + byChange.count(3), 3u);
    const RegionStatistics& block = *byChange[1];
    // 3 m x 3 m raised by 0.5 m: 4.5 m^3; the pit: 3 x 3 x 0.4 = 3.6 m^3 removed.
    ASSERT_TRUE(block.volume.has_value());
    EXPECT_NEAR(*block.volume, 4.5, 0.45);
    EXPECT_NEAR(*byChange[2]->volume, -3.6, 0.36);
    EXPECT_NEAR(block.footprintArea, 9.0, 1.5);
    EXPECT_NEAR(block.maxDistance, 0.5, 0.03);
    EXPECT_NEAR(block.centroid.x(), 4.5, 0.1);
    EXPECT_NEAR(byChange[3]->maxDistance, 1.0, 0.05);

    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    const auto dir = test::tempDir() / "out";
    io::RegionExportOptions options;
    options.dxf.includePoints = true;
    const io::RegionExportFiles files = io::exportRegions(formats, cloud, report, dir, options);
    ASSERT_EQ(files.regionClouds.size(), 3u);
    EXPECT_EQ(files.regionClouds[0].filename(), "region_0001.ply");
    const PointCloud all = io::readPointCloud(formats, files.allRegions);
    std::size_t total = 0;
    for (const auto& r : report)
        total += r.pointCount;
    EXPECT_EQ(all.size(), total);
    ASSERT_NE(all.field("region_id"), nullptr);
    ASSERT_NE(all.field("c2c_distance"), nullptr);
    ASSERT_NE(all.field("truth"), nullptr);
    const PointCloud first = io::readPointCloud(formats, files.regionClouds[0]);
    EXPECT_EQ(first.size(), report[0].pointCount);
    EXPECT_EQ(first.field("region_id")->range().min, 1.0);
    EXPECT_EQ(first.field("region_id")->range().max, 1.0);

    // CSV: a header and one line per region.
    std::ifstream csv(files.csv);
    std::string line;
    std::vector<std::string> lines;
    while (std::getline(csv, line))
        lines.push_back(line);
    ASSERT_EQ(lines.size(), 4u);
    EXPECT_EQ(lines[0].rfind("id,points,min_x", 0), 0u);
    EXPECT_EQ(lines[1].rfind("1," + std::to_string(report[0].pointCount) + ",", 0), 0u);

    const DxfCheck check = checkDxf(files.dxf);
    ASSERT_EQ(check.exitStatus, 0) << "ezdxf rejected " << files.dxf;
    for (const auto& r : report) {
        const std::string layer = io::regionLayerName(r.id);
        EXPECT_EQ(check.count("POLYLINE@" + layer), static_cast<int>(r.outlines.size())) << layer;
        EXPECT_EQ(check.count("TEXT@" + layer), 1) << layer;
        EXPECT_EQ(check.count("POINT@" + layer), static_cast<int>(r.pointCount)) << layer;
    }
}

TEST(EndToEnd, ExportWithNoRegionAndBadInput)
{
    PointCloud cloud;
    cloud.resize(3);
    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    const auto dir = test::tempDir();
    EXPECT_EQ(test::errorCodeOf([&] { io::exportRegions(formats, cloud, {}, dir); }), ErrorCode::InvalidArgument);
    cloud.addField("region_id");
    const io::RegionExportFiles files = io::exportRegions(formats, cloud, {}, dir / "empty");
    EXPECT_TRUE(files.regionClouds.empty());
    EXPECT_EQ(checkDxf(files.dxf).exitStatus, 0);
    io::RegionExportOptions options;
    options.cloudExtension = "nope";
    EXPECT_EQ(test::errorCodeOf([&] { io::exportRegions(formats, cloud, {}, dir / "x", options); }), ErrorCode::Unsupported);
}

namespace {

//! Every file under `dir` with its content.
std::map<std::string, std::string> folderContents(const std::filesystem::path& dir)
{
    std::map<std::string, std::string> contents;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
        std::ifstream in(entry.path(), std::ios::binary);
        contents[std::filesystem::relative(entry.path(), dir).string()] =
            entry.is_regular_file() ? std::string(std::istreambuf_iterator<char>(in), {}) : std::string("<folder>");
    }
    return contents;
}

//! Runs `task` once to count its polls, then with Cancel pressed at the first,
//! a third, two thirds and the last: each must end in Error(Cancelled), and
//! `unchanged()` must hold after each.
template <class Task, class Check>
void cancelAtEveryStage(const std::string& what, Task task, Check unchanged)
{
    test::PollCounter counting;
    ASSERT_NO_THROW(task(&counting)) << what;
    const std::size_t polls = counting.polls();
    ASSERT_GE(polls, 3u) << what << " is polled " << polls << " times";
    for (const std::size_t at : {std::size_t(1), polls / 3, 2 * polls / 3, polls}) {
        test::PollCounter cancel(std::max<std::size_t>(at, 1));
        EXPECT_EQ(test::errorCodeOf([&] { task(&cancel); }), ErrorCode::Cancelled)
            << what << ", Cancel at poll " << at << " of " << polls;
        unchanged();
    }
}

} // namespace

TEST(EndToEnd, CancelAtAnyStageLeavesTheCloudAndTheExportFolderAsTheyWere)
{
    // Segmentation, region report and export on the 3-change scene, each
    // cancelled at several polls: the cloud is unchanged and the export
    // folder holds exactly the previous export's files, byte for byte.
    PointCloud cloud = comparedWithDistances().clone();
    const PointCloud before = cloud.clone();
    auto cloudUnchanged = [&] {
        ASSERT_EQ(cloud.positions(), before.positions());
        ASSERT_EQ(cloud.fields().size(), before.fields().size());
        for (std::size_t f = 0; f < cloud.fields().size(); ++f)
            ASSERT_EQ(cloud.fields()[f].values(), before.fields()[f].values()) << cloud.fields()[f].name();
    };
    for (const std::map<std::string, std::string>& text :
         {std::map<std::string, std::string>{{"field", "c2c_distance"}, {"above", "0.1"}, {"components", "true"}},
          std::map<std::string, std::string>{{"field", "c2c_distance"}, {"stat-test", "gaussian"}, {"components", "true"}},
          std::map<std::string, std::string>{{"field", "c2c_distance"}, {"propagate", "true"}, {"min-seed", "0.15"}}}) {
        const ParameterValues values = resolveParameters(segmentationParameters(), text, "segment");
        cancelAtEveryStage(
            "segmentation " + text.rbegin()->first, [&](ProgressObserver* p) { runSegmentation(cloud, values, p); },
            cloudUnchanged);
    }

    const ParameterValues values =
        resolveParameters(segmentationParameters(), {{"field", "c2c_distance"}, {"above", "0.1"}, {"components", "true"}}, "segment");
    PointCloud segmented = cloud.clone();
    attachFields(segmented, runSegmentation(segmented, values));
    const PointCloud reference = test::referenceEpoch();
    RegionReportParams params = regionReportSettings(values, &reference);
    cancelAtEveryStage(
        "region report", [&](ProgressObserver* p) { regionReport(segmented, params, p); }, [] {});
    const std::vector<RegionStatistics> report = regionReport(segmented, params);
    ASSERT_EQ(report.size(), 3u);

    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    const auto dir = test::tempDir() / "export";
    // A previous export of the first region only, then one of all three,
    // cancelled: the first stays, whole.
    io::exportRegions(formats, segmented, {report.front()}, dir);
    const std::map<std::string, std::string> previous = folderContents(dir);
    ASSERT_EQ(previous.size(), 4u);
    io::RegionExportOptions options;
    bool counting = true; // the counting run goes elsewhere: it completes
    cancelAtEveryStage(
        "region export",
        [&](ProgressObserver* p) {
            options.write.progress = p;
            io::exportRegions(formats, segmented, report, counting ? dir.parent_path() / "counting" : dir, options);
            counting = false;
        },
        [&] { EXPECT_EQ(folderContents(dir), previous); });
}
