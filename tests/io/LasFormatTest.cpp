// SPDX-License-Identifier: GPL-3.0-or-later
// LAS reading and writing through the public API. The hand-built files are
// assembled byte by byte from the ASPRS LAS 1.4 R15 tables, independently of
// the writer, so a symmetric mistake in reader and writer cannot go unnoticed.

#include "internal/Formats.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/processing/CloudEditing.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/CoordinateSystem.h>
#include <scandiff/io/FileIO.h>

#include "../support/TestSupport.h"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <random>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace scandiff;

const float kNaN = std::numeric_limits<float>::quiet_NaN();

io::FormatRegistry lasRegistry()
{
    io::FormatRegistry registry;
    registry.add(io::detail::lasFormat());
    return registry;
}

//! A little-endian byte buffer with writes at absolute offsets.
class Bytes
{
public:
    explicit Bytes(std::size_t size = 0) : data_(size, '\0') {}
    template <class T>
    void put(std::size_t offset, T value)
    {
        if (data_.size() < offset + sizeof value)
            data_.resize(offset + sizeof value, '\0');
        std::memcpy(&data_[offset], &value, sizeof value);
    }
    void putText(std::size_t offset, const std::string& text)
    {
        if (data_.size() < offset + text.size())
            data_.resize(offset + text.size(), '\0');
        std::memcpy(&data_[offset], text.data(), text.size());
    }
    std::size_t size() const { return data_.size(); }
    const std::string& str() const { return data_; }
    std::string& str() { return data_; }

private:
    std::string data_;
};

struct HeaderSpec
{
    int minor = 2;
    int format = 1;
    std::uint16_t recordLength = 28;
    std::uint64_t count = 0;
    std::uint32_t offsetToPoints = 227;
    std::uint32_t vlrCount = 0;
    double scale[3] = {0.01, 0.01, 0.01};
    double offset[3] = {0, 0, 0};
    double min[3] = {0, 0, 0};
    double max[3] = {0, 0, 0};
};

//! The public header block of LAS 1.4 R15 table 3 (1.2: the first 227 bytes).
Bytes makeHeader(const HeaderSpec& s)
{
    const std::size_t headerSize = s.minor >= 4 ? 375 : (s.minor == 3 ? 235 : 227);
    Bytes b(headerSize);
    b.putText(0, "LASF");
    b.put<std::uint8_t>(24, 1);
    b.put<std::uint8_t>(25, static_cast<std::uint8_t>(s.minor));
    b.putText(26, "TEST");
    b.putText(58, "hand made");
    b.put<std::uint16_t>(94, static_cast<std::uint16_t>(headerSize));
    b.put<std::uint32_t>(96, s.offsetToPoints);
    b.put<std::uint32_t>(100, s.vlrCount);
    b.put<std::uint8_t>(104, static_cast<std::uint8_t>(s.format));
    b.put<std::uint16_t>(105, s.recordLength);
    if (s.format < 6 && s.count <= 0xFFFFFFFFu)
        b.put<std::uint32_t>(107, static_cast<std::uint32_t>(s.count));
    for (int a = 0; a < 3; ++a) {
        b.put<double>(131 + 8 * a, s.scale[a]);
        b.put<double>(155 + 8 * a, s.offset[a]);
        b.put<double>(179 + 16 * a, s.max[a]);
        b.put<double>(187 + 16 * a, s.min[a]);
    }
    if (s.minor >= 4)
        b.put<std::uint64_t>(247, s.count);
    return b;
}

//! A LAS 1.2 point format 1 file with two points, 4 undescribed extra bytes
//! per point and an unrelated VLR before the points.
Bytes makeLas12Format1()
{
    HeaderSpec s;
    s.minor = 2;
    s.format = 1;
    s.recordLength = 28 + 4;
    s.count = 2;
    s.vlrCount = 1;
    s.offsetToPoints = 227 + 54 + 10;
    s.scale[0] = 0.01; s.scale[1] = 0.01; s.scale[2] = 0.001;
    s.offset[0] = 1000; s.offset[1] = 2000; s.offset[2] = 0;
    s.min[0] = 1000; s.min[1] = 2000; s.min[2] = -1;
    s.max[0] = 1012; s.max[1] = 2020; s.max[2] = 5;
    Bytes b = makeHeader(s);
    // A VLR the reader must step over: 54-byte header + 10 bytes of payload.
    b.putText(227 + 2, "SomeVendor");
    b.put<std::uint16_t>(227 + 18, 1234);
    b.put<std::uint16_t>(227 + 20, 10);
    b.putText(227 + 54, "0123456789");

    const std::size_t p0 = s.offsetToPoints;
    // Point 0: X = 1000 + 1234*0.01, Y = 2000 + 2000*0.01, Z = -0.5.
    b.put<std::int32_t>(p0 + 0, 1234);
    b.put<std::int32_t>(p0 + 4, 2000);
    b.put<std::int32_t>(p0 + 8, -500);
    b.put<std::uint16_t>(p0 + 12, 40000);                    // intensity
    b.put<std::uint8_t>(p0 + 14, 2 | (3 << 3) | (1 << 6) | (1 << 7)); // return 2 of 3, scan dir 1, edge 1
    b.put<std::uint8_t>(p0 + 15, 6 | (1 << 5) | (1 << 7));     // building, synthetic, withheld
    b.put<std::int8_t>(p0 + 16, -12);                           // scan angle rank
    b.put<std::uint8_t>(p0 + 17, 200);                          // user data
    b.put<std::uint16_t>(p0 + 18, 65000);                       // point source id
    b.put<double>(p0 + 20, 345678.123456);                      // GPS week time
    b.putText(p0 + 28, "XTRA");
    const std::size_t p1 = p0 + s.recordLength;
    // Point 1: every field at another value.
    b.put<std::int32_t>(p1 + 0, 0);
    b.put<std::int32_t>(p1 + 4, 1);
    b.put<std::int32_t>(p1 + 8, 5000);
    b.put<std::uint16_t>(p1 + 12, 7);
    b.put<std::uint8_t>(p1 + 14, 1 | (1 << 3));
    b.put<std::uint8_t>(p1 + 15, 31 | (1 << 6));                // class 31, key-point
    b.put<std::int8_t>(p1 + 16, 90);
    b.put<std::uint8_t>(p1 + 17, 0);
    b.put<std::uint16_t>(p1 + 18, 1);
    b.put<double>(p1 + 20, 345679.5);
    b.putText(p1 + 28, "YYYY");
    return b;
}

//! An Extra Bytes descriptor (LAS 1.4 R15, Extra Bytes VLR), 192 bytes.
std::string extraBytesDescriptor(std::uint8_t type, std::uint8_t options, const std::string& name, double scale = 0,
                                 double offset = 0, std::uint64_t noDataBits = 0)
{
    Bytes d(192);
    d.put<std::uint8_t>(2, type);
    d.put<std::uint8_t>(3, options);
    d.putText(4, name);
    d.put<std::uint64_t>(40, noDataBits);
    d.put<double>(112, scale);
    d.put<double>(136, offset);
    d.putText(160, "test dimension");
    return d.str();
}

