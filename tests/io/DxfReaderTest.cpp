// SPDX-License-Identifier: GPL-3.0-or-later
// DXF meshes read back: a file built by hand from the DXF reference, our own
// 3DFACE export, and a file written by ezdxf (tests/data/dxf).

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/DxfReader.h>
#include <scandiff/io/DxfWriter.h>
#include <scandiff/io/FileIO.h>

#include "../support/TestSupport.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <array>
#include <set>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace scandiff;

io::FormatRegistry registry()
{
    io::FormatRegistry r;
    io::registerBuiltinFormats(r);
    return r;
}

//! DXF text from (code, value) pairs.
std::string dxf(const std::vector<std::pair<int, std::string>>& groups)
{
    std::string out;
    for (const auto& [code, value] : groups)
        out += "  " + std::to_string(code) + "\r\n" + value + "\r\n";
    return out;
}

using Groups = std::vector<std::pair<int, std::string>>;

Groups vertex(const std::string& layer, double x, double y, double z, int flags)
{
    return {{0, "VERTEX"}, {8, layer}, {10, std::to_string(x)}, {20, std::to_string(y)}, {30, std::to_string(z)}, {70, std::to_string(flags)}};
}

void append(Groups& to, const Groups& from) { to.insert(to.end(), from.begin(), from.end()); }

//! Every triangle as its three corners in global coordinates, sorted, so two
//! meshes compare whatever their vertex order.
std::multiset<std::array<std::array<double, 3>, 3>> triangleSet(const Mesh& mesh)
{
    std::multiset<std::array<std::array<double, 3>, 3>> out;
    for (const Triangle& t : mesh.triangles) {
        std::array<std::array<double, 3>, 3> corners{};
        for (int k = 0; k < 3; ++k) {
            const Eigen::Vector3d p = mesh.vertices.globalPosition(t[static_cast<std::size_t>(k)]);
            corners[static_cast<std::size_t>(k)] = {p.x(), p.y(), p.z()};
        }
        std::sort(corners.begin(), corners.end());
        out.insert(corners);
    }
    return out;
}

} // namespace

TEST(DxfReader, FacesPolyfacesAndPolygonMeshesOfTheEntitiesSection)
{
    Groups g = {{0, "SECTION"}, {2, "HEADER"}, {0, "ENDSEC"},
                // A block's face is not a model face (its INSERT is reported, not expanded).
                {0, "SECTION"}, {2, "BLOCKS"}, {0, "BLOCK"}, {8, "0"}, {2, "B"}, {0, "3DFACE"}, {8, "0"},
                {10, "9"}, {20, "9"}, {30, "9"}, {11, "8"}, {21, "9"}, {31, "9"}, {12, "8"}, {22, "8"}, {32, "9"},
                {0, "ENDBLK"}, {0, "ENDSEC"},
                {0, "SECTION"}, {2, "ENTITIES"},
                // A triangle (no fourth corner) and a quadrilateral sharing its edge, layer WALL.
                {0, "3DFACE"}, {8, "WALL"}, {10, "0"}, {20, "0"}, {30, "0"}, {11, "1"}, {21, "0"}, {31, "0"},
                {12, "1"}, {22, "1"}, {32, "0"},
                {0, "3DFACE"}, {8, "WALL"}, {10, "1"}, {20, "0"}, {30, "0"}, {11, "2"}, {21, "0"}, {31, "0"},
                {12, "2"}, {22, "1"}, {32, "0"}, {13, "1"}, {23, "1"}, {33, "0"},
                {0, "LINE"}, {8, "WALL"}, {10, "0"}, {20, "0"}, {30, "0"}, {11, "5"}, {21, "5"}, {31, "5"},
                {0, "INSERT"}, {2, "B"}, {10, "0"}, {20, "0"}, {30, "0"},
                // A polyface tetrahedron, layer BOX: 4 vertices, 4 faces (one with an invisible edge).
                {0, "POLYLINE"}, {8, "BOX"}, {66, "1"}, {70, "64"}, {71, "4"}, {72, "4"}};
    append(g, vertex("BOX", 10, 0, 0, 192));
    append(g, vertex("BOX", 11, 0, 0, 192));
    append(g, vertex("BOX", 10, 1, 0, 192));
    append(g, vertex("BOX", 10, 0, 1, 192));
    for (const std::array<int, 3>& f : {std::array<int, 3>{1, 2, 3}, {1, 2, -4}, {2, 3, 4}, {3, 1, 4}}) {
        Groups face = {{0, "VERTEX"}, {8, "BOX"}, {10, "0"}, {20, "0"}, {30, "0"}, {70, "128"},
                       {71, std::to_string(f[0])}, {72, std::to_string(f[1])}, {73, std::to_string(f[2])}};
        append(g, face);
    }
    append(g, {{0, "SEQEND"},
               // A 2 x 3 polygon mesh closed in N, layer GROUND: 2 quads per row pair plus the closing one.
               {0, "POLYLINE"}, {8, "GROUND"}, {66, "1"}, {70, "48"}, {71, "2"}, {72, "3"}});
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 3; ++j)
            append(g, vertex("GROUND", 20 + i, j, 0.5 * i * j, 64));
    append(g, {{0, "SEQEND"}, {0, "ENDSEC"}, {0, "EOF"}});

    const fs::path file = test::tempDir() / "model.dxf";
    test::writeText(file, dxf(g));
    test::CapturedLog log;
    const Mesh mesh = io::readMesh(registry(), file);
    // 1 + 2 (the quad) + 4 (tetrahedron) + 2 x 3 (three quads of the closed mesh).
    ASSERT_EQ(mesh.triangles.size(), 13u);
    // The two faces share two corners: 3 + 2 vertices, then 4, then 6.
    ASSERT_EQ(mesh.vertices.size(), 15u);
    EXPECT_TRUE(log.has("1 block references (INSERT) were not expanded"));
    EXPECT_TRUE(log.has("0 = WALL, 1 = BOX, 2 = GROUND"));
    const ScalarField* layer = mesh.vertices.field("dxf_layer");
    ASSERT_NE(layer, nullptr);
    std::vector<int> perLayer(3, 0);
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
        ++perLayer[static_cast<std::size_t>(layer->value(i))];
    EXPECT_EQ(perLayer, (std::vector<int>{5, 4, 6}));
    // The closing quad of the polygon mesh joins column 2 to column 0.
    const auto triangles = triangleSet(mesh);
    EXPECT_EQ(triangles.count({{{20, 0, 0}, {20, 2, 0}, {21, 0, 0}}}) + triangles.count({{{20, 2, 0}, {21, 0, 0}, {21, 2, 1}}}), 2u);
}

