// SPDX-License-Identifier: GPL-3.0-or-later
#include "CliRunner.h"

#include <scandiff/core/Error.h>
#include <scandiff/io/E57.h>

#include "TestSupport.h"

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>

using namespace scandiff;

namespace {

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
    const test::CliRun run = test::runCliInProcess(registry, {"info", file.string(), "--json"});
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
    test::CliRun run = test::runCliInProcess(registry, {"info", file.string()});
    ASSERT_EQ(run.status, 0) << run.err;
    EXPECT_NE(run.out.find("points:        4"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("intensity"), std::string::npos);
    for (const char* ext : {"las", "xyz", "pcd", "e57", "ply"}) {
        const auto out = dir / (std::string("converted.") + ext);
        run = test::runCliInProcess(registry, {"convert", file.string(), out.string()});
        ASSERT_EQ(run.status, 0) << ext << ": " << run.err;
        const PointCloud back = io::readPointCloud(registry.formats, out);
        ASSERT_EQ(back.size(), 4u) << ext;
        EXPECT_NEAR(back.globalPosition(2).y(), 5423002.0, 1e-3) << ext;
        ASSERT_NE(back.field("intensity"), nullptr) << ext;
    }
}

TEST(Cli, InfoListsTheScansAndImagesOfAnE57AndConvertKeepsItsScans)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const std::filesystem::path samples = std::filesystem::path(SCANDIFF_SAMPLE_DATA_DIR) / "e57";
    // Images only: listed with their size, extracted as JPEG files.
    test::CliRun run = test::runCliInProcess(registry, {"info", (samples / "PinholeImageWithDistortionParameters.e57").string(), "--json",
                                                        "--extract-images", dir.string()});
    ASSERT_EQ(run.status, 0) << run.err;
    auto j = nlohmann::json::parse(run.out);
    ASSERT_EQ(j["e57"]["images"].size(), 3u);
    EXPECT_EQ(j["e57"]["images"][2]["name"], "JPEG Image Test 3");
    EXPECT_EQ(j["e57"]["images"][2]["bytes"], 375);
    EXPECT_TRUE(std::filesystem::exists(dir / "JPEG Image Test 3.jpg"));

    // Two scans, one posed: info lists both with their pose and counts; convert E57 -> E57 keeps them apart.
    PointCloud a, b;
    a.name = "station A";
    b.name = "station B";
    a.resize(10);
    b.resize(7);
    SensorPose pose;
    pose.position = Eigen::Vector3d(1, 2, 3);
    a.sensors().push_back(pose);
    const auto two = dir / "two.e57";
    io::writePointClouds(registry.formats, {&a, &b}, two);
    run = test::runCliInProcess(registry, {"info", two.string()});
    ASSERT_EQ(run.status, 0) << run.err;
    EXPECT_NE(run.out.find("E57 scans:     2"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("[0] 'station A'  10 records, cartesian, at 1, 2, 3"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("[1] 'station B'  7 records, cartesian, no pose"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("points:        17"), std::string::npos) << run.out;
    run = test::runCliInProcess(registry, {"convert", two.string(), (dir / "copy.e57").string()});
    ASSERT_EQ(run.status, 0) << run.err;
    EXPECT_EQ(io::readE57Scans(dir / "copy.e57").size(), 2u);
    run = test::runCliInProcess(registry, {"convert", two.string(), (dir / "merged.ply").string()});
    ASSERT_EQ(run.status, 0) << run.err;
    const PointCloud merged = io::readPointCloud(registry.formats, dir / "merged.ply");
    EXPECT_EQ(merged.size(), 17u);
    ASSERT_NE(merged.field("scan_index"), nullptr);

    // Broken files: a message naming the problem and a non-zero status.
    run = test::runCliInProcess(registry, {"info", (samples / "bad-crc.e57").string()});
    EXPECT_NE(run.status, 0);
    EXPECT_NE(run.err.find("checksum of page 0"), std::string::npos) << run.err;
}

TEST(Cli, ErrorsExitNonZeroWithAMessage)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    test::CliRun run = test::runCliInProcess(registry, {"info", (dir / "missing.ply").string()});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::Io));
    EXPECT_NE(run.err.find("error: "), std::string::npos);
    EXPECT_NE(run.err.find("missing.ply"), std::string::npos);
    test::writeText(dir / "bad.ply", "ply\nformat nonsense 1.0\nend_header\n");
    run = test::runCliInProcess(registry, {"info", (dir / "bad.ply").string()});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::InvalidData));
    run = test::runCliInProcess(registry, {"convert", (dir / "bad.ply").string()});
    EXPECT_NE(run.status, 0);
    run = test::runCliInProcess(registry, {"frobnicate"});
    EXPECT_NE(run.status, 0);
}