//! A LAS 1.4 point format 10 file: two points with colour, NIR, a wave packet
//! (ignored) and extra bytes described by an Extra Bytes VLR:
//!   "temperature": uint16, scale 0.1, offset -40, no_data 65535
//!   "echo width": float
//!   "pair": short[2] (a deprecated array type), scale 0.5 for its first
//!           element and 2 for its second: fields pair0 and pair1
//!   "tail": uchar (after the array, so its position must still be right)
Bytes makeLas14Format10()
{
    const std::size_t extraSize = 2 + 4 + 4 + 1;
    std::string pair = extraBytesDescriptor(14, 8, "pair", 0.5);
    const double secondScale = 2.0;
    std::memcpy(&pair[112 + 8], &secondScale, sizeof secondScale); // scale[1]
    std::string descriptors = extraBytesDescriptor(3, 1 | 8 | 16, "temperature", 0.1, -40.0, 65535) +
                              extraBytesDescriptor(9, 0, "echo width") + pair + extraBytesDescriptor(1, 0, "tail");
    HeaderSpec s;
    s.minor = 4;
    s.format = 10;
    s.recordLength = static_cast<std::uint16_t>(67 + extraSize);
    s.count = 2;
    s.vlrCount = 1;
    s.offsetToPoints = static_cast<std::uint32_t>(375 + 54 + descriptors.size());
    s.scale[0] = s.scale[1] = s.scale[2] = 0.001;
    s.offset[0] = 300000; s.offset[1] = 5000000; s.offset[2] = 100;
    s.min[0] = 300000; s.min[1] = 5000000; s.min[2] = 100;
    s.max[0] = 300001; s.max[1] = 5000001; s.max[2] = 101;
    Bytes b = makeHeader(s);
    b.put<std::uint16_t>(6, 1 | 16); // adjusted standard GPS time, WKT
    b.putText(375 + 2, "LASF_Spec");
    b.put<std::uint16_t>(375 + 18, 4);
    b.put<std::uint16_t>(375 + 20, static_cast<std::uint16_t>(descriptors.size()));
    b.putText(375 + 54, descriptors);

    const std::size_t p0 = s.offsetToPoints;
    b.put<std::int32_t>(p0 + 0, 100);                     // 300000.1
    b.put<std::int32_t>(p0 + 4, 200);                     // 5000000.2
    b.put<std::int32_t>(p0 + 8, 300);                     // 100.3
    b.put<std::uint16_t>(p0 + 12, 1000);                  // intensity
    b.put<std::uint8_t>(p0 + 14, 12 | (15 << 4));         // return 12 of 15
    b.put<std::uint8_t>(p0 + 15, 0x8 | (2 << 4) | (1 << 7)); // overlap, channel 2, edge
    b.put<std::uint8_t>(p0 + 16, 200);                    // classification beyond 31
    b.put<std::uint8_t>(p0 + 17, 17);                     // user data
    b.put<std::int16_t>(p0 + 18, -5000);                  // -30 degrees
    b.put<std::uint16_t>(p0 + 20, 42);                    // point source id
    b.put<double>(p0 + 22, 312345678.125);                // adjusted standard GPS time
    b.put<std::uint16_t>(p0 + 30, 65535);                 // red
    b.put<std::uint16_t>(p0 + 32, 257 * 128);             // green
    b.put<std::uint16_t>(p0 + 34, 0);                     // blue
    b.put<std::uint16_t>(p0 + 36, 12345);                 // NIR
    b.put<std::uint8_t>(p0 + 38, 7);                      // wave packet descriptor index
    b.put<std::uint64_t>(p0 + 39, 0xDEADBEEFull);         // byte offset to waveform data
    b.put<std::uint16_t>(p0 + 67, 650);                   // temperature: 650*0.1-40 = 25
    b.put<float>(p0 + 69, 2.5f);                          // echo width
    b.put<std::int16_t>(p0 + 73, -1);                     // pair
    b.put<std::int16_t>(p0 + 75, -2);
    b.put<std::uint8_t>(p0 + 77, 99);                     // tail
    const std::size_t p1 = p0 + s.recordLength;
    b.put<std::int32_t>(p1 + 0, 1000);
    b.put<std::int32_t>(p1 + 4, 1000);
    b.put<std::int32_t>(p1 + 8, 1000);
    b.put<std::uint8_t>(p1 + 14, 1 | (1 << 4));
    b.put<std::uint8_t>(p1 + 15, 0x1 | (1 << 6));         // synthetic, scan direction
    b.put<std::int16_t>(p1 + 18, 30000);                  // +180 degrees
    b.put<double>(p1 + 22, 312345679.5);
    b.put<std::uint16_t>(p1 + 30, 257);
    b.put<std::uint16_t>(p1 + 67, 65535);                 // temperature: no data
    b.put<float>(p1 + 69, kNaN);
    b.put<std::uint8_t>(p1 + 77, 1);
    b.str().resize(p1 + s.recordLength, '\0');
    return b;
}

double fieldValue(const PointCloud& cloud, const std::string& name, std::size_t i)
{
    const ScalarField* f = cloud.field(name);
    if (!f) {
        ADD_FAILURE() << "no field '" << name << "'";
        return std::numeric_limits<double>::quiet_NaN();
    }
    return f->value(i);
}

//! Runs `read` and checks it throws scandiff::Error with `code` and a message
//! naming `path` and containing `words`.
// ---------------------------------------------------------------------------

TEST(LasFormat, RoundTripKeepsCoordinatesColoursAndFields)
{
    const fs::path dir = test::tempDir();
    const fs::path file = dir / "survey.las";
    const auto registry = lasRegistry();

    PointCloud cloud;
    cloud.name = "survey";
    cloud.setOrigin(Eigen::Vector3d(512000.0, 5423000.0, 0.0));
    const std::size_t n = 1000;
    cloud.resize(n);
    auto& colors = cloud.enableColors();
    // References are taken after the last addField(): adding a field may move the others.
    for (const char* name : {"intensity", "classification", "gps_time", "c2c_distance"})
        cloud.addField(name);
    ScalarField& intensity = *cloud.field("intensity");
    ScalarField& classification = *cloud.field("classification");
    ScalarField& gps = *cloud.field("gps_time");
    gps.setOffset(312345000.0);
    ScalarField& distance = *cloud.field("c2c_distance");
    std::vector<Eigen::Vector3d> global(n);
    for (std::size_t i = 0; i < n; ++i) {
        const double k = static_cast<double>(i);
        global[i] = Eigen::Vector3d(512345.678 + 0.37 * k, 5423456.789 - 0.21 * k, 123.456 + 0.001 * k);
        cloud.positions()[i] = (global[i] - cloud.origin()).cast<float>();
        colors[i] = Rgb8{static_cast<std::uint8_t>(i % 256), static_cast<std::uint8_t>((i * 7) % 256),
                         static_cast<std::uint8_t>(255 - i % 256)};
        intensity.values()[i] = static_cast<float>((i * 61) % 65536);
        classification.values()[i] = static_cast<float>(i % 20);
        // Times spread over ±4 s around 312345678 s (adjusted standard GPS time).
        gps.setValue(i, 312345678.0 + (static_cast<double>(i) - 500.0) * 0.008123457);
        distance.values()[i] = i % 10 == 3 ? kNaN : static_cast<float>(i) * 0.001f - 0.25f;
    }
    // Keep the inputs for comparison: the float stored value of gps_time is the truth.
    const PointCloud original = cloud.clone();
    io::writePointCloud(registry, cloud, file);

    const PointCloud back = io::readPointCloud(registry, file);
    ASSERT_EQ(back.size(), n);
    EXPECT_EQ(back.name, "survey");
    // The origin comes back from the header offset: the written origin, rounded.
    EXPECT_EQ(back.origin(), Eigen::Vector3d(512000.0, 5423000.0, 0.0));
    ASSERT_TRUE(back.hasColors());
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d p = back.globalPosition(i);
        // 0.1 mm: the LAS quantum; the float local coordinates add less than 0.03 mm here.
        EXPECT_NEAR(p.x(), original.globalPosition(i).x(), 1e-4) << i;
        EXPECT_NEAR(p.y(), original.globalPosition(i).y(), 1e-4) << i;
        EXPECT_NEAR(p.z(), original.globalPosition(i).z(), 1e-4) << i;
        EXPECT_EQ(back.colors()[i], colors[i]) << i;
        EXPECT_EQ(fieldValue(back, "intensity", i), intensity.value(i)) << i;
        EXPECT_EQ(fieldValue(back, "classification", i), classification.value(i)) << i;
        // The file holds the double time; the reader keeps it as float relative to
        // the first time, which over these ±4 s is within 0.5 µs.
        EXPECT_NEAR(fieldValue(back, "gps_time", i), original.field("gps_time")->value(i), 1e-6) << i;
        const float d = back.field("c2c_distance")->values()[i];
        if (i % 10 == 3)
            EXPECT_TRUE(std::isnan(d)) << i;
        else
            EXPECT_EQ(d, distance.values()[i]) << i;
    }
    // The first point, as the task states it, to 0.1 mm.
    EXPECT_NEAR(back.globalPosition(0).x(), 512345.678, 1e-4);
    EXPECT_NEAR(back.globalPosition(0).y(), 5423456.789, 1e-4);
    EXPECT_NEAR(back.globalPosition(0).z(), 123.456, 1e-4);
    // Fields the cloud did not have come back with their LAS defaults.
    EXPECT_EQ(fieldValue(back, "return_number", 0), 1.0);
    EXPECT_EQ(fieldValue(back, "number_of_returns", 0), 1.0);
}

