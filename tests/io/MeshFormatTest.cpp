// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/io/FileIO.h>

#include "TestSupport.h"
#include "internal/Formats.h"

#include <map>
#include <set>

using namespace scandiff;

namespace {

io::FormatRegistry meshFormats()
{
    io::FormatRegistry registry;
    registry.add(io::detail::meshFormat());
    return registry;
}

//! A unit square pyramid: 5 vertices, 6 triangles.
Mesh pyramid(const Eigen::Vector3d& origin = Eigen::Vector3d::Zero())
{
    Mesh m;
    m.vertices.setOrigin(origin);
    m.vertices.resize(5);
    m.vertices.positions() = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, 1}};
    m.triangles = {{0, 2, 1}, {0, 3, 2}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
    return m;
}

//! Triangles as sets of global corner coordinates, independent of vertex order.
std::multiset<std::vector<long long>> corners(const Mesh& m, double resolution)
{
    std::multiset<std::vector<long long>> out;
    for (const auto& t : m.triangles) {
        std::vector<std::vector<long long>> c;
        for (auto v : t) {
            const Eigen::Vector3d p = m.vertices.globalPosition(v);
            c.push_back({std::llround(p.x() / resolution), std::llround(p.y() / resolution), std::llround(p.z() / resolution)});
        }
        // Rotate so the smallest corner comes first: keeps the winding, drops the start.
        const auto first = std::min_element(c.begin(), c.end()) - c.begin();
        std::vector<long long> key;
        for (int i = 0; i < 3; ++i)
            key.insert(key.end(), c[static_cast<std::size_t>((first + i) % 3)].begin(), c[static_cast<std::size_t>((first + i) % 3)].end());
        out.insert(key);
    }
    return out;
}

} // namespace

TEST(MeshFormats, RoundTripObjStlOff)
{
    const auto registry = meshFormats();
    const Mesh original = pyramid();
    const auto dir = test::tempDir();
    for (const char* name : {"p.obj", "p.stl", "p.off"}) {
        io::writeMesh(registry, original, dir / name);
        const Mesh back = io::readMesh(registry, dir / name);
        EXPECT_EQ(back.triangles.size(), 6u) << name;
        EXPECT_EQ(back.vertices.size(), 5u) << name << ": shared vertices are merged";
        EXPECT_EQ(corners(back, 1e-6), corners(original, 1e-6)) << name;
    }
}

TEST(MeshFormats, AsciiStlRoundTrip)
{
    const auto registry = meshFormats();
    const auto dir = test::tempDir();
    io::WriteOptions options;
    options.encoding = io::Encoding::Ascii;
    io::writeMesh(registry, pyramid(), dir / "p.stl", options);
    EXPECT_EQ(test::readBytes(dir / "p.stl").rfind("solid", 0), 0u);
    EXPECT_EQ(corners(io::readMesh(registry, dir / "p.stl"), 1e-6), corners(pyramid(), 1e-6));
}

