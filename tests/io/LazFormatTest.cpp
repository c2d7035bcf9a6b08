// SPDX-License-Identifier: GPL-3.0-or-later
// LAZ reading against real LASzip files (data/laz, from laspy's tests): every
// decoded record equal byte for byte to the same file's uncompressed twin, and
// damaged files refused with a clear error.

#include "internal/Formats.h"
#include "laz/LazDecoder.h"
#include "laz/LazEncoder.h"
#include "laz/ArithmeticCoder.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/Progress.h>
#include <scandiff/io/FileIO.h>

#include "../support/TestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <algorithm>
#include <fstream>
#include <random>
#include <sstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace scandiff;

const fs::path kLazDir = fs::path(SCANDIFF_SAMPLE_DATA_DIR) / "laz";

std::string fileBytes(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

template <typename T>
T at(const std::string& bytes, std::size_t offset)
{
    T value;
    std::memcpy(&value, bytes.data() + offset, sizeof(T));
    return value;
}

template <typename T>
void put(std::string& bytes, std::size_t offset, T value)
{
    std::memcpy(bytes.data() + offset, &value, sizeof(T));
}

// LAS 1.2 header fields (ASPRS LAS 1.4 R15, table 3).
constexpr std::size_t kHeaderSize = 94, kOffsetToPoints = 96, kVlrCount = 100, kRecordLength = 105, kPointCount = 107;

//! Byte offset of the LASzip record's payload in a LAZ file.
std::size_t laszipPayload(const std::string& bytes)
{
    std::size_t p = at<std::uint16_t>(bytes, kHeaderSize);
    for (std::uint32_t v = 0; v < at<std::uint32_t>(bytes, kVlrCount); ++v) {
        if (at<std::uint16_t>(bytes, p + 18) == io::detail::kLaszipRecordId)
            return p + 54;
        p += 54 + at<std::uint16_t>(bytes, p + 20);
    }
    ADD_FAILURE() << "no LASzip record";
    return 0;
}

io::FormatRegistry registry()
{
    io::FormatRegistry r;
    io::registerBuiltinFormats(r);
    return r;
}

//! Writes `bytes` as a .laz file and expects reading it to fail with `code` and `words`.
void expectRefused(const std::string& name, const std::string& bytes, ErrorCode code, const std::string& words)
{
    const fs::path file = test::tempDir() / name;
    test::writeText(file, bytes);
    test::expectError([&] { io::readPointCloud(registry(), file); }, code, file, words);
}

} // namespace

namespace {

//! Decompresses `name`.laz and compares every record with `name`.las's
//! (in `dir`: the LASzip samples unless told).
void expectRecordsOfTheLasTwin(const std::string& name, std::size_t expectedPoints, std::size_t expectedItems,
                               const fs::path& dir = kLazDir)
{
    const std::string las = fileBytes(dir / (name + ".las"));
    const std::string laz = fileBytes(dir / (name + ".laz"));
    // LAS 1.4 keeps the count in a 64-bit field (byte 247), the legacy one is 0 for formats 6-10.
    const bool v14 = laz[25] == 4;
    const std::uint64_t count = v14 ? at<std::uint64_t>(laz, 247) : at<std::uint32_t>(laz, kPointCount);
    const auto length = at<std::uint16_t>(laz, kRecordLength);
    ASSERT_EQ(count, expectedPoints);
    ASSERT_EQ(count, v14 ? at<std::uint64_t>(las, 247) : at<std::uint32_t>(las, kPointCount));
    ASSERT_EQ(length, at<std::uint16_t>(las, kRecordLength));
    const std::size_t payload = laszipPayload(laz);
    const io::detail::LazLayout layout =
        io::detail::parseLazLayout(name + ".laz", laz.data() + payload, at<std::uint16_t>(laz, payload - 54 + 20), length);
    ASSERT_EQ(layout.items.size(), expectedItems);
    std::size_t reported = 0;
    const std::unique_ptr<char[]> records =
        io::detail::decompressLaz(name + ".laz", laz.data(), laz.size(), at<std::uint32_t>(laz, kOffsetToPoints), layout,
                                  length, count, [&](std::size_t points) { reported += points; });
    EXPECT_EQ(reported, count);
    const char* twin = las.data() + at<std::uint32_t>(las, kOffsetToPoints);
    for (std::size_t i = 0; i < count; ++i)
        ASSERT_EQ(std::memcmp(records.get() + i * length, twin + i * length, length), 0) << name << " record " << i;
}

} // namespace

TEST(LazFormat, EveryRecordDecodesByteForByteAsItsLasTwin)
{
    // LAS 1.2 format 3: pointwise items point10, gpstime11, rgb12 (version 2).
    expectRecordsOfTheLasTwin("simple", 1065, 3);
    // LAS 1.4 format 6: the layered point14 item (version 3), its nine layers.
    expectRecordsOfTheLasTwin("1_4_w_evlr", 1000, 1);
}

TEST(LazFormat, ReadsAsTheSameCloudAsTheLasTwin)
{
    const PointCloud las = io::readPointCloud(registry(), kLazDir / "simple.las");
    const PointCloud laz = io::readPointCloud(registry(), kLazDir / "simple.laz");
    ASSERT_EQ(laz.size(), las.size());
    EXPECT_EQ(laz.origin(), las.origin());
    EXPECT_EQ(laz.positions(), las.positions());
    ASSERT_TRUE(laz.hasColors());
    EXPECT_EQ(laz.colors(), las.colors());
    ASSERT_EQ(laz.fields().size(), las.fields().size());
    for (const ScalarField& f : las.fields()) {
        const ScalarField* g = laz.field(f.name());
        ASSERT_NE(g, nullptr) << f.name();
        for (std::size_t i = 0; i < f.size(); ++i)
            ASSERT_EQ(g->value(i), f.value(i)) << f.name() << " " << i;
    }
}

