// SPDX-License-Identifier: GPL-3.0-or-later
// Double-valued attributes (GPS time, double properties, long decimals) come
// back from every writable point format with the same bits, twice over.
#include <scandiff/core/Error.h>
#include <scandiff/io/FileIO.h>

#include "TestSupport.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

using namespace scandiff;

namespace {

io::FormatRegistry builtinFormats()
{
    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    return formats;
}

constexpr std::size_t kPoints = 257;

//! GPS times over 2.6 hours with their microseconds (a float around an offset
//! keeps them to ~1 ms), a double that no float holds (0.1 + (i+1)·1e-12) and
//! a NaN.
PointCloud cloudWithDoubleFields()
{
    PointCloud cloud;
    cloud.setOrigin({512000, 5423000, 100});
    cloud.resize(kPoints);
    for (std::size_t i = 0; i < kPoints; ++i)
        cloud.positions()[i] = Eigen::Vector3f(0.25f * static_cast<float>(i), -0.5f * static_cast<float>(i % 17), 3.0f);
    ScalarField time("gps_time", kPoints);
    time.setOffset(1.4e9);
    time.keepDoubles();
    ScalarField tilt("tilt", kPoints);
    tilt.keepDoubles();
    ScalarField intensity("intensity", kPoints);
    for (std::size_t i = 0; i < kPoints; ++i) {
        const double k = static_cast<double>(i);
        time.setValue(i, 1.4e9 + 1234.5 + k * 37.123457);
        tilt.setValue(i, i % 31 == 5 ? std::numeric_limits<double>::quiet_NaN() : 0.1 + (k + 1) * 1e-12);
        intensity.setValue(i, static_cast<double>((i * 97) % 4096));
    }
    cloud.addField(std::move(time));
    cloud.addField(std::move(tilt));
    cloud.addField(std::move(intensity));
    return cloud;
}

void expectSameValues(const PointCloud& expected, const PointCloud& actual, const std::string& what)
{
    ASSERT_EQ(expected.size(), actual.size()) << what;
    for (const char* name : {"gps_time", "tilt", "intensity"}) {
        const ScalarField* e = expected.field(name);
        const ScalarField* a = actual.field(name);
        ASSERT_NE(a, nullptr) << what << ": no field " << name;
        for (std::size_t i = 0; i < expected.size(); ++i) {
            if (!e->hasValue(i)) {
                // LAS has no "no value": a NaN is written as 0 there.
                EXPECT_TRUE(!a->hasValue(i) || a->value(i) == 0.0) << what << " " << name << " " << i;
                continue;
            }
            // Equality of the doubles, not closeness.
            EXPECT_EQ(e->value(i), a->value(i)) << what << " " << name << " point " << i;
        }
    }
}

struct Target
{
    std::string file;
    io::Encoding encoding;
};

} // namespace

TEST(DoubleFields, EveryWritableFormatGivesTheSameBitsBackTwice)
{
    const io::FormatRegistry formats = builtinFormats();
    const PointCloud original = cloudWithDoubleFields();
    // The fixture really needs doubles: the float view alone would lose them.
    const ScalarField& time = *original.field("gps_time");
    EXPECT_NE(time.offset() + static_cast<double>(time.values()[200]), time.value(200));
    EXPECT_NE(static_cast<double>(original.field("tilt")->values()[0]), original.field("tilt")->value(0));

    const auto dir = test::tempDir();
    const std::vector<Target> targets = {
        {"a.ply", io::Encoding::BinaryLittleEndian}, {"b.ply", io::Encoding::BinaryBigEndian},
        {"c.ply", io::Encoding::Ascii},              {"d.pcd", io::Encoding::Ascii},
        {"e.pcd", io::Encoding::BinaryLittleEndian}, {"f.pcd", io::Encoding::BinaryCompressed},
        {"g.las", io::Encoding::Default},            {"h.xyz", io::Encoding::Default},
        {"i.csv", io::Encoding::Default},
    };
    for (const Target& target : targets) {
        io::WriteOptions write;
        write.encoding = target.encoding;
        io::writePointCloud(formats, original, dir / target.file, write);
        const PointCloud once = io::readPointCloud(formats, dir / target.file);
        expectSameValues(original, once, target.file);
        EXPECT_TRUE(once.field("gps_time")->isDouble()) << target.file;
        EXPECT_TRUE(once.field("tilt")->isDouble()) << target.file;

        const std::string again = "again_" + target.file;
        io::writePointCloud(formats, once, dir / again, write);
        const PointCloud twice = io::readPointCloud(formats, dir / again);
        expectSameValues(original, twice, again);
    }
}

