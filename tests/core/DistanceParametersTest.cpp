// SPDX-License-Identifier: GPL-3.0-or-later
// The c2c/c2m declarations shared by the CLI and the workbench: defaults come
// from the parameter structs, optional values stay unset, text is checked.
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/DistanceParameters.h>

#include "TestSupport.h"

#include <gtest/gtest.h>

using namespace scandiff;

TEST(DistanceParameters, DefaultsAreTheStructsDefaults)
{
    PointCloud reference;
    const ParameterValues values = resolveParameters(cloudToCloudParameters(), {}, "c2c");
    EXPECT_FALSE(values.has("max-dist"));
    EXPECT_FALSE(values.has("radius"));
    EXPECT_FALSE(values.has("sensor"));
    const CloudToCloudParams params = cloudToCloudSettings(values, reference);
    const CloudToCloudParams defaults;
    EXPECT_FALSE(params.maxDistance);
    EXPECT_EQ(params.neighbours, defaults.neighbours);
    EXPECT_EQ(params.model, defaults.model);
    EXPECT_EQ(params.octreeLevel, defaults.octreeLevel);
    EXPECT_DOUBLE_EQ(params.visibility.tolerance, defaults.visibility.tolerance);
    EXPECT_TRUE(params.viewpoints.empty());
    EXPECT_FALSE(cloudToCloudBothWays(values));

    const CloudToMeshParams meshParams = cloudToMeshSettings(resolveParameters(cloudToMeshParameters(), {}, "c2m"));
    EXPECT_FALSE(meshParams.maxDistance);
    EXPECT_EQ(meshParams.signedDistances, CloudToMeshParams{}.signedDistances);
}

TEST(DistanceParameters, UserValuesReachTheSettings)
{
    PointCloud reference;
    const ParameterValues values = resolveParameters(
        cloudToCloudParameters(),
        {{"max-dist", "2.5"}, {"clamp", "true"}, {"model", "quadric"}, {"radius", "0.3"}, {"sensor", "1,2,3; 4,5,6,90,0,0"},
         {"sensor-range", "50"}, {"octree-level", "7"}},
        "c2c");
    const CloudToCloudParams params = cloudToCloudSettings(values, reference);
    EXPECT_DOUBLE_EQ(*params.maxDistance, 2.5);
    EXPECT_TRUE(params.clampBeyondMax);
    EXPECT_EQ(params.model, LocalModel::Quadric);
    EXPECT_DOUBLE_EQ(*params.radius, 0.3);
    EXPECT_EQ(params.octreeLevel, 7);
    ASSERT_EQ(params.viewpoints.size(), 2u);
    EXPECT_EQ(params.viewpoints[1].position, Eigen::Vector3d(4, 5, 6));
    EXPECT_DOUBLE_EQ(params.viewpoints[0].maxRange, 50.0);
    // Heading 90 degrees turns the sensor's X axis onto Y.
    EXPECT_TRUE((params.viewpoints[1].orientation * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
}

TEST(DistanceParameters, InconsistentValuesAreRefused)
{
    PointCloud reference;
    const auto settingsOf = [&](std::map<std::string, std::string> text) {
        return cloudToCloudSettings(resolveParameters(cloudToCloudParameters(), text, "c2c"), reference);
    };
    EXPECT_EQ(test::errorCodeOf([&] { settingsOf({{"clamp", "true"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { settingsOf({{"visibility", "true"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { settingsOf({{"sensor", "1,2"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { settingsOf({{"sensor", "1,2,3"}, {"sensor-fov", "10,0,0,1"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { settingsOf({{"max-dist", "0"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { settingsOf({{"model", "spline"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { settingsOf({{"no-such", "1"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { cloudToMeshSettings(resolveParameters(cloudToMeshParameters(), {{"clamp", "true"}}, "c2m")); }),
              ErrorCode::InvalidArgument);

    // Stored sensor poses serve when visibility is asked without a sensor text.
    reference.sensors().push_back(SensorPose{});
    EXPECT_EQ(settingsOf({{"visibility", "true"}}).viewpoints.size(), 1u);
}

TEST(DistanceParameters, BothWaysComputesTheReverseField)
{
    PointCloud a, b;
    a.resize(2);
    a.positions() = {{0, 0, 0}, {1, 0, 0}};
    b.resize(1);
    b.positions() = {{0, 0, 0.5f}};
    const ParameterValues values = resolveParameters(cloudToCloudParameters(), {{"both-ways", "true"}}, "c2c");
    const CloudToCloudRun run = runCloudToCloud(b, a, values);
    EXPECT_FLOAT_EQ(run.forward.distance.values()[0], 0.5f);
    ASSERT_TRUE(run.reverse);
    ASSERT_EQ(run.reverse->distance.size(), 2u);
    EXPECT_FLOAT_EQ(run.reverse->distance.values()[0], 0.5f);
    EXPECT_NEAR(run.reverse->distance.values()[1], std::sqrt(1.25), 1e-6);
}
