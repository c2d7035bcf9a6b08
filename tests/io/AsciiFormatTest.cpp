// SPDX-License-Identifier: GPL-3.0-or-later
#include "internal/Formats.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/FileIO.h>

#include "TestSupport.h"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace scandiff::test {
namespace {

namespace fs = std::filesystem;

io::FormatRegistry asciiRegistry()
{
    io::FormatRegistry registry;
    registry.add(io::detail::asciiFormat());
    return registry;
}

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

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

//! Writes `text` to a file of the test folder and reads it back.
PointCloud readText(const std::string& fileName, const std::string& text, const io::ReadOptions& options = {})
{
    const fs::path path = tempDir() / fileName;
    writeText(path, text);
    return io::readPointCloud(asciiRegistry(), path, options);
}

void expectReadError(const std::string& fileName, const std::string& text, const std::vector<std::string>& fragments,
                     const io::ReadOptions& options = {}, ErrorCode code = ErrorCode::InvalidData)
{
    const fs::path path = tempDir() / fileName;
    writeText(path, text);
    std::vector<std::string> all = fragments;
    all.push_back(path.string());
    expectError([&] { io::readPointCloud(asciiRegistry(), path, options); }, code, all);
}

std::vector<std::string> fieldNames(const PointCloud& cloud)
{
    std::vector<std::string> names;
    for (const auto& f : cloud.fields())
        names.push_back(f.name());
    return names;
}

PointCloud makeCloud(std::size_t n)
{
    PointCloud cloud;
    cloud.resize(n);
    auto& colors = cloud.enableColors();
    auto& normals = cloud.enableNormals();
    // References only once both exist: addField may move the fields.
    cloud.addField("quality");
    cloud.addField("distance to ref");
    ScalarField& quality = *cloud.field("quality");
    ScalarField& distance = *cloud.field("distance to ref");
    for (std::size_t i = 0; i < n; ++i) {
        const float t = static_cast<float>(i);
        // Multiples of 1/8: exact at 6 decimals, so the round trip can be exact.
        cloud.positions()[i] = Eigen::Vector3f(0.125f * t, -3.5f + t, 100.0f - 0.375f * t);
        colors[i] = Rgb8{static_cast<std::uint8_t>(i * 7), static_cast<std::uint8_t>(255 - i), static_cast<std::uint8_t>(i % 3)};
        normals[i] = Eigen::Vector3f(0.6f, -0.8f, 0.1f * t);
        quality.values()[i] = 0.1f * t;
        distance.values()[i] = (i % 4 == 1) ? kNaN : -1.7f * t;
    }
    return cloud;
}

void expectRoundTrip(const PointCloud& cloud, const PointCloud& read, const std::string& distanceName)
{
    ASSERT_EQ(read.size(), cloud.size());
    ASSERT_TRUE(read.hasColors());
    ASSERT_TRUE(read.hasNormals());
    EXPECT_EQ(fieldNames(read), (std::vector<std::string>{"quality", distanceName}));
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        EXPECT_EQ(read.positions()[i], cloud.positions()[i]) << i;
        EXPECT_EQ(read.colors()[i], cloud.colors()[i]) << i;
        EXPECT_EQ(read.normals()[i], cloud.normals()[i]) << i;
        EXPECT_EQ(read.fields()[0].values()[i], cloud.fields()[0].values()[i]) << i;
        if (std::isnan(cloud.fields()[1].values()[i]))
            EXPECT_TRUE(std::isnan(read.fields()[1].values()[i])) << i;
        else
            EXPECT_EQ(read.fields()[1].values()[i], cloud.fields()[1].values()[i]) << i;
    }
}

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