TEST(LasFormat, WrittenHeaderFollowsLas14Rules)
{
    const fs::path file = test::tempDir() / "header.las";
    PointCloud cloud;
    cloud.resize(3);
    cloud.positions()[0] = Eigen::Vector3f(1.0f, 2.0f, 3.0f);
    cloud.positions()[1] = Eigen::Vector3f(-4.0f, 5.5f, 0.25f);
    cloud.positions()[2] = Eigen::Vector3f(7.0f, -8.0f, 9.0f);
    cloud.addField("return_number").values() = {1.0f, 2.0f, 2.0f};
    io::writePointCloud(lasRegistry(), cloud, file);

    const std::string bytes = test::readBytes(file);
    ASSERT_GE(bytes.size(), 375u + 3 * 30u);
    auto u8 = [&](std::size_t o) { return static_cast<unsigned char>(bytes[o]); };
    auto u16 = [&](std::size_t o) { std::uint16_t v; std::memcpy(&v, &bytes[o], 2); return v; };
    auto u32 = [&](std::size_t o) { std::uint32_t v; std::memcpy(&v, &bytes[o], 4); return v; };
    auto u64 = [&](std::size_t o) { std::uint64_t v; std::memcpy(&v, &bytes[o], 8); return v; };
    auto f64 = [&](std::size_t o) { double v; std::memcpy(&v, &bytes[o], 8); return v; };
    EXPECT_EQ(bytes.substr(0, 4), "LASF");
    EXPECT_EQ(u8(24), 1);
    EXPECT_EQ(u8(25), 4);
    EXPECT_EQ(u16(94), 375);
    EXPECT_EQ(u32(96), 375u);
    EXPECT_EQ(u8(104), 6);                // no colour: format 6
    EXPECT_EQ(u16(105), 30);
    EXPECT_EQ(u32(107), 0u);              // legacy count must be 0 for formats 6-10
    EXPECT_TRUE(u16(6) & 16);             // WKT bit, required for formats 6-10
    EXPECT_EQ(u64(247), 3u);              // 64-bit point count
    EXPECT_EQ(u64(255), 1u);              // one first return
    EXPECT_EQ(u64(263), 2u);              // two second returns
    EXPECT_DOUBLE_EQ(f64(131), 0.0001);   // x scale
    EXPECT_DOUBLE_EQ(f64(179), 7.0);      // max x
    EXPECT_DOUBLE_EQ(f64(187), -4.0);     // min x
    EXPECT_DOUBLE_EQ(f64(195), 5.5);      // max y
    EXPECT_DOUBLE_EQ(f64(203), -8.0);     // min y
    EXPECT_DOUBLE_EQ(f64(211), 9.0);      // max z
    EXPECT_DOUBLE_EQ(f64(219), 0.25);     // min z
    EXPECT_EQ(bytes.size(), 375u + 3 * 30u);
}

TEST(LasFormat, FieldsOutsideTheStandardSlotsBecomeExtraBytes)
{
    test::CapturedLog log;
    const fs::path file = test::tempDir() / "extra.las";
    PointCloud cloud;
    cloud.resize(4);
    for (std::size_t i = 0; i < 4; ++i)
        cloud.positions()[i] = Eigen::Vector3f(static_cast<float>(i), 0.0f, 0.0f);
    const std::string longName = "a_scalar_field_name_longer_than_32_characters_1";
    const std::string longName2 = "a_scalar_field_name_longer_than_32_characters_2";
    cloud.addField(longName).values() = {1, 2, 3, 4};
    cloud.addField(longName2).values() = {5, 6, 7, 8};
    cloud.addField("nir").values() = {10, 20, 30, 40}; // no colours: goes to extra bytes
    ScalarField& time = cloud.addField("acquisition_time");
    time.setOffset(1.6e9);
    time.values() = {0.5f, 1.5f, kNaN, 3.25f};
    io::writePointCloud(lasRegistry(), cloud, file);
    EXPECT_EQ(log.warnings.size(), 2u); // the two shortened names

    const PointCloud back = io::readPointCloud(lasRegistry(), file);
    ASSERT_EQ(back.size(), 4u);
    const ScalarField* first = back.field(longName.substr(0, 32));
    const ScalarField* second = back.field(longName.substr(0, 30) + "~2");
    ASSERT_NE(first, nullptr);
    ASSERT_NE(second, nullptr);
    EXPECT_EQ(first->value(2), 3.0);
    EXPECT_EQ(second->value(2), 7.0);
    const ScalarField* backTime = back.field("acquisition_time");
    ASSERT_NE(backTime, nullptr);
    EXPECT_NEAR(backTime->value(0), 1.6e9 + 0.5, 1e-6);
    EXPECT_NEAR(backTime->value(3), 1.6e9 + 3.25, 1e-6);
    EXPECT_TRUE(std::isnan(backTime->values()[2]));
    ASSERT_NE(back.field("nir"), nullptr);
    EXPECT_EQ(back.field("nir")->value(3), 40.0);
}

TEST(LasFormat, ColoursAndNirUseFormat8AndStandardSlotsAreClamped)
{
    const fs::path file = test::tempDir() / "nir.las";
    PointCloud cloud;
    cloud.resize(2);
    cloud.enableColors()[0] = Rgb8{255, 1, 0};
    cloud.addField("nir").values() = {70000.0f, 3.0f};   // clamped to 65535
    cloud.addField("classification").values() = {kNaN, 300.0f}; // NaN -> 0, clamped to 255
    cloud.addField("scan_angle").values() = {-30.0f, 12.345f};
    io::writePointCloud(lasRegistry(), cloud, file);
    EXPECT_EQ(static_cast<unsigned char>(test::readBytes(file)[104]), 8);

    const PointCloud back = io::readPointCloud(lasRegistry(), file);
    ASSERT_EQ(back.size(), 2u);
    EXPECT_EQ(back.colors()[0], (Rgb8{255, 1, 0}));
    EXPECT_EQ(back.colors()[1], (Rgb8{0, 0, 0}));
    EXPECT_EQ(fieldValue(back, "nir", 0), 65535.0);
    EXPECT_EQ(fieldValue(back, "nir", 1), 3.0);
    EXPECT_EQ(fieldValue(back, "classification", 0), 0.0);
    EXPECT_EQ(fieldValue(back, "classification", 1), 255.0);
    EXPECT_NEAR(fieldValue(back, "scan_angle", 0), -30.0, 1e-5);
    EXPECT_NEAR(fieldValue(back, "scan_angle", 1), 12.345, 0.003); // 0.006 degree steps
}

