// SPDX-License-Identifier: GPL-3.0-or-later
#include "internal/Formats.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/FileIO.h>

#include "TestSupport.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace scandiff::test {
namespace {

namespace fs = std::filesystem;

io::FormatRegistry plyRegistry()
{
    io::FormatRegistry registry;
    registry.add(io::detail::plyFormat());
    return registry;
}

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

//! A cloud with every attribute the writer handles, NaN field values included.
PointCloud makeCloud(std::size_t n)
{
    PointCloud cloud;
    cloud.resize(n);
    auto& colors = cloud.enableColors();
    auto& normals = cloud.enableNormals();
    // References only once both exist: addField may move the fields.
    cloud.addField("intensity");
    cloud.addField("distance");
    ScalarField& intensity = *cloud.field("intensity");
    ScalarField& distance = *cloud.field("distance");
    for (std::size_t i = 0; i < n; ++i) {
        const float t = static_cast<float>(i);
        cloud.positions()[i] = Eigen::Vector3f(0.125f * t, -3.7f + t, 1000.001f - 0.3f * t);
        colors[i] = Rgb8{static_cast<std::uint8_t>(i * 7), static_cast<std::uint8_t>(255 - i), static_cast<std::uint8_t>(i % 3)};
        normals[i] = Eigen::Vector3f(0.6f, -0.8f, 0.0f);
        intensity.values()[i] = 0.1f * t;
        distance.values()[i] = (i % 4 == 1) ? kNaN : -1.5f * t;
    }
    return cloud;
}

void expectSameCloud(const PointCloud& expected, const PointCloud& actual)
{
    ASSERT_EQ(expected.size(), actual.size());
    ASSERT_EQ(expected.hasColors(), actual.hasColors());
    ASSERT_EQ(expected.hasNormals(), actual.hasNormals());
    ASSERT_EQ(expected.fields().size(), actual.fields().size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
        EXPECT_EQ(expected.positions()[i], actual.positions()[i]) << "point " << i;
        if (expected.hasColors()) {
            EXPECT_EQ(expected.colors()[i], actual.colors()[i]) << "point " << i;
        }
        if (expected.hasNormals()) {
            EXPECT_EQ(expected.normals()[i], actual.normals()[i]) << "point " << i;
        }
    }
    for (const auto& field : expected.fields()) {
        const ScalarField* read = actual.field(field.name());
        ASSERT_NE(read, nullptr) << field.name();
        for (std::size_t i = 0; i < field.size(); ++i) {
            if (std::isnan(field.values()[i]))
                EXPECT_TRUE(std::isnan(read->values()[i])) << field.name() << " " << i;
            else
                EXPECT_EQ(field.values()[i], read->values()[i]) << field.name() << " " << i;
        }
    }
}

template <class Action>
void expectError(Action&& action, ErrorCode code, const std::vector<std::string>& fragments)
{
    try {
        action();
        FAIL() << "no exception was thrown";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), code) << e.what();
        for (const auto& fragment : fragments)
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos)
                << "'" << fragment << "' not in: " << e.what();
    }
}

void expectReadError(const fs::path& path, const std::vector<std::string>& fragments)
{
    std::vector<std::string> all = fragments;
    all.push_back(path.string());
    const auto registry = plyRegistry();
    expectError([&] { io::readFile(registry, path); }, ErrorCode::InvalidData, all);
}

//! Little- or big-endian binary bytes for hand-made files.
class Bytes
{
public:
    explicit Bytes(bool bigEndian) : big_(bigEndian) {}
    template <typename T>
    Bytes& put(T value)
    {
        char raw[sizeof(T)];
        std::memcpy(raw, &value, sizeof(T));
        for (std::size_t i = 0; i < sizeof(T); ++i)
            data_ += raw[big_ ? sizeof(T) - 1 - i : i];
        return *this;
    }
    const std::string& str() const { return data_; }

private:
    bool big_;
    std::string data_;
};

class CaptureLog
{
public:
    CaptureLog()
    {
        previous_ = setLogSink([this](LogLevel level, const std::string& message) {
            if (level == LogLevel::Warning)
                warnings.push_back(message);
        });
    }
    ~CaptureLog() { setLogSink(previous_); }
    std::vector<std::string> warnings;

private:
    LogSink previous_;
};