TEST(AsciiFormat, XyzRoundTripKeepsEveryAttribute)
{
    const auto registry = asciiRegistry();
    const fs::path path = tempDir() / "cloud.xyz";
    const PointCloud cloud = makeCloud(50);
    io::writePointCloud(registry, cloud, path);
    const std::string text = readBytes(path);
    EXPECT_EQ(text.rfind("//X Y Z R G B Nx Ny Nz quality distance_to_ref\n", 0), 0u) << text.substr(0, 80);
    EXPECT_NE(text.find(" nan\n"), std::string::npos);
    const PointCloud read = io::readPointCloud(registry, path);
    EXPECT_EQ(read.name, "cloud");
    expectRoundTrip(cloud, read, "distance_to_ref");
}

TEST(AsciiFormat, CsvRoundTripUsesCommas)
{
    const auto registry = asciiRegistry();
    const fs::path path = tempDir() / "cloud.csv";
    const PointCloud cloud = makeCloud(20);
    io::writePointCloud(registry, cloud, path);
    const std::string text = readBytes(path);
    EXPECT_EQ(text.rfind("//X,Y,Z,R,G,B,Nx,Ny,Nz,quality,distance_to_ref\n0.000000,-3.500000,100.000000,0,255,0,", 0), 0u)
        << text.substr(0, 120);
    expectRoundTrip(cloud, io::readPointCloud(registry, path), "distance_to_ref");
}

TEST(AsciiFormat, UtmRoundTripKeepsMillimetres)
{
    const auto registry = asciiRegistry();
    const fs::path path = tempDir() / "utm.txt";
    PointCloud cloud;
    cloud.resize(2);
    cloud.setOrigin(Eigen::Vector3d(512000.0, 5423000.0, 0.0));
    cloud.positions()[0] = Eigen::Vector3f(345.678f, 456.789f, 312.345f);
    cloud.positions()[1] = Eigen::Vector3f(999.999f, 0.001f, 5.5f);
    ScalarField gps("gps_time", 2);
    gps.setOffset(1.3e9);
    gps.values() = {0.25f, 12.125f};
    cloud.addField(std::move(gps));
    io::WriteOptions options;
    options.asciiPrecision = 3;
    io::writePointCloud(registry, cloud, path, options);
    EXPECT_NE(readBytes(path).find("\n512345.678 5423456.789 312.345 1300000000.25\n"), std::string::npos)
        << readBytes(path);

    const PointCloud read = io::readPointCloud(registry, path);
    EXPECT_EQ(read.origin(), Eigen::Vector3d(512000.0, 5423000.0, 0.0));
    for (std::size_t i = 0; i < 2; ++i)
        EXPECT_LT((read.globalPosition(i) - cloud.globalPosition(i)).norm(), 1e-3) << i;
    const ScalarField* time = read.field("gps_time");
    ASSERT_NE(time, nullptr);
    EXPECT_EQ(time->offset(), 1300000000.0);
    EXPECT_NEAR(time->value(1), 1300000012.125, 1e-6);
}

TEST(AsciiFormat, FieldNamesThatLookLikeColumnsSurvive)
{
    const auto registry = asciiRegistry();
    const fs::path path = tempDir() / "names.xyz";
    PointCloud cloud;
    cloud.resize(1);
    cloud.addField("r").values() = {5.0f};
    cloud.addField("Intensity").values() = {6.0f};
    io::writePointCloud(registry, cloud, path);
    const PointCloud read = io::readPointCloud(registry, path);
    EXPECT_FALSE(read.hasColors());
    EXPECT_EQ(fieldNames(read), (std::vector<std::string>{"r_sf", "intensity"}));
}

TEST(AsciiFormat, BinaryEncodingIsRefused)
{
    const fs::path path = tempDir() / "x.xyz";
    io::WriteOptions options;
    options.encoding = io::Encoding::BinaryLittleEndian;
    expectError([&] { io::writePointCloud(asciiRegistry(), makeCloud(2), path, options); },
                ErrorCode::InvalidArgument, {path.string()});
    EXPECT_FALSE(fs::exists(path));
}

