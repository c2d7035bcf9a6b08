// SPDX-License-Identifier: GPL-3.0-or-later
// The declared segmentation parameters and the run every front end makes.

#include <scandiff/core/Error.h>
#include <scandiff/core/segmentation/ConnectedComponents.h>
#include <scandiff/core/segmentation/FastMarching.h>
#include <scandiff/core/segmentation/SegmentationParameters.h>

#include "TestSupport.h"

#include <gtest/gtest.h>

#include <set>

using namespace scandiff;

namespace {

PointCloud twoBumps()
{
    // A line of 200 points, values 1 on [20, 40) and [100, 130), 0 elsewhere.
    PointCloud c;
    c.name = "line";
    c.resize(200);
    ScalarField& d = c.addField("d");
    for (std::size_t i = 0; i < 200; ++i) {
        c.positions()[i] = {0.1f * static_cast<float>(i), 0.0f, 0.0f};
        d.values()[i] = (i >= 20 && i < 40) || (i >= 100 && i < 130) ? 1.0f : 0.0f;
    }
    return c;
}

ParameterValues resolve(const std::map<std::string, std::string>& text)
{
    return resolveParameters(segmentationParameters(), text, "test");
}

} // namespace

TEST(SegmentationParameters, NamesAreUniqueAndDefaultsComeFromTheStructs)
{
    std::set<std::string> names;
    for (const auto& p : segmentationParameters())
        EXPECT_TRUE(names.insert(p.name).second) << p.name;
    const ParameterValues defaults = resolve({});
    EXPECT_EQ(defaults.integer("neighbours"), LocalChiSquareParams{}.neighbours);
    EXPECT_EQ(defaults.real("alpha"), PropagationParams{}.alpha);
    EXPECT_EQ(defaults.integer("min-points"), kDefaultMinRegionPoints);
    EXPECT_FALSE(defaults.has("above"));
}

TEST(SegmentationParameters, RunsEachMethodAndNamesItsFields)
{
    PointCloud c = twoBumps();
    SegmentationRun run = runSegmentation(c, resolve({{"field", "d"}, {"above", "0.5"}, {"components", "true"}, {"level", "6"}}));
    EXPECT_EQ(run.regionCount, 2u);
    EXPECT_EQ(run.regionSizes, (std::vector<std::size_t>{30, 20}));
    EXPECT_EQ(run.changedCount, 50u);
    attachFields(c, std::move(run));
    ASSERT_NE(c.field("region_id"), nullptr);
    ASSERT_NE(c.field("changed"), nullptr);
    EXPECT_EQ(c.field("region_id")->values()[110], 1.0f);
    EXPECT_EQ(c.field("region_id")->values()[30], 2.0f);

    run = runSegmentation(c, resolve({{"field", "d"}, {"range", "0.5;2"}}));
    EXPECT_EQ(run.regionCount, 1u); // no components: one region of every changed point
    // The range as its description gives it and the workbench's dialog fills
    // it from the panel's thresholds ("A B"), and as "A,B": the same run.
    for (const char* text : {"0.5 2", "0.5,2", " 0.5  2 "}) {
        const SegmentationRun same = runSegmentation(c, resolve({{"field", "d"}, {"range", text}}));
        EXPECT_EQ(same.changedCount, run.changedCount) << text;
    }
    run = runSegmentation(c, resolve({{"field", "d"}, {"kmeans", "2"}}));
    EXPECT_EQ(run.changedCount, 50u);
    EXPECT_EQ(run.centres.size(), 2u);
    run = runSegmentation(c, resolve({{"field", "d"}, {"propagate", "true"}, {"min-seed", "0.5"}, {"gradient-radius", "0.3"}}));
    EXPECT_GE(run.regionCount, 2u);
    std::set<std::string> fieldNames;
    for (const auto& f : run.fields)
        fieldNames.insert(f.name());
    EXPECT_EQ(fieldNames, (std::set<std::string>{"region_id", "arrival_time", "gradient_norm"}));
}

TEST(SegmentationParameters, InconsistentChoicesAreErrors)
{
    const PointCloud c = twoBumps();
    EXPECT_EQ(test::errorCodeOf([&] { runSegmentation(c, resolve({{"field", "d"}})); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { runSegmentation(c, resolve({{"field", "d"}, {"above", "1"}, {"kmeans", "2"}})); }),
              ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { runSegmentation(c, resolve({{"field", "e"}, {"above", "1"}})); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { runSegmentation(c, resolve({{"field", "d"}, {"range", "1"}})); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { runSegmentation(c, resolve({{"field", "d"}, {"propagate", "true"}})); }),
              ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] {
                  runSegmentation(c, resolve({{"field", "d"}, {"stat-test", "gaussian"}, {"fit-box", "100,100,100,101,101,101"}}));
              }),
              ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { resolve({{"kmeans", "1"}}); }), ErrorCode::InvalidArgument);
    PointCloud empty;
    empty.addField("d");
    EXPECT_EQ(test::errorCodeOf([&] { runSegmentation(empty, resolve({{"field", "d"}, {"above", "1"}})); }), ErrorCode::InvalidData);
}