TEST(DxfReader, OurExportAndEzdxfsFilesReadBack)
{
    // A georeferenced mesh through our 3DFACE export and back: the same
    // triangles, every coordinate to the digit the export wrote.
    Mesh mesh;
    mesh.vertices.setOrigin({652000.0, 5120000.0, 300.0});
    mesh.vertices.resize(5);
    mesh.vertices.positions() = {{0, 0, 0}, {1.25f, 0, 0}, {1.25f, 2.5f, 0.5f}, {0, 2.5f, 0.75f}, {0.5f, 1, 3}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}, {1, 2, 4}};
    const fs::path ours = test::tempDir() / "ours.dxf";
    io::writeMesh(registry(), mesh, ours);
    const Mesh back = io::readMesh(registry(), ours);
    EXPECT_EQ(triangleSet(back), triangleSet(mesh));

    // ezdxf 0.18.1: a polyface cube (6 quads), a 3 x 4 polygon mesh (6 quads),
    // a 3DFACE triangle and a quadrilateral.
    const Mesh ez = io::readMesh(registry(), test::dataPath("dxf/ezdxf-meshes.dxf"));
    EXPECT_EQ(ez.triangles.size(), 12u + 12u + 1u + 2u);
    EXPECT_EQ(ez.vertices.size(), 8u + 12u + 3u + 4u);
    // The top of the cube: two triangles at z = 302 over its four corners.
    std::set<std::array<double, 3>> top;
    std::size_t topTriangles = 0;
    for (const auto& t : triangleSet(ez))
        if (t[0][2] == 302 && t[1][2] == 302 && t[2][2] == 302) {
            ++topTriangles;
            top.insert(t.begin(), t.end());
        }
    EXPECT_EQ(topTriangles, 2u);
    EXPECT_EQ(top, (std::set<std::array<double, 3>>{{652000, 5120000, 302}, {652002, 5120000, 302}, {652002, 5120002, 302},
                                                    {652000, 5120002, 302}}));
    // The corner of the polygon mesh at i = 2, j = 3 (z = 300 + 0.125 * 6).
    bool corner = false;
    for (std::size_t i = 0; i < ez.vertices.size(); ++i)
        corner = corner || ez.vertices.globalPosition(i).isApprox(Eigen::Vector3d(652012, 5120003, 300.75), 1e-12);
    EXPECT_TRUE(corner);
}

