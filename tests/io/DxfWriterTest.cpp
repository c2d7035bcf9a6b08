// SPDX-License-Identifier: GPL-3.0-or-later
// DXF export, checked by an independent reader (support/DxfCheck.h: ezdxf loads
// and audits each file and reports the entity counts per type and layer).

#include "internal/Formats.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/DxfWriter.h>
#include <scandiff/io/FileIO.h>

#include "../support/DxfCheck.h"
#include "../support/TestSupport.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace scandiff;

using test::checkDxf;
using test::DxfCheck;

io::FormatRegistry dxfRegistry()
{
    io::FormatRegistry registry;
    registry.add(io::detail::dxfFormat());
    return registry;
}

template <class Fn>
void expectErrorCode(Fn&& fn, ErrorCode code)
{
    try {
        fn();
        ADD_FAILURE() << "no error thrown";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), code) << e.what();
    }
}

TEST(DxfDrawing, AllEntityKindsOnTwoLayersPassTheAudit)
{
    const fs::path file = test::tempDir() / "drawing.dxf";
    io::DxfDrawing drawing;
    drawing.addLayer("Points", 1);
    drawing.addLayer("Breaklines", 3);
    drawing.addPoint("Points", {512345.678, 5423456.789, 123.456});
    drawing.addPoint("Points", {512346.0, 5423457.0, 124.0});
    drawing.addPoint("Points", {512347.0, 5423458.0, 125.0});
    drawing.addPolyline("Breaklines", {{512340, 5423450, 120}, {512341, 5423451, 121.5}, {512342, 5423450, 119}},
                        false);
    drawing.addPolyline("Breaklines", {{512340, 5423450, 100}, {512350, 5423450, 100}, {512350, 5423460, 100}},
                        true, true);
    drawing.add3dFace("Points", {Eigen::Vector3d(512340, 5423450, 120), Eigen::Vector3d(512341, 5423450, 120),
                                 Eigen::Vector3d(512340, 5423451, 121)});
    drawing.addText("Breaklines", {512340, 5423449, 120}, 0.5, "Profile 1");
    drawing.write(file);

    const DxfCheck check = checkDxf(file);
    ASSERT_EQ(check.exitStatus, 0);
    EXPECT_EQ(check.version, "AC1009");
    EXPECT_EQ(check.count("total"), 7);
    EXPECT_EQ(check.count("POINT@Points"), 3);
    EXPECT_EQ(check.count("3DFACE@Points"), 1);
    EXPECT_EQ(check.count("POLYLINE@Breaklines"), 2);
    EXPECT_EQ(check.count("TEXT@Breaklines"), 1);

    // Georeferenced coordinates keep their micrometres.
    const std::string text = test::readBytes(file);
    EXPECT_NE(text.find("512345.678000\n"), std::string::npos);
    EXPECT_NE(text.find("5423456.789000\n"), std::string::npos);
    // Closed 2D polyline: flag 1; open 3D polyline: flag 8.
    EXPECT_NE(text.find(" 70\n1\n  0\nVERTEX"), std::string::npos);
    EXPECT_NE(text.find(" 70\n8\n  0\nVERTEX"), std::string::npos);
}

TEST(DxfDrawing, LayerNamesAreMadeValid)
{
    const fs::path file = test::tempDir() / "layers.dxf";
    io::DxfDrawing drawing;
    drawing.addPoint("a<b>c/d\\e\"f:g;h?i*j|k=l'm n", {0, 0, 0});
    const std::string longName = "a_layer_name_much_longer_than_thirty_one_characters";
    drawing.addPoint(longName, {1, 0, 0});
    // DXF layer names ignore case: one layer, the first spelling.
    drawing.addPoint("Survey", {2, 0, 0});
    drawing.addPoint("SURVEY", {3, 0, 0});
    drawing.addPoint("", {4, 0, 0}); // no name: layer "0"
    drawing.addPoint("G\xC3\xA9o", {5, 0, 0}); // "Géo" in UTF-8
    drawing.write(file);

    const DxfCheck check = checkDxf(file);
    ASSERT_EQ(check.exitStatus, 0);
    EXPECT_EQ(check.count("POINT@a_b_c_d_e_f_g_h_i_j_k_l_m_n"), 1);
    EXPECT_EQ(check.count("POINT@" + longName.substr(0, 31)), 1);
    EXPECT_EQ(check.count("POINT@Survey"), 2);
    EXPECT_EQ(check.count("POINT@0"), 1);
    EXPECT_EQ(check.count("POINT@G_o"), 1);
}