TEST(Cli, ConvertNeverLeavesAHalfWrittenFile)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const auto file = sampleCloud(registry, dir);
    test::writeText(dir / "target.obj", "precious");
    // A cloud cannot become an OBJ mesh: the error must leave the old file as it was.
    const test::CliRun run = test::runCliInProcess(registry, {"convert", file.string(), (dir / "target.obj").string()});
    EXPECT_NE(run.status, 0);
    EXPECT_EQ(test::readBytes(dir / "target.obj"), "precious");
}

TEST(Cli, ToolsBecomeSubcommandsWithTheirDeclaredOptions)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const auto file = sampleCloud(registry, dir);
    test::CliRun run = test::runCliInProcess(registry, {"sor-filter", "--help"});
    EXPECT_EQ(run.status, 0);
    EXPECT_NE(run.out.find("--n-sigma"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("default 6"), std::string::npos) << run.out;
    run = test::runCliInProcess(registry, {"sor-filter", file.string(), "--k", "2", "-o", (dir / "filtered.ply").string()});
    ASSERT_EQ(run.status, 0) << run.err;
    EXPECT_TRUE(std::filesystem::exists(dir / "filtered.ply"));
    run = test::runCliInProcess(registry, {"sor-filter", file.string(), "--k", "0"});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::InvalidArgument));
    EXPECT_NE(run.err.find("[1, 1000]"), std::string::npos) << run.err;
    run = test::runCliInProcess(registry, {"tools"});
    EXPECT_NE(run.out.find("sor-filter"), std::string::npos);
    run = test::runCliInProcess(registry, {"formats"});
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

namespace {

//! What the dynamic loader says of the libraries a command of the installed binary loads.
std::string librariesLoadedBy(const std::string& arguments, const std::filesystem::path& dir)
{
    const std::filesystem::path log = dir / "loader.log";
    const std::string command = "LD_DEBUG=libs " + std::string(SCANDIFF_CLI_PATH) + " " + arguments + " > /dev/null 2> " + log.string();
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    std::ifstream in(log);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

} // namespace

// GDAL and its hundred dependencies cost 75 ms of a process's start: they are
// loaded when a coordinate system, a GeoTIFF or a PNG preview needs them.
TEST(Cli, GdalIsLoadedOnlyByTheCommandsThatNeedIt)
{
    const PluginRegistry registry = makePluginRegistry();
    const std::filesystem::path dir = test::tempDir();
    PointCloud cloud;
    cloud.resize(3);
    cloud.positions()[1] = {1, 0, 0};
    cloud.positions()[2] = {0, 1, 0};
    io::writePointCloud(registry.formats, cloud, dir / "three.ply");
    const std::string plain = librariesLoadedBy("convert " + (dir / "three.ply").string() + " " + (dir / "three.las").string(), dir);
    EXPECT_NE(plain.find("libtbb"), std::string::npos); // the log does list what the process loads
    EXPECT_EQ(plain.find("libgdal"), std::string::npos);
    EXPECT_EQ(plain.find("libxerces"), std::string::npos);
    const std::string withSystem =
        librariesLoadedBy("convert " + (dir / "three.ply").string() + " " + (dir / "three.las").string() + " --crs EPSG:2056", dir);
    EXPECT_NE(withSystem.find("libgdal"), std::string::npos);
    EXPECT_NE(io::readPointCloud(registry.formats, dir / "three.las").crsWkt().find("CH1903+"), std::string::npos);
}

namespace {

//! A 21 x 21 grid on z = 0 (spacing 0.1 m) as a cloud, and the same grid as a mesh.
void writePlane(const PluginRegistry& registry, const std::filesystem::path& cloudPath, const std::filesystem::path& meshPath)
{
    Mesh mesh;
    mesh.vertices.resize(21 * 21);
    for (int j = 0; j < 21; ++j)
        for (int i = 0; i < 21; ++i)
            mesh.vertices.positions()[static_cast<std::size_t>(j * 21 + i)] = {i * 0.1f, j * 0.1f, 0.0f};
    for (std::uint32_t j = 0; j < 20; ++j)
        for (std::uint32_t i = 0; i < 20; ++i) {
            const std::uint32_t a = j * 21 + i;
            mesh.triangles.push_back({a, a + 1, a + 22});
            mesh.triangles.push_back({a, a + 22, a + 21});
        }
    io::writePointCloud(registry.formats, mesh.vertices, cloudPath);
    io::writeMesh(registry.formats, mesh, meshPath);
}

} // namespace

TEST(Cli, CloudToCloudAndCloudToMeshWriteTheirFields)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    writePlane(registry, dir / "reference.ply", dir / "mesh.ply");
    PointCloud compared;
    compared.resize(3);
    compared.positions() = {{0.55f, 0.55f, 0.2f}, {1.0f, 1.0f, -0.1f}, {1.23f, 0.47f, 0.05f}};
    io::writePointCloud(registry.formats, compared, dir / "compared.ply");