TEST(AsciiFormat, CancellingAWriteLeavesNothingBehind)
{
    const fs::path dir = tempDir();
    CancelAfter observer(3);
    io::WriteOptions options;
    options.progress = &observer;
    expectError([&] { io::writePointCloud(asciiRegistry(), makeCloud(300000), dir / "out.xyz", options); },
                ErrorCode::Cancelled, {});
    EXPECT_TRUE(fs::is_empty(dir));
}

TEST(AsciiFormat, CancellingAReadThrowsCancelled)
{
    const auto registry = asciiRegistry();
    const fs::path path = tempDir() / "big.xyz";
    io::writePointCloud(registry, makeCloud(300000), path);
    CancelAfter observer(3);
    io::ReadOptions options;
    options.progress = &observer;
    expectError([&] { io::readFile(registry, path, options); }, ErrorCode::Cancelled, {});
}

// ---------------------------------------------------------------- headers and separators

TEST(AsciiFormat, HeaderNamesTheColumns)
{
    const PointCloud cloud = readText("h.txt", "Title of the survey\nX;Y;Z;Intensity;Red;Green;Blue;Classification\n"
                                               "1;2;3;40;255;128;0;2\n4;5;6;41;1;2;3;5\n");
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.positions()[1], Eigen::Vector3f(4, 5, 6));
    ASSERT_TRUE(cloud.hasColors());
    EXPECT_EQ(cloud.colors()[0], (Rgb8{255, 128, 0}));
    EXPECT_EQ(fieldNames(cloud), (std::vector<std::string>{"intensity", "Classification"}));
    EXPECT_EQ(cloud.field("Classification")->value(1), 5.0);
}

TEST(AsciiFormat, AThousandColumnsAreReadAndMoreAreRefused)
{
    // 1024 values a row are read (1021 fields, named apart in linear time);
    // beyond, and on a hostile single line of a quarter million numbers (it
    // took 8 s and 65,536 fields), a clear error after 1025 values.
    std::string row;
    for (int i = 0; i < 1024; ++i)
        row += (i ? " " : "") + std::to_string(i);
    const PointCloud wide = readText("wide.xyz", row + "\n" + row + "\n");
    EXPECT_EQ(wide.size(), 2u);
    EXPECT_EQ(wide.fields().size(), 1021u);
    std::string line;
    for (int i = 0; i < 65536; ++i)
        line += "1.5 ";
    for (const std::string& text : {row + " 1024\n", line + "\n"}) {
        try {
            readText("long.xyz", text);
            ADD_FAILURE() << "accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ErrorCode::InvalidData);
            EXPECT_NE(std::string(e.what()).find("more than 1024 values in a row"), std::string::npos) << e.what();
        }
    }
}

TEST(AsciiFormat, CommentedHeaderWithFloatColoursAndNormals)
{
    const PointCloud cloud = readText("c.xyz", "# exported\n#  nx ny nz x y z rf gf bf\n"
                                               "0 0 1 1.5 2.5 3.5 1 0.5 0\n");
    ASSERT_EQ(cloud.size(), 1u);
    EXPECT_EQ(cloud.positions()[0], Eigen::Vector3f(1.5f, 2.5f, 3.5f));
    EXPECT_EQ(cloud.normals()[0], Eigen::Vector3f(0, 0, 1));
    EXPECT_EQ(cloud.colors()[0], (Rgb8{255, 128, 0}));
}

TEST(AsciiFormat, HeaderWithAnotherCountFallsBackToColumnRules)
{
    const PointCloud cloud = readText("f.txt", "x y z r g b extra\n1 2 3 200 100 50\n");
    ASSERT_TRUE(cloud.hasColors());
    EXPECT_EQ(cloud.colors()[0], (Rgb8{200, 100, 50}));
}