TEST(LazFormat, ExtraBytesAndALargerChunkDecodeExactly)
{
    // extra.laz is simple.las with four Extra Bytes dimensions appended: the
    // colours again as uint16[3] and the returns as int8[2] (deprecated array
    // types), a copy of the intensity, and the GPS time in whole seconds. The
    // byte item; the arrays give a field per element (Colors0, Colors1...).
    test::CapturedLog log;
    const PointCloud simple = io::readPointCloud(registry(), kLazDir / "simple.las");
    const PointCloud extra = io::readPointCloud(registry(), kLazDir / "extra.laz");
    EXPECT_TRUE(log.warnings.empty());
    ASSERT_EQ(extra.size(), simple.size());
    EXPECT_EQ(extra.positions(), simple.positions());
    const ScalarField* copy = extra.field("Intensity");
    const ScalarField* seconds = extra.field("Time");
    ASSERT_NE(copy, nullptr);
    ASSERT_NE(seconds, nullptr);
    const ScalarField* colours[3] = {extra.field("Colors0"), extra.field("Colors1"), extra.field("Colors2")};
    const ScalarField* returns[2] = {extra.field("Flags0"), extra.field("Flags1")};
    for (const ScalarField* f : {colours[0], colours[1], colours[2], returns[0], returns[1]})
        ASSERT_NE(f, nullptr);
    ASSERT_TRUE(simple.hasColors());
    for (std::size_t i = 0; i < extra.size(); ++i) {
        ASSERT_EQ(copy->value(i), simple.field("intensity")->value(i)) << i;
        ASSERT_EQ(seconds->value(i), std::floor(simple.field("gps_time")->value(i))) << i;
        const Rgb8 c = simple.colors()[i]; // simple.las keeps 8-bit values in its 16-bit slots
        ASSERT_EQ(colours[0]->value(i), c.r) << i;
        ASSERT_EQ(colours[1]->value(i), c.g) << i;
        ASSERT_EQ(colours[2]->value(i), c.b) << i;
        ASSERT_EQ(returns[0]->value(i), simple.field("return_number")->value(i)) << i;
        ASSERT_EQ(returns[1]->value(i), simple.field("number_of_returns")->value(i)) << i;
    }

    // plane.laz: 28,185 points in one chunk, no twin. Every point lies within
    // the header's bounds, and the decoder used the chunk to its last byte
    // (it refuses a chunk whose stream ends anywhere else).
    const std::string bytes = fileBytes(kLazDir / "plane.laz");
    const PointCloud plane = io::readPointCloud(registry(), kLazDir / "plane.laz");
    ASSERT_EQ(plane.size(), 28185u);
    const double scale = 0.01; // the file's scale: bounds rounded to it
    for (std::size_t i = 0; i < plane.size(); ++i) {
        const Eigen::Vector3d p = plane.globalPosition(i);
        for (int a = 0; a < 3; ++a) {
            const double hi = at<double>(bytes, 179 + 16 * static_cast<std::size_t>(a));
            const double lo = at<double>(bytes, 187 + 16 * static_cast<std::size_t>(a));
            ASSERT_GE(p[a], lo - scale) << i;
            ASSERT_LE(p[a], hi + scale) << i;
        }
    }
}

namespace {

//! `count` records of `length` bytes, point `format` and the rest Extra
//! Bytes, through our LAZ writer: the chunk table's offset, the chunks, the
//! chunk table.
std::string ourCompressedPoints(const char* records, std::uint64_t count, std::uint8_t format, std::size_t length)
{
    const std::size_t standard = format == 6 ? 30 : format == 7 ? 36 : 38;
    std::ostringstream out;
    io::detail::LazPointWriter writer(out, io::detail::lazLayoutForFormat(format, length - standard), length);
    writer.add(records, count);
    writer.finish();
    return out.str();
}

//! The records of `name`.las through our layered encoder (point `format`,
//! the rest of each record Extra Bytes): the chunk and chunk table of
//! `name`.laz, byte for byte.
void expectOurEncoderWritesTheLaz(const std::string& name, std::uint8_t format)
{
    const std::string las = fileBytes(kLazDir / (name + ".las"));
    const std::string laz = fileBytes(kLazDir / (name + ".laz"));
    const std::string ours = ourCompressedPoints(las.data() + at<std::uint32_t>(las, kOffsetToPoints), at<std::uint64_t>(las, 247),
                                                 format, at<std::uint16_t>(las, kRecordLength));
    const std::size_t points = at<std::uint32_t>(laz, kOffsetToPoints);
    const auto theirTable = static_cast<std::size_t>(at<std::int64_t>(laz, points));
    const std::string theirChunk = laz.substr(points + 8, theirTable - points - 8);
    const auto ourTable = static_cast<std::size_t>(at<std::int64_t>(ours, 0));
    // Where they part, rather than kilobytes of both.
    auto firstDifference = [](const std::string& a, const std::string& b) {
        return static_cast<std::size_t>(std::mismatch(a.begin(), a.begin() + std::min(a.size(), b.size()), b.begin()).first - a.begin());
    };
    const std::string ourChunk = ours.substr(8, ourTable - 8);
    ASSERT_EQ(ourChunk.size(), theirChunk.size()) << name << ": chunks part at byte " << firstDifference(ourChunk, theirChunk);
    ASSERT_TRUE(ourChunk == theirChunk) << name << ": chunks part at byte " << firstDifference(ourChunk, theirChunk);
    // And the chunk table after it.
    EXPECT_TRUE(ours.substr(ourTable) == laz.substr(theirTable, ours.size() - ourTable)) << name << ": the chunk tables differ";
}

} // namespace

TEST(LazFormat, OurEncoderWritesLaszipsBytes)
{
    // 1_4_w_evlr.laz was written by LASzip.
    expectOurEncoderWritesTheLaz("1_4_w_evlr", 6);
}

TEST(LazFormat, SeveralScannerChannelsAreCodedAsLaszipCodesThem)
{
    // LASzip hands the items after point14 the point's channel only where it
    // changes, 0 elsewhere (laz/Items.h). The samples' four channels come and
    // go; laz-perf, an independent reader, decodes these .laz files into the
    // .las twins' records (data/laz/README.md). Handing the items the
    // channel of every point instead refuses both files as corrupt.
    expectRecordsOfTheLasTwin("channels7", 2000, 3); // point14, rgb14, byte14
    expectRecordsOfTheLasTwin("channels8", 2000, 3); // point14, rgbnir14, byte14
    expectOurEncoderWritesTheLaz("channels7", 7);
    expectOurEncoderWritesTheLaz("channels8", 8);
}