class CancelAfter : public ProgressObserver
{
public:
    explicit CancelAfter(int reports) : remaining_(reports) {}
    void beginStage(const std::string&) override {}
    void report(double) override { --remaining_; }
    bool cancelRequested() const override { return remaining_ <= 0; }

private:
    int remaining_;
};

// ---------------------------------------------------------------- round trips

class PlyEncodingTest : public ::testing::TestWithParam<io::Encoding>
{
};

TEST_P(PlyEncodingTest, CloudRoundTripKeepsEveryAttribute)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "cloud.ply";
    const PointCloud cloud = makeCloud(100);
    io::WriteOptions options;
    options.encoding = GetParam();
    io::writePointCloud(registry, cloud, path, options);

    const std::string bytes = readBytes(path);
    const char* format = GetParam() == io::Encoding::Ascii             ? "format ascii 1.0"
                         : GetParam() == io::Encoding::BinaryBigEndian ? "format binary_big_endian 1.0"
                                                                       : "format binary_little_endian 1.0";
    EXPECT_NE(bytes.find(format), std::string::npos);
    EXPECT_NE(bytes.find("property float x\n"), std::string::npos);

    const PointCloud read = io::readPointCloud(registry, path);
    EXPECT_EQ(read.name, "cloud");
    EXPECT_EQ(read.origin(), Eigen::Vector3d::Zero());
    expectSameCloud(cloud, read);
}

TEST_P(PlyEncodingTest, UtmCloudKeepsMillimetres)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "utm.ply";
    PointCloud cloud;
    cloud.resize(3);
    cloud.setOrigin(Eigen::Vector3d(512000.0, 5423000.0, 0.0));
    cloud.positions()[0] = Eigen::Vector3f(345.678f, 456.789f, 312.345f);
    cloud.positions()[1] = Eigen::Vector3f(1.001f, 2.002f, 3.003f);
    cloud.positions()[2] = Eigen::Vector3f(999.999f, 0.0f, 5.5f);
    ScalarField gpsTime("gps_time", 3);
    gpsTime.setOffset(1.3e9);
    gpsTime.values() = {0.25f, 1.5f, 12.125f};
    cloud.addField(std::move(gpsTime));

    io::WriteOptions options;
    options.encoding = GetParam();
    io::writePointCloud(registry, cloud, path, options);
    const std::string bytes = readBytes(path);
    EXPECT_NE(bytes.find("property double x\n"), std::string::npos);
    EXPECT_NE(bytes.find("property double gps_time\n"), std::string::npos);

    const PointCloud read = io::readPointCloud(registry, path);
    ASSERT_EQ(read.size(), 3u);
    EXPECT_EQ(read.origin(), Eigen::Vector3d(512000.0, 5423000.0, 0.0));
    for (std::size_t i = 0; i < 3; ++i)
        EXPECT_LT((read.globalPosition(i) - cloud.globalPosition(i)).norm(), 1e-3) << i;
    EXPECT_NEAR(read.globalPosition(0).x(), 512345.678, 1e-3);
    EXPECT_NEAR(read.globalPosition(0).y(), 5423456.789, 1e-3);
    const ScalarField* readTime = read.field("gps_time");
    ASSERT_NE(readTime, nullptr);
    EXPECT_GT(readTime->offset(), 1e9);
    for (std::size_t i = 0; i < 3; ++i)
        EXPECT_NEAR(readTime->value(i), cloud.field("gps_time")->value(i), 1e-4) << i;
}

