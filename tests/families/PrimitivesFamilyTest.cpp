// SPDX-License-Identifier: GPL-3.0-or-later
// Efficient RANSAC with its defaults (`primitives`) on the plant corner built
// apart from the code (tests/support/families/PrimitivesFamily.h): 1 M
// points from four stations, 15 shapes, 5 mm noise, 5 % clutter, a 16 m
// pipe of radius 0.10 m hidden in pieces by a tank and a platform, a column
// touching a wall, an elbow torus between two legs.
#include "TestSupport.h"
#include "families/PrimitiveTrials.h"

#include <gtest/gtest.h>

namespace scandiff {
namespace {

namespace pf = test::family::primitives;

const pf::ShapeScore& shapeNamed(const pf::DetectionScore& score, const std::string& name)
{
    for (const pf::ShapeScore& s : score.shapes)
        if (s.name == name)
            return s;
    throw std::runtime_error("no shape " + name);
}

TEST(PrimitivesFamily, TheIssuePlantComesOutWholeWithoutFalseShapes)
{
    // Before: 4 of 15 shapes found, 24 false shapes (far walls left in pieces
    // by normals fitted on one or two neighbours, the pipe in plane strips,
    // the cone lost). Target: every shape of its type, 80 % of its points at
    // 90 % purity, no false shape.
    const pf::PrimitivesScene scene = pf::make(pf::issueCase());
    const test::family::PrimitivesTrial t = test::family::runPrimitives(scene, {});
    const std::string table = t.score.table() + "\n" + t.report;
    EXPECT_TRUE(t.score.meetsTarget()) << table;
    EXPECT_EQ(t.score.found, 15u) << table;
    const pf::ShapeScore& pipe = shapeNamed(t.score, "long pipe r0.10");
    EXPECT_LT(pipe.radiusError, 0.002) << table;
    EXPECT_LT(pipe.axisErrorDeg, 0.1) << table;
}

TEST(PrimitivesFamily, HeldOutDrawsFindMostShapesAndAlmostNoFalseOnes)
{
    // Twelve draws the code was not changed on (seeds 13-24 at 0.3 scale:
    // 150-450 k points, rooms in any heading, 8-20 shapes, noise 1-10 mm,
    // clutter 0-10 %, UTM offsets in half). Measured 113 of 136 shapes and 2
    // false ones (CloudCompare's plugin: 91 and 25; this code at the start
    // of the work: about half). Asserted: at least 78 % of the required
    // shapes over the twelve, at most 4 false shapes, each draw at least
    // half of its shapes. The whole target on every draw is not met yet.
    std::size_t required = 0, found = 0, falseShapes = 0;
    for (std::uint64_t seed = 13; seed <= 24; ++seed) {
        const pf::PrimitivesScene scene = pf::make(pf::drawFamily(seed, 0.3));
        const test::family::PrimitivesTrial t = test::family::runPrimitives(scene, {});
        required += t.score.required;
        found += t.score.found;
        falseShapes += t.score.falseShapes.size();
        EXPECT_GE(2 * t.score.found, t.score.required) << "seed " << seed << "\n" << t.score.table();
    }
    EXPECT_GE(100 * found, 78 * required) << found << " of " << required;
    EXPECT_LE(falseShapes, 4u);
}

} // namespace
} // namespace scandiff
