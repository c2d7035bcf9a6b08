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

} // namespace
} // namespace scandiff