TEST(AsciiFormat, SeparatorsAreDetected)
{
    const std::vector<std::string> rows = {"1\t2\t3\n4\t5\t6\n", "1   2  3\n  4 5 6  \n", "1, 2, 3,\n4 ,5 ,6,\n",
                                           "1;2;3\n4;5;6\n", "1,2,3\r\n4,5,6\r\n"};
    for (const auto& text : rows) {
        const PointCloud cloud = readText("s.txt", text);
        ASSERT_EQ(cloud.size(), 2u) << text;
        EXPECT_EQ(cloud.positions()[1], Eigen::Vector3f(4, 5, 6)) << text;
        EXPECT_TRUE(cloud.fields().empty()) << text;
    }
}

TEST(AsciiFormat, BlankAndCommentLinesAfterTheHeaderAreSkipped)
{
    const PointCloud cloud = readText("b.xyz", "x y z\n\n1 2 3\n# a comment\n// another\n   \n4 5 6\n");
    EXPECT_EQ(cloud.size(), 2u);
}

TEST(AsciiFormat, NanFieldValuesAndNonFinitePoints)
{
    CaptureLog log;
    const fs::path path = tempDir() / "nan.xyz";
    writeText(path, "x y z quality\n1 2 3 nan\n4 5 6 0.5\nnan 1 1 2\n1 -inf 1 3\n");
    const PointCloud cloud = io::readPointCloud(asciiRegistry(), path);
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_TRUE(std::isnan(cloud.field("quality")->values()[0]));
    EXPECT_EQ(cloud.field("quality")->value(1), 0.5);
    ASSERT_EQ(log.warnings.size(), 1u);
    EXPECT_EQ(log.warnings[0], path.string() + ": 2 points with non-finite coordinates were skipped");
}

TEST(AsciiFormat, LargeFieldValuesGetAnOffset)
{
    const PointCloud cloud = readText("gps.txt", "x y z gps\n1 2 3 1300000001.25\n1 2 3 1300000002.5\n");
    const ScalarField* gps = cloud.field("gps");
    ASSERT_NE(gps, nullptr);
    EXPECT_EQ(gps->offset(), 1300000001.0);
    EXPECT_EQ(gps->value(1), 1300000002.5);
}

TEST(AsciiFormat, UtmCoordinatesPickAnOriginOrTheForcedOne)
{
    const std::string text = "512345.678 5423456.789 312.345\n512346.001 5423457.002 312.5\n";
    const PointCloud cloud = readText("utm.xyz", text);
    EXPECT_EQ(cloud.origin(), Eigen::Vector3d(512000.0, 5423000.0, 0.0));
    EXPECT_NEAR(cloud.globalPosition(0).x(), 512345.678, 1e-3);
    EXPECT_NEAR(cloud.globalPosition(1).y(), 5423457.002, 1e-3);

    io::ReadOptions options;
    options.origin = Eigen::Vector3d(512300.0, 5423400.0, 300.0);
    const PointCloud forced = readText("utm.xyz", text, options);
    EXPECT_EQ(forced.origin(), *options.origin);
    EXPECT_NEAR(forced.positions()[0].z(), 12.345f, 1e-5);
}

// ---------------------------------------------------------------- PTS and column counts

TEST(AsciiFormat, PtsWithCountLineAndColours)
{
    const PointCloud cloud = readText("scan.pts", "2\n1.5 2.5 3.5 -120 10 20 30\n4 5 6 300 40 50 60\n");
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(fieldNames(cloud), (std::vector<std::string>{"intensity"}));
    EXPECT_EQ(cloud.field("intensity")->value(0), -120.0);
    EXPECT_EQ(cloud.colors()[1], (Rgb8{40, 50, 60}));
}

TEST(AsciiFormat, PtsWithFourColumnsAndConcatenatedScans)
{
    const PointCloud cloud = readText("scans.pts", "2\n1 2 3 -5\n4 5 6 7\n1\n7 8 9 10\n");
    ASSERT_EQ(cloud.size(), 3u);
    EXPECT_EQ(fieldNames(cloud), (std::vector<std::string>{"intensity"}));
    EXPECT_EQ(cloud.positions()[2], Eigen::Vector3f(7, 8, 9));
    EXPECT_EQ(cloud.field("intensity")->value(2), 10.0);
}

