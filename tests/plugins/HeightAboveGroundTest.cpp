// SPDX-License-Identifier: GPL-3.0-or-later
// Height above ground (the meshing plugin's "hag"): on terrains a TIN holds
// exactly (a tilted plane in any heading, a valley whose crease runs along a
// grid line), every point's height is its analytic height over the terrain.
#include "StageWatcher.h"
#include "TestSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/plugins/PluginRegistry.h>
#include <scandiff/plugins/meshing/HeightAboveGround.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace scandiff;

namespace {

//! A drawn terrain: ground points (class 2) and objects above them (class 1,
//! 5 or 6: vegetation, buildings) at known heights.
struct Terrain
{
    PointCloud cloud;
    std::vector<double> height; //!< each point's analytic height above the terrain
};

//! z = slope * (cos(heading) x + sin(heading) y) (a plane) or, as a valley,
//! slope * |x| with the crease on a grid line; ground sampled on a jittered
//! grid (plane) or a regular one (valley), objects anywhere inside.
Terrain drawTerrain(std::uint64_t seed, bool valley)
{
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> unit(0, 1);
    const double spacing = 0.02 + unit(random) * 2.98; // 2 cm to 3 m
    const int cells = 2 * (20 + static_cast<int>(unit(random) * 40)); // even: the valley's crease x = 0 on a grid line
    const double slope = unit(random);        // up to 45 degrees
    const double heading = unit(random) * 2 * M_PI;
    const double half = cells * spacing / 2;
    const auto groundZ = [&](double x, double y) {
        return valley ? slope * std::abs(x) : slope * (std::cos(heading) * x + std::sin(heading) * y);
    };
    Terrain t;
    std::vector<Eigen::Vector3f> positions;
    std::vector<float> classes;
    for (int i = 0; i <= cells; ++i)
        for (int j = 0; j <= cells; ++j) {
            double x = -half + i * spacing, y = -half + j * spacing;
            if (!valley && i > 0 && i < cells && j > 0 && j < cells) {
                x += (unit(random) - 0.5) * 0.6 * spacing;
                y += (unit(random) - 0.5) * 0.6 * spacing;
            }
            positions.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(groundZ(x, y)));
            classes.push_back(2);
            t.height.push_back(0);
        }
    const int objects = 2000;
    for (int k = 0; k < objects; ++k) {
        const double x = (unit(random) - 0.5) * 1.98 * half, y = (unit(random) - 0.5) * 1.98 * half;
        const double h = 0.05 + unit(random) * 30; // bushes to canopy
        const float z = static_cast<float>(groundZ(x, y) + h);
        positions.emplace_back(static_cast<float>(x), static_cast<float>(y), z);
        classes.push_back(k % 3 == 0 ? 6.f : k % 3 == 1 ? 5.f : 1.f);
        t.height.push_back(static_cast<double>(z) - groundZ(static_cast<float>(x), static_cast<float>(y)));
    }
    t.cloud.resize(positions.size());
    t.cloud.positions() = positions;
    // Georeferenced, as airborne tiles are: the heights do not depend on it.
    t.cloud.setOrigin({512000.0 + 1000 * unit(random), 5403000.0, 230.0});
    t.cloud.addField("classification").values() = classes;
    return t;
}

std::vector<float> hagThroughTheTool(const PointCloud& cloud, const std::map<std::string, std::string>& options = {})
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("hag");
    ToolInputs inputs;
    inputs.add("input", cloud);
    ToolResult result = tool.execute(inputs, tool.resolve(options), nullptr);
    const PointCloud& out = std::get<PointCloud>(result.find("output")->data);
    EXPECT_EQ(out.size(), cloud.size());
    return out.field("height_above_ground")->values();
}

} // namespace

// 24 seeded draws of each terrain: spacing 2 cm-3 m, slopes to 45 degrees in
// any heading, UTM-sized origins; every point of every draw asserted. The
// tolerance is the float coordinates' own (their ulp at 100 m is 8 um).
TEST(HeightAboveGround, EveryPointAtItsAnalyticHeightOnTerrainsATinHolds)
{
    for (bool valley : {false, true})
        for (std::uint64_t seed = 1; seed <= 24; ++seed) {
            const Terrain t = drawTerrain(seed, valley);
            const std::vector<float> hag = hagThroughTheTool(t.cloud);
            std::size_t wrong = 0;
            double worst = 0;
            for (std::size_t i = 0; i < t.height.size(); ++i) {
                const double error = std::abs(static_cast<double>(hag[i]) - t.height[i]);
                worst = std::max(worst, error);
                wrong += !(error <= 2e-4);
            }
            EXPECT_EQ(wrong, 0u) << (valley ? "valley" : "plane") << " draw " << seed << ", worst " << worst << " m";
        }
}

