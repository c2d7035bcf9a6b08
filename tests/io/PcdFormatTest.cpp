// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/io/FileIO.h>

#include "TestSupport.h"

#include <cmath>
#include <optional>

using namespace scandiff;

namespace {

io::FormatRegistry builtinFormats()
{
    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    return formats;
}

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
    const io::FormatRegistry formats = builtinFormats();
    const PointCloud cloud = io::readPointCloud(formats, sample("region_growing_tutorial.pcd"));
    EXPECT_EQ(cloud.size(), 108104u);
    EXPECT_TRUE(cloud.hasColors());
    EXPECT_EQ(cloud.name, "region_growing_tutorial");
}

TEST(PcdFormat, GeoreferencedAirborneSampleGetsAGlobalShift)
{
    const io::FormatRegistry formats = builtinFormats();
    const PointCloud cloud = io::readPointCloud(formats, sample("samp11-utm.pcd"));
    EXPECT_EQ(cloud.size(), 38010u);
    EXPECT_FALSE(cloud.origin().isZero());
    EXPECT_EQ(std::fmod(cloud.origin().x(), 1000.0), 0.0);
    const BoundingBox box = cloud.bounds();
    EXPECT_GT(box.min.x(), 1e5); // UTM eastings
    // Local coordinates stay small, so float keeps millimetres.
    for (const auto& p : cloud.positions())
        ASSERT_LT(p.cwiseAbs().maxCoeff(), 1e4f);
    const PointCloud ground = io::readPointCloud(formats, sample("samp11-utm-ground.pcd"));
    EXPECT_LT(ground.size(), cloud.size());
}

TEST(PcdFormat, OrganisedCaptureDropsNaNAndKeepsTheViewpoint)
{
    const io::FormatRegistry formats = builtinFormats();
    const PointCloud cloud = io::readPointCloud(formats, sample("capture0001.pcd"));
    EXPECT_GT(cloud.size(), 100000u);
    EXPECT_LT(cloud.size(), 307200u);
    for (const auto& p : cloud.positions())
        ASSERT_TRUE(p.allFinite());
    ASSERT_EQ(cloud.sensors().size(), 1u);
}

TEST(PcdFormat, RoundTripInEveryEncoding)
{
    const io::FormatRegistry formats = builtinFormats();
    PointCloud cloud = io::readPointCloud(formats, sample("region_growing_tutorial.pcd"));
    ScalarField& f = cloud.addField("c2c_distance");
    for (std::size_t i = 0; i < cloud.size(); ++i)
        f.values()[i] = i % 10 == 0 ? std::nanf("") : static_cast<float>(i) * 0.001f;
    cloud.enableNormals()[3] = {0, 0, 1};
    const auto dir = test::tempDir();
    for (io::Encoding encoding : {io::Encoding::Ascii, io::Encoding::BinaryLittleEndian, io::Encoding::BinaryCompressed}) {
        io::WriteOptions options;
        options.encoding = encoding;
        io::writePointCloud(formats, cloud, dir / "copy.pcd", options);
        const PointCloud back = io::readPointCloud(formats, dir / "copy.pcd");
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
    const io::FormatRegistry formats = builtinFormats();
    PointCloud cloud;
    cloud.setOrigin({512000, 5423000, 0});
    cloud.resize(2);
    cloud.positions()[0] = {345.678f, 456.789f, 123.456f};
    cloud.positions()[1] = {1.0f, 2.0f, 3.0f};
    const auto path = test::tempDir() / "utm.pcd";
    io::writePointCloud(formats, cloud, path);
    const PointCloud back = io::readPointCloud(formats, path);
    EXPECT_NEAR(back.globalPosition(0).x(), 512345.678, 1e-3);
    EXPECT_NEAR(back.globalPosition(0).y(), 5423456.789, 1e-3);
}

TEST(PcdFormat, BadFilesAreClearErrors)
{
    const io::FormatRegistry formats = builtinFormats();
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
            io::readPointCloud(formats, dir / name);
            ADD_FAILURE() << name << " was accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ErrorCode::InvalidData) << name << ": " << e.what();
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        }
    }
}

namespace {

//! A PCD header followed by `data`.
std::string pcd(const std::string& fields, const std::string& sizes, const std::string& types, const std::string& counts,
                std::size_t points, const std::string& encoding, const std::string& data)
{
    return "# .PCD v0.7\nVERSION 0.7\nFIELDS " + fields + "\nSIZE " + sizes + "\nTYPE " + types + "\nCOUNT " + counts +
           "\nWIDTH " + std::to_string(points) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(points) +
           "\nDATA " + encoding + "\n" + data;
}

template <typename T>
void append(std::string& bytes, T value)
{
    bytes.append(reinterpret_cast<const char*>(&value), sizeof value);
}

//! The error reading `path` gives; empty when it reads.
std::optional<ErrorCode> readError(const io::FormatRegistry& formats, const std::filesystem::path& path, std::string& message)
{
    try {
        io::readPointCloud(formats, path);
    } catch (const Error& e) {
        message = e.what();
        return e.code();
    }
    return std::nullopt;
}

} // namespace