TEST(AsciiFormat, CountLineMakesAnyFilePts)
{
    const PointCloud cloud = readText("scan.txt", "1\n1 2 3 0.5\n");
    EXPECT_EQ(fieldNames(cloud), (std::vector<std::string>{"intensity"}));
}

TEST(AsciiFormat, ColumnCountRules)
{
    struct Case
    {
        std::string text;
        bool colors;
        bool normals;
        std::vector<std::string> fields;
    };
    const std::vector<Case> cases = {
        {"1 2 3\n", false, false, {}},
        {"1 2 3 0.5\n", false, false, {"field_4"}},
        {"1 2 3 4 5\n", false, false, {"field_4", "field_5"}},
        {"1 2 3 0 128 255\n1 2 3 0 0 1\n", true, false, {}},
        {"1 2 3 0 0 1\n1 2 3 0.6 -0.8 0\n", false, true, {}},
        {"1 2 3 0 0 1\n1 2 3 0 0 1\n", false, true, {}},
        {"1 2 3 0.5 12 300\n", false, false, {"field_4", "field_5", "field_6"}},
        {"1 2 3 -200 10 20 30\n", true, false, {"intensity"}},
        {"1 2 3 0.5 0.1 0.2 0.3\n", false, false, {"field_4", "field_5", "field_6", "field_7"}},
        {"1 2 3 10 20 30 0 0 1\n", true, true, {}},
        {"1 2 3 10 20 30 0 0 7\n", false, false,
         {"field_4", "field_5", "field_6", "field_7", "field_8", "field_9"}},
    };
    for (const auto& c : cases) {
        const PointCloud cloud = readText("count.txt", c.text);
        EXPECT_EQ(cloud.positions()[0], Eigen::Vector3f(1, 2, 3)) << c.text;
        EXPECT_EQ(cloud.hasColors(), c.colors) << c.text;
        EXPECT_EQ(cloud.hasNormals(), c.normals) << c.text;
        EXPECT_EQ(fieldNames(cloud), c.fields) << c.text;
    }
    const PointCloud rgbn = readText("count.txt", "1 2 3 10 20 30 0 0.6 -0.8\n");
    EXPECT_EQ(rgbn.colors()[0], (Rgb8{10, 20, 30}));
    EXPECT_EQ(rgbn.normals()[0], Eigen::Vector3f(0, 0.6f, -0.8f));
}

TEST(AsciiFormat, OptionsOverrideDetection)
{
    io::ReadOptions options;
    options.asciiSkipLines = 2;
    options.asciiSeparator = ';';
    options.asciiColumns = io::AsciiColumns{{"id", "Z", "y", "x", "skip", "R", "g", "b"}};
    const PointCloud cloud = readText("o.txt", "1 2 3\nsomething;else\n7;3;2;1;label;9;8;7\n8;6;5;4;text;1;2;3\n",
                                      options);
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.positions()[0], Eigen::Vector3f(1, 2, 3));
    EXPECT_EQ(cloud.colors()[1], (Rgb8{1, 2, 3}));
    EXPECT_EQ(fieldNames(cloud), (std::vector<std::string>{"id"}));
    EXPECT_EQ(cloud.field("id")->value(1), 8.0);
}

TEST(AsciiFormat, SkipColumnsMayHoldTextWhenTheHeaderIsDetected)
{
    io::ReadOptions options;
    options.asciiColumns = io::AsciiColumns{{"skip", "x", "y", "z"}};
    const PointCloud cloud = readText("t.txt", "name east north up\npole 1 2 3\n", options);
    ASSERT_EQ(cloud.size(), 1u);
    EXPECT_EQ(cloud.positions()[0], Eigen::Vector3f(1, 2, 3));
}