namespace {

//! A cloud with every LAS 1.4 attribute varying as a scanner's would:
//! returns of pulses, four scanner channels interleaved, GPS times in
//! sequences, colours (and NIR), extra fields; `count` points.
PointCloud varyingCloud(std::size_t count, bool colours, bool nir, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    PointCloud cloud;
    cloud.setOrigin({652000.0, 5120000.0, 300.0});
    cloud.resize(count);
    const char* names[] = {"intensity", "return_number", "number_of_returns", "classification", "classification_flags",
                           "scanner_channel", "scan_direction_flag", "edge_of_flight_line", "scan_angle", "user_data",
                           "point_source_id", "gps_time", "height_above_ground", "amplitude"};
    for (const char* name : names)
        cloud.addField(ScalarField(name, count));
    if (nir)
        cloud.addField(ScalarField("nir", count));
    std::vector<Rgb8>* rgb = colours ? &cloud.enableColors() : nullptr;
    auto set = [&](const char* name, std::size_t i, double v) { cloud.field(name)->setValue(i, v); };
    double time = 345678.0;
    for (std::size_t i = 0; i < count; ++i) {
        const std::size_t pulse = i / 3, ret = i % 3;
        cloud.positions()[i] = Eigen::Vector3f(static_cast<float>(i % 1000) * 0.05f, static_cast<float>(i / 1000) * 0.05f,
                                               static_cast<float>(10.0 * u(rng) - ret * 1.5));
        set("intensity", i, std::floor(u(rng) * 4000));
        set("return_number", i, double(ret + 1));
        set("number_of_returns", i, 3);
        set("classification", i, i % 97 == 0 ? 7 : (ret == 2 ? 2 : 5));
        set("classification_flags", i, i % 501 == 0 ? 4 : 0);
        set("scanner_channel", i, double((pulse / 5) % 4));
        set("scan_direction_flag", i, double((pulse / 40) % 2));
        set("edge_of_flight_line", i, pulse % 40 == 39 ? 1 : 0);
        set("scan_angle", i, std::round((-20.0 + double(pulse % 400) * 0.1) / 0.006) * 0.006);
        set("user_data", i, double(i % 7));
        set("point_source_id", i, i < count / 2 ? 12 : 13);
        if (ret == 0)
            time += (i % 1000 == 999) ? 12.5 : 1e-5 * (1 + (pulse % 3)); // regular pulses, a gap now and then
        set("gps_time", i, time);
        set("height_above_ground", i, std::round(u(rng) * 1000) / 100);
        set("amplitude", i, std::floor(u(rng) * 300));
        if (nir)
            set("nir", i, std::floor(u(rng) * 65535));
        if (colours) {
            const auto grey = static_cast<std::uint8_t>(u(rng) * 255);
            (*rgb)[i] = i % 5 == 0 ? Rgb8{grey, grey, grey}
                                           : Rgb8{static_cast<std::uint8_t>(i % 256), static_cast<std::uint8_t>(u(rng) * 255), 40};
        }
    }
    return cloud;
}

void expectSameClouds(const PointCloud& a, const PointCloud& b, const std::string& what)
{
    ASSERT_EQ(a.size(), b.size()) << what;
    EXPECT_EQ(a.origin(), b.origin()) << what;
    EXPECT_EQ(a.positions(), b.positions()) << what;
    EXPECT_EQ(a.hasColors(), b.hasColors()) << what;
    if (a.hasColors()) {
        EXPECT_EQ(a.colors(), b.colors()) << what;
    }
    ASSERT_EQ(a.fields().size(), b.fields().size()) << what;
    for (const ScalarField& f : a.fields()) {
        const ScalarField* g = b.field(f.name());
        ASSERT_NE(g, nullptr) << what << " " << f.name();
        for (std::size_t i = 0; i < f.size(); ++i) {
            if (std::isnan(f.value(i))) {
                ASSERT_TRUE(std::isnan(g->value(i))) << what << " " << f.name() << " " << i;
            } else {
                ASSERT_EQ(g->value(i), f.value(i)) << what << " " << f.name() << " " << i;
            }
        }
        EXPECT_EQ(g->isDouble(), f.isDouble()) << what << " " << f.name();
    }
}

} // namespace

namespace {

//! The points of channels8 laid out as a COPC file lays them out (COPC 1.0,
//! copc.io): the COPC info VLR right after the header, variable-size chunks
//! (LASzip's chunk size 2^32 - 1, each chunk's point count in the chunk
//! table), one chunk per hierarchy node, the hierarchy in an EVLR. The
//! nodes' points are not in their octants: not a valid COPC, but what a LAZ
//! reader meets in one.
std::string copcShapedLaz(const std::vector<std::uint32_t>& chunkPoints)
{
    const std::string las = fileBytes(kLazDir / "channels8.las");
    const std::string laz = fileBytes(kLazDir / "channels8.laz");
    const auto length = at<std::uint16_t>(las, kRecordLength);
    const char* records = las.data() + at<std::uint32_t>(las, kOffsetToPoints);
    // Each chunk alone through our encoder (format 8, the rest Extra Bytes).
    std::vector<std::string> chunks;
    std::size_t first = 0;
    for (const std::uint32_t n : chunkPoints) {
        const std::string bytes = ourCompressedPoints(records + first * length, n, 8, length);
        chunks.push_back(bytes.substr(8, static_cast<std::size_t>(at<std::int64_t>(bytes, 0)) - 8));
        first += n;
    }
    EXPECT_EQ(first, at<std::uint64_t>(las, 247));
    constexpr std::size_t kVlrHeader = 54, kEvlrHeader = 60, kCopcInfo = 160, kEntry = 32;
    constexpr std::size_t kEvlrStart = 235, kEvlrCount = 243;
    std::string info(kVlrHeader + kCopcInfo, '\0');
    std::memcpy(info.data() + 2, "copc", 4);
    put<std::uint16_t>(info, 18, 1);
    put<std::uint16_t>(info, 20, static_cast<std::uint16_t>(kCopcInfo));
    const auto headerSize = at<std::uint16_t>(laz, kHeaderSize);
    const std::size_t pointsAt = at<std::uint32_t>(laz, kOffsetToPoints);
    std::string out = laz.substr(0, headerSize) + info + laz.substr(headerSize, pointsAt - headerSize);
    put<std::uint32_t>(out, kOffsetToPoints, static_cast<std::uint32_t>(out.size()));
    put<std::uint32_t>(out, kVlrCount, at<std::uint32_t>(laz, kVlrCount) + 1);
    put<std::uint32_t>(out, laszipPayload(out) + 12, UINT32_MAX); // variable chunks
    const std::size_t tableOffsetAt = out.size();
    out.append(8, '\0');
    std::vector<std::uint64_t> nodeAt;
    for (const std::string& chunk : chunks) {
        nodeAt.push_back(out.size());
        out += chunk;
    }
    put<std::int64_t>(out, tableOffsetAt, static_cast<std::int64_t>(out.size()));
    // The chunk table: each chunk's point count (context 0) and byte count
    // (context 1), each coded after the previous chunk's, as LASzip writes it.
    std::string table(8, '\0');
    put<std::uint32_t>(table, 4, static_cast<std::uint32_t>(chunks.size()));
    io::detail::laz::ArithmeticEncoder encoder;
    io::detail::laz::IntegerCoder sizes(32, 2);
    for (std::size_t i = 0; i < chunks.size(); ++i) {
        sizes.compress(encoder, i ? static_cast<std::int32_t>(chunkPoints[i - 1]) : 0, static_cast<std::int32_t>(chunkPoints[i]), 0);
        sizes.compress(encoder, i ? static_cast<std::int32_t>(chunks[i - 1].size()) : 0, static_cast<std::int32_t>(chunks[i].size()), 1);
    }
    const std::vector<unsigned char> coded = encoder.done();
    out += table + std::string(coded.begin(), coded.end());
    // The hierarchy: the root, its children, then grandchildren, one chunk each.
    const std::size_t evlrAt = out.size();
    std::string evlr(kEvlrHeader + kEntry * chunks.size(), '\0');
    std::memcpy(evlr.data() + 2, "copc", 4);
    put<std::uint16_t>(evlr, 18, 1000);
    put<std::uint64_t>(evlr, 20, kEntry * chunks.size());
    for (std::size_t i = 0; i < chunks.size(); ++i) {
        const std::size_t e = kEvlrHeader + kEntry * i;
        const auto j = static_cast<std::int32_t>(i <= 8 ? i - 1 : i - 9);
        const std::int32_t depth = i == 0 ? 0 : i <= 8 ? 1 : 2, side = depth == 2 ? 3 : 1;
        const std::int32_t key[4] = {depth, i ? j & side : 0, i ? (j >> (depth == 2 ? 2 : 1)) & side : 0,
                                     i ? (j >> (depth == 2 ? 4 : 2)) & side : 0};
        std::memcpy(evlr.data() + e, key, sizeof key);
        put<std::uint64_t>(evlr, e + 16, nodeAt[i]);
        put<std::int32_t>(evlr, e + 24, static_cast<std::int32_t>(chunks[i].size()));
        put<std::int32_t>(evlr, e + 28, static_cast<std::int32_t>(chunkPoints[i]));
    }
    out += evlr;
    put<std::uint64_t>(out, kEvlrStart, evlrAt);
    put<std::uint32_t>(out, kEvlrCount, 1);
    // The info VLR's root hierarchy page (offset 40 and 48 of its payload).
    put<std::uint64_t>(out, headerSize + kVlrHeader + 40, evlrAt + kEvlrHeader);
    put<std::uint64_t>(out, headerSize + kVlrHeader + 48, kEntry * chunks.size());
    return out;
}

} // namespace

