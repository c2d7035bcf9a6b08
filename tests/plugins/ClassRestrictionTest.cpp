// SPDX-License-Identifier: GPL-3.0-or-later
// `--classes` / `--exclude-classes` on every tool of the registry
// (core/src/ClassRestriction.h): each tool answers as on clouds filtered by
// class beforehand, and what it gives in place of its input keeps every point.

#include "TestSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/DistanceParameters.h>
#include <scandiff/core/processing/CloudEditing.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace scandiff {
namespace {

//! A hilly ground (class 2) with scattered crowns over it (class 5), and a
//! few points of class 7 (noise) below; the crowns and noise drawn from `seed`.
PointCloud vegetatedGround(std::size_t n, std::uint64_t seed, double crownLift)
{
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 30.0);
    std::normal_distribution<double> noise(0.0, 0.005);
    PointCloud cloud;
    cloud.name = "epoch" + std::to_string(seed);
    cloud.setOrigin(Eigen::Vector3d(652000, 6862000, 100)); // Lambert-93
    ScalarField classes("classification", 0);
    for (std::size_t i = 0; i < n; ++i) {
        const double x = u(rng), y = u(rng);
        double z = 0.8 * std::sin(x / 4) + 0.5 * std::cos(y / 5) + noise(rng);
        int c = 2;
        const double pick = u(rng) / 30.0;
        if (pick < 0.3) {
            c = 5;
            z += 2 + crownLift + 3 * u(rng) / 30.0;
        } else if (pick < 0.33) {
            c = 7;
            z -= 1 + u(rng) / 10;
        }
        cloud.positions().push_back(Eigen::Vector3f(float(x), float(y), float(z)));
        classes.values().push_back(float(c));
    }
    cloud.addField(std::move(classes));
    return cloud;
}

PointCloud ofClasses(const PointCloud& cloud, std::initializer_list<int> keep)
{
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        for (int c : keep)
            if (cloud.field("classification")->value(i) == c)
                kept.push_back(i);
    return cloud.subset(kept);
}

const ToolSpec& toolNamed(const PluginRegistry& registry, const std::string& name)
{
    const ToolSpec* tool = registry.tools.find(name);
    EXPECT_NE(tool, nullptr) << name;
    return *tool;
}

TEST(ClassRestriction, EveryToolOnCloudsOffersIt)
{
    const PluginRegistry registry = makePluginRegistry();
    for (const char* name : {"m3c2", "dod", "register", "normals", "primitives", "sor-filter", "subsample"}) {
        const ToolSpec& tool = toolNamed(registry, name);
        EXPECT_NE(tool.parameter("classes"), nullptr) << name;
        EXPECT_NE(tool.parameter("exclude-classes"), nullptr) << name;
    }
    // The stations' poses are not one matrix to move left-out points by; a
    // field is renamed or deleted, a cloud moved, on every point.
    for (const char* name : {"register-stations", "field-rename", "field-delete", "transform", "undo-transform"})
        EXPECT_EQ(toolNamed(registry, name).parameter("classes"), nullptr) << name;
}

TEST(ClassRestriction, ColouringTheGroundLeavesTheTreesAsTheyWere)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = toolNamed(registry, "set-colour");
    PointCloud cloud = vegetatedGround(3000, 9, 0.0);
    for (auto& colour : cloud.enableColors())
        colour = {10, 20, 30};
    const ToolResult result =
        tool.execute(ToolInputs().add("input", cloud), tool.resolve({{"colour", "255,0,0"}, {"classes", "2"}}), nullptr);
    const PointCloud& out = result.cloud();
    ASSERT_EQ(out.size(), cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const bool ground = cloud.field("classification")->value(i) == 2;
        const Rgb8 expected = ground ? Rgb8{255, 0, 0} : Rgb8{10, 20, 30};
        EXPECT_EQ(out.colors()[i], expected) << i;
    }
}

TEST(ClassRestriction, CorePointsWithoutClassesAreAllUsed)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = toolNamed(registry, "m3c2");
    const PointCloud earlier = vegetatedGround(20000, 10, 0.0), later = vegetatedGround(20000, 11, 1.5);
    PointCloud cores;
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j)
            cores.positions().push_back(Eigen::Vector3f(3.0f * i + 1, 3.0f * j + 1, 0.8f * std::sin((3.0f * i + 1) / 4) + 0.5f * std::cos((3.0f * j + 1) / 5)));
    cores.setOrigin(earlier.origin());
    const ToolResult result = tool.execute(ToolInputs().add("reference", earlier).add("compared", later).add("core-points", cores),
                                           tool.resolve({{"normal-scale", "1"}, {"projection-scale", "0.5"}, {"max-depth", "3"}, {"classes", "2"}}),
                                           nullptr);
    EXPECT_EQ(result.cloud().size(), cores.size());
}

