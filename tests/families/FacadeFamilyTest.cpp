// SPDX-License-Identifier: GPL-3.0-or-later
// `contours --vectorise` on façades built apart from the code (tests/support/
// families/FacadeFamily.h): a wall scanned from one station, windows and
// doors (some arched), relief on the face, glass and rooms behind; spacing
// 5 mm-3 cm, noise 1-10 mm, any heading, a lean up to 2 deg, large
// coordinates. The tool gets the wall's own points (its face and relief), as
// a segmentation gives them. Every draw asserted: every opening one closed
// polygon within 3 cm (symmetric Hausdorff) of the truth (a door as the
// outline's notch), at most two false polygons; and rectangular windows as
// four corners in all but a few.
#include "TestSupport.h"
#include "families/WallTrials.h"

#include <gtest/gtest.h>

namespace scandiff {
namespace {

namespace fa = test::family::facade;

void expectMet(const test::family::FacadeTrial& t, const std::string& what)
{
    EXPECT_TRUE(t.score.meetsIssueTarget) << what << "\n" << t.score.summary();
    for (std::size_t k = 0; k < t.score.openings.size(); ++k) {
        const auto& s = t.score.openings[k];
        EXPECT_TRUE(s.right) << what << ": opening " << k << " IoU " << s.iou << " Hausdorff " << s.hausdorff << " m, " << s.vertices
                             << " vertices, " << s.ringsMatching << " rings";
    }
}

TEST(FacadeFamily, TheIssueWallAt26MillimetresIsDrawnRectangleByRectangle)
{
    // 20 x 10 m, 18 windows of 1.5 m, 2.6 cm spacing, 5 mm noise, sills and
    // string courses 2 cm proud: before, 15-32 vertices and spikes of 4-11 cm.
    const fa::FacadeScene scene = fa::make(fa::issueCase());
    const test::family::FacadeTrial t = test::family::runFacadeContours(scene, {});
    expectMet(t, "issue case");
    EXPECT_EQ(t.largestRingVertices, 4u);
    EXPECT_EQ(t.score.falsePolygons, 0);
}

class FacadeDraws : public ::testing::TestWithParam<int>
{
};

TEST_P(FacadeDraws, EveryOpeningWithin3cm)
{
    const fa::FacadeParams params = fa::drawFamily(static_cast<std::uint64_t>(GetParam()), 0.15);
    const fa::FacadeScene scene = fa::make(params);
    const test::family::FacadeTrial t = test::family::runFacadeContours(scene, {});
    expectMet(t, fa::describe(params));
    EXPECT_LE(t.rectanglesNotFourCorners, 1u) << fa::describe(params);
}

INSTANTIATE_TEST_SUITE_P(Seeds, FacadeDraws, ::testing::Range(1, 41));

} // namespace
} // namespace scandiff