TEST(PlyFormat, AScanAsASurveyorHasItCostsThirtyOneBytesAPoint)
{
    // A terrestrial scan as scanners export it (and as scandiff-make-scan
    // writes it): double coordinates far from the origin, RGB, intensity,
    // classification and GPS time in double. Held: positions 12 bytes,
    // colours 3, intensity and class 4 each as floats, GPS time 4 + 4 (its
    // float view and the float residual that gives its doubles back): 31.
    // (The workbench's own bytes are asserted in its Qt test.)
    constexpr std::size_t kPoints = 200'000;
    const fs::path path = tempDir() / "survey.ply";
    {
        std::ofstream out(path, std::ios::binary);
        out << "ply\nformat binary_little_endian 1.0\nelement vertex " << kPoints
            << "\nproperty double x\nproperty double y\nproperty double z\nproperty uchar red\nproperty uchar green\n"
               "property uchar blue\nproperty float intensity\nproperty float classification\nproperty double gps_time\n"
               "end_header\n";
        for (std::size_t i = 0; i < kPoints; ++i) {
            const double xyz[3] = {512000.0 + 0.001 * static_cast<double>(i % 1000), 5423000.0 + 0.003 * static_cast<double>(i / 1000),
                                   112.5 + 1e-4 * static_cast<double>(i % 77)};
            const unsigned char rgb[3] = {static_cast<unsigned char>(i), static_cast<unsigned char>(i >> 8), 7};
            const float intensity = static_cast<float>(i % 4096), classification = static_cast<float>(i % 7);
            const double time = 3.2e8 + 1.25e-6 * static_cast<double>(i);
            out.write(reinterpret_cast<const char*>(xyz), sizeof xyz);
            out.write(reinterpret_cast<const char*>(rgb), sizeof rgb);
            out.write(reinterpret_cast<const char*>(&intensity), sizeof intensity);
            out.write(reinterpret_cast<const char*>(&classification), sizeof classification);
            out.write(reinterpret_cast<const char*>(&time), sizeof time);
        }
    }
    const PointCloud cloud = io::readPointCloud(plyRegistry(), path);
    ASSERT_EQ(cloud.size(), kPoints);
    for (std::size_t i : {std::size_t(0), std::size_t(12345), kPoints - 1})
        EXPECT_EQ(cloud.field("gps_time")->value(i), 3.2e8 + 1.25e-6 * static_cast<double>(i)) << i; // a double stays a double
    EXPECT_LE(cloud.heldBytes(), 31 * kPoints) << static_cast<double>(cloud.heldBytes()) / kPoints << " bytes a point";
}

TEST_P(PlyEncodingTest, MeshRoundTripIsExact)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "mesh.ply";
    Mesh mesh;
    mesh.vertices.resize(5);
    for (std::size_t i = 0; i < 5; ++i)
        mesh.vertices.positions()[i] = Eigen::Vector3f(static_cast<float>(i) * 0.3f, std::sqrt(static_cast<float>(i)), -1.0f);
    mesh.triangles = {{0, 1, 2}, {2, 3, 4}, {4, 3, 0}};
    io::WriteOptions options;
    options.encoding = GetParam();
    io::writeMesh(registry, mesh, path, options);
    EXPECT_NE(readBytes(path).find("property list uchar int vertex_indices\n"), std::string::npos);

    const Mesh read = io::readMesh(registry, path);
    EXPECT_EQ(read.triangles, mesh.triangles);
    expectSameCloud(mesh.vertices, read.vertices);
}

INSTANTIATE_TEST_SUITE_P(AllEncodings, PlyEncodingTest,
                         ::testing::Values(io::Encoding::Ascii, io::Encoding::BinaryLittleEndian,
                                           io::Encoding::BinaryBigEndian));

TEST(PlyFormat, DefaultEncodingIsBinaryLittleEndian)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "default.ply";
    io::writePointCloud(registry, makeCloud(4), path);
    EXPECT_EQ(readBytes(path).rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
}

TEST(PlyFormat, CompressedEncodingIsRefused)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "c.ply";
    io::WriteOptions options;
    options.encoding = io::Encoding::BinaryCompressed;
    expectError([&] { io::writePointCloud(registry, makeCloud(2), path, options); }, ErrorCode::InvalidArgument,
                {path.string()});
    EXPECT_FALSE(fs::exists(path));
}

TEST(PlyFormat, FieldNamesSurviveTheRoundTrip)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "names.ply";
    PointCloud cloud;
    cloud.resize(2);
    cloud.addField("x").values() = {1.0f, 2.0f};
    cloud.addField("scalar_a").values() = {3.0f, 4.0f};
    cloud.addField("Red").values() = {5.0f, 6.0f};
    cloud.addField("distance to ref").values() = {7.0f, 8.0f};
    io::writePointCloud(registry, cloud, path);
    const PointCloud read = io::readPointCloud(registry, path);
    ASSERT_EQ(read.fields().size(), 4u);
    EXPECT_FALSE(read.hasColors());
    ASSERT_NE(read.field("distance_to_ref"), nullptr); // PLY names cannot hold spaces
    ASSERT_NE(read.field("x"), nullptr);
    ASSERT_NE(read.field("scalar_a"), nullptr);
    ASSERT_NE(read.field("Red"), nullptr);
    EXPECT_EQ(read.field("Red")->values()[1], 6.0f);
}