TEST(MeshFormats, ObjQuadsAreTriangulated)
{
    const auto registry = meshFormats();
    const auto path = test::tempDir() / "quad.obj";
    test::writeText(path, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    const Mesh m = io::readMesh(registry, path);
    EXPECT_EQ(m.triangles.size(), 2u);
}

TEST(MeshFormats, GeoreferencedObjWritesFullPrecision)
{
    const auto registry = meshFormats();
    const auto path = test::tempDir() / "utm.obj";
    io::writeMesh(registry, pyramid({512345.678, 5423456.789, 100.0}), path);
    // The text carries every digit, and reading keeps them (MeshFormats.ReadingKeepsDoublePrecision).
    EXPECT_NE(test::readBytes(path).find("v 512345.678 5423456.789 100"), std::string::npos);
}

TEST(MeshFormats, DegenerateTrianglesAreKept)
{
    const auto registry = meshFormats();
    Mesh m = pyramid();
    m.triangles.push_back({0, 1, 1});
    m.triangles.push_back({0, 1, 0});
    const auto path = test::tempDir() / "degenerate.off";
    io::writeMesh(registry, m, path);
    const Mesh back = io::readMesh(registry, path);
    EXPECT_GE(back.triangles.size(), 6u);
    EXPECT_EQ(back.countDegenerateTriangles() + 6, back.triangles.size());
}

TEST(MeshFormats, GarbageAndPointOnlyFilesAreErrors)
{
    const auto registry = meshFormats();
    const auto dir = test::tempDir();
    test::writeText(dir / "garbage.obj", "this is not an obj file\n\x01\x02\x03");
    test::writeText(dir / "points.obj", "v 0 0 0\nv 1 0 0\n");
    test::writeText(dir / "bad.off", "OFF\n3 1 0\n0 0 0\n1 0\n");
    test::writeText(dir / "truncated.stl", std::string(80, ' ') + std::string("\x05\x00\x00\x00", 4) + std::string(20, '\0'));
    for (const char* name : {"garbage.obj", "points.obj", "bad.off", "truncated.stl"}) {
        try {
            io::readMesh(registry, dir / name);
            ADD_FAILURE() << name << " was accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ErrorCode::InvalidData) << name << ": " << e.what();
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        }
    }
}

TEST(MeshFormats, ReadingKeepsDoublePrecision)
{
    // OBJ and OFF carry doubles: a UTM vertex comes back to the micrometre
    // when read in its own frame (through float, as assimp read them, it was
    // off by up to 9 mm whatever the frame).
    const auto registry = meshFormats();
    const Mesh original = pyramid({512345.678, 5423456.789, 100.0});
    io::ReadOptions sameFrame;
    sameFrame.origin = original.vertices.origin();
    for (const char* name : {"utm.obj", "utm.off"}) {
        const auto path = test::tempDir() / name;
        io::writeMesh(registry, original, path);
        const Mesh back = io::readMesh(registry, path, sameFrame);
        ASSERT_EQ(back.vertices.size(), 5u) << name;
        for (std::size_t i = 0; i < 5; ++i)
            ASSERT_LT((back.vertices.globalPosition(i) - original.vertices.globalPosition(i)).norm(), 1e-6) << name << " vertex " << i;
    }
}

TEST(MeshFormats, ObjIndexFormsPolygonsColoursAndNormals)
{
    const auto registry = meshFormats();
    const auto dir = test::tempDir();
    // 1-based and negative indices, v/t/n, v//n and v forms, a quad (two
    // triangles), vertex colours, a comment after the values, statements read past.
    test::writeText(dir / "forms.obj", "mtllib x.mtl\no thing\n"
                                       "v 0 0 0 1 0 0\nv 1 0 0 0 1 0 # a comment\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\n"
                                       "vt 0 0\nvn 0 0 1\ng side\nusemtl a\ns off\n"
                                       "f 1/1/1 2/1/1 3/1/1\nf -4//1 -2//1 -1//1\nf 1//1 2//1 3//1 4//1\n");
    const Mesh m = io::readMesh(registry, dir / "forms.obj");
    ASSERT_EQ(m.vertices.size(), 4u);
    ASSERT_EQ(m.triangles.size(), 4u);
    EXPECT_EQ(m.triangles[1], (Triangle{0, 2, 3}));
    EXPECT_EQ(m.triangles[2], (Triangle{0, 1, 2}));
    EXPECT_EQ(m.triangles[3], (Triangle{0, 2, 3}));
    ASSERT_TRUE(m.vertices.hasColors());
    EXPECT_EQ(m.vertices.colors()[1], (Rgb8{0, 255, 0}));
    ASSERT_TRUE(m.vertices.hasNormals());
    EXPECT_EQ(m.vertices.normals()[3], Eigen::Vector3f(0, 0, 1));
    // Wrong indices name the line.
    test::writeText(dir / "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
    test::writeText(dir / "ahead.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n");
    test::writeText(dir / "normal.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n");
    for (const char* name : {"zero.obj", "ahead.obj", "normal.obj"})
        EXPECT_EQ(test::errorCodeOf([&] { io::readMesh(registry, dir / name); }), ErrorCode::InvalidData) << name;
    try {
        io::readMesh(registry, dir / "ahead.obj");
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
    }
}

TEST(MeshFormats, OffVariants)
{
    const auto registry = meshFormats();
    const auto dir = test::tempDir();
    // Counts on the first line, comments, a quad, an edge (no surface: read
    // past), normals and colours (0..255 integers, and 0..1 reals).
    test::writeText(dir / "counts.off", "OFF 4 3 0\n# corners\n0 0 0\n1 0 0\n1 1 0 # third\n0 1 0\n4 0 1 2 3\n2 0 1\n3 0 1 3\n");
    const Mesh counts = io::readMesh(registry, dir / "counts.off");
    EXPECT_EQ(counts.vertices.size(), 4u);
    EXPECT_EQ(counts.triangles.size(), 3u);
    test::writeText(dir / "cn.off", "CNOFF\n3 1 0\n0 0 0 0 0 1 255 0 0 255\n1 0 0 0 0 1 0 255 0 255\n0 1 0 0 0 1 0 0 255 255\n3 0 1 2\n");
    const Mesh cn = io::readMesh(registry, dir / "cn.off");
    ASSERT_TRUE(cn.vertices.hasNormals() && cn.vertices.hasColors());
    EXPECT_EQ(cn.vertices.colors()[1], (Rgb8{0, 255, 0}));
    EXPECT_EQ(cn.vertices.normals()[2], Eigen::Vector3f(0, 0, 1));
    test::writeText(dir / "reals.off", "COFF\n3 1 0\n0 0 0 1 0 0\n1 0 0 0 0.5 0\n0 1 0 0 0 1\n3 0 1 2\n");
    EXPECT_EQ(io::readMesh(registry, dir / "reals.off").vertices.colors()[1], (Rgb8{0, 128, 0}));
    // Lying counts are refused before anything is allocated; bad indices name the line.
    test::writeText(dir / "lying.off", "OFF\n4000000000 1 0\n0 0 0\n");
    test::writeText(dir / "wide.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2000000000 0 1 2\n");
    test::writeText(dir / "index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
    test::writeText(dir / "binary.off", "OFF BINARY\n3 1 0\n");
    for (const char* name : {"lying.off", "wide.off", "index.off", "binary.off"}) {
        try {
            io::readMesh(registry, dir / name);
            ADD_FAILURE() << name << " was accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ErrorCode::InvalidData) << e.what();
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        }
    }
}

TEST(MeshFormats, StlBinaryStartingWithSolidAndMergedCorners)
{
    // Many binary STL headers start with "solid": the size decides.
    const auto registry = meshFormats();
    const auto dir = test::tempDir();
    io::writeMesh(registry, pyramid(), dir / "p.stl");
    std::string bytes = test::readBytes(dir / "p.stl");
    bytes.replace(0, 5, "solid");
    test::writeText(dir / "solid.stl", bytes);
    const Mesh m = io::readMesh(registry, dir / "solid.stl");
    EXPECT_EQ(m.triangles.size(), 6u);
    EXPECT_EQ(m.vertices.size(), 5u); // corners shared by facets merged
    EXPECT_FALSE(m.vertices.hasNormals());
    // One byte short is neither binary nor ASCII.
    test::writeText(dir / "short.stl", bytes.substr(0, bytes.size() - 1));
    EXPECT_EQ(test::errorCodeOf([&] { io::readMesh(registry, dir / "short.stl"); }), ErrorCode::InvalidData);
}

TEST(MeshFormats, ColoursSurviveObjAndOffRoundTrips)
{
    const auto registry = meshFormats();
    Mesh m = pyramid();
    m.vertices.enableColors() = {{0, 0, 0}, {1, 0, 1}, {255, 128, 7}, {2, 254, 1}, {100, 200, 50}};
    for (const char* name : {"c.obj", "c.off"}) {
        const auto path = test::tempDir() / name;
        io::writeMesh(registry, m, path);
        const Mesh back = io::readMesh(registry, path);
        ASSERT_TRUE(back.vertices.hasColors()) << name;
        EXPECT_EQ(back.vertices.colors(), m.vertices.colors()) << name;
    }
}

TEST(MeshFormats, AsciiStlKeepsFloatPrecisionAtUtmMagnitudes)
{
    // STL is float32; its ASCII form printed six digits (half a metre off at
    // 512 km). Each coordinate now reads back as its float, exactly.
    const auto registry = meshFormats();
    const Mesh original = pyramid({512345.678, 5423456.789, 100.0});
    io::WriteOptions ascii;
    ascii.encoding = io::Encoding::Ascii;
    const auto path = test::tempDir() / "utm.stl";
    io::writeMesh(registry, original, path, ascii);
    const Mesh back = io::readMesh(registry, path);
    ASSERT_EQ(back.vertices.size(), 5u);
    for (std::size_t i = 0; i < 5; ++i) {
        const Eigen::Vector3d p = original.vertices.globalPosition(i);
        const Eigen::Vector3d asFloat(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
        bool found = false;
        for (std::size_t j = 0; j < 5 && !found; ++j)
            found = back.vertices.globalPosition(j) == asFloat;
        EXPECT_TRUE(found) << "vertex " << i;
    }
}