TEST(LasFormat, EmptyCloudAndNonFinitePoints)
{
    test::CapturedLog log;
    const fs::path dir = test::tempDir();
    PointCloud empty;
    io::writePointCloud(lasRegistry(), empty, dir / "empty.las");
    const PointCloud emptyBack = io::readPointCloud(lasRegistry(), dir / "empty.las");
    EXPECT_EQ(emptyBack.size(), 0u);
    EXPECT_NE(emptyBack.field("intensity"), nullptr) << "no record: the standard fields are kept, empty";

    PointCloud cloud;
    cloud.resize(3);
    cloud.positions()[1] = Eigen::Vector3f(kNaN, 0.0f, 0.0f);
    cloud.positions()[2] = Eigen::Vector3f(1.0f, 2.0f, 3.0f);
    cloud.addField("intensity").values() = {1.0f, 2.0f, 3.0f};
    io::writePointCloud(lasRegistry(), cloud, dir / "nan.las");
    ASSERT_EQ(log.warnings.size(), 1u);
    EXPECT_NE(log.warnings[0].find("1 points with non-finite coordinates"), std::string::npos);
    const PointCloud back = io::readPointCloud(lasRegistry(), dir / "nan.las");
    ASSERT_EQ(back.size(), 2u);
    EXPECT_EQ(fieldValue(back, "intensity", 1), 3.0);
    EXPECT_EQ(back.positions()[1], Eigen::Vector3f(1.0f, 2.0f, 3.0f));
}

TEST(LasFormat, HandBuiltLas12Format1DecodesAsTheSpecSays)
{
    test::CapturedLog log;
    const fs::path file = test::tempDir() / "v12.las";
    test::writeText(file, makeLas12Format1().str());
    const PointCloud cloud = io::readPointCloud(lasRegistry(), file);
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_FALSE(cloud.hasColors());
    EXPECT_EQ(cloud.origin(), Eigen::Vector3d(1000, 2000, 0)); // the header offset
    EXPECT_NEAR(cloud.globalPosition(0).x(), 1012.34, 1e-4);
    EXPECT_NEAR(cloud.globalPosition(0).y(), 2020.0, 1e-4);
    EXPECT_NEAR(cloud.globalPosition(0).z(), -0.5, 1e-6);
    EXPECT_NEAR(cloud.globalPosition(1).x(), 1000.0, 1e-4);
    EXPECT_NEAR(cloud.globalPosition(1).y(), 2000.01, 1e-4);
    EXPECT_NEAR(cloud.globalPosition(1).z(), 5.0, 1e-6);

    EXPECT_EQ(fieldValue(cloud, "intensity", 0), 40000);
    EXPECT_EQ(fieldValue(cloud, "return_number", 0), 2);
    EXPECT_EQ(fieldValue(cloud, "number_of_returns", 0), 3);
    EXPECT_EQ(fieldValue(cloud, "scan_direction_flag", 0), 1);
    EXPECT_EQ(fieldValue(cloud, "edge_of_flight_line", 0), 1);
    EXPECT_EQ(fieldValue(cloud, "classification", 0), 6);
    EXPECT_EQ(fieldValue(cloud, "classification_flags", 0), 1 | 4); // synthetic + withheld
    EXPECT_EQ(fieldValue(cloud, "scan_angle", 0), -12);
    EXPECT_EQ(fieldValue(cloud, "user_data", 0), 200);
    EXPECT_EQ(fieldValue(cloud, "point_source_id", 0), 65000);
    EXPECT_NEAR(fieldValue(cloud, "gps_time", 0), 345678.123456, 1e-6);

    EXPECT_EQ(fieldValue(cloud, "intensity", 1), 7);
    EXPECT_EQ(fieldValue(cloud, "return_number", 1), 1);
    EXPECT_EQ(fieldValue(cloud, "number_of_returns", 1), 1);
    EXPECT_EQ(fieldValue(cloud, "scan_direction_flag", 1), 0);
    EXPECT_EQ(fieldValue(cloud, "edge_of_flight_line", 1), 0);
    EXPECT_EQ(fieldValue(cloud, "classification", 1), 31);
    EXPECT_EQ(fieldValue(cloud, "classification_flags", 1), 2); // key-point
    EXPECT_EQ(fieldValue(cloud, "scan_angle", 1), 90);
    EXPECT_EQ(fieldValue(cloud, "point_source_id", 1), 1);
    EXPECT_NEAR(fieldValue(cloud, "gps_time", 1), 345679.5, 1e-6);
    // Formats 0-5 have neither scanner channel nor NIR.
    EXPECT_EQ(cloud.field("scanner_channel"), nullptr);
    EXPECT_EQ(cloud.field("nir"), nullptr);
    EXPECT_TRUE(log.warnings.empty());
}

TEST(LasFormat, RoundTripKeepsTheScaleOffsetAndIntegers)
{
    // A file at 1 cm (scale 0.01) written back: the same scale and offset in
    // the header and the same integer coordinates in every record (the writer
    // used to pick 0.1 mm, moving points off the input's grid). Through a crop
    // (a subset) too; a transformation leaves the grid.
    const fs::path dir = test::tempDir();
    test::writeText(dir / "in.las", makeLas12Format1().str());
    const auto registry = lasRegistry();
    const PointCloud cloud = io::readPointCloud(registry, dir / "in.las");
    ASSERT_TRUE(cloud.sourceGrid());
    io::writePointCloud(registry, cloud, dir / "out.las");
    io::writePointCloud(registry, cloud.subset({1}), dir / "subset.las");
    const std::string in = test::readBytes(dir / "in.las"), out = test::readBytes(dir / "out.las"),
                      subset = test::readBytes(dir / "subset.las");
    const auto number = [](const std::string& bytes, std::size_t at, auto type) {
        decltype(type) v;
        std::memcpy(&v, bytes.data() + at, sizeof v);
        return v;
    };
    for (std::size_t a = 0; a < 3; ++a) {
        EXPECT_EQ(number(out, 131 + 8 * a, double{}), number(in, 131 + 8 * a, double{})) << "scale " << a;
        EXPECT_EQ(number(out, 155 + 8 * a, double{}), number(in, 155 + 8 * a, double{})) << "offset " << a;
    }
    const auto records = [&](const std::string& bytes) { return static_cast<std::size_t>(number(bytes, 96, std::uint32_t{})); };
    const auto length = [&](const std::string& bytes) { return static_cast<std::size_t>(number(bytes, 94 + 11, std::uint16_t{})); };
    for (std::size_t i = 0; i < 2; ++i)
        for (std::size_t a = 0; a < 3; ++a) {
            const std::int32_t original = number(in, records(in) + i * length(in) + 4 * a, std::int32_t{});
            EXPECT_EQ(number(out, records(out) + i * length(out) + 4 * a, std::int32_t{}), original) << "point " << i << " axis " << a;
            if (i == 1) {
                EXPECT_EQ(number(subset, records(subset) + 4 * a, std::int32_t{}), original) << "subset axis " << a;
            }
        }
    EXPECT_FALSE(transformCloud(cloud, Eigen::Matrix4d::Identity(), "test").sourceGrid());
}

