// SPDX-License-Identifier: GPL-3.0-or-later
// The processing tools as every front end runs them: declarations, parameter
// text, inputs by role, outputs by role.
#include "StageWatcher.h"
#include "SyntheticClouds.h"
#include "TestSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <gtest/gtest.h>

#include <atomic>

using namespace scandiff;

namespace {

class ProcessingTools : public ::testing::Test
{
protected:
    const ToolSpec& tool(const std::string& name)
    {
        const ToolSpec* spec = registry_.tools.find(name);
        if (!spec)
            throw std::runtime_error("no tool " + name);
        return *spec;
    }
    ToolResult run(const std::string& name, const PointCloud& input, const std::map<std::string, std::string>& text)
    {
        const ToolSpec& spec = tool(name);
        return spec.execute(ToolInputs().add("input", input), spec.resolve(text), nullptr);
    }
    PluginRegistry registry_ = makePluginRegistry();
};

} // namespace

TEST_F(ProcessingTools, EveryToolIsDeclaredWithHelpAndValidDefaults)
{
    for (const char* name : {"normals", "orient-normals", "features", "subsample", "clone", "merge", "set-colour", "transform", "crop", "field",
                             "field-gradient", "field-smooth", "field-rename", "field-delete", "field-to-colours",
                             "colours-to-field", "field-histogram", "primitive-distance", "unroll", "sample-mesh", "mesh"}) {
        const ToolSpec& spec = tool(name);
        EXPECT_FALSE(spec.title.empty()) << name;
        EXPECT_FALSE(spec.description.empty()) << name;
        EXPECT_FALSE(spec.category.empty()) << name;
        EXPECT_FALSE(spec.outputs.empty()) << name;
        for (const auto& p : spec.parameters) {
            EXPECT_FALSE(p.description.empty()) << name << " --" << p.name;
            EXPECT_NO_THROW(p.validate(p.defaultValue)) << name << " --" << p.name;
        }
    }
}

TEST_F(ProcessingTools, SetColourGivesEveryPointOneColourAndRefusesWhatIsNoColour)
{
    PointCloud cloud = test::sphereCloud(500, 1.0);
    cloud.addField("d");
    for (const auto& [text, expected] : std::vector<std::pair<std::string, Rgb8>>{
             {"#ff8000", Rgb8{255, 128, 0}}, {"12, 34, 56", Rgb8{12, 34, 56}}, {"0;0;255", Rgb8{0, 0, 255}}}) {
        const ToolResult result = run("set-colour", cloud, {{"colour", text}});
        const PointCloud& out = result.cloud();
        ASSERT_TRUE(out.hasColors()) << text;
        EXPECT_EQ(out.positions(), cloud.positions());
        EXPECT_NE(out.field("d"), nullptr); // the rest kept
        for (const Rgb8& c : out.colors())
            ASSERT_EQ(c, expected) << text;
    }
    EXPECT_TRUE(tool("set-colour").outputs.front().updatesInput);
    for (const char* bad : {"256,0,0", "#12345", "#gg0000", "1,2", "1.5,2,3", "-1,0,0", "red"})
        EXPECT_EQ(test::errorCodeOf([&] { run("set-colour", cloud, {{"colour", bad}}); }), ErrorCode::InvalidArgument) << bad;
}

TEST_F(ProcessingTools, NormalsUpdateTheirInputAndKeepItsPoints)
{
    const PointCloud sphere = test::sphereCloud(3000, 1.0);
    const ToolResult result = run("normals", sphere, {{"orient", "centroid"}});
    EXPECT_TRUE(tool("normals").outputs.front().updatesInput);
    const PointCloud& out = result.cloud();
    ASSERT_TRUE(out.hasNormals());
    EXPECT_EQ(out.positions(), sphere.positions()); // same points, same order
    ASSERT_NE(out.field("surface_variation"), nullptr);
    for (std::size_t i = 0; i < out.size(); ++i)
        ASSERT_GT(out.normals()[i].dot(sphere.positions()[i]), 0.0f);
    // Two alternatives at once are refused; a bad orientation names the accepted ones.
    EXPECT_EQ(test::errorCodeOf([&] { run("normals", sphere, {{"knn", "8"}, {"radius", "0.1"}}); }), ErrorCode::InvalidArgument);
    try {
        run("normals", sphere, {{"orient", "upwards"}});
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("mst"), std::string::npos);
    }
    // orient-normals needs normals.
    EXPECT_EQ(test::errorCodeOf([&] { run("orient-normals", sphere, {}); }), ErrorCode::InvalidArgument);
    const ToolResult flipped = run("orient-normals", out, {{"orient", "centroid"}, {"flip", "true"}});
    for (std::size_t i = 0; i < out.size(); ++i)
        ASSERT_LT(flipped.cloud().normals()[i].dot(sphere.positions()[i]), 0.0f);
}