TEST(PlyFormat, RepeatedPropertyNamesAreKeptApartInLinearTime)
{
    // One name four thousand times (a hostile header took 44 s): a, a_2 ... a_4000.
    std::string text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
    for (int i = 0; i < 4000; ++i)
        text += "property float a\n";
    text += "end_header\n0 0 0";
    for (int i = 0; i < 4000; ++i)
        text += " " + std::to_string(i);
    text += "\n";
    const fs::path path = tempDir() / "repeated.ply";
    writeText(path, text);
    const PointCloud read = io::readPointCloud(plyRegistry(), path);
    ASSERT_EQ(read.fields().size(), 4000u);
    EXPECT_EQ(read.field("a")->value(0), 0.0);
    EXPECT_EQ(read.field("a_2")->value(0), 1.0);
    EXPECT_EQ(read.field("a_4000")->value(0), 3999.0);
}

TEST(PlyFormat, ForcedOriginIsUsed)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "forced.ply";
    writeText(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n"
                    "property double z\nend_header\n512345.678 5423456.789 12.5\n");
    io::ReadOptions options;
    options.origin = Eigen::Vector3d(512300.0, 5423400.0, 10.0);
    const PointCloud read = io::readPointCloud(registry, path, options);
    EXPECT_EQ(read.origin(), *options.origin);
    EXPECT_NEAR(read.positions()[0].x(), 45.678f, 1e-4);
    EXPECT_NEAR(read.positions()[0].z(), 2.5f, 1e-6);
}

// ---------------------------------------------------------------- hand-written files

//! Vertex: uchar, short, int, double, float colours; an unknown element with a
//! list property before the vertices; faces with an extra property.
std::string mixedHeader(const char* format)
{
    return std::string("ply\nformat ") + format +
           " 1.0\n"
           "comment hand written\n"
           "obj_info test\n"
           "element material 2\n"
           "property list uchar int ids\n"
           "property float shininess\n"
           "element vertex 3\n"
           "property double x\n"
           "property double y\n"
           "property float z\n"
           "property uchar class\n"
           "property short scalar_height\n"
           "property int count\n"
           "property double gps\n"
           "property float red\n"
           "property float green\n"
           "property float blue\n"
           "property uchar alpha\n"
           "element face 1\n"
           "property uchar flags\n"
           "property list uchar uint vertex_indices\n"
           "element edge 1\n"
           "property int vertex1\n"
           "property int vertex2\n"
           "end_header\n";
}

void checkMixed(const Mesh& mesh)
{
    const PointCloud& v = mesh.vertices;
    ASSERT_EQ(v.size(), 3u);
    EXPECT_EQ(v.origin(), Eigen::Vector3d(512000.0, 5423000.0, 0.0));
    EXPECT_NEAR(v.globalPosition(1).x(), 512345.678, 1e-3);
    EXPECT_NEAR(v.globalPosition(1).y(), 5423456.789, 1e-3);
    EXPECT_NEAR(v.globalPosition(1).z(), 7.25, 1e-6);
    ASSERT_EQ(v.fields().size(), 4u);
    EXPECT_EQ(v.fields()[0].name(), "class");
    EXPECT_EQ(v.fields()[1].name(), "height");
    EXPECT_EQ(v.fields()[2].name(), "count");
    EXPECT_EQ(v.fields()[3].name(), "gps");
    EXPECT_EQ(v.field("class")->value(2), 200.0);
    EXPECT_EQ(v.field("height")->value(1), -1234.0);
    EXPECT_EQ(v.field("count")->value(0), 70000.0);
    EXPECT_NEAR(v.field("gps")->value(2), 1300000002.5, 1e-4);
    ASSERT_TRUE(v.hasColors());
    EXPECT_EQ(v.colors()[0], (Rgb8{255, 128, 0}));
    EXPECT_FALSE(v.hasNormals());
    ASSERT_EQ(mesh.triangles.size(), 1u);
    EXPECT_EQ(mesh.triangles[0], (Triangle{2, 1, 0}));
}

TEST(PlyFormat, MixedTypesAsciiWithUnknownElements)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "mixed.ply";
    writeText(path, mixedHeader("ascii") +
                        "3 1 2 3 0.5\n"
                        "0 0.25\n"
                        "512000.5 5423000.5 1.5 10 100 70000 1300000000.5 1 0.5 0 255\n"
                        "512345.678 5423456.789 7.25 20 -1234 5 1300000001.5 0 0 0 0\n"
                        "+512999 5423999 3 200 7 6 1300000002.5 1 1 1 255\n"
                        "7 3 2 1 0\n"
                        "0 1\n");
    const Mesh mesh = io::readMesh(registry, path);
    checkMixed(mesh);
}