TEST(LasFormat, HandBuiltLas14Format10DecodesAsTheSpecSays)
{
    test::CapturedLog log;
    const fs::path file = test::tempDir() / "v14.las";
    test::writeText(file, makeLas14Format10().str());
    const PointCloud cloud = io::readPointCloud(lasRegistry(), file);
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.origin(), Eigen::Vector3d(300000, 5000000, 100));
    EXPECT_NEAR(cloud.globalPosition(0).x(), 300000.1, 1e-6);
    EXPECT_NEAR(cloud.globalPosition(0).y(), 5000000.2, 1e-6);
    EXPECT_NEAR(cloud.globalPosition(0).z(), 100.3, 1e-6);
    EXPECT_NEAR(cloud.globalPosition(1).x(), 300001.0, 1e-6);

    EXPECT_EQ(fieldValue(cloud, "intensity", 0), 1000);
    EXPECT_EQ(fieldValue(cloud, "return_number", 0), 12);
    EXPECT_EQ(fieldValue(cloud, "number_of_returns", 0), 15);
    EXPECT_EQ(fieldValue(cloud, "classification_flags", 0), 8); // overlap
    EXPECT_EQ(fieldValue(cloud, "scanner_channel", 0), 2);
    EXPECT_EQ(fieldValue(cloud, "scan_direction_flag", 0), 0);
    EXPECT_EQ(fieldValue(cloud, "edge_of_flight_line", 0), 1);
    EXPECT_EQ(fieldValue(cloud, "classification", 0), 200);
    EXPECT_EQ(fieldValue(cloud, "user_data", 0), 17);
    EXPECT_NEAR(fieldValue(cloud, "scan_angle", 0), -30.0, 1e-5);
    EXPECT_EQ(fieldValue(cloud, "point_source_id", 0), 42);
    EXPECT_NEAR(fieldValue(cloud, "gps_time", 0), 312345678.125, 1e-6);
    EXPECT_EQ(fieldValue(cloud, "nir", 0), 12345);
    ASSERT_TRUE(cloud.hasColors());
    EXPECT_EQ(cloud.colors()[0], (Rgb8{255, 128, 0})); // 16-bit / 257
    EXPECT_EQ(cloud.colors()[1], (Rgb8{1, 0, 0}));

    EXPECT_EQ(fieldValue(cloud, "return_number", 1), 1);
    EXPECT_EQ(fieldValue(cloud, "classification_flags", 1), 1); // synthetic
    EXPECT_EQ(fieldValue(cloud, "scan_direction_flag", 1), 1);
    EXPECT_EQ(fieldValue(cloud, "edge_of_flight_line", 1), 0);
    EXPECT_NEAR(fieldValue(cloud, "scan_angle", 1), 180.0, 1e-4);
    EXPECT_NEAR(fieldValue(cloud, "gps_time", 1), 312345679.5, 1e-6);

    // Extra bytes: scale and offset applied, no_data -> NaN, an array's
    // elements as fields of their own, each with its scale.
    EXPECT_NEAR(fieldValue(cloud, "temperature", 0), 25.0, 1e-5);
    EXPECT_TRUE(std::isnan(fieldValue(cloud, "temperature", 1)));
    EXPECT_EQ(fieldValue(cloud, "echo width", 0), 2.5);
    EXPECT_TRUE(std::isnan(fieldValue(cloud, "echo width", 1)));
    EXPECT_EQ(cloud.field("pair"), nullptr);
    EXPECT_EQ(fieldValue(cloud, "pair0", 0), -0.5);
    EXPECT_EQ(fieldValue(cloud, "pair1", 0), -4.0);
    EXPECT_EQ(fieldValue(cloud, "pair0", 1), 0.0);
    EXPECT_EQ(fieldValue(cloud, "pair1", 1), 0.0);
    EXPECT_EQ(fieldValue(cloud, "tail", 0), 99);
    EXPECT_EQ(fieldValue(cloud, "tail", 1), 1);
    EXPECT_TRUE(log.warnings.empty());
}

TEST(LasFormat, EightBitColoursStoredUnscaledAreTakenAsIs)
{
    // Format 2 written by a tool that stores 0..255 in the 16-bit slots.
    HeaderSpec s;
    s.format = 2;
    s.recordLength = 26;
    s.count = 1;
    Bytes b = makeHeader(s);
    b.put<std::uint16_t>(227 + 20, 200);
    b.put<std::uint16_t>(227 + 22, 100);
    b.put<std::uint16_t>(227 + 24, 50);
    const fs::path file = test::tempDir() / "rgb8.las";
    test::writeText(file, b.str());
    const PointCloud cloud = io::readPointCloud(lasRegistry(), file);
    ASSERT_EQ(cloud.size(), 1u);
    EXPECT_EQ(cloud.colors()[0], (Rgb8{200, 100, 50}));
    EXPECT_EQ(cloud.field("gps_time"), nullptr); // format 2 has none
}

TEST(LasFormat, OriginFollowsOffsetBoundsAndOptions)
{
    const fs::path dir = test::tempDir();
    // Offset (0,0,0) with UTM-sized bounds: the origin comes from the bounds.
    HeaderSpec s;
    s.format = 0;
    s.recordLength = 20;
    s.count = 1;
    s.scale[0] = s.scale[1] = s.scale[2] = 0.001;
    s.min[0] = s.max[0] = 512345.678;
    s.min[1] = s.max[1] = 1234.5;
    s.min[2] = s.max[2] = 0.0;
    Bytes b = makeHeader(s);
    b.put<std::int32_t>(227, 512345678);
    b.put<std::int32_t>(231, 1234500);
    b.str().resize(227 + 20, '\0');
    test::writeText(dir / "zero_offset.las", b.str());
    PointCloud cloud = io::readPointCloud(lasRegistry(), dir / "zero_offset.las");
    EXPECT_EQ(cloud.origin(), Eigen::Vector3d(512000, 1000, 0));
    // float32 local coordinates, 345.678 m from the origin: steps of 30 µm.
    EXPECT_NEAR(cloud.globalPosition(0).x(), 512345.678, 2e-5);
    EXPECT_NEAR(cloud.globalPosition(0).y(), 1234.5, 2e-5);

    io::ReadOptions options;
    options.origin = Eigen::Vector3d(512300, 1200, -10);
    cloud = io::readPointCloud(lasRegistry(), dir / "zero_offset.las", options);
    EXPECT_EQ(cloud.origin(), *options.origin);
    EXPECT_NEAR(cloud.globalPosition(0).x(), 512345.678, 2e-5);
    EXPECT_NEAR(cloud.positions()[0].z(), 10.0f, 1e-6);
}

