// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/ToolRegistry.h>

#include "TestSupport.h"

#include <gtest/gtest.h>

using namespace scandiff;

namespace {

ToolSpec sampleTool()
{
    ToolSpec tool;
    tool.name = "sample";
    tool.parameters = {
        ParameterSpec::integer("k", "K", "neighbours", 6, 1, 100),
        ParameterSpec::real("radius", "Radius", "search radius", 0.5, 0.0, 10.0, "m"),
        ParameterSpec::boolean("signed", "Signed", "signed distances", false),
        ParameterSpec::choice("model", "Model", "local model", {"none", "plane", "quadric"}, "none"),
    };
    tool.run = [](const ToolInputs&, const ParameterValues&, ProgressObserver*) { return ToolResult{}; };
    return tool;
}

} // namespace

TEST(ToolRegistry, DefaultsComeFromTheDeclarations)
{
    const ToolSpec tool = sampleTool();
    const ParameterValues v = tool.defaults();
    EXPECT_EQ(v.integer("k"), 6);
    EXPECT_DOUBLE_EQ(v.real("radius"), 0.5);
    EXPECT_FALSE(v.boolean("signed"));
    EXPECT_EQ(v.text("model"), "none");
}

TEST(ToolRegistry, UserTextIsParsedAndChecked)
{
    const ToolSpec tool = sampleTool();
    const ParameterValues v = tool.resolve({{"k", "12"}, {"radius", "2.5"}, {"signed", "true"}, {"model", "quadric"}});
    EXPECT_EQ(v.integer("k"), 12);
    EXPECT_DOUBLE_EQ(v.real("radius"), 2.5);
    EXPECT_TRUE(v.boolean("signed"));
    EXPECT_EQ(v.text("model"), "quadric");

    EXPECT_EQ(test::errorCodeOf([&] { tool.resolve({{"k", "0"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { tool.resolve({{"k", "1.5"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { tool.resolve({{"radius", "11"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { tool.resolve({{"radius", "nan"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { tool.resolve({{"model", "spline"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { tool.resolve({{"signed", "maybe"}}); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { tool.resolve({{"unknown", "1"}}); }), ErrorCode::InvalidArgument);
    try {
        tool.resolve({{"radius", "11"}});
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("radius"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("[0, 10]"), std::string::npos);
    }
}

TEST(ToolRegistry, FormatIsTheInverseOfParse)
{
    const ToolSpec tool = sampleTool();
    for (const auto& p : tool.parameters)
        EXPECT_EQ(p.parse(ParameterSpec::format(p.defaultValue)), p.defaultValue) << p.name;
}

TEST(ToolRegistry, NamesAreUnique)
{
    ToolRegistry registry;
    registry.add(sampleTool());
    EXPECT_NE(registry.find("sample"), nullptr);
    EXPECT_EQ(registry.find("other"), nullptr);
    EXPECT_THROW(registry.add(sampleTool()), Error);
}

TEST(ToolRegistry, DefaultsOutsideTheirRangeAreABug)
{
    EXPECT_THROW(ParameterSpec::integer("k", "K", "", 0, 1, 10), Error);
    EXPECT_THROW(ParameterSpec::choice("m", "M", "", {"a"}, "b"), Error);
}

TEST(ToolRegistry, AlternativesAreExclusive)
{
    ToolSpec tool = sampleTool();
    tool.parameters.push_back(ParameterSpec::real("within", "Within", "radius", 1.0, 0.0, 10.0).asAlternative("neighbourhood"));
    tool.parameters.push_back(ParameterSpec::integer("knn", "Knn", "count", 6, 1, 100).asAlternative("neighbourhood"));
    EXPECT_FALSE(tool.defaults().has("within"));
    EXPECT_FALSE(tool.defaults().has("knn"));
    EXPECT_DOUBLE_EQ(tool.resolve({{"within", "2"}}).real("within"), 2.0);
    EXPECT_EQ(tool.resolve({{"knn", "8"}}).integer("knn"), 8);
    try {
        tool.resolve({{"within", "2"}, {"knn", "8"}});
        FAIL() << "two alternatives were accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
        EXPECT_NE(std::string(e.what()).find("--within"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("--knn"), std::string::npos);
    }
}

TEST(ToolRegistry, InputsAreCheckedAgainstTheirDeclaration)
{
    ToolSpec tool = sampleTool();
    tool.inputs = {InputSpec{"input", "Clouds", "", DataKind::Cloud, true, false},
                   InputSpec{"mesh", "Mesh", "", DataKind::Mesh, false, false},
                   InputSpec{"extra", "Extra", "", DataKind::Cloud, false, true}};
    PointCloud a, b;
    a.name = "a";
    b.name = "b";
    Mesh mesh;
    mesh.vertices.resize(3);
    mesh.triangles.push_back({0, 1, 2});

    ToolInputs complete;
    complete.add("input", a).add("input", b).add("mesh", mesh);
    EXPECT_NO_THROW(tool.checkInputs(complete));
    EXPECT_EQ(complete.count("input"), 2u);
    EXPECT_EQ(&complete.cloud("input", 1), &b);
    EXPECT_EQ(&complete.mesh("mesh"), &mesh);
    EXPECT_EQ(&complete.cloud("mesh"), &mesh.vertices); // a Cloud role may read a mesh's vertices
    EXPECT_EQ(complete.meshOrNull("input"), nullptr);
    EXPECT_FALSE(complete.has("extra"));
    EXPECT_EQ(test::errorCodeOf([&] { complete.cloud("extra"); }), ErrorCode::InvalidArgument);

    ToolInputs noMesh;
    noMesh.add("input", a);
    EXPECT_EQ(test::errorCodeOf([&] { tool.checkInputs(noMesh); }), ErrorCode::InvalidArgument);

    ToolInputs cloudAsMesh;
    cloudAsMesh.add("input", a).add("mesh", b);
    EXPECT_EQ(test::errorCodeOf([&] { tool.checkInputs(cloudAsMesh); }), ErrorCode::InvalidArgument);

    ToolInputs twoMeshes;
    twoMeshes.add("input", a).add("mesh", mesh).add("mesh", mesh);
    EXPECT_EQ(test::errorCodeOf([&] { tool.checkInputs(twoMeshes); }), ErrorCode::InvalidArgument);

    // execute() checks before it runs.
    bool ran = false;
    tool.run = [&](const ToolInputs&, const ParameterValues&, ProgressObserver*) {
        ran = true;
        return ToolResult{};
    };
    EXPECT_EQ(test::errorCodeOf([&] { tool.execute(noMesh, tool.defaults(), nullptr); }), ErrorCode::InvalidArgument);
    EXPECT_FALSE(ran);
    tool.execute(complete, tool.defaults(), nullptr);
    EXPECT_TRUE(ran);
}

TEST(ToolRegistry, ResultsAreFoundByRoleAndKind)
{
    ToolResult result;
    PointCloud cloud;
    cloud.resize(4);
    Table table;
    table.columns = {"a"};
    result.add("output", std::move(cloud)).add("histogram", std::move(table)).add("transform", Eigen::Matrix4d::Identity().eval());
    EXPECT_EQ(result.cloud().size(), 4u);
    EXPECT_EQ(result.table("histogram").columns.size(), 1u);
    EXPECT_TRUE(result.transform("transform").isIdentity());
    EXPECT_EQ(result.find("missing"), nullptr);
    EXPECT_EQ(test::errorCodeOf([&] { result.mesh(); }), ErrorCode::Internal);
    EXPECT_EQ(test::errorCodeOf([&] { result.cloud("histogram"); }), ErrorCode::Internal);
}

TEST(Table, CsvKeepsEveryDigitAndQuotesText)
{
    Table table;
    table.columns = {"name", "value"};
    table.rows = {{std::string("plain"), 0.1}, {std::string("with, comma"), 1.0 / 3.0}, {std::string("say \"hi\""), std::nan("")}};
    const std::string csv = table.toCsv();
    EXPECT_EQ(csv, "name,value\nplain,0.1\n\"with, comma\",0.3333333333333333\n\"say \"\"hi\"\"\",nan\n");
}