    test::CliRun run = test::runCliInProcess(registry, {"c2c", "--reference", (dir / "reference.ply").string(), "--compared",
                                   (dir / "compared.ply").string(), "--model", "plane", "--split-xyz", "-o",
                                   (dir / "c2c.ply").string(), "--both-ways", "--closest-points"});
    ASSERT_EQ(run.status, 0) << run.err;
    EXPECT_NE(run.out.find("3 values"), std::string::npos) << run.out;
    PointCloud out = io::readPointCloud(registry.formats, dir / "c2c.ply");
    ASSERT_EQ(out.size(), 3u);
    ASSERT_NE(out.field("c2c_distance"), nullptr);
    EXPECT_NEAR(out.field("c2c_distance")->values()[0], 0.2, 1e-5);
    EXPECT_NEAR(out.field("c2c_distance")->values()[1], 0.1, 1e-5);
    EXPECT_NEAR(out.field("c2c_distance")->values()[2], 0.05, 1e-5);
    EXPECT_NE(out.field("c2c_dz"), nullptr);
    EXPECT_TRUE(std::filesystem::exists(dir / "c2c_reference.ply"));
    const PointCloud closest = io::readPointCloud(registry.formats, dir / "c2c_closest.ply");
    EXPECT_EQ(closest.size(), 3u);

    run = test::runCliInProcess(registry, {"c2m", "--reference", (dir / "mesh.ply").string(), "--compared", (dir / "compared.ply").string(),
                            "--signed", "-o", (dir / "c2m.ply").string()});
    ASSERT_EQ(run.status, 0) << run.err;
    out = io::readPointCloud(registry.formats, dir / "c2m.ply");
    ASSERT_NE(out.field("c2m_distance"), nullptr);
    EXPECT_NEAR(out.field("c2m_distance")->values()[0], 0.2, 1e-6);
    EXPECT_NEAR(out.field("c2m_distance")->values()[1], -0.1, 1e-6);

    // Without -o nothing is written; bad options are refused with a message.
    run = test::runCliInProcess(registry, {"c2c", "--reference", (dir / "reference.ply").string(), "--compared", (dir / "compared.ply").string()});
    EXPECT_EQ(run.status, 0);
    run = test::runCliInProcess(registry, {"c2c", "--reference", (dir / "reference.ply").string(), "--compared", (dir / "compared.ply").string(),
                            "--signed"});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::InvalidArgument));
    EXPECT_NE(run.err.find("normals"), std::string::npos) << run.err;
    run = test::runCliInProcess(registry, {"c2c", "--reference", (dir / "reference.ply").string(), "--compared", (dir / "compared.ply").string(),
                            "--clamp"});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::InvalidArgument));
    run = test::runCliInProcess(registry, {"c2c", "--reference", (dir / "reference.ply").string(), "--compared", (dir / "compared.ply").string(),
                            "--knn", "8", "--radius", "0.5"});
    EXPECT_NE(run.status, 0);
    run = test::runCliInProcess(registry, {"c2c", "--reference", (dir / "reference.ply").string(), "--compared", (dir / "compared.ply").string(),
                            "--visibility"});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::InvalidArgument));
    EXPECT_NE(run.err.find("sensor"), std::string::npos) << run.err;
    run = test::runCliInProcess(registry, {"c2m", "--reference", (dir / "reference.ply").string(), "--compared", (dir / "compared.ply").string()});
    EXPECT_EQ(run.status, static_cast<int>(ErrorCode::InvalidData)) << run.err;
}

TEST(Cli, CloudToCloudVisibilityFromTheCommandLine)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    PointCloud wall;
    for (int i = -20; i <= 20; ++i)
        for (int j = -20; j <= 20; ++j) {
            wall.resize(wall.size() + 1);
            wall.positions().back() = {10.0f, i * 0.1f, j * 0.1f};
        }
    io::writePointCloud(registry.formats, wall, dir / "wall.ply");
    PointCloud compared;
    compared.resize(2);
    compared.positions() = {{10.0f, 0.3f, 0.2f}, {12.0f, 0.5f, -0.4f}};
    io::writePointCloud(registry.formats, compared, dir / "compared.ply");
    const test::CliRun run = test::runCliInProcess(registry, {"c2c", "--reference", (dir / "wall.ply").string(), "--compared",
                                         (dir / "compared.ply").string(), "--sensor", "0,0,0", "-o", (dir / "out.ply").string()});
    ASSERT_EQ(run.status, 0) << run.err;
    const PointCloud out = io::readPointCloud(registry.formats, dir / "out.ply");
    ASSERT_NE(out.field("visibility"), nullptr);
    EXPECT_EQ(out.field("visibility")->values()[0], 0.0f);
    EXPECT_EQ(out.field("visibility")->values()[1], 1.0f);
    EXPECT_TRUE(std::isnan(out.field("c2c_distance")->values()[1]));
}