// Standard fields 0 in every record are left out before the cloud's arrays
// are made: the records are read once for it, in blocks of 65,536 on every
// core. Format 0's 20-byte records (the shortest), four blocks, each field's
// only other value in another block.
TEST(LasFormat, FieldsZeroInEveryRecordAreFoundBeforeTheArraysAreMade)
{
    const fs::path dir = test::tempDir();
    const std::size_t n = 3 * 65536 + 5;
    HeaderSpec s;
    s.format = 0;
    s.recordLength = 20;
    s.count = n;
    s.max[0] = s.max[1] = s.max[2] = 1.0;
    Bytes b = makeHeader(s);
    b.str().resize(227 + n * 20, '\0');
    for (std::size_t i = 0; i < n; ++i)
        b.put<std::uint8_t>(227 + i * 20 + 14, 1 | (1 << 3)); // return 1 of 1
    b.put<std::uint8_t>(227 + 15, 2);                          // classification, first record only
    b.put<std::uint16_t>(227 + 70000 * 20 + 18, 3);            // point source, second block
    b.put<std::uint16_t>(227 + (n - 1) * 20 + 12, 7);          // intensity, last record
    test::writeText(dir / "zeros.las", b.str());
    PointCloud cloud = io::readPointCloud(lasRegistry(), dir / "zeros.las");
    for (const char* dropped : {"user_data", "scan_angle", "scan_direction_flag", "edge_of_flight_line", "classification_flags"})
        EXPECT_EQ(cloud.field(dropped), nullptr) << dropped;
    ASSERT_NE(cloud.field("classification"), nullptr);
    ASSERT_NE(cloud.field("point_source_id"), nullptr);
    ASSERT_NE(cloud.field("intensity"), nullptr);
    EXPECT_EQ(fieldValue(cloud, "classification", 0), 2.0);
    EXPECT_EQ(fieldValue(cloud, "classification", 1), 0.0);
    EXPECT_EQ(fieldValue(cloud, "point_source_id", 70000), 3.0);
    EXPECT_EQ(fieldValue(cloud, "point_source_id", 69999), 0.0);
    EXPECT_EQ(fieldValue(cloud, "intensity", n - 1), 7.0);
    EXPECT_EQ(fieldValue(cloud, "intensity", n - 2), 0.0);
    EXPECT_EQ(fieldValue(cloud, "number_of_returns", n - 1), 1.0);

    // User data too in the last record: no field is 0 everywhere any more,
    // which the blocks only know at the last one.
    b.put<std::uint8_t>(227 + (n - 1) * 20 + 17, 9);
    test::writeText(dir / "zeros.las", b.str());
    cloud = io::readPointCloud(lasRegistry(), dir / "zeros.las");
    ASSERT_NE(cloud.field("user_data"), nullptr);
    EXPECT_EQ(fieldValue(cloud, "user_data", n - 1), 9.0);
    EXPECT_EQ(fieldValue(cloud, "user_data", 0), 0.0);
    EXPECT_EQ(cloud.field("scan_angle"), nullptr);
}

class CancelAtOnce : public ProgressObserver
{
public:
    void beginStage(const std::string&) override {}
    void report(double) override {}
    bool cancelRequested() const override { return true; }
};

TEST(LasFormat, CancellationThrowsCancelled)
{
    test::CapturedLog log;
    const fs::path file = test::tempDir() / "cancel.las";
    test::writeText(file, makeLas12Format1().str());
    CancelAtOnce cancel;
    io::ReadOptions options;
    options.progress = &cancel;
    test::expectError([&] { io::readPointCloud(lasRegistry(), file, options); }, ErrorCode::Cancelled, fs::path(),
                "cancelled");
}

//! Asks to cancel at the given poll, and counts the progress reported before.
class CancelAtPoll : public ProgressObserver
{
public:
    explicit CancelAtPoll(int poll) : poll_(poll) {}
    void beginStage(const std::string&) override {}
    void report(double fraction) override
    {
        if (fraction > 0)
            ++reports;
    }
    bool cancelRequested() const override { return ++polls_ >= poll_; }
    int reports = 0;

private:
    int poll_;
    mutable std::atomic<int> polls_{0};
};

// The read of the records that finds the fields 0 everywhere (a whole pass
// when one is, here user data) answers Cancel between its blocks, before the
// parse has reported any progress: asked at the third poll (the ticker's own
// first, then one per block), with four blocks of records.
TEST(LasFormat, CancelIsHeardWhileTheRecordsAreReadForZeroFields)
{
    const std::size_t n = 3 * 65536 + 5;
    HeaderSpec s;
    s.format = 0;
    s.recordLength = 20;
    s.count = n;
    Bytes b = makeHeader(s);
    b.str().resize(227 + n * 20, '\0');
    for (std::size_t i = 0; i < n; ++i)
        b.put<std::uint16_t>(227 + i * 20 + 12, static_cast<std::uint16_t>(i)); // intensity
    const fs::path file = test::tempDir() / "cancel_scan.las";
    test::writeText(file, b.str());
    CancelAtPoll cancel(3);
    io::ReadOptions options;
    options.progress = &cancel;
    test::expectError([&] { io::readPointCloud(lasRegistry(), file, options); }, ErrorCode::Cancelled, fs::path(),
                      "cancelled");
    EXPECT_EQ(cancel.reports, 0) << "cancelled in the parse, not in the read before it";
}

// ---------------------------------------------------------------------------
// Bad input: each case throws scandiff::Error with the right code and names the file.

class LasBadInput : public ::testing::Test
{
protected:
    void SetUp() override { dir_ = test::tempDir(); }

    void expectInvalid(const std::string& name, const std::string& bytes, ErrorCode code, const std::string& words)
    {
        const fs::path file = dir_ / name;
        test::writeText(file, bytes);
        test::expectError([&] { io::readPointCloud(lasRegistry(), file); }, code, file, words);
    }

    fs::path dir_;
};

TEST_F(LasBadInput, EmptyFile)
{
    expectInvalid("empty.las", "", ErrorCode::InvalidData, "empty file");
}

TEST_F(LasBadInput, WrongSignature)
{
    std::string bytes = makeLas12Format1().str();
    bytes[3] = 'X';
    expectInvalid("signature.las", bytes, ErrorCode::InvalidData, "LASF");
    expectInvalid("text.las", "x y z\n1 2 3\n", ErrorCode::InvalidData, "LASF");
}

TEST_F(LasBadInput, HeaderTooShort)
{
    expectInvalid("short.las", makeLas12Format1().str().substr(0, 100), ErrorCode::InvalidData, "header too short");
    // A 1.4 file whose header size field says 227.
    Bytes b = makeLas14Format10();
    b.put<std::uint16_t>(94, 227);
    expectInvalid("short14.las", b.str(), ErrorCode::InvalidData, "header too short");
}

TEST_F(LasBadInput, UnknownVersion)
{
    Bytes b = makeLas12Format1();
    b.put<std::uint8_t>(25, 9);
    expectInvalid("v19.las", b.str(), ErrorCode::InvalidData, "unknown LAS version 1.9");
    b.put<std::uint8_t>(24, 2);
    b.put<std::uint8_t>(25, 0);
    expectInvalid("v20.las", b.str(), ErrorCode::InvalidData, "unknown LAS version 2.0");
}

TEST_F(LasBadInput, UnknownPointFormat)
{
    Bytes b = makeLas12Format1();
    b.put<std::uint8_t>(104, 11);
    expectInvalid("format11.las", b.str(), ErrorCode::InvalidData, "unknown point data record format 11");
}

TEST_F(LasBadInput, CompressedPointsWithoutALaszipRecord)
{
    Bytes b = makeLas12Format1();
    b.put<std::uint8_t>(104, 0x80 | 1);
    expectInvalid("compressed.las", b.str(), ErrorCode::InvalidData, "no LASzip record");
    b.put<std::uint8_t>(104, 0x40 | 1);
    expectInvalid("compressed_bit6.las", b.str(), ErrorCode::InvalidData, "no LASzip record");
}