TEST(ClassRestriction, M3c2OnGroundOnlyEqualsM3c2OnGroundClouds)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = toolNamed(registry, "m3c2");
    const PointCloud earlier = vegetatedGround(20000, 1, 0.0), later = vegetatedGround(20000, 2, 1.5);
    std::map<std::string, std::string> options{{"normal-scale", "1"}, {"projection-scale", "0.5"}, {"max-depth", "3"},
                                               {"core-spacing", "0.5"}};
    const ToolResult plain = tool.execute(ToolInputs().add("reference", ofClasses(earlier, {2})).add("compared", ofClasses(later, {2})),
                                          tool.resolve(options), nullptr);
    options["classes"] = "2";
    const ToolResult restricted =
        tool.execute(ToolInputs().add("reference", earlier).add("compared", later), tool.resolve(options), nullptr);
    const PointCloud &a = plain.cloud(), &b = restricted.cloud();
    ASSERT_EQ(a.size(), b.size());
    ASSERT_EQ(a.fields().size(), b.fields().size());
    for (std::size_t f = 0; f < a.fields().size(); ++f)
        for (std::size_t i = 0; i < a.size(); ++i) {
            const double x = a.fields()[f].value(i), y = b.fields()[f].value(i);
            ASSERT_TRUE(x == y || (std::isnan(x) && std::isnan(y))) << a.fields()[f].name() << " " << i;
        }
    // On the ground alone, the grown crowns are gone: no change beyond the noise.
    const ScalarField* distance = b.field("m3c2_distance");
    ASSERT_NE(distance, nullptr);
    std::size_t measured = 0;
    for (std::size_t i = 0; i < b.size(); ++i) {
        if (!std::isfinite(distance->value(i)))
            continue;
        EXPECT_LT(std::abs(distance->value(i)), 0.05) << i;
        ++measured;
    }
    EXPECT_GT(measured, b.size() / 2);
}

TEST(ClassRestriction, RegisteringOnTheGroundMovesTheWholeCloud)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = toolNamed(registry, "register");
    const PointCloud earlier = vegetatedGround(30000, 3, 0.0);
    // The later epoch: another sampling, crowns grown 1.5 m, moved by a known motion.
    Eigen::Matrix4d motion = Eigen::Matrix4d::Identity();
    motion.topLeftCorner<3, 3>() = Eigen::AngleAxisd(0.01, Eigen::Vector3d(0.2, 0.3, 1).normalized()).toRotationMatrix();
    motion.topRightCorner<3, 1>() = Eigen::Vector3d(0.3, -0.2, 0.15) - motion.topLeftCorner<3, 3>() * Eigen::Vector3d(652015, 6862015, 100) +
                                    Eigen::Vector3d(652015, 6862015, 100);
    const PointCloud later = transformCloud(vegetatedGround(30000, 4, 1.5), motion, "known motion");

    std::map<std::string, std::string> options{{"classes", "2"}};
    const ToolResult restricted = tool.execute(ToolInputs().add("moving", later).add("reference", earlier), tool.resolve(options), nullptr);
    const ToolResult plain = tool.execute(ToolInputs().add("moving", ofClasses(later, {2})).add("reference", ofClasses(earlier, {2})),
                                          tool.resolve({}), nullptr);
    // The same matrix as on the ground clouds, and back to the truth.
    EXPECT_TRUE(restricted.transform("matrix").isApprox(plain.transform("matrix"), 0.0)) << restricted.transform("matrix");
    const Eigen::Matrix4d error = restricted.transform("matrix") * motion;
    EXPECT_LT((error.topRightCorner<3, 1>() + error.topLeftCorner<3, 3>() * Eigen::Vector3d(652015, 6862015, 100) -
               Eigen::Vector3d(652015, 6862015, 100)).norm(),
              0.005);

    // Every point of the later epoch is moved, the crowns and the noise too;
    // the residual is on the ground points only.
    const PointCloud& moved = restricted.cloud("output");
    ASSERT_EQ(moved.size(), later.size());
    const Eigen::Matrix4d m = restricted.transform("matrix");
    const ScalarField* residual = moved.field("registration_residual");
    ASSERT_NE(residual, nullptr);
    const ScalarField* classes = moved.field("classification");
    ASSERT_NE(classes, nullptr);
    std::size_t ground = 0;
    for (std::size_t i = 0; i < later.size(); ++i) {
        const Eigen::Vector3d expected = (m * later.globalPosition(i).homogeneous()).head<3>();
        ASSERT_LT((moved.globalPosition(i) - expected).norm(), 1e-4) << i;
        EXPECT_EQ(classes->value(i), later.field("classification")->value(i));
        if (classes->value(i) == 2) {
            EXPECT_TRUE(std::isfinite(residual->value(i))) << i;
            ++ground;
        } else {
            EXPECT_TRUE(std::isnan(residual->value(i))) << i;
        }
    }
    EXPECT_EQ(ground, ofClasses(later, {2}).size());
    EXPECT_NE(restricted.summary.find("by class"), std::string::npos) << restricted.summary;
}

