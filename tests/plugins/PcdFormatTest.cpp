// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/plugins/PluginRegistry.h>

#include "TestSupport.h"

#include <cmath>

using namespace scandiff;

namespace {

std::filesystem::path sample(const std::string& name)
{
    return std::filesystem::path(SCANDIFF_SAMPLE_DATA_DIR) / "pcl-data" / name;
}

void expectSameCloud(const PointCloud& a, const PointCloud& b)
{
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); i += 97)
        EXPECT_LT((a.globalPosition(i) - b.globalPosition(i)).norm(), 1e-3) << i;
    EXPECT_EQ(a.colors(), b.colors());
    ASSERT_EQ(a.fields().size(), b.fields().size());
    for (std::size_t f = 0; f < a.fields().size(); ++f)
        EXPECT_EQ(a.fields()[f].name(), b.fields()[f].name());
}

} // namespace

TEST(PcdFormat, ReadsTheRealColourScan)
{
    const PluginRegistry registry = makePluginRegistry();
    const PointCloud cloud = io::readPointCloud(registry.formats, sample("region_growing_tutorial.pcd"));
    EXPECT_EQ(cloud.size(), 108104u);
    EXPECT_TRUE(cloud.hasColors());
    EXPECT_EQ(cloud.name, "region_growing_tutorial");
}

TEST(PcdFormat, GeoreferencedAirborneSampleGetsAGlobalShift)
{
    const PluginRegistry registry = makePluginRegistry();
    const PointCloud cloud = io::readPointCloud(registry.formats, sample("samp11-utm.pcd"));
    EXPECT_EQ(cloud.size(), 38010u);
    EXPECT_FALSE(cloud.origin().isZero());
    EXPECT_EQ(std::fmod(cloud.origin().x(), 1000.0), 0.0);
    const BoundingBox box = cloud.bounds();
    EXPECT_GT(box.min.x(), 1e5); // UTM eastings
    // Local coordinates stay small, so float keeps millimetres.
    for (const auto& p : cloud.positions())
        ASSERT_LT(p.cwiseAbs().maxCoeff(), 1e4f);
    const PointCloud ground = io::readPointCloud(registry.formats, sample("samp11-utm-ground.pcd"));
    EXPECT_LT(ground.size(), cloud.size());
}

TEST(PcdFormat, OrganisedCaptureDropsNaNAndKeepsTheViewpoint)
{
    const PluginRegistry registry = makePluginRegistry();
    const PointCloud cloud = io::readPointCloud(registry.formats, sample("capture0001.pcd"));
    EXPECT_GT(cloud.size(), 100000u);
    EXPECT_LT(cloud.size(), 307200u);
    for (const auto& p : cloud.positions())
        ASSERT_TRUE(p.allFinite());
    ASSERT_EQ(cloud.sensors().size(), 1u);
}

TEST(PcdFormat, RoundTripInEveryEncoding)
{
    const PluginRegistry registry = makePluginRegistry();
    PointCloud cloud = io::readPointCloud(registry.formats, sample("region_growing_tutorial.pcd"));
    ScalarField& f = cloud.addField("c2c_distance");
    for (std::size_t i = 0; i < cloud.size(); ++i)
        f.values()[i] = i % 10 == 0 ? std::nanf("") : static_cast<float>(i) * 0.001f;
    cloud.enableNormals()[3] = {0, 0, 1};
    const auto dir = test::tempDir();
    for (io::Encoding encoding : {io::Encoding::Ascii, io::Encoding::BinaryLittleEndian, io::Encoding::BinaryCompressed}) {
        io::WriteOptions options;
        options.encoding = encoding;
        io::writePointCloud(registry.formats, cloud, dir / "copy.pcd", options);
        const PointCloud back = io::readPointCloud(registry.formats, dir / "copy.pcd");
        expectSameCloud(back, cloud);
        ASSERT_NE(back.field("c2c_distance"), nullptr);
        EXPECT_TRUE(std::isnan(back.field("c2c_distance")->values()[0]));
        EXPECT_NEAR(back.field("c2c_distance")->values()[11], 0.011f, 1e-6);
        ASSERT_TRUE(back.hasNormals());
        EXPECT_EQ(back.normals()[3], Eigen::Vector3f(0, 0, 1));
    }
}

TEST(PcdFormat, GeoreferencedRoundTripKeepsMillimetres)
{
    const PluginRegistry registry = makePluginRegistry();
    PointCloud cloud;
    cloud.setOrigin({512000, 5423000, 0});
    cloud.resize(2);
    cloud.positions()[0] = {345.678f, 456.789f, 123.456f};
    cloud.positions()[1] = {1.0f, 2.0f, 3.0f};
    const auto path = test::tempDir() / "utm.pcd";
    io::writePointCloud(registry.formats, cloud, path);
    const PointCloud back = io::readPointCloud(registry.formats, path);
    EXPECT_NEAR(back.globalPosition(0).x(), 512345.678, 1e-3);
    EXPECT_NEAR(back.globalPosition(0).y(), 5423456.789, 1e-3);
}

TEST(PcdFormat, BadFilesAreClearErrors)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    test::writeText(dir / "garbage.pcd", "not a pcd file at all\n");
    test::writeText(dir / "empty.pcd", "");
    const std::string header = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                               "WIDTH 100\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 100\nDATA binary\n";
    test::writeText(dir / "truncated.pcd", header + std::string(24, '\0'));
    test::writeText(dir / "noxyz.pcd", "VERSION 0.7\nFIELDS a b\nSIZE 4 4\nTYPE F F\nCOUNT 1 1\nWIDTH 1\nHEIGHT 1\n"
                                       "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 2\n");
    std::string compressed = test::readBytes(sample("samp11-utm.pcd"));
    test::writeText(dir / "cut.pcd", compressed.substr(0, compressed.size() / 2));
    for (const char* name : {"garbage.pcd", "empty.pcd", "truncated.pcd", "noxyz.pcd", "cut.pcd"}) {
        try {
            io::readPointCloud(registry.formats, dir / name);
            ADD_FAILURE() << name << " was accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ErrorCode::InvalidData) << name << ": " << e.what();
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        }
    }
}