TEST_F(LasBadInput, OffsetToPointDataBeyondTheFile)
{
    Bytes b = makeLas12Format1();
    b.put<std::uint32_t>(96, static_cast<std::uint32_t>(b.size() + 1));
    expectInvalid("offset.las", b.str(), ErrorCode::InvalidData, "beyond the end of the file");
}

TEST_F(LasBadInput, Truncated)
{
    std::string bytes = makeLas12Format1().str();
    bytes.pop_back();
    expectInvalid("truncated.las", bytes, ErrorCode::InvalidData, "truncated");
    // A point count far beyond the data, in the 64-bit count of a 1.4 header.
    Bytes b = makeLas14Format10();
    b.put<std::uint64_t>(247, 0xFFFFFFFFFFFFull);
    expectInvalid("count.las", b.str(), ErrorCode::InvalidData, "truncated");
}

TEST_F(LasBadInput, RecordLengthSmallerThanTheFormat)
{
    Bytes b = makeLas12Format1();
    b.put<std::uint16_t>(105, 20); // format 1 needs 28
    expectInvalid("record.las", b.str(), ErrorCode::InvalidData, "point record length");
}

TEST_F(LasBadInput, MissingFile)
{
    const fs::path file = dir_ / "missing.las";
    test::expectError([&] { io::readPointCloud(lasRegistry(), file); }, ErrorCode::Io, file, "no such file");
}

// ---------------------------------------------------------------------------
// Coordinate reference systems.

//! A LAS 1.2 file of one point whose only VLR is a GeoKeyDirectoryTag
//! (LASF_Projection 34735) holding the given (key, value) pairs, each stored
//! in place (location 0).
Bytes makeLasWithGeoKeys(const std::vector<std::pair<std::uint16_t, std::uint16_t>>& keys)
{
    const std::size_t payload = 8 + 8 * keys.size();
    HeaderSpec s;
    s.count = 1;
    s.vlrCount = 1;
    s.offsetToPoints = static_cast<std::uint32_t>(227 + 54 + payload);
    Bytes b = makeHeader(s);
    b.putText(227 + 2, "LASF_Projection");
    b.put<std::uint16_t>(227 + 18, 34735);
    b.put<std::uint16_t>(227 + 20, static_cast<std::uint16_t>(payload));
    const std::size_t p = 227 + 54;
    b.put<std::uint16_t>(p + 0, 1); // KeyDirectoryVersion
    b.put<std::uint16_t>(p + 2, 1); // KeyRevision
    b.put<std::uint16_t>(p + 4, 0); // MinorRevision
    b.put<std::uint16_t>(p + 6, static_cast<std::uint16_t>(keys.size()));
    for (std::size_t k = 0; k < keys.size(); ++k) {
        b.put<std::uint16_t>(p + 8 + 8 * k, keys[k].first);
        b.put<std::uint16_t>(p + 8 + 8 * k + 2, 0);
        b.put<std::uint16_t>(p + 8 + 8 * k + 4, 1);
        b.put<std::uint16_t>(p + 8 + 8 * k + 6, keys[k].second);
    }
    b.put<std::int32_t>(s.offsetToPoints + 27, 0); // one all-zero point of 28 bytes
    return b;
}

TEST(LasCrs, GeoTiffKeysBecomeTheWktOfTheirEpsgCodes)
{
    const fs::path file = test::tempDir() / "geokeys.las";
    // GTModelType projected, Lambert-93 (EPSG 2154), NGF-IGN69 height (EPSG 5720).
    test::writeText(file, makeLasWithGeoKeys({{1024, 1}, {3072, 2154}, {4096, 5720}}).str());
    const PointCloud cloud = io::readPointCloud(lasRegistry(), file);
    ASSERT_EQ(cloud.size(), 1u);
    EXPECT_EQ(cloud.crsWkt(), io::crsFromUserInput("EPSG:2154+5720"));
    EXPECT_NE(io::crsName(cloud.crsWkt()).find("Lambert-93"), std::string::npos) << io::crsName(cloud.crsWkt());

    // Geographic only.
    test::writeText(file, makeLasWithGeoKeys({{1024, 2}, {2048, 4326}}).str());
    EXPECT_EQ(io::readPointCloud(lasRegistry(), file).crsWkt(), io::crsFromUserInput("EPSG:4326"));
}

TEST(LasCrs, UserDefinedOrUnknownKeysLeaveNoSystemAndAWarning)
{
    const fs::path file = test::tempDir() / "userkeys.las";
    for (std::uint16_t code : {std::uint16_t{32767}, std::uint16_t{65000}}) {
        test::CapturedLog log;
        test::writeText(file, makeLasWithGeoKeys({{3072, code}}).str());
        const PointCloud cloud = io::readPointCloud(lasRegistry(), file);
        EXPECT_EQ(cloud.size(), 1u);
        EXPECT_TRUE(cloud.crsWkt().empty()) << code;
        ASSERT_EQ(log.warnings.size(), 1u) << code;
        EXPECT_NE(log.warnings[0].find("coordinate reference system"), std::string::npos) << log.warnings[0];
    }
    {
        // A user-defined projection over a known geographic base is not
        // labelled with the base: its coordinates are metres, not degrees.
        test::CapturedLog log;
        test::writeText(file, makeLasWithGeoKeys({{1024, 1}, {3072, 32767}, {2048, 4269}}).str());
        EXPECT_TRUE(io::readPointCloud(lasRegistry(), file).crsWkt().empty());
        EXPECT_EQ(log.warnings.size(), 1u);
    }
    {
        // An unknown vertical system leaves the horizontal one, with a warning.
        test::CapturedLog log;
        test::writeText(file, makeLasWithGeoKeys({{3072, 2154}, {4096, 65000}}).str());
        EXPECT_EQ(io::readPointCloud(lasRegistry(), file).crsWkt(), io::crsFromUserInput("EPSG:2154"));
        ASSERT_EQ(log.warnings.size(), 1u);
        EXPECT_NE(log.warnings[0].find("vertical"), std::string::npos) << log.warnings[0];
    }
    // A key count beyond the record reads only the keys that are there.
    Bytes b = makeLasWithGeoKeys({{3072, 2154}});
    b.put<std::uint16_t>(227 + 54 + 6, 60000);
    test::writeText(file, b.str());
    EXPECT_EQ(io::readPointCloud(lasRegistry(), file).crsWkt(), io::crsFromUserInput("EPSG:2154"));
}

TEST(LasCrs, TheWktRecordRoundTripsExactlyEvenBeyondAVariableLengthRecord)
{
    PointCloud cloud;
    cloud.setOrigin({651000, 6862000, 0});
    cloud.positions() = {{1.5f, 2.25f, 30.0f}, {2.5f, 3.0f, 31.0f}};
    cloud.setCrsWkt(io::crsFromUserInput("EPSG:2154+5720"));
    const fs::path file = test::tempDir() / "crs.las";
    io::writePointCloud(lasRegistry(), cloud, file);
    EXPECT_EQ(io::readPointCloud(lasRegistry(), file).crsWkt(), cloud.crsWkt());

    // A WKT longer than a VLR's 65535 bytes goes into an extended record after
    // the points (the header then counts one EVLR).
    const std::string longWkt = "LOCAL_CS[\"" + std::string(70000, 'x') + "\",UNIT[\"metre\",1]]";
    cloud.setCrsWkt(longWkt);
    io::writePointCloud(lasRegistry(), cloud, file);
    const std::string bytes = test::readBytes(file);
    std::uint32_t evlrCount = 0;
    std::memcpy(&evlrCount, bytes.data() + 243, 4);
    EXPECT_EQ(evlrCount, 1u);
    const PointCloud back = io::readPointCloud(lasRegistry(), file);
    EXPECT_EQ(back.crsWkt(), longWkt);
    EXPECT_EQ(back.size(), 2u);
}

