// SPDX-License-Identifier: GPL-3.0-or-later
// C2C then the local chi-square test with its defaults (thesis 000 §3.2.3),
// on terrains built apart from the code (tests/support/families/
// TerrainChangeFamily.h): two independent samplings of one terrain, blocks
// raised or lowered, objects appeared or removed, slumps; spacing 5 mm-10 cm,
// noise 1-10 mm, the reference 0.5-2 times as dense, large coordinates. Every
// draw is asserted: at most 1 % of the unchanged points in a region, every
// change in a region of its own holding at least 95 % of its points.
#include "TestSupport.h"
#include "families/ChangeTrials.h"

#include <scandiff/io/FileIO.h>

#include <gtest/gtest.h>

namespace scandiff {
namespace {

using test::family::ChangeTrial;
using test::family::runChangeSegmentation;
namespace tc = test::family::terrainchange;

void expectMet(const ChangeTrial& t, const std::string& what)
{
    EXPECT_LE(t.score.unchangedFlaggedFraction, 0.01) << what << "\n" << t.summary << "\n" << tc::describe(t.score);
    for (const auto& c : t.score.changes) {
        EXPECT_GE(c.largestShare, 0.95) << what << ": change " << c.id << " " << c.label << "\n" << tc::describe(t.score);
        EXPECT_FALSE(c.merged) << what << ": change " << c.id << " " << c.label << "\n" << tc::describe(t.score);
    }
}

TEST(ChangeFamily, TheIssueTerrainWithDefaults)
{
    // 1 M points, a block raised 0.3 m and an appeared cylinder: before the
    // calibration, 28 % of the unchanged points were flagged and all merged.
    const tc::TerrainChangeScene scene = tc::make(tc::issueCase());
    for (const char* model : {"weibull", "gaussian"}) {
        const ChangeTrial t = runChangeSegmentation(scene, {}, {{"stat-test", model}, {"components", "true"}});
        expectMet(t, std::string("issue case, ") + model);
    }
    // A larger neighbourhood makes the test steadier, not wilder.
    const ChangeTrial wide = runChangeSegmentation(scene, {}, {{"stat-test", "weibull"}, {"components", "true"}, {"neighbours", "64"}});
    expectMet(wide, "issue case, 64 neighbours");
}

class ChangeDraws : public ::testing::TestWithParam<int>
{
};

TEST_P(ChangeDraws, EveryDrawMeetsTheTargetsWithDefaults)
{
    const tc::TerrainChangeParams params = tc::drawFamily(static_cast<std::uint64_t>(GetParam()), 0.1);
    const tc::TerrainChangeScene scene = tc::make(params);
    const ChangeTrial t = runChangeSegmentation(scene, {}, {{"stat-test", GetParam() % 4 == 0 ? "gaussian" : "weibull"}, {"components", "true"}});
    expectMet(t, tc::describe(params));
}

INSTANTIATE_TEST_SUITE_P(Seeds, ChangeDraws, ::testing::Range(1, 25));

TEST(ChangeFamily, TwoHalvesOfARealAirborneScanFlagAtMostOnePercent)
{
    // samp11 (ISPRS filter test, PCL's data): the points split at random into
    // two epochs of one unchanged site. Airborne sampling varies along and
    // across the strips, so neighbouring nearest-neighbour distances are far
    // from independent (lambda about 6): the tabulated cut flags most of the
    // site, the calibrated one at most 1 %.
    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    const PointCloud real = io::readPointCloud(formats, std::filesystem::path(SCANDIFF_SAMPLE_DATA_DIR) / "pcl-data" / "samp11-utm.pcd");
    std::vector<std::size_t> first, second;
    SplitMix64 random(11, 0);
    for (std::size_t i = 0; i < real.size(); ++i)
        (random.uniform() < 0.5 ? first : second).push_back(i);
    const PointCloud reference = real.subset(first);
    PointCloud compared = real.subset(second);
    CloudToCloudRun distances = runCloudToCloud(compared, reference, resolveParameters(cloudToCloudParameters(), {}, "c2c"), nullptr);
    attachFields(compared, std::move(distances.forward));
    for (const char* calibration : {"spatial", "tabulated"}) {
        const SegmentationRun run = runSegmentation(
            compared,
            resolveParameters(segmentationParameters(), {{"field", "c2c_distance"}, {"stat-test", "weibull"}, {"components", "true"},
                                                         {"neighbours", "64"}, {"calibration", calibration}},
                              "segment"),
            nullptr);
        std::size_t inRegions = 0;
        for (const ScalarField& f : run.fields)
            if (f.name() == "region_id")
                for (std::size_t i = 0; i < f.size(); ++i)
                    inRegions += f.hasValue(i);
        const double share = static_cast<double>(inRegions) / static_cast<double>(compared.size());
        if (std::string(calibration) == "spatial")
            EXPECT_LE(share, 0.01) << run.summary;
        else
            EXPECT_GE(share, 0.5) << run.summary; // the textbook cut on correlated distances
    }
}

} // namespace
} // namespace scandiff
