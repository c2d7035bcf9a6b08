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
    registry.add(io::detail::assimpMeshFormat());
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
    // The text carries every digit; reading goes through assimp's float (documented limit).
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