TEST(Crs, UnknownUserInputIsAClearError)
{
    try {
        io::crsFromUserInput("EPSG:99999999");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
        EXPECT_NE(std::string(e.what()).find("EPSG:99999999"), std::string::npos);
    }
    EXPECT_EQ(io::crsName(""), "");
    EXPECT_EQ(io::crsName("not a wkt"), "not a wkt");
}

} // namespace

namespace {

//! The integer coordinates of every record of a LAS file (uncompressed).
std::vector<std::array<std::int32_t, 3>> recordIntegers(const std::string& bytes)
{
    std::uint32_t offsetToPoints = 0, legacyCount = 0;
    std::uint16_t recordLength = 0;
    std::uint64_t count = 0;
    std::memcpy(&offsetToPoints, bytes.data() + 96, 4);
    std::memcpy(&recordLength, bytes.data() + 105, 2);
    std::memcpy(&legacyCount, bytes.data() + 107, 4);
    count = legacyCount;
    if (static_cast<unsigned char>(bytes[25]) >= 4 && bytes.size() >= 255)
        std::memcpy(&count, bytes.data() + 247, 8);
    std::vector<std::array<std::int32_t, 3>> integers(count);
    for (std::size_t i = 0; i < count; ++i)
        std::memcpy(integers[i].data(), bytes.data() + offsetToPoints + i * recordLength, 12);
    return integers;
}

} // namespace

TEST(LasFormat, RoundTripsKeepEveryIntegerAtAnyScale)
{
    // Grids finer than a float's step where the points lie: scales of 1e-7 to
    // 1e-3 over boxes of 1 m to 5 km, offsets far from zero, some headers
    // whose box is wrong (all zeros). Written back as LAS and LAZ, through a
    // subset and a merge of the file with itself: every integer the same.
    io::FormatRegistry registry;
    io::registerBuiltinFormats(registry);
    const fs::path dir = test::tempDir();
    for (std::uint32_t seed = 1; seed <= 24; ++seed) {
        std::mt19937_64 rng(seed);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        HeaderSpec s;
        s.minor = 2;
        s.format = 0;
        s.recordLength = 20;
        s.count = 400;
        std::vector<std::array<std::int32_t, 3>> truth(s.count);
        for (int a = 0; a < 3; ++a) {
            s.scale[a] = std::pow(10.0, -7.0 + 4.0 * u(rng)) * (1.0 + u(rng));
            s.offset[a] = std::round(1e6 * u(rng) * 5.0) + (a == 2 ? 0.123456 : 0.0);
            const double extent = std::pow(10.0, 3.7 * u(rng)); // 1 m to 5 km
            const auto span = static_cast<std::int64_t>(std::min(extent / s.scale[a], 2.0e9));
            const std::int64_t start = static_cast<std::int64_t>(u(rng) * static_cast<double>(2'000'000'000 - span)) - 1'000'000'000;
            std::int32_t lo = std::numeric_limits<std::int32_t>::max(), hi = std::numeric_limits<std::int32_t>::lowest();
            for (auto& point : truth) {
                point[a] = static_cast<std::int32_t>(start + static_cast<std::int64_t>(u(rng) * static_cast<double>(span)));
                lo = std::min(lo, point[a]);
                hi = std::max(hi, point[a]);
            }
            const bool honestBox = seed % 5 != 0;
            s.min[a] = honestBox ? s.offset[a] + lo * s.scale[a] : 0.0;
            s.max[a] = honestBox ? s.offset[a] + hi * s.scale[a] : 0.0;
        }
        Bytes b = makeHeader(s);
        b.put<std::uint8_t>(s.offsetToPoints + s.count * s.recordLength - 1, 0); // every record's bytes
        for (std::size_t i = 0; i < truth.size(); ++i)
            for (int a = 0; a < 3; ++a)
                b.put<std::int32_t>(s.offsetToPoints + i * s.recordLength + 4 * static_cast<std::size_t>(a), truth[i][static_cast<std::size_t>(a)]);
        test::writeText(dir / "in.las", b.str());
        const PointCloud cloud = io::readPointCloud(registry, dir / "in.las");
        io::writePointCloud(registry, cloud, dir / "out.las");
        EXPECT_EQ(recordIntegers(test::readBytes(dir / "out.las")), truth) << "seed " << seed;
        io::writePointCloud(registry, cloud, dir / "out.laz");
        io::writePointCloud(registry, io::readPointCloud(registry, dir / "out.laz"), dir / "again.las");
        EXPECT_EQ(recordIntegers(test::readBytes(dir / "again.las")), truth) << "seed " << seed << " through LAZ";
        std::vector<std::size_t> odd;
        for (std::size_t i = 1; i < truth.size(); i += 2)
            odd.push_back(i);
        io::writePointCloud(registry, cloud.subset(odd), dir / "subset.las");
        const auto subset = recordIntegers(test::readBytes(dir / "subset.las"));
        ASSERT_EQ(subset.size(), odd.size());
        for (std::size_t k = 0; k < odd.size(); ++k)
            ASSERT_EQ(subset[k], truth[odd[k]]) << "seed " << seed << " subset " << k;
        PointCloud shifted = cloud.clone();
        shifted.shiftOrigin(shifted.origin() + Eigen::Vector3d(1234.5, -987.25, 3.0));
        const PointCloud merged = mergeClouds({&cloud, &shifted});
        io::writePointCloud(registry, merged, dir / "merged.las");
        const auto both = recordIntegers(test::readBytes(dir / "merged.las"));
        ASSERT_EQ(both.size(), 2 * truth.size());
        for (std::size_t i = 0; i < truth.size(); ++i) {
            ASSERT_EQ(both[i], truth[i]) << "seed " << seed << " merged " << i;
            ASSERT_EQ(both[truth.size() + i], truth[i]) << "seed " << seed << " merged, shifted origin " << i;
        }
    }
}

TEST(LasFormat, LaspysFineGridSampleComesBackWithTheSameIntegers)
{
    // 1_4_w_evlr (laspy's test data, data/laz/README.md): a scale of 1.2e-6
    // ft about 2,000 ft from the offset, where a float's step is 1.2e-4 ft.
    io::FormatRegistry registry;
    io::registerBuiltinFormats(registry);
    const fs::path sample = fs::path(SCANDIFF_SAMPLE_DATA_DIR) / "laz" / "1_4_w_evlr.las";
    const auto truth = recordIntegers(test::readBytes(sample));
    ASSERT_EQ(truth.size(), 1000u);
    const fs::path dir = test::tempDir();
    for (const char* source : {"1_4_w_evlr.las", "1_4_w_evlr.laz"}) {
        const PointCloud cloud = io::readPointCloud(registry, sample.parent_path() / source);
        EXPECT_FALSE(cloud.positionResiduals().empty());
        io::writePointCloud(registry, cloud, dir / "out.las");
        EXPECT_EQ(recordIntegers(test::readBytes(dir / "out.las")), truth) << source;
    }
    // A file a float holds exactly (1 cm, 12 m from the offset) keeps no residuals.
    test::writeText(dir / "coarse.las", makeLas12Format1().str());
    EXPECT_TRUE(io::readPointCloud(registry, dir / "coarse.las").positionResiduals().empty());
}
