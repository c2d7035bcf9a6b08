// SPDX-License-Identifier: GPL-3.0-or-later
#include "Commands.h"

#include <scandiff/core/Error.h>

#include "TestSupport.h"

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <sstream>

using namespace scandiff;

namespace {

struct CliRun
{
    int status = 0;
    std::string out, err;
};

CliRun runCli(const PluginRegistry& registry, std::vector<std::string> args)
{
    args.insert(args.begin(), "scandiff-cli");
    std::vector<const char*> argv;
    for (const auto& a : args)
        argv.push_back(a.c_str());
    std::ostringstream out, err;
    CliRun run;
    run.status = cli::runCli(static_cast<int>(argv.size()), argv.data(), registry, {out, err});
    run.out = out.str();
    run.err = err.str();
    return run;
}

std::filesystem::path sampleCloud(const PluginRegistry& registry, const std::filesystem::path& dir)
{
    PointCloud cloud;
    cloud.setOrigin({512000, 5423000, 0});
    cloud.resize(4);
    cloud.positions() = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0, 0, 3}};
    ScalarField& f = cloud.addField("intensity");
    f.values() = {1, 2, 3, std::nanf("")};
    const auto path = dir / "sample.ply";
    io::writePointCloud(registry.formats, cloud, path);
    return path;
}

} // namespace

TEST(Cli, InfoJsonDescribesTheFile)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto file = sampleCloud(registry, test::tempDir());
    const CliRun run = runCli(registry, {"info", file.string(), "--json"});
    ASSERT_EQ(run.status, 0) << run.err;
    const auto j = nlohmann::json::parse(run.out);
    EXPECT_EQ(j["points"], 4);
    EXPECT_EQ(j["type"], "cloud");
    EXPECT_DOUBLE_EQ(j["bounds"]["min"][0].get<double>(), 512000.0);
    EXPECT_DOUBLE_EQ(j["bounds"]["max"][2].get<double>(), 3.0);
    EXPECT_DOUBLE_EQ(j["global_shift"][1].get<double>(), 5423000.0);
    ASSERT_EQ(j["fields"].size(), 1u);
    EXPECT_EQ(j["fields"][0]["name"], "intensity");
    EXPECT_DOUBLE_EQ(j["fields"][0]["min"].get<double>(), 1.0);
    EXPECT_DOUBLE_EQ(j["fields"][0]["max"].get<double>(), 3.0);
    EXPECT_EQ(j["fields"][0]["valid"], 3);
}

TEST(Cli, InfoTextAndConvertRoundTrip)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const auto file = sampleCloud(registry, dir);
    CliRun run = runCli(registry, {"info", file.string()});
    ASSERT_EQ(run.status, 0) << run.err;
    EXPECT_NE(run.out.find("points:        4"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("intensity"), std::string::npos);
    for (const char* ext : {"las", "xyz", "pcd", "ply"}) {
        const auto out = dir / (std::string("converted.") + ext);
        run = runCli(registry, {"convert", file.string(), out.string()});
        ASSERT_EQ(run.status, 0) << ext << ": " << run.err;
        const PointCloud back = io::readPointCloud(registry.formats, out);
        ASSERT_EQ(back.size(), 4u) << ext;
        EXPECT_NEAR(back.globalPosition(2).y(), 5423002.0, 1e-3) << ext;
        ASSERT_NE(back.field("intensity"), nullptr) << ext;
    }
}

TEST(Cli, ErrorsExitNonZeroWithAMessage)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    CliRun run = runCli(registry, {"info", (dir / "missing.ply").string()});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::Io));
    EXPECT_NE(run.err.find("error: "), std::string::npos);
    EXPECT_NE(run.err.find("missing.ply"), std::string::npos);
    test::writeText(dir / "bad.ply", "ply\nformat nonsense 1.0\nend_header\n");
    run = runCli(registry, {"info", (dir / "bad.ply").string()});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::InvalidData));
    run = runCli(registry, {"convert", (dir / "bad.ply").string()});
    EXPECT_NE(run.status, 0);
    run = runCli(registry, {"frobnicate"});
    EXPECT_NE(run.status, 0);
}

TEST(Cli, ConvertNeverLeavesAHalfWrittenFile)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const auto file = sampleCloud(registry, dir);
    test::writeText(dir / "target.obj", "precious");
    // A cloud cannot become an OBJ mesh: the error must leave the old file as it was.
    const CliRun run = runCli(registry, {"convert", file.string(), (dir / "target.obj").string()});
    EXPECT_NE(run.status, 0);
    EXPECT_EQ(test::readBytes(dir / "target.obj"), "precious");
}

TEST(Cli, ToolsBecomeSubcommandsWithTheirDeclaredOptions)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const auto file = sampleCloud(registry, dir);
    CliRun run = runCli(registry, {"sor-filter", "--help"});
    EXPECT_EQ(run.status, 0);
    EXPECT_NE(run.out.find("--n-sigma"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("default 6"), std::string::npos) << run.out;
    run = runCli(registry, {"sor-filter", file.string(), "--k", "2", "-o", (dir / "filtered.ply").string()});
    ASSERT_EQ(run.status, 0) << run.err;
    EXPECT_TRUE(std::filesystem::exists(dir / "filtered.ply"));
    run = runCli(registry, {"sor-filter", file.string(), "--k", "0"});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::InvalidArgument));
    EXPECT_NE(run.err.find("[1, 1000]"), std::string::npos) << run.err;
    run = runCli(registry, {"tools"});
    EXPECT_NE(run.out.find("sor-filter"), std::string::npos);
    run = runCli(registry, {"formats"});
    EXPECT_NE(run.out.find(".pcd"), std::string::npos);
    EXPECT_NE(run.out.find(".las"), std::string::npos);
}

TEST(Cli, TheInstalledBinaryReportsErrorsThroughItsExitStatus)
{
    const std::string command = std::string(SCANDIFF_CLI_PATH) + " info /nonexistent/file.ply 2>/dev/null";
    const int status = std::system(command.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), static_cast<int>(ErrorCode::Io));
}