std::string mixedBinary(bool big)
{
    Bytes b(big);
    // materials: lists of 3 and 0 items
    b.put<std::uint8_t>(3).put<std::int32_t>(1).put<std::int32_t>(2).put<std::int32_t>(3).put<float>(0.5f);
    b.put<std::uint8_t>(0).put<float>(0.25f);
    const double xs[3] = {512000.5, 512345.678, 512999};
    const double ys[3] = {5423000.5, 5423456.789, 5423999};
    const float zs[3] = {1.5f, 7.25f, 3.0f};
    const std::uint8_t classes[3] = {10, 20, 200};
    const std::int16_t heights[3] = {100, -1234, 7};
    const std::int32_t counts[3] = {70000, 5, 6};
    const double gps[3] = {1300000000.5, 1300000001.5, 1300000002.5};
    const float rgb[3][3] = {{1.0f, 0.5f, 0.0f}, {0, 0, 0}, {1, 1, 1}};
    for (int i = 0; i < 3; ++i) {
        b.put(xs[i]).put(ys[i]).put(zs[i]).put(classes[i]).put(heights[i]).put(counts[i]).put(gps[i]);
        b.put(rgb[i][0]).put(rgb[i][1]).put(rgb[i][2]).put<std::uint8_t>(255);
    }
    b.put<std::uint8_t>(7).put<std::uint8_t>(3).put<std::uint32_t>(2).put<std::uint32_t>(1).put<std::uint32_t>(0);
    b.put<std::int32_t>(0).put<std::int32_t>(1);
    return b.str();
}

TEST(PlyFormat, MixedTypesBinaryLittleEndianWithUnknownElements)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "mixed.ply";
    writeText(path, mixedHeader("binary_little_endian") + mixedBinary(false));
    checkMixed(io::readMesh(registry, path));
}

TEST(PlyFormat, MixedTypesBinaryBigEndianWithUnknownElements)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "mixed.ply";
    writeText(path, mixedHeader("binary_big_endian") + mixedBinary(true));
    checkMixed(io::readMesh(registry, path));
}

TEST(PlyFormat, TypeAliasesListOnVertexAndCrlfHeader)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "aliases.ply";
    std::string header = "ply\r\nformat binary_little_endian 1.0\r\nelement vertex 2\r\nproperty float32 x\r\n"
                         "property float32 y\r\nproperty float32 z\r\nproperty list uint8 int32 neighbours\r\n"
                         "property uint16 diffuse_red\r\nproperty uint16 diffuse_green\r\nproperty uint16 diffuse_blue\r\n"
                         "property float64 nx\r\nproperty float64 ny\r\nproperty float64 nz\r\n"
                         "property int8 scalar_Label\r\nend_header\r\n";
    Bytes b(false);
    b.put(1.0f).put(2.0f).put(3.0f).put<std::uint8_t>(2).put<std::int32_t>(1).put<std::int32_t>(7);
    b.put<std::uint16_t>(65535).put<std::uint16_t>(0).put<std::uint16_t>(32896);
    b.put(0.0).put(0.0).put(1.0).put<std::int8_t>(-3);
    b.put(4.0f).put(5.0f).put(6.0f).put<std::uint8_t>(0);
    b.put<std::uint16_t>(0).put<std::uint16_t>(65535).put<std::uint16_t>(0);
    b.put(1.0).put(0.0).put(0.0).put<std::int8_t>(4);
    writeText(path, header + b.str());

    const io::Entity entity = io::readFile(registry, path);
    ASSERT_TRUE(std::holds_alternative<PointCloud>(entity));
    const PointCloud& cloud = std::get<PointCloud>(entity);
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.positions()[1], Eigen::Vector3f(4, 5, 6));
    EXPECT_EQ(cloud.colors()[0], (Rgb8{255, 0, 128}));
    EXPECT_EQ(cloud.normals()[1], Eigen::Vector3f(1, 0, 0));
    ASSERT_NE(cloud.field("Label"), nullptr);
    EXPECT_EQ(cloud.field("Label")->value(0), -3.0);
    EXPECT_EQ(cloud.field("Label")->value(1), 4.0);
}