TEST(DoubleFields, APointDroppedByTheReaderTakesItsDoubleWithIt)
{
    const io::FormatRegistry formats = builtinFormats();
    const PointCloud original = cloudWithDoubleFields();
    const auto dir = test::tempDir();
    // A cloud whose point 3 has a non-finite coordinate: the reader drops it.
    PointCloud holed = original.clone();
    holed.positions()[3].x() = std::numeric_limits<float>::quiet_NaN();
    io::WriteOptions ascii;
    ascii.encoding = io::Encoding::Ascii;
    io::writePointCloud(formats, holed, dir / "holed.ply", ascii);
    const PointCloud back = io::readPointCloud(formats, dir / "holed.ply");
    ASSERT_EQ(back.size(), kPoints - 1);
    for (std::size_t i = 0; i + 1 < kPoints; ++i)
        EXPECT_EQ(back.field("gps_time")->value(i), original.field("gps_time")->value(i < 3 ? i : i + 1)) << i;
}

TEST(DoubleFields, PlyIntegersWiderThanAFloatAreKeptOnlyWhenNeeded)
{
    const io::FormatRegistry formats = builtinFormats();
    const auto dir = test::tempDir();
    {
        std::ofstream out(dir / "ints.ply");
        out << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
               "property int wide\nproperty int narrow\nproperty double exact\nend_header\n"
               "0 0 0 -2000000001 1000001 0.5\n1 0 0 2000000003 1000002 0.25\n2 0 0 7 1000003 2\n";
    }
    const PointCloud cloud = io::readPointCloud(formats, dir / "ints.ply");
    const ScalarField& wide = *cloud.field("wide");
    const ScalarField& narrow = *cloud.field("narrow");
    const ScalarField& exact = *cloud.field("exact");
    EXPECT_TRUE(wide.isDouble());    // a span of 4e9: no float around an offset holds it
    EXPECT_FALSE(narrow.isDouble()); // a float around 1000001 holds 1000001..1000003
    EXPECT_TRUE(exact.isDouble());   // a double property stays a double
    EXPECT_EQ(wide.value(0), -2000000001.0);
    EXPECT_EQ(wide.value(1), 2000000003.0);
    EXPECT_EQ(wide.value(2), 7.0);
    EXPECT_EQ(narrow.value(2), 1000003.0);
    EXPECT_EQ(exact.value(1), 0.25);
}

TEST(DoubleFields, TextKeepsDoublesOnlyForColumnsAFloatCannotGiveBack)
{
    const io::FormatRegistry formats = builtinFormats();
    const auto dir = test::tempDir();
    {
        std::ofstream out(dir / "columns.txt");
        out << "//X Y Z short long late\n"
               "1 2 3 0.1 0.123456789012 5\n"
               "4 5 6 0.35 0.2 6\n"
               "7 8 9 12.5 0.3 6.00000000001\n";
    }
    const PointCloud cloud = io::readPointCloud(formats, dir / "columns.txt");
    ASSERT_EQ(cloud.size(), 3u);
    EXPECT_FALSE(cloud.field("short")->isDouble()); // six digits at most: the float's shortest form gives them back
    EXPECT_TRUE(cloud.field("long")->isDouble());
    EXPECT_EQ(cloud.field("long")->value(0), 0.123456789012);
    EXPECT_EQ(cloud.field("long")->value(1), 0.2);
    // A column turns double at its first long value; the earlier ones are exact.
    ASSERT_TRUE(cloud.field("late")->isDouble());
    EXPECT_EQ(cloud.field("late")->value(0), 5.0);
    EXPECT_EQ(cloud.field("late")->value(1), 6.0);
    EXPECT_EQ(cloud.field("late")->value(2), 6.00000000001);
}

TEST(DoubleFields, ResidualsHoldGpsTimesAndDoublesTakeOverWhereTheyCannot)
{
    // Real GPS times (hours from the offset, microseconds) fit a float and its
    // float residual: 4 bytes more a point. Times spread over years from the
    // first one do not (over 50 bits): the reader then keeps doubles. Both come back
    // to the bit.
    const io::FormatRegistry formats = builtinFormats();
    const auto dir = test::tempDir();
    for (const double spacing : {37.123457, 1e8 + 0.123457}) {
        PointCloud cloud;
        cloud.resize(100);
        ScalarField time("gps_time", 100);
        time.setOffset(1.4e9);
        time.keepDoubles();
        for (std::size_t i = 0; i < 100; ++i) {
            cloud.positions()[i] = Eigen::Vector3f(static_cast<float>(i), 0.0f, 0.0f);
            time.setValue(i, 1.4e9 + static_cast<double>(i) * spacing);
        }
        cloud.addField(std::move(time));
        for (const char* file : {"t.las", "t.ply"}) {
            io::writePointCloud(formats, cloud, dir / file);
            const PointCloud back = io::readPointCloud(formats, dir / file);
            const ScalarField& read = *back.field("gps_time");
            const bool residuals = spacing < 100;
            EXPECT_EQ(read.residuals().empty(), !residuals) << file << " " << spacing;
            EXPECT_EQ(read.doubles().empty(), residuals) << file << " " << spacing;
            for (std::size_t i = 0; i < 100; ++i)
                ASSERT_EQ(read.value(i), cloud.field("gps_time")->value(i)) << file << " " << spacing << " " << i;
        }
    }
}
