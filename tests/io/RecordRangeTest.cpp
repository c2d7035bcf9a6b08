// SPDX-License-Identifier: GPL-3.0-or-later
// Reading a file by ranges of records and writing one chunk by chunk (what
// scandiff-mpi streams its clouds with): the ranges put together are the
// whole read, value for value, in the whole read's frame.
#include <scandiff/core/Error.h>
#include <scandiff/io/FileIO.h>

#include "BuiltinFormats.h"
#include "TestSupport.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

namespace scandiff::test {
namespace {

namespace fs = std::filesystem;

//! UTM-sized coordinates (so the origin matters), colours, a float field, a
//! double field, and a point with a NaN coordinate the readers drop.
PointCloud sampleCloud(std::size_t n)
{
    PointCloud cloud;
    cloud.setOrigin({500000.0, 5400000.0, 100.0});
    cloud.resize(n);
    std::mt19937 random(7);
    std::uniform_real_distribution<float> coordinate(-300.f, 300.f);
    auto& colours = cloud.enableColors();
    cloud.addField(ScalarField("intensity", n));
    cloud.addField(ScalarField("gps_time", n));
    // References once both exist: adding a field may move the others.
    ScalarField& intensity = *cloud.field("intensity");
    ScalarField& time = *cloud.field("gps_time");
    time.keepDoubles();
    for (std::size_t i = 0; i < n; ++i) {
        cloud.positions()[i] = {coordinate(random), coordinate(random), coordinate(random) / 30};
        colours[i] = {static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(i / 7), 200};
        intensity.values()[i] = static_cast<float>(i % 1000);
        time.setValue(i, 1.4e9 + static_cast<double>(i) * 1.000001e-3);
    }
    cloud.positions()[n / 2].x() = std::numeric_limits<float>::quiet_NaN();
    return cloud;
}

bool sameBits(double a, double b)
{
    return std::memcmp(&a, &b, sizeof a) == 0 || (std::isnan(a) && std::isnan(b));
}

void expectSameCloud(const PointCloud& a, const PointCloud& b)
{
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i)
        for (int k = 0; k < 3; ++k)
            ASSERT_TRUE(sameBits(a.globalPosition(i)[k], b.globalPosition(i)[k])) << "point " << i;
    ASSERT_EQ(a.hasColors(), b.hasColors());
    if (a.hasColors())
        for (std::size_t i = 0; i < a.size(); ++i)
            ASSERT_TRUE(a.colors()[i].r == b.colors()[i].r && a.colors()[i].g == b.colors()[i].g) << i;
    ASSERT_EQ(a.fields().size(), b.fields().size());
    for (const ScalarField& f : a.fields()) {
        const ScalarField* g = b.field(f.name());
        ASSERT_NE(g, nullptr) << f.name();
        for (std::size_t i = 0; i < a.size(); ++i)
            ASSERT_TRUE(sameBits(f.value(i), g->value(i))) << f.name() << " " << i << ": " << f.value(i) << " vs " << g->value(i);
    }
}

//! The ranges of `path`, read one by one and put back together.
PointCloud readByRanges(const io::FormatRegistry& registry, const fs::path& path, std::uint64_t step)
{
    const std::uint64_t records = io::pointRecordCount(registry, path);
    std::unique_ptr<io::PointChunkWriter> writer;
    std::vector<PointCloud> parts;
    std::uint64_t kept = 0;
    for (std::uint64_t first = 0; first < records; first += step) {
        parts.push_back(io::readPointRecords(registry, path, {first, step}));
        kept += parts.back().size();
    }
    for (const PointCloud& part : parts) {
        if (!writer)
            writer = io::openPointChunkWriter(registry, path.parent_path() / "joined.ply", part, kept);
        writer->append(part);
    }
    writer->commit();
    return io::readPointCloud(registry, path.parent_path() / "joined.ply");
}

TEST(RecordRanges, BinaryPlyRangesPutTogetherAreTheWholeRead)
{
    const auto registry = builtinFormats();
    const fs::path dir = tempDir();
    io::writePointCloud(registry, sampleCloud(10007), dir / "cloud.ply");
    EXPECT_EQ(io::pointRecordCount(registry, dir / "cloud.ply"), 10007u);
    const PointCloud whole = io::readPointCloud(registry, dir / "cloud.ply");
    EXPECT_EQ(whole.size(), 10006u); // the NaN point is dropped either way
    // A range in the middle has the whole read's origin, not one of its own.
    const PointCloud middle = io::readPointRecords(registry, dir / "cloud.ply", {5000, 100});
    EXPECT_EQ(middle.origin(), whole.origin());
    EXPECT_EQ(middle.size(), 99u);
    expectSameCloud(readByRanges(registry, dir / "cloud.ply", 999), whole);
}

TEST(RecordRanges, GeometryOnlySkipsColoursAndFields)
{
    const auto registry = builtinFormats();
    const fs::path dir = tempDir();
    io::writePointCloud(registry, sampleCloud(500), dir / "cloud.ply");
    io::ReadOptions options;
    options.geometryOnly = true;
    const PointCloud part = io::readPointRecords(registry, dir / "cloud.ply", {10, 20}, options);
    const PointCloud whole = io::readPointCloud(registry, dir / "cloud.ply");
    EXPECT_FALSE(part.hasColors());
    EXPECT_TRUE(part.fields().empty());
    ASSERT_EQ(part.size(), 20u);
    for (std::size_t i = 0; i < part.size(); ++i)
        EXPECT_EQ(part.globalPosition(i), whole.globalPosition(10 + i));
}

TEST(RecordRanges, LasRangesPutTogetherAreTheWholeRead)
{
    const auto registry = builtinFormats();
    const fs::path dir = tempDir();
    PointCloud cloud = sampleCloud(3001);
    cloud.positions()[1500].x() = 0; // LAS cannot hold a NaN coordinate
    io::writePointCloud(registry, cloud, dir / "cloud.las");
    const PointCloud whole = io::readPointCloud(registry, dir / "cloud.las");
    // The ranges keep the standard fields a whole read drops for being all 0;
    // every field of the whole read is among them, with the same values.
    std::size_t next = 0;
    for (std::uint64_t first = 0; first < 3001; first += 700) {
        const PointCloud part = io::readPointRecords(registry, dir / "cloud.las", {first, 700});
        EXPECT_EQ(part.origin(), whole.origin());
        for (std::size_t i = 0; i < part.size(); ++i, ++next) {
            ASSERT_EQ(part.globalPosition(i), whole.globalPosition(next));
            for (const ScalarField& f : whole.fields()) {
                const ScalarField* g = part.field(f.name());
                ASSERT_NE(g, nullptr) << f.name();
                ASSERT_TRUE(sameBits(f.value(next), g->value(i))) << f.name() << " " << next;
            }
        }
    }
    EXPECT_EQ(next, whole.size());
}

TEST(RecordRanges, FormatsThatCannotSeekSaySo)
{
    const auto registry = builtinFormats();
    const fs::path dir = tempDir();
    io::writePointCloud(registry, sampleCloud(50), dir / "cloud.xyz");
    EXPECT_FALSE(io::canReadRecordRanges(registry, dir / "cloud.xyz"));
    EXPECT_EQ(errorCodeOf([&] { io::readPointRecords(registry, dir / "cloud.xyz", {0, 10}); }), ErrorCode::Unsupported);
    io::WriteOptions ascii;
    ascii.encoding = io::Encoding::Ascii;
    io::writePointCloud(registry, sampleCloud(50), dir / "text.ply", ascii);
    EXPECT_EQ(errorCodeOf([&] { io::readPointRecords(registry, dir / "text.ply", {0, 10}); }), ErrorCode::Unsupported);
    io::writePointCloud(registry, sampleCloud(50), dir / "cloud.laz");
    EXPECT_EQ(errorCodeOf([&] { io::readPointRecords(registry, dir / "cloud.laz", {0, 10}); }), ErrorCode::Unsupported);
}

TEST(RecordRanges, ChunkWriterChecksWhatItIsGiven)
{
    const auto registry = builtinFormats();
    const fs::path dir = tempDir();
    const PointCloud cloud = sampleCloud(100);
    {
        auto writer = io::openPointChunkWriter(registry, dir / "short.ply", cloud, 150);
        writer->append(cloud);
        EXPECT_EQ(errorCodeOf([&] { writer->commit(); }), ErrorCode::InvalidArgument); // 100 of 150
        EXPECT_EQ(errorCodeOf([&] { writer->append(cloud); }), ErrorCode::InvalidArgument); // 200 > 150
    }
    EXPECT_FALSE(fs::exists(dir / "short.ply")); // never committed: nothing left
    PointCloud other = cloud.clone();
    other.removeField("intensity");
    auto writer = io::openPointChunkWriter(registry, dir / "mixed.ply", cloud, 200);
    EXPECT_EQ(errorCodeOf([&] { writer->append(other); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(errorCodeOf([&] { io::openPointChunkWriter(registry, dir / "cloud.las", cloud, 100); }), ErrorCode::Unsupported);
}

} // namespace
} // namespace scandiff::test