TEST(DxfReader, BrokenFilesAreClearErrors)
{
    const fs::path dir = test::tempDir();
    auto expectError = [&](const std::string& name, const std::string& text, ErrorCode code, const std::string& words) {
        const fs::path file = dir / name;
        test::writeText(file, text);
        try {
            io::readMesh(registry(), file);
            ADD_FAILURE() << name << ": no error";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), code) << e.what();
            EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
        }
    };
    const Groups start = {{0, "SECTION"}, {2, "ENTITIES"}};
    Groups g = start;
    append(g, {{0, "POLYLINE"}, {70, "64"}});
    append(g, vertex("0", 0, 0, 0, 192));
    append(g, {{0, "VERTEX"}, {70, "128"}, {71, "1"}, {72, "2"}, {73, "3"}, {0, "SEQEND"}, {0, "ENDSEC"}, {0, "EOF"}});
    expectError("index.dxf", dxf(g), ErrorCode::InvalidData, "uses vertex 2 of 1");
    g = start;
    append(g, {{0, "POLYLINE"}, {70, "16"}, {71, "3"}, {72, "3"}});
    append(g, vertex("0", 0, 0, 0, 64));
    append(g, {{0, "SEQEND"}, {0, "ENDSEC"}});
    expectError("grid.dxf", dxf(g), ErrorCode::InvalidData, "3 x 3 vertices has 1");
    g = start;
    append(g, {{0, "3DFACE"}, {10, "1e999"}, {20, "0"}, {30, "0"}, {0, "ENDSEC"}});
    expectError("inf.dxf", dxf(g), ErrorCode::InvalidData, "must be a finite number");
    expectError("code.dxf", "  0\nSECTION\nxx\nENTITIES\n", ErrorCode::InvalidData, "line 3: a group code must be an integer");
    expectError("cut.dxf", "  0\nSECTION\n  2\n", ErrorCode::InvalidData, "without its value");
    expectError("lines.dxf", dxf({{0, "SECTION"}, {2, "ENTITIES"}, {0, "LINE"}, {0, "ENDSEC"}}), ErrorCode::InvalidData,
                "no surface");
    expectError("binary.dxf", std::string("AutoCAD Binary DXF\r\n\x1a\0", 22), ErrorCode::Unsupported, "binary DXF");
}

TEST(DxfDrawingReader, LinesOfEveryKindInWorldCoordinates)
{
    // ezdxf's file (tests/data/dxf/README.md); the object coordinate system
    // of the vertical square as ezdxf computes it.
    test::CapturedLog log;
    const Drawing drawing = io::readDrawingDxf(std::filesystem::path(SCANDIFF_TEST_DATA_DIR) / "dxf" / "ezdxf-lines.dxf");
    std::map<std::string, const DrawingPolyline*> byLayer;
    for (const DrawingPolyline& p : drawing.polylines)
        byLayer[p.layer] = &p;
    ASSERT_EQ(drawing.polylines.size(), 6u); // the polyface mesh is not a line
    const DrawingPolyline& square = *byLayer.at("SQUARE");
    EXPECT_TRUE(square.closed);
    ASSERT_EQ(square.points.size(), 4u);
    EXPECT_EQ(square.points[2], Eigen::Vector3d(4, 3, 2));
    const DrawingPolyline& vertical = *byLayer.at("VERTICAL");
    const std::vector<Eigen::Vector3d> expected{{5, 1, 1}, {5, 2, 1}, {5, 2, 2}, {5, 1, 2}};
    ASSERT_EQ(vertical.points.size(), 4u);
    for (std::size_t i = 0; i < 4; ++i)
        EXPECT_LT((vertical.points[i] - expected[i]).norm(), 1e-12) << i;
    // The half circle (bulge 1, counter-clockwise from (0,0) to (2,0) seen
    // from +z) passes through (1,-1).
    const DrawingPolyline& arc = *byLayer.at("ARC");
    EXPECT_FALSE(arc.closed);
    ASSERT_EQ(arc.bulges.size(), 2u);
    EXPECT_EQ(arc.bulges[0], 1.0);
    EXPECT_EQ(arc.normal, Eigen::Vector3d::UnitZ());
    const std::vector<Eigen::Vector3d> along = polylineVertices(arc, 2.0);
    EXPECT_EQ(along.size(), 2u + 89u); // 90 steps of 2 degrees
    for (const Eigen::Vector3d& p : along)
        EXPECT_NEAR((p - Eigen::Vector3d(1, 0, 0)).norm(), 1.0, 1e-12);
    EXPECT_LT((along[45] - Eigen::Vector3d(1, -1, 0)).norm(), 1e-12);
    EXPECT_EQ(byLayer.at("P3D")->points[2], Eigen::Vector3d(1, 1, 2));
    EXPECT_TRUE(byLayer.at("P3D")->closed);
    EXPECT_EQ(byLayer.at("P2D")->points[1], Eigen::Vector3d(1, 0, 7));
    EXPECT_EQ(byLayer.at("LINES")->points[1], Eigen::Vector3d(1, 2, 3));
    ASSERT_EQ(drawing.texts.size(), 1u);
    EXPECT_EQ(drawing.texts[0].text, "hello");
    EXPECT_EQ(drawing.texts[0].position, Eigen::Vector3d(1, 2, 3));
}