TEST(ClassRestriction, AnInPlaceToolKeepsEveryPointAndWhatItHad)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = toolNamed(registry, "normals");
    const PointCloud cloud = vegetatedGround(8000, 5, 0.0);
    const ToolResult restricted = tool.execute(ToolInputs().add("input", cloud), tool.resolve({{"exclude-classes", "5,7"}}), nullptr);
    const ToolResult plain = tool.execute(ToolInputs().add("input", ofClasses(cloud, {2})), tool.resolve({}), nullptr);
    const PointCloud &whole = restricted.cloud(), &ground = plain.cloud();
    ASSERT_EQ(whole.size(), cloud.size());
    ASSERT_TRUE(whole.hasNormals());
    std::size_t k = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        ASSERT_EQ(whole.positions()[i], cloud.positions()[i]);
        ASSERT_EQ(whole.field("classification")->value(i), cloud.field("classification")->value(i));
        if (cloud.field("classification")->value(i) == 2)
            EXPECT_EQ(whole.normals()[i], ground.normals()[k++]) << i;
        else
            EXPECT_EQ(whole.normals()[i], Eigen::Vector3f::Zero()) << i; // no normal there
    }
    EXPECT_EQ(k, ground.size());
}

// c2c is declared outside the registry (cloudToCloudParameters, shared by
// the command and the workbench's dialog) and takes the classes the same way.
TEST(ClassRestriction, CloudToCloudOnGroundOnlyEqualsItOnGroundClouds)
{
    const PointCloud earlier = vegetatedGround(20000, 7, 0.0), later = vegetatedGround(20000, 8, 1.5);
    std::map<std::string, std::string> options{{"model", "quadric"}, {"both-ways", "true"}};
    const CloudToCloudRun plain = runCloudToCloud(ofClasses(later, {2}), ofClasses(earlier, {2}),
                                                  resolveParameters(cloudToCloudParameters(), options, "c2c"));
    options["classes"] = "2";
    const CloudToCloudRun restricted = runCloudToCloud(later, earlier, resolveParameters(cloudToCloudParameters(), options, "c2c"));
    auto sameOnGround = [](const PointCloud& whole, const ScalarField& spread, const ScalarField& ground) {
        ASSERT_EQ(spread.size(), whole.size());
        std::size_t k = 0;
        for (std::size_t i = 0; i < whole.size(); ++i) {
            if (whole.field("classification")->value(i) == 2) {
                ASSERT_EQ(spread.value(i), ground.value(k++)) << i;
            } else {
                ASSERT_TRUE(std::isnan(spread.value(i))) << i;
            }
        }
        EXPECT_EQ(k, ground.size());
    };
    sameOnGround(later, restricted.forward.distance, plain.forward.distance);
    ASSERT_TRUE(restricted.reverse && plain.reverse);
    sameOnGround(earlier, restricted.reverse->distance, plain.reverse->distance);
    EXPECT_EQ(restricted.forward.statistics.count, plain.forward.statistics.count);
    // The grown crowns are out: ground against ground, within the noise and the sampling.
    EXPECT_LT(restricted.forward.statistics.max, 0.2);
}

TEST(ClassRestriction, BadClassListsAndCloudsWithoutClassesAreRefused)
{
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = toolNamed(registry, "normals");
    const PointCloud cloud = vegetatedGround(500, 6, 0.0);
    PointCloud unclassified = cloud.clone();
    unclassified.removeField("classification");
    auto code = [&](const PointCloud& c, std::map<std::string, std::string> options) {
        return test::errorCodeOf([&] { tool.execute(ToolInputs().add("input", c), tool.resolve(options), nullptr); });
    };
    EXPECT_EQ(code(unclassified, {{"classes", "2"}}), ErrorCode::InvalidArgument);
    EXPECT_EQ(code(cloud, {{"classes", "300"}}), ErrorCode::InvalidArgument);
    EXPECT_EQ(code(cloud, {{"classes", "2.5"}}), ErrorCode::InvalidArgument);
    EXPECT_EQ(code(cloud, {{"classes", "9"}}), ErrorCode::InvalidArgument);            // no point left
    EXPECT_EQ(code(cloud, {{"exclude-classes", "2,5,7"}}), ErrorCode::InvalidArgument); // none either
    EXPECT_EQ(code(cloud, {{"classes", "x"}}), ErrorCode::InvalidArgument);
}

} // namespace
} // namespace scandiff
