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

} // namespace
} // namespace scandiff
