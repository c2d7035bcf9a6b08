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
    tool.run = [](const PointCloud&, const ParameterValues&, ProgressObserver*) { return ToolResult{}; };
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