TEST(DxfDrawing, TextIsEncodedForCad)
{
    const fs::path file = test::tempDir() / "text.dxf";
    io::DxfDrawing drawing;
    drawing.addText("notes", {0, 0, 0}, 1.0, "n\xC2\xB0" "1\nline two 100%% \xE4\xB8\xAD"); // UTF-8
    drawing.write(file);
    ASSERT_EQ(checkDxf(file).exitStatus, 0);
    const std::string text = test::readBytes(file);
    // ° is byte 0xB0 in Windows-1252 ($DWGCODEPAGE ANSI_1252), the line break a
    // space, "%%" escaped, and a character outside the code page as \U+XXXX.
    EXPECT_NE(text.find("n\xB0"
                        "1 line two 100%%%% \\U+4E2D\n"),
              std::string::npos);
}

TEST(DxfDrawing, RejectsInvalidInput)
{
    io::DxfDrawing drawing;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    expectErrorCode([&] { drawing.addLayer("x", 0); }, ErrorCode::InvalidArgument);
    expectErrorCode([&] { drawing.addLayer("x", 256); }, ErrorCode::InvalidArgument);
    expectErrorCode([&] { drawing.addPoint("x", {nan, 0, 0}); }, ErrorCode::InvalidArgument);
    expectErrorCode([&] { drawing.addPolyline("x", {{0, 0, 0}}, false); }, ErrorCode::InvalidArgument);
    expectErrorCode([&] { drawing.addPolyline("x", {{0, 0, 0}, {1, 1, 1}}, false, true); },
                    ErrorCode::InvalidArgument);
    expectErrorCode([&] { drawing.addText("x", {0, 0, 0}, 0.0, "t"); }, ErrorCode::InvalidArgument);
    expectErrorCode([&] { drawing.write(test::tempDir() / "no" / "such" / "folder.dxf"); }, ErrorCode::Io);
}

TEST(DxfFormat, CloudThroughTheRegistry)
{
    test::CapturedLog log;
    const fs::path file = test::tempDir() / "cloud.dxf";
    PointCloud cloud;
    cloud.name = "scan 2024/05";
    cloud.setOrigin(Eigen::Vector3d(512000, 5423000, 0));
    cloud.resize(5);
    cloud.positions()[0] = Eigen::Vector3f(345.5f, 456.25f, 123.125f);
    cloud.positions()[2] = Eigen::Vector3f(std::numeric_limits<float>::quiet_NaN(), 0, 0);
    io::writePointCloud(dxfRegistry(), cloud, file);
    ASSERT_EQ(log.warnings.size(), 1u);

    const DxfCheck check = checkDxf(file);
    ASSERT_EQ(check.exitStatus, 0);
    EXPECT_EQ(check.count("POINT@scan_2024_05"), 4);
    EXPECT_EQ(check.count("total"), 4);
    EXPECT_NE(test::readBytes(file).find(" 10\n512345.500000\n 20\n5423456.250000\n 30\n123.125000\n"),
              std::string::npos);

    PointCloud unnamed;
    unnamed.resize(2);
    io::writePointCloud(dxfRegistry(), unnamed, file);
    EXPECT_EQ(checkDxf(file).count("POINT@points"), 2);
}

TEST(DxfFormat, MeshThroughTheRegistry)
{
    const fs::path file = test::tempDir() / "mesh.dxf";
    Mesh mesh;
    mesh.name = "terrain";
    mesh.vertices.resize(4);
    mesh.vertices.positions()[1] = Eigen::Vector3f(1, 0, 0);
    mesh.vertices.positions()[2] = Eigen::Vector3f(0, 1, 0);
    mesh.vertices.positions()[3] = Eigen::Vector3f(1, 1, 0.5f);
    mesh.triangles = {{0, 1, 2}, {1, 3, 2}};
    io::writeMesh(dxfRegistry(), mesh, file);

    const DxfCheck check = checkDxf(file);
    ASSERT_EQ(check.exitStatus, 0);
    EXPECT_EQ(check.count("3DFACE@terrain"), 2);
    EXPECT_EQ(check.count("total"), 2);
}

TEST(DxfFormat, AFileWithoutSurfacesIsAClearError)
{
    // Reading takes meshes (DxfReaderTest.cpp); a drawing without one says so.
    const fs::path file = test::tempDir() / "in.dxf";
    test::writeText(file, "  0\nEOF\n");
    expectErrorCode([&] { io::readPointCloud(dxfRegistry(), file); }, ErrorCode::InvalidData);
}

} // namespace