// Records of variable size (a list on the vertex) with colours and normals
// before double coordinates: the pass that finds the origin must see x, y, z
// only, whatever comes before them, in a whole read as in a geometry-only one.
TEST(PlyFormat, OriginOfVariableRecordsComesFromTheCoordinatesAlone)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "variable.ply";
    const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty uchar red\n"
                               "property uchar green\nproperty uchar blue\nproperty float nx\nproperty float ny\n"
                               "property float nz\nproperty double x\nproperty double y\nproperty double z\n"
                               "property list uchar int neighbours\nend_header\n";
    Bytes b(false);
    b.put<std::uint8_t>(255).put<std::uint8_t>(7).put<std::uint8_t>(9).put(0.0f).put(0.0f).put(1.0f);
    b.put(512345.25).put(5401234.5).put(101.125).put<std::uint8_t>(1).put<std::int32_t>(1);
    b.put<std::uint8_t>(3).put<std::uint8_t>(4).put<std::uint8_t>(5).put(1.0f).put(0.0f).put(0.0f);
    b.put(512346.75).put(5401236.0).put(102.5).put<std::uint8_t>(0);
    writeText(path, header + b.str());
    for (const bool geometryOnly : {false, true}) {
        io::ReadOptions options;
        options.geometryOnly = geometryOnly;
        const PointCloud cloud = io::readPointCloud(registry, path, options);
        ASSERT_EQ(cloud.size(), 2u);
        EXPECT_EQ(cloud.origin(), Eigen::Vector3d(512000.0, 5401000.0, 0.0)) << geometryOnly;
        EXPECT_EQ(cloud.globalPosition(0), Eigen::Vector3d(512345.25, 5401234.5, 101.125)) << geometryOnly;
        EXPECT_EQ(cloud.globalPosition(1), Eigen::Vector3d(512346.75, 5401236.0, 102.5)) << geometryOnly;
        EXPECT_EQ(cloud.normals()[1], Eigen::Vector3f(1, 0, 0));
    }
}

TEST(PlyFormat, CrlfAsciiFile)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "crlf.ply";
    writeText(path, "ply\r\nformat ascii 1.0\r\nelement vertex 2\r\nproperty float x\r\nproperty float y\r\n"
                    "property float z\r\nproperty uchar red\r\nproperty uchar green\r\nproperty uchar blue\r\n"
                    "end_header\r\n1 2 3 10 20 30\r\n\r\n4 5 6 40 50 60\r\n");
    const PointCloud cloud = io::readPointCloud(registry, path);
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.positions()[1], Eigen::Vector3f(4, 5, 6));
    EXPECT_EQ(cloud.colors()[1], (Rgb8{40, 50, 60}));
}

TEST(PlyFormat, PolygonsAreFanTriangulated)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "quad.ply";
    writeText(path, "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 2\nproperty list uchar int vertex_index\nend_header\n"
                    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 2 0\n"
                    "4 0 1 2 3\n3 3 2 4\n");
    const Mesh mesh = io::readMesh(registry, path);
    const std::vector<Triangle> expected = {{0, 1, 2}, {0, 2, 3}, {3, 2, 4}};
    EXPECT_EQ(mesh.triangles, expected);
}

TEST(PlyFormat, FaceElementWithoutFacesGivesACloud)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "nofaces.ply";
    writeText(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 0\nproperty list uchar int vertex_indices\nend_header\n1 2 3\n");
    EXPECT_TRUE(std::holds_alternative<PointCloud>(io::readFile(registry, path)));
}

TEST(PlyFormat, NonFinitePointsAreSkippedWithAWarning)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "nan.ply";
    writeText(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "property float quality\nend_header\n1 2 3 0.5\nnan 0 0 1.5\n4 inf 6 2.5\n");
    CaptureLog log;
    const PointCloud cloud = io::readPointCloud(registry, path);
    ASSERT_EQ(cloud.size(), 1u);
    EXPECT_EQ(cloud.field("quality")->value(0), 0.5);
    ASSERT_EQ(log.warnings.size(), 1u);
    EXPECT_NE(log.warnings[0].find(path.string() + ": 2 points with non-finite coordinates were skipped"),
              std::string::npos)
        << log.warnings[0];
}

TEST(PlyFormat, NonFiniteMeshVertexIsAnError)
{
    const fs::path path = tempDir() / "nanmesh.ply";
    writeText(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                    "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
    expectReadError(path, {"vertex 2", "non-finite"});
}

TEST(PlyFormat, CancellingAReadThrowsCancelled)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "big.ply";
    io::writePointCloud(registry, makeCloud(300000), path);
    CancelAfter observer(3);
    io::ReadOptions options;
    options.progress = &observer;
    expectError([&] { io::readFile(registry, path, options); }, ErrorCode::Cancelled, {});
}