TEST(HeightAboveGround, BeyondTheOutlineTheNearestGroundPointAndTheChosenClasses)
{
    PointCloud cloud;
    cloud.resize(6);
    // Ground: a unit square at heights 0, 1, 2, 3 (the plane z = x + 2y; its
    // corner (1, 1) in class 8), a roof point over its middle, one point
    // beyond its outline, nearest the ground point (1, 0, 1).
    cloud.positions() = {{0, 0, 0}, {1, 0, 1}, {0, 1, 2}, {1, 1, 3}, {0.5f, 0.5f, 10}, {3, 0.2f, 7}};
    cloud.addField("classification").values() = {2, 2, 2, 8, 6, 1};
    const std::vector<float> withKeyPoints = hagThroughTheTool(cloud, {{"ground-classes", "2,8"}});
    EXPECT_FLOAT_EQ(withKeyPoints[3], 0);
    EXPECT_NEAR(withKeyPoints[4], 10 - 1.5, 1e-6);
    EXPECT_NEAR(withKeyPoints[5], 7 - 1, 1e-6);
    // Class 2 alone: a triangle whose outline runs under the roof point (on
    // the outline: the edge's height, not a corner's).
    const std::vector<float> groundOnly = hagThroughTheTool(cloud);
    EXPECT_NEAR(groundOnly[4], 10 - 1.5, 1e-6);
    EXPECT_NEAR(groundOnly[5], 7 - 1, 1e-6);
}

TEST(HeightAboveGround, BadInputIsRefusedClearly)
{
    const auto cloudOf = [](std::vector<Eigen::Vector3f> positions, std::vector<float> classes) {
        PointCloud cloud;
        cloud.resize(positions.size());
        cloud.positions() = std::move(positions);
        if (!classes.empty())
            cloud.addField("classification").values() = std::move(classes);
        return cloud;
    };
    EXPECT_THROW(hagThroughTheTool(cloudOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {})), Error); // no classification
    try {
        hagThroughTheTool(cloudOf({{0, 0, 0}, {1, 1, 0}, {2, 2, 0}}, {2, 2, 2}));
        FAIL() << "ground on a line accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidData);
        EXPECT_NE(std::string(e.what()).find("line"), std::string::npos);
    }
    EXPECT_THROW(hagThroughTheTool(cloudOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {2, 2, 1})), Error); // two ground points
    const PointCloud withNan = cloudOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {NAN, 0, 5}}, {2, 2, 2, 1});
    const std::vector<float> hag = hagThroughTheTool(withNan);
    EXPECT_TRUE(std::isnan(hag[3]));
    EXPECT_EQ(hag[0], 0.f);
    EXPECT_THROW(hagThroughTheTool(withNan, {{"ground-classes", "2.5"}}), Error);
}

// Cancel is heard from the first poll (building the TIN) to the last (the
// last points located), and the input is left as it was.
TEST(HeightAboveGround, CancelStopsItAtAnyPoll)
{
    const Terrain t0 = drawTerrain(5, false);
    // Four copies side by side: a bigger ground, more polls while the TIN grows.
    Terrain t;
    std::vector<Eigen::Vector3f> positions;
    std::vector<float> classes;
    for (int copy = 0; copy < 4; ++copy)
        for (std::size_t i = 0; i < t0.cloud.size(); ++i) {
            positions.push_back(t0.cloud.positions()[i] + Eigen::Vector3f(1000.0f * static_cast<float>(copy), 0, 0));
            classes.push_back(t0.cloud.field("classification")->values()[i]);
        }
    t.cloud.resize(positions.size());
    t.cloud.positions() = positions;
    t.cloud.addField("classification").values() = classes;
    const std::vector<Eigen::Vector3f> before = t.cloud.positions();
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("hag");
    const ParameterValues values = tool.resolve({});
    test::PollCounter counting;
    ASSERT_NO_THROW(tool.execute(ToolInputs().add("input", t.cloud), values, &counting));
    const std::size_t polls = counting.polls();
    ASSERT_GE(polls, 3u);
    for (const std::size_t at : {std::size_t(1), polls / 3, 2 * polls / 3, polls}) {
        test::PollCounter cancel(std::max<std::size_t>(at, 1));
        EXPECT_EQ(test::errorCodeOf([&] { tool.execute(ToolInputs().add("input", t.cloud), values, &cancel); }), ErrorCode::Cancelled)
            << "Cancel at poll " << at << " of " << polls;
    }
    EXPECT_EQ(t.cloud.positions(), before);
}