TEST(PcdFormat, EveryNumericTypeAndCountIsDecoded)
{
    const io::FormatRegistry formats = builtinFormats();
    // Two points: x y z as float, then I1, U2, I4, U8, F8, and a field of COUNT 3.
    std::string data;
    for (int i = 0; i < 2; ++i) {
        append<float>(data, 1.5f + i);
        append<float>(data, -2.0f);
        append<float>(data, 3.25f);
        append<std::int8_t>(data, static_cast<std::int8_t>(-100 + i));
        append<std::uint16_t>(data, static_cast<std::uint16_t>(65000 + i));
        append<std::int32_t>(data, -2000000000 + i);
        append<std::uint64_t>(data, (std::uint64_t(1) << 40) + static_cast<std::uint64_t>(i));
        append<double>(data, 0.1 + i);
        for (int c = 0; c < 3; ++c)
            append<float>(data, static_cast<float>(10 * i + c));
    }
    const auto path = test::tempDir() / "types.pcd";
    test::writeText(path, pcd("x y z a b c d e hist", "4 4 4 1 2 4 8 8 4", "F F F I U I U F F", "1 1 1 1 1 1 1 1 3", 2, "binary", data));
    const PointCloud cloud = io::readPointCloud(formats, path);
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.globalPosition(1), Eigen::Vector3d(2.5, -2.0, 3.25));
    ASSERT_NE(cloud.field("a"), nullptr);
    EXPECT_EQ(cloud.field("a")->value(0), -100.0);
    EXPECT_EQ(cloud.field("b")->value(1), 65001.0);
    EXPECT_EQ(cloud.field("c")->value(0), -2000000000.0);
    EXPECT_EQ(cloud.field("d")->value(1), static_cast<double>((std::uint64_t(1) << 40) + 1));
    EXPECT_NEAR(cloud.field("e")->value(1), 1.1, 1e-6);
    ASSERT_NE(cloud.field("hist_2"), nullptr);
    EXPECT_EQ(cloud.field("hist_0")->value(1), 10.0);
    EXPECT_EQ(cloud.field("hist_2")->value(1), 12.0);
}

TEST(PcdFormat, HostileHeadersAreRefusedBeforeAllocating)
{
    const io::FormatRegistry formats = builtinFormats();
    const auto dir = test::tempDir();
    struct Case
    {
        const char* name;
        std::string text;
        const char* expected; //!< part of the message
    };
    std::string hugeCompressed = pcd("x y z", "4 4 4", "F F F", "1 1 1", 357913941, "binary_compressed", "");
    append<std::uint32_t>(hugeCompressed, 40);
    append<std::uint32_t>(hugeCompressed, 4294967292u);
    hugeCompressed += std::string(40, 'a');
    const std::vector<Case> cases = {
        {"count-minus-one.pcd", pcd("x y z", "4 4 4", "F F F", "1 -1 1", 1, "ascii", "1 2 3\n"), "COUNT"},
        {"count-huge.pcd", pcd("x y z", "4 4 4", "F F F", "1 200000 1", 1, "ascii", "1 2 3\n"), "COUNT"},
        // Found by the fuzzer: a z of COUNT 5,000 made 5,000 fields, named in quadratic time.
        {"many-fields.pcd", pcd("x y z", "4 4 4", "F F F", "1 1 5000", 0, "ascii", ""), "scalar values"},
        {"ascii-half-billion.pcd", pcd("x y z", "4 4 4", "F F F", "1 1 1", 500000000, "ascii", "1 2 3\n"), "cannot fit"},
        {"binary-half-billion.pcd", pcd("x y z", "4 4 4", "F F F", "1 1 1", 500000000, "binary", std::string(12, '\0')), "truncated"},
        {"compressed-4gb.pcd", hugeCompressed, "cannot hold"},
        {"repeated-fields.pcd",
         "VERSION 0.7\nFIELDS x y z\nFIELDS x y z w\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n", "twice"},
        {"keyword-after-data.pcd", pcd("x y z", "4 4 4", "F F F", "1 1 1", 1, "ascii", "FIELDS a b\n"), "line"},
        {"points-disagree.pcd",
         "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 1\nPOINTS 3\nDATA ascii\n1 2 3\n1 2 3\n1 2 3\n", "POINTS"},
        {"bad-type.pcd", pcd("x y z", "4 4 3", "F F F", "1 1 1", 1, "ascii", "1 2 3\n"), "TYPE"},
        {"duplicate-field.pcd", pcd("x y z x", "4 4 4 4", "F F F F", "1 1 1 1", 1, "ascii", "1 2 3 4\n"), "twice"},
        {"missing-value.pcd", pcd("x y z", "4 4 4", "F F F", "1 1 1", 2, "ascii", "1.0 2.0 3.0\n4.0 5.0\n"), "data line 2"},
        {"extra-value.pcd", pcd("x y z", "4 4 4", "F F F", "1 1 1", 2, "ascii", "1 2 3\n4 5 6 7\n"), "more than"},
        {"not-a-number.pcd", pcd("x y z", "4 4 4", "F F F", "1 1 1", 1, "ascii", "1 2 zz\n"), "not a number"},
        {"corrupt-lzf.pcd",
         [] {
             std::string t = pcd("x y z", "4 4 4", "F F F", "1 1 1", 1, "binary_compressed", "");
             append<std::uint32_t>(t, 4);
             append<std::uint32_t>(t, 12);
             t += "\xff\xff\xff\xff";
             return t;
         }(),
         "corrupt"},
    };
    for (const Case& c : cases) {
        test::writeText(dir / c.name, c.text);
        std::string message;
        EXPECT_EQ(readError(formats, dir / c.name, message), ErrorCode::InvalidData) << c.name;
        EXPECT_NE(message.find(c.name), std::string::npos) << message;
        EXPECT_NE(message.find(c.expected), std::string::npos) << c.name << ": " << message;
    }
}