TEST(LazFormat, ACopcLayoutWithVariableChunksReadsAsItsLasTwin)
{
    // Twelve chunks, of 1 to 700 points. laz-perf decodes the file this
    // builds (data/laz/copc8.laz) into channels8.las's records. Twelve: the
    // chunk table's two contexts (point counts, byte counts) only differ once
    // their models have adapted, after about ten chunks.
    const std::string built = copcShapedLaz({700, 1, 13, 300, 86, 100, 200, 150, 50, 250, 100, 50});
    EXPECT_TRUE(built == fileBytes(kLazDir / "copc8.laz")) << "the layout changed: check it again with laz-perf (data/laz/README.md)";
    const fs::path dir = test::tempDir();
    test::writeText(dir / "copc8.laz", built);
    fs::copy_file(kLazDir / "channels8.las", dir / "copc8.las");
    expectRecordsOfTheLasTwin("copc8", 2000, 3, dir);
    // Through the reader, as a whole and by ranges that cross the chunks.
    const auto formats = registry();
    const PointCloud fromLas = io::readPointCloud(formats, kLazDir / "channels8.las");
    expectSameClouds(fromLas, io::readPointCloud(formats, dir / "copc8.laz"), "copc8");
    for (const io::RecordRange range : {io::RecordRange{699, 3}, io::RecordRange{701, 1300}, io::RecordRange{1799, 2},
                                        io::RecordRange{1990, 20}}) {
        const PointCloud part = io::readPointRecords(formats, dir / "copc8.laz", range);
        expectSameClouds(io::readPointRecords(formats, kLazDir / "channels8.las", range), part,
                         "copc8 from " + std::to_string(range.first));
    }
}

TEST(LazFormat, RecordsOfFourInterleavedScannerChannelsDecodeByteForByte)
{
    // The layered decoder takes a run of points' x, y layer (1,024 points at
    // a time) before their other layers; a scanner channel used for the
    // first time starts from the last point of the one before it, every
    // attribute of it. Channels interleaved from the start of each chunk of
    // 50,000 points, and channels that first appear at the chunk's second
    // point, inside a later run, and at a run's first point.
    const fs::path dir = test::tempDir();
    auto lateChannel = [](std::size_t i) -> double {
        const std::size_t q = i % 50000; // in its chunk
        if (q == 1)
            return 3;
        if (q >= 1500 && q < 1510)
            return 1;
        if (q >= 2049 && q < 2060) // 2,049: the first point of the third run
            return 2;
        return q >= 3000 ? double(q / 7 % 4) : 0;
    };
    for (const bool late : {false, true})
        for (const bool colours : {false, true}) {
            const std::string name = std::string(late ? "late" : "interleaved") + (colours ? "7" : "6");
            PointCloud cloud = varyingCloud(120000, colours, false, 11);
            // Times a pulse apart that a 32-bit float keeps, so that the first
            // point of a channel differs in time from the last of the one before.
            ScalarField& time = *cloud.field("gps_time");
            for (std::size_t i = 0; i < cloud.size(); ++i)
                time.setValue(i, 345678.0 + 0.25 * double(i / 3) + (i / 3 % 7 == 0 ? 0.5 : 0.0));
            if (late)
                for (std::size_t i = 0; i < cloud.size(); ++i)
                    cloud.field("scanner_channel")->setValue(i, lateChannel(i));
            io::writePointCloud(registry(), cloud, dir / (name + ".las"));
            io::writePointCloud(registry(), cloud, dir / (name + ".laz"));
            // point14, rgb14 for format 7, and the two Extra Bytes dimensions as byte14.
            expectRecordsOfTheLasTwin(name, 120000, colours ? 3 : 2, dir);
        }
}

TEST(LazFormat, WrittenLazReadsBackAsTheSameCloudAsLas)
{
    // Formats 6, 7 and 8 with extra bytes, over several chunks (120,000
    // points: chunks of 50,000) and four interleaved scanner channels.
    const fs::path dir = test::tempDir();
    struct Case
    {
        const char* name;
        bool colours, nir;
    } cases[] = {{"format6", false, false}, {"format7", true, false}, {"format8", true, true}};
    for (const Case& c : cases) {
        const PointCloud cloud = varyingCloud(120000, c.colours, c.nir, 5);
        io::writePointCloud(registry(), cloud, dir / (std::string(c.name) + ".las"));
        io::writePointCloud(registry(), cloud, dir / (std::string(c.name) + ".laz"));
        const PointCloud las = io::readPointCloud(registry(), dir / (std::string(c.name) + ".las"));
        const PointCloud laz = io::readPointCloud(registry(), dir / (std::string(c.name) + ".laz"));
        expectSameClouds(las, laz, c.name);
        // The LAZ holds the LAS file's records exactly: same header fields, same records.
        const std::string lasBytes = fileBytes(dir / (std::string(c.name) + ".las"));
        const std::string lazBytes = fileBytes(dir / (std::string(c.name) + ".laz"));
        EXPECT_EQ(static_cast<unsigned char>(lazBytes[104]), static_cast<unsigned char>(lasBytes[104]) | 0x80) << c.name;
        EXPECT_LT(lazBytes.size(), lasBytes.size() / 2) << c.name;
    }
    // A cloud of one point, and an empty one.
    PointCloud one = varyingCloud(1, true, false, 6);
    io::writePointCloud(registry(), one, dir / "one.laz");
    expectSameClouds(io::readPointCloud(registry(), dir / "one.laz"), io::readPointCloud(registry(), [&] {
                         io::writePointCloud(registry(), one, dir / "one.las");
                         return dir / "one.las";
                     }()),
                     "one point");
    PointCloud none;
    io::writePointCloud(registry(), none, dir / "none.laz");
    EXPECT_EQ(io::readPointCloud(registry(), dir / "none.laz").size(), 0u);
}