TEST(DxfDrawingReader, WhatOurWriterWritesReadsBack)
{
    Drawing drawing;
    drawing.polylines.push_back({"A", {{512000.125, 5423000.5, 101.25}, {512001, 5423000.5, 101.25}, {512001, 5423001, 102}}, true});
    drawing.polylines.push_back({"B", {{0, 0, 0}, {1, 1, 1}}, false});
    const auto file = test::tempDir() / "drawing.dxf";
    io::writeDrawingDxf(drawing, file);
    const Drawing back = io::readDrawingDxf(file);
    ASSERT_EQ(back.polylines.size(), 2u);
    EXPECT_EQ(back.polylines[0].points, drawing.polylines[0].points); // 6 decimals hold these exactly
    EXPECT_TRUE(back.polylines[0].closed);
    EXPECT_FALSE(back.polylines[1].closed);
    // Arcs: a closed quarter-disc on a vertical plane turned 30 degrees at
    // UTM coordinates (a normal that 6 decimals would turn), written as a 2D
    // polyline with a bulge in its object coordinate system, read back with
    // the same vertices, bulges and plane, its arc on its circle.
    Drawing arcs;
    const Eigen::Vector3d o(512000.25, 5423000.5, 101.0), u(std::cos(0.5235987755982988), std::sin(0.5235987755982988), 0.0),
        up = Eigen::Vector3d::UnitZ();
    DrawingPolyline quarter{"ARCS", {o, o + 2.0 * u, o + 2.0 * up}, true};
    quarter.normal = u.cross(up);
    quarter.bulges = {0.0, std::tan(3.14159265358979323846 / 8), 0.0}; // 90 degrees, counter-clockwise
    arcs.polylines.push_back(quarter);
    const auto arcFile = file.parent_path() / "arcs.dxf";
    io::writeDrawingDxf(arcs, arcFile);
    const Drawing arcsBack = io::readDrawingDxf(arcFile);
    ASSERT_EQ(arcsBack.polylines.size(), 1u);
    const DrawingPolyline& q = arcsBack.polylines[0];
    ASSERT_EQ(q.points.size(), 3u);
    for (std::size_t i = 0; i < 3; ++i)
        EXPECT_LT((q.points[i] - quarter.points[i]).norm(), 2e-6) << i; // 6 decimals in the object system
    ASSERT_EQ(q.bulges.size(), 3u);
    EXPECT_EQ(q.bulges[1], quarter.bulges[1]); // written in full
    EXPECT_LT((q.normal - quarter.normal).norm(), 1e-12);
    const std::vector<Eigen::Vector3d> along = polylineVertices(q);
    ASSERT_EQ(along.size(), 3u + 44u); // 45 steps of 2 degrees
    for (std::size_t i = 1; i < along.size() - 1; ++i) {
        EXPECT_LT(std::abs((along[i] - o).dot(quarter.normal)), 2e-6) << i; // in its plane
        EXPECT_NEAR((along[i] - o).norm(), 2.0, 2e-6) << i;                // on its circle about o
    }
    // Damaged: a vertex coordinate that is not a number names its line.
    const auto bad = file.parent_path() / "bad.dxf";
    std::ofstream(bad) << "0\nSECTION\n2\nENTITIES\n0\nLWPOLYLINE\n8\nA\n90\n2\n10\n1.0\n20\nabc\n0\nENDSEC\n0\nEOF\n";
    EXPECT_EQ(test::errorCodeOf([&] { io::readDrawingDxf(bad); }), ErrorCode::InvalidData);
}