TEST(PcdFormat, FuzzerReproducersGiveCleanErrors)
{
    // Files that crashed, hung or exhausted memory in PCL's reader
    // (tests/data/fuzz-found/README.md). Each is refused with a message that
    // names it, or read as the valid cloud it happens to be.
    const io::FormatRegistry formats = builtinFormats();
    int seen = 0;
    for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(SCANDIFF_TEST_DATA_DIR) / "fuzz-found")) {
        if (entry.path().extension() != ".pcd")
            continue;
        ++seen;
        std::string message;
        const std::optional<ErrorCode> code = readError(formats, entry.path(), message);
        if (code) {
            EXPECT_EQ(*code, ErrorCode::InvalidData) << entry.path() << ": " << message;
            EXPECT_NE(message.find(entry.path().filename().string()), std::string::npos) << message;
        }
    }
    EXPECT_EQ(seen, 10);
}

TEST(PcdFormat, WrittenValuesComeBackExactly)
{
    // Shortest exact decimal forms in ascii; doubles stay doubles; names with
    // blanks become words, and a name taken twice gets a suffix.
    const io::FormatRegistry formats = builtinFormats();
    PointCloud cloud;
    cloud.setOrigin({512000, 5423000, 100});
    cloud.resize(3);
    cloud.positions() = {{0.1f, -3.3333333f, 345.678f}, {1234.5677f, 0.0f, -0.125f}, {7.0f, 8.0f, 9.0f}};
    cloud.enableColors() = {{255, 0, 1}, {0, 128, 255}, {12, 34, 56}};
    ScalarField gps("GPS time", 3);
    gps.setOffset(1.4e9);
    for (std::size_t i = 0; i < 3; ++i)
        gps.setValue(i, 1.4e9 + 0.123456 * static_cast<double>(i + 1));
    cloud.addField(std::move(gps));
    cloud.addField("rgb").values() = {1, 2, 3};
    const auto dir = test::tempDir();
    for (io::Encoding encoding : {io::Encoding::Ascii, io::Encoding::BinaryLittleEndian, io::Encoding::BinaryCompressed}) {
        io::WriteOptions options;
        options.encoding = encoding;
        io::writePointCloud(formats, cloud, dir / "exact.pcd", options);
        io::ReadOptions read;
        read.origin = cloud.origin();
        const PointCloud back = io::readPointCloud(formats, dir / "exact.pcd", read);
        ASSERT_EQ(back.size(), 3u);
        EXPECT_EQ(back.positions(), cloud.positions());
        EXPECT_EQ(back.colors(), cloud.colors());
        ASSERT_NE(back.field("GPS_time"), nullptr);
        ASSERT_NE(back.field("rgb_2"), nullptr);
        for (std::size_t i = 0; i < 3; ++i) {
            EXPECT_EQ(back.field("GPS_time")->value(i), cloud.field("GPS time")->value(i));
            EXPECT_EQ(back.field("rgb_2")->value(i), cloud.field("rgb")->value(i));
        }
    }
}