namespace {

//! The records of `las` (a LAS file scandiff wrote, its records patched since)
//! compressed as `lazTemplate` (the same cloud written as LAZ by scandiff,
//! whose header and records only differ in the compression) lays them out.
std::string compressLikeTemplate(const std::string& las, const std::string& lazTemplate)
{
    const auto length = at<std::uint16_t>(las, kRecordLength);
    const auto count = at<std::uint64_t>(las, 247);
    const std::size_t payload = laszipPayload(lazTemplate);
    const io::detail::LazLayout layout =
        io::detail::parseLazLayout("template.laz", lazTemplate.data() + payload, at<std::uint16_t>(lazTemplate, payload - 54 + 20),
                                   length);
    std::ostringstream out;
    out.write(lazTemplate.data(), at<std::uint32_t>(lazTemplate, kOffsetToPoints));
    io::detail::LazPointWriter writer(out, layout, length);
    writer.add(las.data() + at<std::uint32_t>(las, kOffsetToPoints), static_cast<std::size_t>(count));
    writer.finish();
    return out.str();
}

//! Writes `las` (records patched) as NAME.las in `dir` and its records
//! compressed as `lazTemplate` lays them out as NAME.laz, checks that both read
//! as the same cloud, and returns both reads (LAS, LAZ).
std::pair<PointCloud, PointCloud> expectPatchedTwins(const fs::path& dir, const std::string& name, const std::string& las,
                                                     const std::string& lazTemplate)
{
    test::writeText(dir / (name + ".las"), las);
    test::writeText(dir / (name + ".laz"), compressLikeTemplate(las, lazTemplate));
    std::pair<PointCloud, PointCloud> twins{io::readPointCloud(registry(), dir / (name + ".las")),
                                            io::readPointCloud(registry(), dir / (name + ".laz"))};
    expectSameClouds(twins.first, twins.second, name);
    return twins;
}

//! varyingCloud() without its two Extra Bytes dimensions.
PointCloud standardCloud(std::size_t count, bool colours, bool nir, unsigned seed)
{
    PointCloud cloud = varyingCloud(count, colours, nir, seed);
    cloud.removeField("height_above_ground");
    cloud.removeField("amplitude");
    return cloud;
}

} // namespace

TEST(LazFormat, ChunkByChunkParsingGivesTheLasTwinsCloud)
{
    // 120,000 points: chunks of 50,000, parsed by the workers as they decode them.
    const fs::path dir = test::tempDir();
    for (const bool colours : {false, true}) {
        for (const bool nir : {false, true}) {
            if (nir && !colours)
                continue;
            const std::string name = std::string("standard") + (colours ? "_rgb" : "") + (nir ? "_nir" : "");
            const PointCloud cloud = standardCloud(120000, colours, nir, 8);
            io::writePointCloud(registry(), cloud, dir / (name + ".las"));
            io::writePointCloud(registry(), cloud, dir / (name + ".laz"));
            expectSameClouds(io::readPointCloud(registry(), dir / (name + ".las")),
                             io::readPointCloud(registry(), dir / (name + ".laz")), name);
        }
    }

    // Colours: each chunk decides alone whether its channels fit in 8 bits,
    // the file as a whole whether they are 8-bit values. The first chunk's
    // fit, the others' do not: the file's colours are 16-bit, the first
    // chunk's too (LAS 1.4 R15), as the LAS reader reads them.
    const PointCloud cloud = standardCloud(120000, true, false, 9);
    io::writePointCloud(registry(), cloud, dir / "colours.las");
    io::writePointCloud(registry(), cloud, dir / "colours.laz");
    const std::string lazTemplate = fileBytes(dir / "colours.laz");
    std::string las = fileBytes(dir / "colours.las");
    const std::size_t start = at<std::uint32_t>(las, kOffsetToPoints), length = at<std::uint16_t>(las, kRecordLength);
    ASSERT_EQ(length, 36u);
    auto setColour = [&](std::size_t i, std::uint16_t r, std::uint16_t g, std::uint16_t b) {
        put<std::uint16_t>(las, start + i * length + 30, r);
        put<std::uint16_t>(las, start + i * length + 32, g);
        put<std::uint16_t>(las, start + i * length + 34, b);
    };
    for (std::size_t i = 0; i < 50000; ++i)
        setColour(i, static_cast<std::uint16_t>(i % 256), static_cast<std::uint16_t>((i / 7) % 256), 200);
    auto expectTwins = [&](const std::string& name) { return expectPatchedTwins(dir, name, las, lazTemplate).first; };
    const PointCloud mixed = expectTwins("mixed_colours");
    EXPECT_EQ(mixed.colors()[255], (Rgb8{1, 0, 1})) << "200 of 65535 is 1 of 255";
    // Every chunk fits: 8-bit colours, taken as they are.
    for (std::size_t i = 50000; i < 120000; ++i)
        setColour(i, 17, 99, static_cast<std::uint16_t>(i % 256));
    const PointCloud eightBit = expectTwins("eight_bit_colours");
    EXPECT_EQ(eightBit.colors()[255], (Rgb8{255, 36, 200}));

    // A time the float residuals cannot hold, in the third chunk: every time
    // is then decoded again and kept as a double.
    put<double>(las, start + 110000 * length + 22, 4.0e15);
    const PointCloud farTime = expectTwins("far_time");
    EXPECT_EQ(farTime.field("gps_time")->value(110000), 4.0e15);
    EXPECT_EQ(farTime.field("gps_time")->value(0), cloud.field("gps_time")->value(0));
}

