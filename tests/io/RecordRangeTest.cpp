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
    if (a.hasColors()) {
        for (std::size_t i = 0; i < a.size(); ++i)
            ASSERT_TRUE(a.colors()[i].r == b.colors()[i].r && a.colors()[i].g == b.colors()[i].g) << i;
    }
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
    // LAZ reads ranges (the chunks holding them): LazFormat.RangesOfRecordsReadAsTheLasTwinsRanges.
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

TEST(RecordRanges, TheRangesBoxesMakeTheWholeReadsOrigin)
{
    const auto registry = builtinFormats();
    const fs::path dir = tempDir();
    const PointCloud written = sampleCloud(10007);
    io::writePointCloud(registry, written, dir / "cloud.ply");
    const PointCloud whole = io::readPointCloud(registry, dir / "cloud.ply");
    // Three uneven parts and an empty one, as ranks scan them.
    BoundingBox joined;
    for (const io::RecordRange range : {io::RecordRange{0, 10}, io::RecordRange{10, 6000}, io::RecordRange{6010, 5000},
                                        io::RecordRange{10007, 0}}) {
        const std::optional<BoundingBox> part = io::pointRecordBounds(registry, dir / "cloud.ply", range);
        ASSERT_TRUE(part.has_value());
        if (part->empty)
            continue;
        joined.min = joined.empty ? part->min : joined.min.cwiseMin(part->min);
        joined.max = joined.empty ? part->max : joined.max.cwiseMax(part->max);
        joined.empty = false;
    }
    // Exactly the box of the coordinates in the file (the doubles written),
    // axis by axis, the NaN left out.
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (std::size_t i = 0; i < written.size(); ++i)
        for (int a = 0; a < 3; ++a)
            if (const double v = written.globalPosition(i)[a]; std::isfinite(v)) {
                lo[a] = std::min(lo[a], v);
                hi[a] = std::max(hi[a], v);
            }
    EXPECT_EQ(joined.min, lo);
    EXPECT_EQ(joined.max, hi);
    EXPECT_EQ(suggestOrigin(joined), whole.origin());

    // Float coordinates and LAS: the header fixes the origin, no box is needed.
    PointCloud local = sampleCloud(100);
    local.setOrigin(Eigen::Vector3d::Zero());
    io::writePointCloud(registry, local, dir / "local.ply");
    EXPECT_FALSE(io::pointRecordBounds(registry, dir / "local.ply", {0, 100}).has_value());
    PointCloud las = sampleCloud(100);
    las.positions()[50].x() = 0;
    io::writePointCloud(registry, las, dir / "cloud.las");
    EXPECT_FALSE(io::pointRecordBounds(registry, dir / "cloud.las", {0, 100}).has_value());
    io::WriteOptions ascii;
    ascii.encoding = io::Encoding::Ascii;
    io::writePointCloud(registry, sampleCloud(50), dir / "text.ply", ascii);
    EXPECT_EQ(errorCodeOf([&] { io::pointRecordBounds(registry, dir / "text.ply", {0, 10}); }), ErrorCode::Unsupported);
}

// scandiff-mpi reads a chunk's coordinates once, in double, to choose the
// origin, then takes its geometry from them: they must be the file's values
// to the bit, in either byte order, and make the range's geometry read.
TEST(RecordRanges, PositionsOfARangeAreTheFilesDoubles)
{
    const auto registry = builtinFormats();
    const fs::path dir = tempDir();
    const PointCloud written = sampleCloud(10007);
    io::WriteOptions bigEndian;
    bigEndian.encoding = io::Encoding::BinaryBigEndian;
    io::writePointCloud(registry, written, dir / "little.ply");
    io::writePointCloud(registry, written, dir / "big.ply", bigEndian);
    const PointCloud whole = io::readPointCloud(registry, dir / "little.ply");
    for (const char* name : {"little.ply", "big.ply"}) {
        std::size_t next = 0;
        for (const io::RecordRange range : {io::RecordRange{0, 10}, io::RecordRange{10, 6000}, io::RecordRange{6010, 5000},
                                            io::RecordRange{10007, 0}}) {
            const std::optional<std::vector<Eigen::Vector3d>> positions =
                io::pointRecordPositions(registry, dir / name, range);
            ASSERT_TRUE(positions.has_value()) << name;
            ASSERT_EQ(positions->size(), std::min<std::uint64_t>(range.count, written.size() - range.first)) << name;
            for (const Eigen::Vector3d& p : *positions) {
                for (int a = 0; a < 3; ++a)
                    ASSERT_TRUE(sameBits(p[a], written.globalPosition(next)[a])) << name << ", record " << next;
                ++next;
            }
            // In the whole read's frame, non-finite points left out: the
            // range's geometry read.
            io::ReadOptions geometry;
            geometry.geometryOnly = true;
            geometry.origin = whole.origin();
            const PointCloud read = io::readPointRecords(registry, dir / name, range, geometry);
            std::vector<Eigen::Vector3f> converted;
            for (const Eigen::Vector3d& p : *positions) {
                const Eigen::Vector3f f = (p - whole.origin()).cast<float>();
                if (f.allFinite())
                    converted.push_back(f);
            }
            EXPECT_EQ(converted, read.positions()) << name;
        }
        EXPECT_EQ(next, written.size());
    }
    // Float coordinates: the origin is zero, nothing to choose; LAS has no
    // such reader; text cannot be read by ranges.
    PointCloud local = sampleCloud(100);
    local.setOrigin(Eigen::Vector3d::Zero());
    io::writePointCloud(registry, local, dir / "local.ply");
    EXPECT_FALSE(io::pointRecordPositions(registry, dir / "local.ply", {0, 100}).has_value());
    PointCloud las = sampleCloud(100);
    las.positions()[50].x() = 0;
    io::writePointCloud(registry, las, dir / "cloud.las");
    EXPECT_FALSE(io::pointRecordPositions(registry, dir / "cloud.las", {0, 100}).has_value());
    io::WriteOptions ascii;
    ascii.encoding = io::Encoding::Ascii;
    io::writePointCloud(registry, sampleCloud(50), dir / "text.ply", ascii);
    EXPECT_EQ(errorCodeOf([&] { io::pointRecordPositions(registry, dir / "text.ply", {0, 10}); }), ErrorCode::Unsupported);
}

