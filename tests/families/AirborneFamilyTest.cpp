// SPDX-License-Identifier: GPL-3.0-or-later
// Change-robust ICP (`register --exclude-changes`) on airborne epochs whose
// vegetation grew, built apart from the code (tests/support/families/
// AirborneEpochsFamily.h, AirborneRealPair.h): 0.4-10 pulses/m², vegetation
// 20-70 % of the points, growth 0.2-3 m, 0-5 cm of survey disagreement, flat
// or hilly terrain, a known motion of 0-2 m and 0-2 deg, UTM coordinates,
// with or without ASPRS classes; and pairs made from the real ISPRS samples
// samp11 and samp53 (data/pcl-data), grown and moved by 1 m and 0.5 deg.
#include "TestSupport.h"
#include "families/RegistrationTrials.h"

#include <scandiff/io/FileIO.h>

#include <gtest/gtest.h>

namespace scandiff {
namespace {

namespace ab = test::family::airborne;

TEST(AirborneFamily, TheIssueParkStaysWhereItsGroundIsAndHoldsTheFreeDirections)
{
    // 250 m of flat park, half the points vegetation that grew 1 m: the ICP
    // lowered the later epoch by 0.53 m onto the canopy (CloudCompare: 1 m).
    const ab::AirborneEpochsScene scene = ab::make(ab::issueCase());
    const test::family::AirborneTrial t = test::family::runAirborneRegistration(scene, {});
    EXPECT_TRUE(ab::meetsParkTarget(t.error)) << ab::describe(t.error) << "\n" << t.report;
    // Flat ground holds neither the horizontal translations nor the turn
    // about the vertical: the epoch does not move that way, and says so.
    EXPECT_LE(t.error.maxHorizontalGround, 0.05) << ab::describe(t.error);
    EXPECT_NE(t.report.find("degenerate geometry"), std::string::npos) << t.report;
    EXPECT_NE(t.report.find("held fixed"), std::string::npos) << t.report;
}

class AirborneDraws : public ::testing::TestWithParam<int>
{
};

TEST_P(AirborneDraws, TheLaterEpochComesBackOnItsGround)
{
    const ab::AirborneEpochsParams params = ab::drawFamily(static_cast<std::uint64_t>(GetParam()), 0.3);
    const ab::AirborneEpochsScene scene = ab::make(params);
    const test::family::AirborneTrial t = test::family::runAirborneRegistration(scene, {});
    EXPECT_TRUE(ab::meetsParkTarget(t.error)) << scene.description << "\n" << ab::describe(t.error) << "\n" << t.report;
    // On flat terrain the draws move the epoch only up and by a tilt: the
    // horizontal is free, and held (within 12 cm at the edges of sites of
    // 60-300 m, asserted 15 cm).
    if (params.motionTranslation.head<2>().norm() == 0) {
        EXPECT_LE(t.error.maxHorizontalGround, 0.15) << scene.description << "\n" << ab::describe(t.error);
    }
}

INSTANTIATE_TEST_SUITE_P(Seeds, AirborneDraws, ::testing::Range(1, 25));

struct RealSample
{
    PointCloud all, ground;
};

RealSample readSample(const std::string& name)
{
    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    const std::filesystem::path dir = std::filesystem::path(SCANDIFF_SAMPLE_DATA_DIR) / "pcl-data";
    return {io::readPointCloud(formats, dir / (name + ".pcd")), io::readPointCloud(formats, dir / (name + "-ground.pcd"))};
}

TEST(AirborneFamily, RealPairsMovedByOneMetreAndHalfADegreeComeBack)
{
    // samp53 (mostly ground): every ground point back within 5 cm.
    const RealSample s53 = readSample("samp53-utm");
    const ab::AirborneEpochsScene pair53 = ab::makeRealPair(s53.all, s53.ground, ab::realIssueCase());
    const test::family::AirborneTrial t53 = test::family::runAirborneRegistration(pair53, {});
    EXPECT_TRUE(ab::meetsRealPairTarget(t53.error)) << ab::describe(t53.error) << "\n" << t53.report;
    // samp11 (a steep site with buildings and trees, every object grown
    // 0.3-1.5 m): with the file's classes, within 5 cm; from the geometry
    // alone the grown roofs still pull it (median 8.8 cm, p90 15 cm: the
    // median asserted within 10 cm), unless the ICP registers on the ground
    // it filters and uses the roofs for the horizontal only (--stable
    // ground): within 5 cm (4.6 cm measured).
    const RealSample s11 = readSample("samp11-utm");
    ab::RealPairParams classed = ab::realIssueCase();
    classed.withClassification = true;
    const test::family::AirborneTrial withClasses =
        test::family::runAirborneRegistration(ab::makeRealPair(s11.all, s11.ground, classed), {});
    EXPECT_TRUE(ab::meetsRealPairTarget(withClasses.error)) << ab::describe(withClasses.error) << "\n" << withClasses.report;
    const ab::AirborneEpochsScene pair11 = ab::makeRealPair(s11.all, s11.ground, ab::realIssueCase());
    const test::family::AirborneTrial t11 = test::family::runAirborneRegistration(pair11, {});
    EXPECT_LE(t11.error.medianAbsDz, 0.10) << ab::describe(t11.error) << "\n" << t11.report;
    const test::family::AirborneTrial onGround = test::family::runAirborneRegistration(pair11, {{"stable", "ground"}});
    EXPECT_TRUE(ab::meetsRealPairTarget(onGround.error)) << ab::describe(onGround.error) << "\n" << onGround.report;
    EXPECT_NE(onGround.report.find("on the ground (morphological filter)"), std::string::npos) << onGround.report;
}

// Windows of half the real samples, classed, moved by 0-2 m and 0-2 deg, with
// grown vegetation and a survey disagreement. The ground is rough where it is
// steep (returns 1 m apart): before the change-robust threshold widened
// there (tolerancesOf in Icp.cpp), it kept only the smooth ground and these
// came back 6-19 cm off horizontally; every ground point now within 5 cm.
TEST(AirborneFamily, ClassedRealDrawsComeBackOnSteepGroundToo)
{
    const RealSample s11 = readSample("samp11-utm");
    const RealSample s53 = readSample("samp53-utm");
    const struct { const RealSample* sample; std::uint64_t seed; } draws[] = {{&s11, 1}, {&s11, 3}, {&s11, 6}, {&s53, 2}};
    for (const auto& draw : draws) {
        const ab::RealPairParams p = ab::drawRealPair(draw.seed, 0.5);
        ASSERT_TRUE(p.withClassification) << ab::describe(p);
        const test::family::AirborneTrial t =
            test::family::runAirborneRegistration(ab::makeRealPair(draw.sample->all, draw.sample->ground, p), {});
        EXPECT_TRUE(ab::meetsRealPairTarget(t.error)) << ab::describe(p) << "\n" << ab::describe(t.error) << "\n" << t.report;
    }
}

} // namespace
} // namespace scandiff