// A standard field 0 in every record is dropped by the reader; a LAZ file's
// chunks tell which before anything is decoded (a layer empty in a chunk is
// an attribute that never changes there, equal to the chunk's first record),
// so the LAZ reader does not make those fields at all. Each case against the
// LAS twin, which reads every record: the same fields, the same values.
TEST(LazFormat, FieldsTheLayersShowToBeZeroEverywhereAreNotMade)
{
    const fs::path dir = test::tempDir();
    const PointCloud cloud = standardCloud(120000, true, false, 10);
    io::writePointCloud(registry(), cloud, dir / "zeros.las");
    io::writePointCloud(registry(), cloud, dir / "zeros.laz");
    const std::string lazTemplate = fileBytes(dir / "zeros.laz");
    std::string las = fileBytes(dir / "zeros.las");
    const std::size_t start = at<std::uint32_t>(las, kOffsetToPoints), length = at<std::uint16_t>(las, kRecordLength);
    auto record = [&](std::size_t i) { return start + i * length; };
    auto twins = [&](const std::string& name) { return expectPatchedTwins(dir, name, las, lazTemplate).second; };
    // User data (byte 17) 0 everywhere, and of the flags byte (15) only the
    // scanner channel's bits left.
    for (std::size_t i = 0; i < 120000; ++i) {
        las[record(i) + 17] = 0;
        las[record(i) + 15] = static_cast<char>(las[record(i) + 15] & 0x30);
    }
    const PointCloud zero = twins("zero_everywhere");
    EXPECT_EQ(zero.field("user_data"), nullptr);
    EXPECT_EQ(zero.field("classification_flags"), nullptr);
    EXPECT_EQ(zero.field("scan_direction_flag"), nullptr);
    EXPECT_EQ(zero.field("edge_of_flight_line"), nullptr);
    ASSERT_NE(zero.field("scanner_channel"), nullptr);
    ASSERT_NE(zero.field("classification"), nullptr);

    // 5 at every point of the second chunk: its layer is empty there too,
    // only its first record tells.
    for (std::size_t i = 50000; i < 100000; ++i)
        las[record(i) + 17] = 5;
    // The scan direction set in all of the first chunk, the other flags not.
    for (std::size_t i = 0; i < 50000; ++i)
        las[record(i) + 15] = static_cast<char>(las[record(i) + 15] | 0x40);
    const PointCloud firstRecords = twins("constant_in_a_chunk");
    ASSERT_NE(firstRecords.field("user_data"), nullptr);
    EXPECT_EQ(firstRecords.field("user_data")->value(50000), 5.0);
    EXPECT_EQ(firstRecords.field("user_data")->value(100000), 0.0);
    ASSERT_NE(firstRecords.field("scan_direction_flag"), nullptr);
    EXPECT_EQ(firstRecords.field("scan_direction_flag")->value(49999), 1.0);
    EXPECT_EQ(firstRecords.field("classification_flags"), nullptr);
    EXPECT_EQ(firstRecords.field("edge_of_flight_line"), nullptr);

    // 0 in every chunk's first record, 9 at one point inside the third
    // chunk: only its layer's size tells.
    for (std::size_t i = 0; i < 120000; ++i)
        las[record(i) + 17] = 0;
    las[record(110000) + 17] = 9;
    const PointCloud oneInside = twins("one_inside_a_chunk");
    ASSERT_NE(oneInside.field("user_data"), nullptr);
    EXPECT_EQ(oneInside.field("user_data")->value(110000), 9.0);
    EXPECT_EQ(oneInside.field("user_data")->value(110001), 0.0);

    // A range of records keeps every field, as the LAS reader's ranges do.
    const PointCloud range = io::readPointRecords(registry(), dir / "zero_everywhere.laz", io::RecordRange{100, 50});
    EXPECT_NE(range.field("classification_flags"), nullptr);
}

TEST(LazFormat, TheScannerChannelIsMadeOnceAChunkShowsAChannelOtherThanZero)
{
    // The channel is coded in the x, y layer, which no chunk leaves empty:
    // the reader makes its field only when a decoded chunk has a point of a
    // channel other than 0, and puts it where the LAS reader has it.
    const fs::path dir = test::tempDir();
    auto names = [](const PointCloud& cloud) {
        std::vector<std::string> out;
        for (const ScalarField& f : cloud.fields())
            out.push_back(f.name());
        return out;
    };
    auto twins = [&](const PointCloud& cloud, const std::string& name) {
        io::writePointCloud(registry(), cloud, dir / (name + ".las"));
        io::writePointCloud(registry(), cloud, dir / (name + ".laz"));
        const PointCloud las = io::readPointCloud(registry(), dir / (name + ".las"));
        PointCloud laz = io::readPointCloud(registry(), dir / (name + ".laz"));
        expectSameClouds(las, laz, name);
        EXPECT_EQ(names(laz), names(las)) << name;
        return laz;
    };
    PointCloud cloud = varyingCloud(120000, true, false, 12); // chunks of 50,000
    ScalarField& channel = *cloud.field("scanner_channel");
    for (std::size_t i = 0; i < cloud.size(); ++i)
        channel.setValue(i, 0.0);
    EXPECT_EQ(twins(cloud, "channel0").field("scanner_channel"), nullptr);

    // Channels in the third chunk only, then in the first and the third:
    // the chunks decoded before the field is made stay 0.
    channel.setValue(100001, 2.0);
    channel.setValue(100002, 3.0);
    const PointCloud third = twins(cloud, "third_chunk");
    ASSERT_NE(third.field("scanner_channel"), nullptr);
    EXPECT_EQ(third.field("scanner_channel")->value(100002), 3.0);
    EXPECT_EQ(third.field("scanner_channel")->value(0), 0.0);
    channel.setValue(7, 1.0);
    const PointCloud both = twins(cloud, "first_and_third");
    ASSERT_NE(both.field("scanner_channel"), nullptr);
    EXPECT_EQ(both.field("scanner_channel")->value(7), 1.0);
    EXPECT_EQ(both.field("scanner_channel")->value(60000), 0.0);

    // An Extra Bytes dimension named as the standard attribute (its name
    // patched in both files): it takes a suffix whether the channel is made
    // or not, and the channel made late never meets it.
    auto renamedTwins = [&](const std::string& name) {
        for (const char* extension : {".las", ".laz"}) {
            std::string bytes = fileBytes(dir / (name + extension));
            const std::string from("amplitude\0\0\0\0\0\0\0", 16), to("scanner_channel\0", 16);
            const std::size_t at = bytes.find(from);
            EXPECT_NE(at, std::string::npos) << name << extension;
            if (at != std::string::npos)
                bytes.replace(at, 16, to);
            test::writeText(dir / ("renamed_" + name + extension), bytes);
        }
        const PointCloud las = io::readPointCloud(registry(), dir / ("renamed_" + name + ".las"));
        PointCloud laz = io::readPointCloud(registry(), dir / ("renamed_" + name + ".laz"));
        expectSameClouds(las, laz, "renamed " + name);
        EXPECT_EQ(names(laz), names(las)) << name;
        const ScalarField* extra = laz.field("scanner_channel_2");
        EXPECT_NE(extra, nullptr) << name;
        if (extra)
            EXPECT_EQ(extra->value(100002), cloud.field("amplitude")->value(100002)) << name;
        return laz;
    };
    EXPECT_EQ(renamedTwins("channel0").field("scanner_channel"), nullptr);
    const PointCloud renamed = renamedTwins("first_and_third");
    ASSERT_NE(renamed.field("scanner_channel"), nullptr);
    EXPECT_EQ(renamed.field("scanner_channel")->value(100002), 3.0);
}