TEST(AsciiFormat, SkipLinesStillReadsTheNamesOfTheLastSkippedLine)
{
    io::ReadOptions options;
    options.asciiSkipLines = 1;
    const PointCloud cloud = readText("n.txt", "x,y,z,temperature\n1,2,3,21.5\n", options);
    EXPECT_EQ(fieldNames(cloud), (std::vector<std::string>{"temperature"}));
}

// ---------------------------------------------------------------- bad input

TEST(AsciiFormatErrors, DamagedFilesNeverCrash)
{
    const fs::path dir = tempDir();
    io::writePointCloud(asciiRegistry(), makeCloud(8), dir / "good.csv");
    const std::string good = readBytes(dir / "good.csv");
    const std::string noise = std::string("0123456789,; \n\r#/.-+enax\t") + '\0';
    std::uint32_t seed = 987;
    for (int round = 0; round < 400; ++round) {
        std::string bytes = good.substr(0, seed % good.size());
        for (int flip = 0; flip < 3; ++flip) {
            seed = seed * 1664525u + 1013904223u;
            if (!bytes.empty())
                bytes[seed % bytes.size()] = noise[(seed >> 24) % noise.size()];
        }
        // A new file per variant: truncating a file that was just mapped is slow on some file systems.
        const fs::path damaged = dir / ("damaged" + std::to_string(round) + ".csv");
        writeText(damaged, bytes);
        try {
            io::readPointCloud(asciiRegistry(), damaged);
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ErrorCode::InvalidData) << e.what();
        }
    }
}

TEST(AsciiFormatErrors, EmptyFile)
{
    expectReadError("empty.xyz", "", {"empty"});
}

TEST(AsciiFormatErrors, HeaderOnly)
{
    expectReadError("header.xyz", "x y z\n\n", {"no data row"});
}

TEST(AsciiFormatErrors, WrongColumnCountGivesTheLine)
{
    expectReadError("rows.xyz", "// x y z i r g b\n1 2 3 4 5 6 7\n\n1 2 3 4 5\n", {"rows.xyz:4: expected 7 values, found 5"});
}

TEST(AsciiFormatErrors, NonNumericValueGivesTheLineAndColumn)
{
    expectReadError("word.csv", "x,y,z\n1,2,3\n4,five,6\n", {"word.csv:3: column 2: 'five' is not a number"});
}

TEST(AsciiFormatErrors, EmptyValue)
{
    expectReadError("hole.csv", "1,2,3\n4,,6\n", {"hole.csv:2: column 2"});
}

TEST(AsciiFormatErrors, TooFewColumns)
{
    expectReadError("two.xyz", "1 2\n3 4\n", {"two.xyz:1:", "at least 3"});
}

TEST(AsciiFormatErrors, NoNumericLine)
{
    expectReadError("text.txt", "hello world\nthis is not a cloud\n", {"no data row"});
}

TEST(AsciiFormatErrors, ColumnMappingWithAnotherCount)
{
    io::ReadOptions options;
    options.asciiColumns = io::AsciiColumns{{"x", "y", "z", "i"}};
    expectReadError("map.xyz", "1 2 3\n", {"4 columns", "has 3"}, options, ErrorCode::InvalidArgument);
}

TEST(AsciiFormatErrors, ColumnMappingWithoutXyz)
{
    io::ReadOptions options;
    options.asciiColumns = io::AsciiColumns{{"x", "y", "i"}};
    expectReadError("map.xyz", "1 2 3\n", {"x, y and z"}, options, ErrorCode::InvalidArgument);
}

TEST(AsciiFormatErrors, SkipLinesBeyondTheFile)
{
    io::ReadOptions options;
    options.asciiSkipLines = 5;
    expectReadError("skip.xyz", "1 2 3\n", {"no data row"}, options);
}

} // namespace
} // namespace scandiff::test
