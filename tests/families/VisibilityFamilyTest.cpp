// SPDX-License-Identifier: GPL-3.0-or-later
// The visibility test of C2C (thesis 000 §2.3.3) at grazing incidence, on
// scenes built apart from the code (tests/support/families/
// GrazingVisibilityFamily.h): a tripod scan of open ground with a wall, the
// compared epoch the same ground and wall sampled independently plus a cube
// in the wall's shadow. Tripod 1.4-2 m, steps 0.03-0.2 deg, range 20-60 m,
// walls 1.5-4 m high, ground sloping up to 5 deg, noise 1-10 mm, large
// coordinates. Every draw asserted: at least 97 % of the compared points get
// the label the geometry gives, at most 3 % of the visible ones are called
// hidden, the cube stays hidden.
#include "TestSupport.h"
#include "families/ChangeTrials.h"

#include <gtest/gtest.h>

namespace scandiff {
namespace {

namespace gz = test::family::grazing;

void expectMet(const gz::VisibilityScore& s, const std::string& what)
{
    EXPECT_GE(s.agreement, 0.97) << what;
    EXPECT_LE(s.visibleLabelledHidden, 0.03) << what;
    EXPECT_LE(s.cubeLabelledVisible, 0.01) << what;
}

TEST(VisibilityFamily, TheIssueScanAtTheThesisOutdoorTolerance)
{
    // 2.1 M reference points, a full turn at 0.1 deg to 40 m, the map's step
    // the scan's: before, 86 % agreement and 24 % of the visible ground
    // hidden at 0.1 m, 49 % with this step.
    const gz::GrazingScene scene = gz::make(gz::issueCase());
    for (const char* tolerance : {"0.1", "0.05"})
        expectMet(test::family::runVisibility(scene, {{"visibility-tolerance", tolerance}}), std::string("tolerance ") + tolerance);
}

class VisibilityDraws : public ::testing::TestWithParam<int>
{
};

TEST_P(VisibilityDraws, EveryDrawMeetsTheTargetsWithDefaults)
{
    gz::GrazingScene scene = gz::make(gz::drawFamily(static_cast<std::uint64_t>(GetParam()), 0.1));
    const std::string what = gz::describe(scene.params);
    expectMet(test::family::runVisibility(scene, {}), what);
    // Without the scanner's steps: the map's step from the reference's density.
    scene.reference.sensors()[0].yawStep = scene.reference.sensors()[0].pitchStep = 0;
    expectMet(test::family::runVisibility(scene, {}), what + ", steps from the data");
}

INSTANTIATE_TEST_SUITE_P(Seeds, VisibilityDraws, ::testing::Range(1, 25));

} // namespace
} // namespace scandiff