TEST(LazFormat, ExtraBytesAreTakenChunkByChunkAsTheWorkersDecode)
{
    // An extra dimension's offset comes from its first value in the read:
    // here in the third of three chunks, which either core may decode first.
    // Its values need doubles in the file (4e9 and more); around the offset
    // floats hold them all, and the field stays exact only so that it is
    // written back as doubles, as from the LAS.
    const fs::path dir = test::tempDir();
    PointCloud cloud = standardCloud(120000, true, false, 12);
    ScalarField& pulse = cloud.addField("pulse_id");
    pulse.keepDoubles();
    auto pulseOf = [](std::size_t i) { return i < 110000 ? std::nan("") : 4.0e9 + 0.5 * double(i); };
    for (std::size_t i = 0; i < cloud.size(); ++i)
        pulse.setValue(i, pulseOf(i));
    io::writePointCloud(registry(), cloud, dir / "pulses.las");
    io::writePointCloud(registry(), cloud, dir / "pulses.laz");
    const PointCloud las = io::readPointCloud(registry(), dir / "pulses.las");
    const PointCloud laz = io::readPointCloud(registry(), dir / "pulses.laz");
    expectSameClouds(las, laz, "pulses");
    const ScalarField* read = laz.field("pulse_id");
    ASSERT_NE(read, nullptr);
    EXPECT_EQ(read->offset(), 4.0e9 + 55000.0);
    for (std::size_t i = 0; i < laz.size(); ++i) {
        if (i < 110000) {
            ASSERT_TRUE(std::isnan(read->value(i))) << i;
        } else {
            ASSERT_EQ(read->value(i), pulseOf(i)) << i;
        }
    }
    // A range inside the third chunk, starting on a point without a value:
    // its offset is its own first value's.
    const PointCloud part = io::readPointRecords(registry(), dir / "pulses.laz", {109999, 3});
    EXPECT_TRUE(std::isnan(part.field("pulse_id")->value(0)));
    EXPECT_EQ(part.field("pulse_id")->value(2), pulseOf(110001));
    EXPECT_EQ(part.field("pulse_id")->offset(), 4.0e9 + 55000.0);
}

TEST(LazFormat, RangesOfRecordsReadAsTheLasTwinsRanges)
{
    // Only the chunks holding a range are decoded; a range may start or end
    // inside a chunk, span a border, run past the end or start beyond it.
    const fs::path dir = test::tempDir();
    const auto formats = registry();
    for (const bool extras : {false, true}) {
        const PointCloud cloud = extras ? varyingCloud(120000, true, false, 10) : standardCloud(120000, true, false, 10);
        const std::string name = extras ? "with_extras" : "standard";
        io::writePointCloud(formats, cloud, dir / (name + ".las"));
        io::writePointCloud(formats, cloud, dir / (name + ".laz"));
        ASSERT_TRUE(io::canReadRecordRanges(formats, dir / (name + ".laz")));
        const PointCloud whole = io::readPointCloud(formats, dir / (name + ".las"));
        for (const io::RecordRange range : {io::RecordRange{0, 10}, io::RecordRange{49990, 20}, io::RecordRange{60000, 50000},
                                            io::RecordRange{119990, 100}, io::RecordRange{200000, 5}}) {
            const std::string what = name + " from " + std::to_string(range.first);
            const PointCloud laz = io::readPointRecords(formats, dir / (name + ".laz"), range);
            const PointCloud las = io::readPointRecords(formats, dir / (name + ".las"), range);
            expectSameClouds(las, laz, what);
            // And the same points as the whole read's.
            ASSERT_EQ(laz.size(), std::min<std::uint64_t>(range.count, 120000 - std::min<std::uint64_t>(range.first, 120000))) << what;
            for (std::size_t i = 0; i < laz.size(); ++i) {
                ASSERT_EQ(laz.positions()[i], whole.positions()[range.first + i]) << what << " " << i;
                ASSERT_EQ(laz.field("gps_time")->value(i), whole.field("gps_time")->value(range.first + i)) << what << " " << i;
            }
        }

        // Only the chunks holding a range are decoded: with the last of the
        // three chunks damaged, the first two still read, the last does not.
        std::string bytes = fileBytes(dir / (name + ".laz"));
        const std::size_t payload = laszipPayload(bytes);
        const auto length = at<std::uint16_t>(bytes, kRecordLength);
        const io::detail::LazLayout layout =
            io::detail::parseLazLayout(name, bytes.data() + payload, at<std::uint16_t>(bytes, payload - 54 + 20), length);
        const std::vector<io::detail::LazChunk> chunks = io::detail::readLazChunks(
            name, bytes.data(), bytes.size(), at<std::uint32_t>(bytes, kOffsetToPoints), layout, length, 120000);
        ASSERT_EQ(chunks.size(), 3u);
        const std::size_t middle = static_cast<std::size_t>(chunks[2].offset + chunks[2].bytes / 2);
        std::fill(bytes.begin() + static_cast<std::ptrdiff_t>(middle), bytes.begin() + static_cast<std::ptrdiff_t>(middle + 2000), '\xFF');
        const fs::path damaged = dir / (name + "_damaged.laz");
        test::writeText(damaged, bytes);
        EXPECT_EQ(io::readPointRecords(formats, damaged, {0, 100000}).size(), 100000u) << name;
        test::expectError([&] { io::readPointRecords(formats, damaged, {99990, 20}); }, ErrorCode::InvalidData, damaged,
                          "LAZ chunk 2");
    }
}