TEST_F(ProcessingTools, RequiredAndAlternativeParameters)
{
    const PointCloud plane = test::randomPlaneCloud(500, 1.0, 1);
    EXPECT_EQ(test::errorCodeOf([&] { run("features", plane, {}); }), ErrorCode::InvalidArgument); // --radius
    EXPECT_EQ(run("features", plane, {{"radius", "0.2"}, {"roughness", "true"}}).cloud().fields().size(), 1u);
    EXPECT_EQ(test::errorCodeOf([&] { run("subsample", plane, {}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(run("subsample", plane, {{"random", "50"}}).cloud().size(), 50u);
    EXPECT_EQ(test::errorCodeOf([&] { run("subsample", plane, {{"random", "50"}, {"octree", "3"}}); }), ErrorCode::InvalidArgument);
}

TEST_F(ProcessingTools, MergeTakesSeveralInputs)
{
    const ToolSpec& merge = tool("merge");
    EXPECT_TRUE(merge.inputs.front().repeated);
    const PointCloud a = test::randomPlaneCloud(10, 1.0, 1), b = test::randomPlaneCloud(20, 1.0, 2), c = test::randomPlaneCloud(5, 1.0, 3);
    const ToolResult result = merge.execute(ToolInputs().add("input", a).add("input", b).add("input", c), merge.resolve({}), nullptr);
    EXPECT_EQ(result.cloud().size(), 35u);
    EXPECT_EQ(result.cloud().field("source_index")->value(34), 2.0);
}

TEST_F(ProcessingTools, TransformGivesTheMatrixAndReadsMatrixFiles)
{
    PointCloud cloud = test::randomPlaneCloud(100, 1.0, 4);
    cloud.setOrigin(Eigen::Vector3d(512000, 5403000, 0));
    const auto dir = test::tempDir();
    test::writeText(dir / "m.txt", "1 0 0 10\n0 1 0 -5\n0 0 1 2\n0 0 0 1\n");
    const ToolResult moved = run("transform", cloud, {{"matrix", (dir / "m.txt").string()}});
    const Eigen::Matrix4d& m = moved.transform("matrix");
    EXPECT_EQ(m(0, 3), 10.0);
    // To the float32 step of a local coordinate within a kilometre of its origin.
    EXPECT_LT((moved.cloud().globalPosition(7) - (cloud.globalPosition(7) + Eigen::Vector3d(10, -5, 2))).norm(), 1.2e-4);
    ASSERT_EQ(moved.cloud().transformHistory().size(), 1u);
    // The same matrix typed, inverted: back where it was.
    const ToolResult back = run("transform", moved.cloud(), {{"matrix", "1,0,0,10, 0,1,0,-5, 0,0,1,2, 0,0,0,1"}, {"inverse", "true"}});
    EXPECT_LT((back.cloud().globalPosition(7) - cloud.globalPosition(7)).norm(), 1.2e-4);
    EXPECT_EQ(back.cloud().transformHistory().size(), 2u);
    // Rotation about the centroid keeps the centroid.
    const ToolResult turned = run("transform", cloud, {{"rotate", "z,90"}, {"centre", "centroid"}});
    Eigen::Vector3d before = Eigen::Vector3d::Zero(), after = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        before += cloud.globalPosition(i);
        after += turned.cloud().globalPosition(i);
    }
    EXPECT_LT((before - after).norm() / 100, 1.2e-4);
    EXPECT_EQ(test::errorCodeOf([&] { run("transform", cloud, {{"matrix", "1 2 3"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { run("transform", cloud, {}); }), ErrorCode::InvalidArgument);
}

TEST_F(ProcessingTools, CropByTextAndFieldToolsByName)
{
    PointCloud cloud = test::gridCloud(10, 10, 1.0);
    ScalarField& v = cloud.addField("value");
    for (std::size_t i = 0; i < cloud.size(); ++i)
        v.setValue(i, static_cast<double>(i));
    // The polygon as the CLI joins repeated values: A,B;A,B;...
    EXPECT_EQ(run("crop", cloud, {{"polygon", "-0.5,-0.5;2.5,-0.5;2.5,2.5;-0.5,2.5"}}).cloud().size(), 9u);
    EXPECT_EQ(run("crop", cloud, {{"box", "-1,-1,-1,4.5,1.5,1"}, {"outside", "true"}}).cloud().size(), 100u - 10u);

    const ToolResult withSum = run("field", cloud, {{"expr", "twice = value * 2"}});
    EXPECT_EQ(withSum.cloud().field("twice")->value(21), 42.0);
    const ToolResult renaming = run("field-rename", withSum.cloud(), {{"field", "twice"}, {"to", "double"}});
    const PointCloud& renamed = renaming.cloud();
    EXPECT_NE(renamed.field("double"), nullptr);
    EXPECT_EQ(renamed.field("twice"), nullptr);
    EXPECT_EQ(run("field-delete", renamed, {{"field", "double;value"}}).cloud().fields().size(), 0u);
    EXPECT_EQ(test::errorCodeOf([&] { run("field-delete", renamed, {{"field", "nothing"}}); }), ErrorCode::InvalidArgument);

    const ToolResult histogram = run("field-histogram", cloud, {{"field", "value"}, {"bins", "4"}});
    EXPECT_EQ(histogram.table().rows.size(), 4u);
    EXPECT_EQ(tool("field-histogram").outputs.front().kind, DataKind::Table);
    EXPECT_TRUE(run("field-to-colours", cloud, {{"field", "value"}}).cloud().hasColors());
}

TEST_F(ProcessingTools, PrimitiveDistanceAndUnrollGiveTheirSurfaceAsATable)
{
    const PointCloud sphere = test::sphereCloud(2000, 2.0, Eigen::Vector3d(1, 1, 1));
    const ToolResult result = run("primitive-distance", sphere, {{"kind", "sphere"}});
    const Table& table = result.table("primitive");
    EXPECT_EQ(std::get<std::string>(table.rows.front()[1]), "sphere");
    for (std::size_t i = 0; i < sphere.size(); ++i)
        ASSERT_NEAR(result.cloud().field("primitive_distance")->value(i), 0.0, 1e-5);
    const ToolResult given = run("primitive-distance", sphere, {{"kind", "sphere"}, {"surface", "sphere:1,1,1,1.5"}});
    EXPECT_NEAR(given.cloud().field("primitive_distance")->value(0), 0.5, 1e-6);
    EXPECT_EQ(test::errorCodeOf([&] { run("primitive-distance", sphere, {{"kind", "plane"}, {"surface", "sphere:1,1,1,1"}}); }),
              ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { run("unroll", sphere, {{"roll-back", "true"}}); }), ErrorCode::InvalidArgument);
}

TEST_F(ProcessingTools, SampleMeshNeedsAMesh)
{
    const ToolSpec& sample = tool("sample-mesh");
    EXPECT_EQ(sample.inputs.front().kind, DataKind::Mesh);
    const PointCloud cloud = test::randomPlaneCloud(10, 1.0, 1);
    EXPECT_EQ(test::errorCodeOf([&] { sample.execute(ToolInputs().add("input", cloud), sample.resolve({{"count", "5"}}), nullptr); }),
              ErrorCode::InvalidArgument);
    Mesh mesh;
    mesh.vertices.resize(3);
    mesh.vertices.positions() = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}};
    EXPECT_EQ(sample.execute(ToolInputs().add("input", mesh), sample.resolve({{"count", "5"}}), nullptr).cloud().size(), 5u);
}


TEST_F(ProcessingTools, EveryLongToolStopsAtAnyPollAndLeavesItsInputAsItWas)
{
    // Each tool runs once to count its polls, then again with Cancel pressed
    // at the first poll, a third of the way, two thirds and the last one: it
    // must stop with Error(Cancelled) every time, and its input (a const
    // reference, but a tool could cast or share buffers) is unchanged.
    PointCloud cloud = test::sphereCloud(30000, 2.0);
    cloud.enableNormals() = run("normals", cloud, {{"orient", "centroid"}}).cloud().normals();
    ScalarField& field = cloud.addField("height");
    for (std::size_t i = 0; i < cloud.size(); ++i)
        field.setValue(i, cloud.positions()[i].z());
    const PointCloud before = cloud.clone();
    const std::vector<std::pair<std::string, std::map<std::string, std::string>>> runs = {
        {"normals", {}},
        {"orient-normals", {}},
        {"features", {{"radius", "0.2"}}},
        {"subsample", {{"spatial", "0.05"}}},
        {"sor-filter", {}},
        {"field-smooth", {{"field", "height"}, {"sigma", "0.1"}}},
        {"field-gradient", {{"field", "height"}, {"radius", "0.2"}}},
        {"mesh", {}},
        {"primitives", {}},
        {"ground", {}},
    };
    for (const auto& [name, text] : runs) {
        const ToolSpec& spec = tool(name);
        const ParameterValues values = spec.resolve(text);
        test::PollCounter counting;
        ASSERT_NO_THROW(spec.execute(ToolInputs().add("input", cloud), values, &counting)) << name;
        const std::size_t polls = counting.polls();
        ASSERT_GE(polls, 3u) << name << " is polled " << polls << " times";
        // The last poll too: a run polls as often as the one before it
        // (ProgressTicker's thresholds do not depend on how threads batch steps).
        for (const std::size_t at : {std::size_t(1), polls / 3, 2 * polls / 3, polls}) {
            test::PollCounter cancel(std::max<std::size_t>(at, 1));
            EXPECT_EQ(test::errorCodeOf([&] { spec.execute(ToolInputs().add("input", cloud), values, &cancel); }),
                      ErrorCode::Cancelled)
                << name << ", Cancel at poll " << at << " of " << polls;
        }
        ASSERT_EQ(cloud.positions(), before.positions()) << name;
        ASSERT_EQ(cloud.normals(), before.normals()) << name;
        ASSERT_EQ(cloud.fields().size(), before.fields().size()) << name;
        ASSERT_EQ(cloud.field("height")->values(), before.field("height")->values()) << name;
    }
}

TEST_F(ProcessingTools, GroundWritesAsprsClassesAndKeepsExistingOnesUnlessAsked)
{
    PointCloud cloud;
    cloud.name = "lot";
    for (int i = 0; i < 40; ++i)
        for (int j = 0; j < 40; ++j)
            cloud.positions().emplace_back(0.5f * i, 0.5f * j, (i >= 10 && i < 20 && j >= 10 && j < 20) ? 6.0f : 0.0f);
    cloud.resize(cloud.positions().size());
    const ToolResult first = run("ground", cloud, {});
    const ScalarField* classes = first.cloud().field("classification");
    ASSERT_NE(classes, nullptr);
    for (std::size_t i = 0; i < cloud.size(); ++i)
        ASSERT_EQ(classes->value(i), cloud.positions()[i].z() > 1 ? 1.0 : 2.0) << "point " << i;
    // A cloud that has classes already: refused, then replaced when asked.
    PointCloud classed = first.cloud().clone();
    classed.field("classification")->values().assign(classed.size(), 6.f);
    EXPECT_EQ(test::errorCodeOf([&] { run("ground", classed, {}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(run("ground", classed, {{"overwrite-classes", "true"}}).cloud().field("classification")->values(), classes->values());
}
