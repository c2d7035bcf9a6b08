// SPDX-License-Identifier: GPL-3.0-or-later
// The multi-station adjustment (`register-stations`, start any) on a hall
// built apart from the code (tests/support/families/StationsFamily.h): four
// levelled stations in headings 0, 35, 120 and 250 deg, two on each side of
// a 0.2 m partition with a door, racks and machines, 2 mm range noise, each
// in its own scanner frame as a scanner writes it.
#include "TestSupport.h"
#include "families/RegistrationTrials.h"

#include <gtest/gtest.h>

namespace scandiff {
namespace {

namespace st = test::family::stations;

std::string describeErrors(const std::vector<st::PoseError>& errors)
{
    std::string text;
    for (const st::PoseError& e : errors)
        text += std::to_string(e.rotationDeg) + " deg / " + std::to_string(1000 * e.maxDisplacement) + " mm; ";
    return text;
}

TEST(StationsFamily, TheIssueHallComesTogetherInAnyHeading)
{
    // Before: poses off by 43, 90 and 117 deg; then every station but the
    // first turned by the hall's half turn; then the two across the
    // partition slid by its thickness. Target: 0.005 deg and 2 mm.
    const st::StationsScene scene = st::make(st::issueCase());
    const test::family::StationsTrial t = test::family::runStations(scene, {});
    EXPECT_TRUE(st::withinTolerance(t.errors, scene.clouds.size())) << describeErrors(t.errors) << "\n" << t.report;
}

// Two draws of the family at the issue's density (scale 0.3: 250-300 k
// points a station, 7.5 cm between points at 10 m): draw 2 (three stations in
// headings 101, 255 and 231 deg in a 68 x 16 m hall) from the draws the
// search was mended on, draw 11 (four stations) from the held-out ones, run
// for the first time after the change. The other draws and their figures:
// `scandiff-family-trials stations --draws 16 --scale 0.3`, docs/benchmarks.md.
class StationsFamilyDraw : public ::testing::TestWithParam<int>
{
};

TEST_P(StationsFamilyDraw, EveryStationWithinTheIssuesTolerance)
{
    const st::StationsScene scene = st::make(st::drawFamily(static_cast<std::uint64_t>(GetParam()), 0.3));
    const test::family::StationsTrial t = test::family::runStations(scene, {});
    EXPECT_TRUE(st::withinTolerance(t.errors, scene.clouds.size())) << st::describe(scene.params) << "\n"
                                                                     << describeErrors(t.errors) << "\n"
                                                                     << t.report;
}

INSTANTIATE_TEST_SUITE_P(IssueDensity, StationsFamilyDraw, ::testing::Values(2, 11));

} // namespace
} // namespace scandiff