TEST(LazFormat, DamagedFilesAreClearErrors)
{
    const std::string good = fileBytes(kLazDir / "simple.laz");
    const std::size_t payload = laszipPayload(good);
    const auto points = at<std::uint32_t>(good, kOffsetToPoints);

    // Cut in the middle of the compressed points: the chunk table's offset
    // now points beyond the end.
    expectRefused("truncated.laz", good.substr(0, good.size() / 2), ErrorCode::InvalidData, "points outside the file");
    // The chunk table says a byte count the chunk does not use.
    std::string bytes = good;
    const auto table = static_cast<std::size_t>(at<std::int64_t>(good, points));
    put<std::int64_t>(bytes, points, static_cast<std::int64_t>(good.size() + 100));
    expectRefused("table.laz", bytes, ErrorCode::InvalidData, "chunk table's offset");
    // A damaged byte inside the compressed stream.
    bytes = good;
    bytes[points + 8 + 34 + 500] ^= 0x5A;
    expectRefused("flipped.laz", bytes, ErrorCode::InvalidData, "LAZ chunk 0");
    // A stream of 0xFF bytes (it leaves the coding interval): refused, not decoded into garbage.
    bytes = good;
    std::fill(bytes.begin() + static_cast<std::ptrdiff_t>(points + 8 + 34), bytes.begin() + static_cast<std::ptrdiff_t>(table), '\xFF');
    expectRefused("ff.laz", bytes, ErrorCode::InvalidData, "LAZ chunk 0");
    // A chunk table giving the chunk fewer bytes than its first record.
    bytes = good;
    {
        // Re-encode the table with a chunk of 10 bytes.
        std::ostringstream table10;
        const std::uint32_t header[2] = {0, 1};
        table10.write(reinterpret_cast<const char*>(header), 8);
        io::detail::laz::ArithmeticEncoder e;
        io::detail::laz::IntegerCoder ic(32, 2);
        ic.compress(e, 0, 10, 1);
        const auto coded = e.done();
        table10.write(reinterpret_cast<const char*>(coded.data()), static_cast<std::streamsize>(coded.size()));
        bytes.replace(table, std::string::npos, table10.str());
    }
    expectRefused("short.laz", bytes, ErrorCode::InvalidData, "cannot hold 1065 points in 10 bytes");
    // An unknown chunk table version.
    bytes = good;
    put<std::uint32_t>(bytes, table, 7u);
    expectRefused("version.laz", bytes, ErrorCode::InvalidData, "chunk table version 7");
    // Items that do not add up to the record length.
    bytes = good;
    put<std::uint16_t>(bytes, payload + 34 + 2, 21);
    expectRefused("items.laz", bytes, ErrorCode::InvalidData, "add up to 35 bytes");
    // An item version this reader does not know (LASzip 1.x wrote version 1).
    bytes = good;
    put<std::uint16_t>(bytes, payload + 34 + 4, 1);
    expectRefused("v1.laz", bytes, ErrorCode::Unsupported, "point10 version 1");
    // An item type it does not know.
    bytes = good;
    put<std::uint16_t>(bytes, payload + 34 + 12, 9);
    expectRefused("wave.laz", bytes, ErrorCode::Unsupported, "wavepacket13");
    // A header claiming far more points than the chunk table is refused
    // before anything is allocated.
    bytes = good;
    put<std::uint32_t>(bytes, kPointCount, 4000000000u);
    expectRefused("count.laz", bytes, ErrorCode::InvalidData, "the header says 4000000000");
    // And so is a chunk size no chunk of these bytes can hold.
    bytes = good;
    put<std::uint32_t>(bytes, kPointCount, 4000000000u);
    put<std::uint32_t>(bytes, payload + 12, 4000000000u);
    expectRefused("dense.laz", bytes, ErrorCode::InvalidData, "cannot hold 4000000000 points");
    // Fewer points in the header than in the chunk: decoding them leaves
    // bytes of the chunk unused.
    bytes = good;
    put<std::uint32_t>(bytes, kPointCount, 1000u);
    expectRefused("fewer.laz", bytes, ErrorCode::InvalidData, "its 1000 points use");
    // More: a second chunk the table does not list.
    bytes = good;
    put<std::uint32_t>(bytes, payload + 12, 500u); // 500 points a chunk: the table's one chunk holds 500, not 1,065
    expectRefused("chunks.laz", bytes, ErrorCode::InvalidData, "chunk table accounts for 500 points");
}

TEST(LazFormat, ASecondPoint14ItemIsAClearError)
{
    // The chunk's first layer (the first point14's x, y) is the only one that
    // must not be empty; a second point14 item would decode from an empty one.
    const std::string good = fileBytes(kLazDir / "1_4_w_evlr.laz");
    const std::size_t payload = laszipPayload(good);
    ASSERT_EQ(at<std::uint16_t>(good, payload + 32), 1u); // one item: point14, 30 bytes, version 3
    std::string twice = good.substr(payload, 34 + 6);
    put<std::uint16_t>(twice, 32, 2);
    twice += good.substr(payload + 34, 6);
    test::expectError([&] { io::detail::parseLazLayout("twice.laz", twice.data(), twice.size(), 60); }, ErrorCode::InvalidData,
                      "twice.laz", "more than one point14 item");
}

TEST(LazFormat, DamagedLayeredChunksAreClearErrors)
{
    const std::string good = fileBytes(kLazDir / "1_4_w_evlr.laz");
    const std::size_t payload = laszipPayload(good);
    const std::size_t chunk = at<std::uint32_t>(good, kOffsetToPoints) + 8;
    const std::size_t count = chunk + 30, sizes = count + 4; // after the first record: the count, then nine layer sizes
    ASSERT_EQ(at<std::uint32_t>(good, count), 1000u);

    std::string bytes = good;
    put<std::uint32_t>(bytes, count, 999u);
    expectRefused("count.laz", bytes, ErrorCode::InvalidData, "says it holds 999 points");
    bytes = good;
    put<std::uint32_t>(bytes, sizes, at<std::uint32_t>(good, sizes) + 100000u);
    expectRefused("layer.laz", bytes, ErrorCode::InvalidData, "runs past its end");
    // A damaged byte in the first layer (returns and x, y).
    bytes = good;
    bytes[sizes + 36 + 200] ^= 0x5A;
    expectRefused("flipped.laz", bytes, ErrorCode::InvalidData, "LAZ chunk 0");
    bytes = good;
    put<std::uint16_t>(bytes, payload + 34 + 4, 4);
    expectRefused("v4.laz", bytes, ErrorCode::Unsupported, "point14 version 4");
    // No x, y layer although the chunk has 1,000 points.
    bytes = good;
    put<std::uint32_t>(bytes, sizes, 0u);
    expectRefused("noxy.laz", bytes, ErrorCode::InvalidData, "no x, y layer");
    // Layers of 0xFF bytes: the stream leaves the coding interval at once (it
    // read past the models' tables before), and the GPS time coder would
    // switch sequence forever; both are refused.
    bytes = good;
    const std::size_t layers = sizes + 36;
    std::fill(bytes.begin() + static_cast<std::ptrdiff_t>(layers), bytes.begin() + static_cast<std::ptrdiff_t>(layers + 3000), '\xFF');
    expectRefused("ff.laz", bytes, ErrorCode::InvalidData, "is corrupt");
    bytes = good;
    std::size_t gps = layers;
    for (int layer = 0; layer < 8; ++layer)
        gps += at<std::uint32_t>(good, sizes + 4 * static_cast<std::size_t>(layer));
    std::fill(bytes.begin() + static_cast<std::ptrdiff_t>(gps), bytes.begin() + static_cast<std::ptrdiff_t>(gps + 555), '\xFF');
    expectRefused("gps.laz", bytes, ErrorCode::InvalidData, "is corrupt");
}

namespace {

class CancelAtOnce : public ProgressObserver
{
public:
    void beginStage(const std::string&) override {}
    void report(double) override {}
    bool cancelRequested() const override { return true; }
};

} // namespace

TEST(LazFormat, CancelStopsTheDecompression)
{
    CancelAtOnce cancel;
    io::ReadOptions options;
    options.progress = &cancel;
    test::expectError([&] { io::readPointCloud(registry(), kLazDir / "plane.laz", options); }, ErrorCode::Cancelled, fs::path(),
                "cancelled");
}