TEST(RecordRanges, AnAxisWithNoValueInOnePartStillJoinsAxisByAxis)
{
    // The first half's points have no z (dropped by every read) but their x,
    // 1.5 km west of the rest, still counts for the origin, as in a whole read.
    const auto registry = builtinFormats();
    const fs::path dir = tempDir();
    PointCloud cloud = sampleCloud(2000);
    for (std::size_t i = 0; i < 1000; ++i) {
        cloud.positions()[i].x() -= 1500.f;
        cloud.positions()[i].z() = std::numeric_limits<float>::quiet_NaN();
    }
    io::writePointCloud(registry, cloud, dir / "cloud.ply");
    const PointCloud whole = io::readPointCloud(registry, dir / "cloud.ply");
    EXPECT_EQ(whole.origin().x(), 498000.0);
    const std::optional<BoundingBox> west = io::pointRecordBounds(registry, dir / "cloud.ply", {0, 1000});
    const std::optional<BoundingBox> east = io::pointRecordBounds(registry, dir / "cloud.ply", {1000, 1000});
    ASSERT_TRUE(west && east);
    EXPECT_TRUE(west->empty); // no z there
    BoundingBox joined;
    joined.min = west->min.cwiseMin(east->min);
    joined.max = west->max.cwiseMax(east->max);
    joined.empty = !(joined.min.array() <= joined.max.array()).all();
    EXPECT_EQ(suggestOrigin(joined), whole.origin());
}

TEST(RecordRanges, PlacedWritersFillOneFileAsTheWholeWrite)
{
    const auto registry = builtinFormats();
    const fs::path dir = tempDir();
    io::writePointCloud(registry, sampleCloud(10007), dir / "cloud.ply");
    const PointCloud whole = io::readPointCloud(registry, dir / "cloud.ply");
    io::writePointCloud(registry, whole, dir / "expected.ply");
    // Two writers (two processes in scandiff-mpi), each its own chunks, out of order.
    const std::uint64_t step = 3000;
    std::vector<PointCloud> parts;
    std::vector<std::uint64_t> starts;
    for (std::uint64_t first = 0; first < whole.size(); first += step) {
        std::vector<std::size_t> indices;
        for (std::uint64_t i = first; i < std::min<std::uint64_t>(whole.size(), first + step); ++i)
            indices.push_back(static_cast<std::size_t>(i));
        parts.push_back(whole.subset(indices));
        starts.push_back(first);
    }
    auto creator = io::openPlacedChunkWriter(registry, dir / "placed.ply", {}, parts[1], whole.size());
    auto joiner = io::openPlacedChunkWriter(registry, dir / "placed.ply", creator->temporaryPath(), parts[0], whole.size());
    for (std::size_t k = parts.size(); k-- > 0;)
        (k % 2 ? *creator : *joiner).write(starts[k], parts[k]);
    EXPECT_FALSE(fs::exists(dir / "placed.ply")); // not before the commit
    joiner->close();
    EXPECT_EQ(errorCodeOf([&] { joiner->commit(whole.size()); }), ErrorCode::Internal); // only the creator commits
    creator->commit(whole.size()); // what both wrote, as scandiff-mpi adds it up
    EXPECT_EQ(readBytes(dir / "placed.ply"), readBytes(dir / "expected.ply"));
    EXPECT_FALSE(fs::exists(creator->temporaryPath()));
}

TEST(RecordRanges, PlacedWritersCheckWhatTheyAreGiven)
{
    const auto registry = builtinFormats();
    const fs::path dir = tempDir();
    const PointCloud cloud = sampleCloud(100);
    {
        auto writer = io::openPlacedChunkWriter(registry, dir / "short.ply", {}, cloud, 150);
        writer->write(0, cloud);
        EXPECT_EQ(errorCodeOf([&] { writer->write(60, cloud); }), ErrorCode::InvalidArgument); // past 150
        EXPECT_EQ(errorCodeOf([&] { writer->commit(100); }), ErrorCode::InvalidArgument);     // 100 of 150
        // A process whose cloud has other attributes cannot join.
        PointCloud other = cloud.clone();
        other.removeField("intensity");
        EXPECT_EQ(errorCodeOf([&] { io::openPlacedChunkWriter(registry, dir / "short.ply", writer->temporaryPath(), other, 150); }),
                  ErrorCode::InvalidArgument);
    }
    EXPECT_FALSE(fs::exists(dir / "short.ply")); // never committed: nothing left
    io::WriteOptions ascii;
    ascii.encoding = io::Encoding::Ascii;
    EXPECT_EQ(errorCodeOf([&] { io::openPlacedChunkWriter(registry, dir / "text.ply", {}, cloud, 100, ascii); }),
              ErrorCode::Unsupported);
    EXPECT_EQ(errorCodeOf([&] { io::openPlacedChunkWriter(registry, dir / "cloud.las", {}, cloud, 100); }), ErrorCode::Unsupported);
}

} // namespace
} // namespace scandiff::test
