// SPDX-License-Identifier: GPL-3.0-or-later
// LAZ reading against real LASzip files (data/laz, from laspy's tests): every
// decoded record equal byte for byte to the same file's uncompressed twin, and
// damaged files refused with a clear error.

#include "internal/Formats.h"
#include "internal/LazDecoder.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/Progress.h>
#include <scandiff/io/FileIO.h>

#include "../support/TestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
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

//! Keeps the warnings of a read (extra.laz has dimensions we skip) out of the output.
class CapturedWarnings
{
public:
    CapturedWarnings()
    {
        previous_ = setLogSink([this](LogLevel level, const std::string& message) {
            if (level == LogLevel::Warning)
                warnings.push_back(message);
        });
    }
    ~CapturedWarnings() { setLogSink(std::move(previous_)); }
    std::vector<std::string> warnings;

private:
    LogSink previous_;
};

io::FormatRegistry registry()
{
    io::FormatRegistry r;
    io::registerBuiltinFormats(r);
    return r;
}

template <typename Fn>
void expectError(Fn&& read, ErrorCode code, const fs::path& path, const std::string& words)
{
    try {
        read();
        ADD_FAILURE() << "no error for " << path << " (expected: " << words << ")";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), code) << e.what();
        EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
}

//! Writes `bytes` as a .laz file and expects reading it to fail with `code` and `words`.
void expectRefused(const std::string& name, const std::string& bytes, ErrorCode code, const std::string& words)
{
    const fs::path file = test::tempDir() / name;
    test::writeText(file, bytes);
    expectError([&] { io::readPointCloud(registry(), file); }, code, file, words);
}

} // namespace

namespace {

//! Decompresses `name`.laz and compares every record with `name`.las's.
void expectRecordsOfTheLasTwin(const std::string& name, std::size_t expectedPoints, std::size_t expectedItems)
{
    const std::string las = fileBytes(kLazDir / (name + ".las"));
    const std::string laz = fileBytes(kLazDir / (name + ".laz"));
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
    std::vector<char> records(std::size_t(count) * length);
    std::size_t reported = 0;
    io::detail::decompressLaz(name + ".laz", laz.data(), laz.size(), at<std::uint32_t>(laz, kOffsetToPoints), layout,
                              length, count, records.data(), [&](std::size_t points) { reported += points; });
    EXPECT_EQ(reported, count);
    const char* twin = las.data() + at<std::uint32_t>(las, kOffsetToPoints);
    for (std::size_t i = 0; i < count; ++i)
        ASSERT_EQ(std::memcmp(records.data() + i * length, twin + i * length, length), 0) << name << " record " << i;
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
    // extra.laz is simple.las with two Extra Bytes dimensions appended (a copy
    // of the intensity and the GPS time in whole seconds): the byte item.
    CapturedWarnings quiet;
    const PointCloud simple = io::readPointCloud(registry(), kLazDir / "simple.las");
    const PointCloud extra = io::readPointCloud(registry(), kLazDir / "extra.laz");
    ASSERT_EQ(extra.size(), simple.size());
    EXPECT_EQ(extra.positions(), simple.positions());
    const ScalarField* copy = extra.field("Intensity");
    const ScalarField* seconds = extra.field("Time");
    ASSERT_NE(copy, nullptr);
    ASSERT_NE(seconds, nullptr);
    for (std::size_t i = 0; i < extra.size(); ++i) {
        ASSERT_EQ(copy->value(i), simple.field("intensity")->value(i)) << i;
        ASSERT_EQ(seconds->value(i), std::floor(simple.field("gps_time")->value(i))) << i;
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

TEST(LazFormat, WritingIsRefusedClearly)
{
    const PointCloud cloud = io::readPointCloud(registry(), kLazDir / "simple.laz");
    const fs::path out = test::tempDir() / "out.laz";
    expectError([&] { io::writePointCloud(registry(), cloud, out); }, ErrorCode::Unsupported, out, "can be read but not written");
    EXPECT_FALSE(fs::exists(out));
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
    // A header claiming far more points than the compressed bytes can hold
    // is refused before anything is allocated.
    bytes = good;
    put<std::uint32_t>(bytes, kPointCount, 4000000000u);
    expectRefused("count.laz", bytes, ErrorCode::InvalidData, "per byte");
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
    expectError([&] { io::readPointCloud(registry(), kLazDir / "plane.laz", options); }, ErrorCode::Cancelled, fs::path(),
                "cancelled");
}