TEST(PlyFormat, CancellingAWriteLeavesNothingBehind)
{
    const auto registry = plyRegistry();
    const fs::path dir = tempDir();
    CancelAfter observer(3);
    io::WriteOptions options;
    options.progress = &observer;
    expectError([&] { io::writePointCloud(registry, makeCloud(300000), dir / "out.ply", options); },
                ErrorCode::Cancelled, {});
    EXPECT_TRUE(fs::is_empty(dir));
}

// ---------------------------------------------------------------- bad input

const char* kXyzHeader = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                         "property float z\nend_header\n";

TEST(PlyFormatErrors, EmptyFile)
{
    const fs::path path = tempDir() / "empty.ply";
    writeText(path, "");
    expectReadError(path, {"empty"});
}

TEST(PlyFormatErrors, MissingMagic)
{
    const fs::path path = tempDir() / "magic.ply";
    writeText(path, "solid cube\nformat ascii 1.0\n");
    expectReadError(path, {"not a PLY file"});
}

TEST(PlyFormatErrors, UnknownFormat)
{
    const fs::path path = tempDir() / "format.ply";
    writeText(path, "ply\nformat binary_middle_endian 1.0\nelement vertex 0\nend_header\n");
    expectReadError(path, {":2:", "unknown format 'binary_middle_endian'"});
}

TEST(PlyFormatErrors, BadPropertyType)
{
    const fs::path path = tempDir() / "type.ply";
    writeText(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty half y\nend_header\n");
    expectReadError(path, {":5:", "unknown property type 'half'"});
}

TEST(PlyFormatErrors, GarbageInHeader)
{
    const fs::path path = tempDir() / "garbage.ply";
    writeText(path, std::string("ply\nformat ascii 1.0\nelement vertex 1\n\x01\x02garbage here\nend_header\n"));
    expectReadError(path, {":4:", "unexpected"});
}

TEST(PlyFormatErrors, MalformedElementCount)
{
    const fs::path path = tempDir() / "count.ply";
    writeText(path, "ply\nformat ascii 1.0\nelement vertex many\nend_header\n");
    expectReadError(path, {":3:", "element"});
}

TEST(PlyFormatErrors, MissingEndHeader)
{
    const fs::path path = tempDir() / "noend.ply";
    writeText(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
    expectReadError(path, {"missing end_header"});
}

TEST(PlyFormatErrors, MissingFormatLine)
{
    const fs::path path = tempDir() / "noformat.ply";
    writeText(path, "ply\nelement vertex 0\nend_header\n");
    expectReadError(path, {"format"});
}

TEST(PlyFormatErrors, TruncatedBinaryVertices)
{
    const fs::path path = tempDir() / "short.ply";
    Bytes b(false);
    for (int i = 0; i < 7; ++i)
        b.put(1.0f).put(2.0f).put(3.0f);
    b.put(1.0f); // vertex 8 is cut after its x
    writeText(path, "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\n"
                    "property float z\nend_header\n" + b.str());
    expectReadError(path, {"truncated", "vertex 8 of 1000"});
}

TEST(PlyFormatErrors, TruncatedBinaryFaces)
{
    const fs::path path = tempDir() / "shortfaces.ply";
    Bytes b(true);
    for (int i = 0; i < 3; ++i)
        b.put(1.0f).put(2.0f).put(static_cast<float>(i));
    b.put<std::uint8_t>(3).put<std::int32_t>(0).put<std::int32_t>(1).put<std::int32_t>(2);
    b.put<std::uint8_t>(3).put<std::int32_t>(0); // face 2 ends early
    writeText(path, "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n" + b.str());
    expectReadError(path, {"truncated", "face 2 of 2"});
}

TEST(PlyFormatErrors, TruncatedAscii)
{
    const fs::path path = tempDir() / "shortascii.ply";
    writeText(path, "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                    "property float z\nend_header\n1 2 3\n4 5 6\n7 8 9\n");
    expectReadError(path, {"truncated", "vertex 4 of 4"});
}

TEST(PlyFormatErrors, HugeCountIsRefusedBeforeAllocating)
{
    const fs::path path = tempDir() / "huge.ply";
    writeText(path, "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\nproperty float x\n"
                    "property float y\nproperty float z\nend_header\n" + std::string(24, '\0'));
    expectReadError(path, {"truncated"});
}

TEST(PlyFormatErrors, NonNumericAsciiTokenGivesTheLine)
{
    const fs::path path = tempDir() / "word.ply";
    writeText(path, std::string(kXyzHeader) + "1 2 3\n4 five 6\n");
    expectReadError(path, {":9:", "'five' is not a number", "'y'"});
}

TEST(PlyFormatErrors, FewerTokensThanProperties)
{
    const fs::path path = tempDir() / "few.ply";
    writeText(path, std::string(kXyzHeader) + "1 2 3\n4 5\n");
    expectReadError(path, {":9:", "fewer values"});
}

TEST(PlyFormatErrors, MoreTokensThanProperties)
{
    const fs::path path = tempDir() / "many.ply";
    writeText(path, std::string(kXyzHeader) + "1 2 3 4\n4 5 6\n");
    expectReadError(path, {":8:", "more values"});
}

TEST(PlyFormatErrors, VertexWithoutXyz)
{
    const fs::path path = tempDir() / "noxyz.ply";
    writeText(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                    "property float height\nend_header\n1 2 3\n");
    expectReadError(path, {"no x, y and z"});
}

TEST(PlyFormatErrors, NoVertexElement)
{
    const fs::path path = tempDir() / "novertex.ply";
    writeText(path, "ply\nformat ascii 1.0\nelement point 1\nproperty float x\nend_header\n1\n");
    expectReadError(path, {"no vertex element"});
}

TEST(PlyFormatErrors, FaceIndexOutOfRange)
{
    const fs::path path = tempDir() / "index.ply";
    writeText(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
                    "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 3\n");
    expectReadError(path, {"face 2 of 2", "vertex 3", "only 3 vertices"});
}

TEST(PlyFormatErrors, NegativeFaceIndexInBinary)
{
    const fs::path path = tempDir() / "negative.ply";
    Bytes b(false);
    for (int i = 0; i < 3; ++i)
        b.put(1.0f).put(2.0f).put(static_cast<float>(i));
    b.put<std::uint8_t>(3).put<std::int32_t>(0).put<std::int32_t>(-1).put<std::int32_t>(2);
    writeText(path, "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" + b.str());
    expectReadError(path, {"face 1 of 1", "vertex -1"});
}

//! Reads a damaged file: it may load or throw scandiff::Error, but nothing else.
void expectErrorOrSuccess(const fs::path& path)
{
    try {
        io::readFile(plyRegistry(), path);
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidData) << e.what();
    }
}

TEST(PlyFormatErrors, DamagedFilesNeverCrash)
{
    const auto registry = plyRegistry();
    const fs::path dir = tempDir();
    Mesh mesh;
    mesh.vertices = makeCloud(6);
    mesh.triangles = {{0, 1, 2}, {3, 4, 5}};
    for (const auto encoding : {io::Encoding::Ascii, io::Encoding::BinaryLittleEndian, io::Encoding::BinaryBigEndian}) {
        io::WriteOptions options;
        options.encoding = encoding;
        io::writeMesh(registry, mesh, dir / "good.ply", options);
        const std::string good = readBytes(dir / "good.ply");
        // A new file per variant: truncating a file that was just mapped is slow on some file systems.
        int variant = 0;
        auto check = [&](const std::string& bytes) {
            const fs::path damaged = dir / ("damaged" + std::to_string(variant++) + ".ply");
            writeText(damaged, bytes);
            expectErrorOrSuccess(damaged);
        };
        for (std::size_t size = 0; size < good.size(); ++size)
            check(good.substr(0, size));
        std::uint32_t seed = 12345;
        for (int round = 0; round < 300; ++round) {
            std::string bytes = good;
            for (int flip = 0; flip < 3; ++flip) {
                seed = seed * 1664525u + 1013904223u;
                bytes[seed % bytes.size()] = static_cast<char>(seed >> 24);
            }
            check(bytes);
        }
        fs::remove_all(dir);
        fs::create_directories(dir);
    }
}

TEST(PlyFormatErrors, MissingFileIsAnIoError)
{
    const auto registry = plyRegistry();
    const fs::path path = tempDir() / "absent.ply";
    expectError([&] { io::readFile(registry, path); }, ErrorCode::Io, {path.string()});
}

} // namespace
} // namespace scandiff::test
