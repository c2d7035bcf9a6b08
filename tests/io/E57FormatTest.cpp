// SPDX-License-Identifier: GPL-3.0-or-later
// E57 reading against files written by the reference implementation,
// libE57Format and las2e57 (data/e57), round trips through our writer that
// check every value, and damaged files refused with an error naming the
// problem.

#include "e57/E57Pages.h"
#include "e57/E57Tree.h"

#include <scandiff/core/Error.h>
#include <scandiff/io/E57.h>
#include <scandiff/io/FileIO.h>

#include "../support/TestSupport.h"

#include "BuiltinFormats.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>

namespace {

namespace fs = std::filesystem;
using namespace scandiff;
using namespace scandiff::test;

const fs::path kE57Dir = fs::path(SCANDIFF_SAMPLE_DATA_DIR) / "e57";

std::string errorOf(const std::function<void()>& f)
{
    try {
        f();
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidData) << e.what();
        return e.what();
    }
    ADD_FAILURE() << "no error";
    return {};
}

//! Recomputes every page checksum, after a test edited the file's bytes on purpose.
void resealPages(std::string& bytes)
{
    for (std::size_t page = 0; page + 1024 <= bytes.size(); page += 1024) {
        const std::uint32_t crc = io::e57::crc32c(bytes.data() + page, 1020);
        for (int k = 0; k < 4; ++k)
            bytes[page + 1020 + k] = static_cast<char>(crc >> (24 - 8 * k));
    }
}

void writeBytes(const fs::path& path, const std::string& bytes)
{
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(E57Format, Crc32cMatchesTheStandardCheckValue)
{
    // The CRC-32C check value of "123456789" (RFC 3720, appendix B.4).
    EXPECT_EQ(io::e57::crc32c("123456789", 9), 0xE3069283u);
}

TEST(E57Format, ReadsTheReferenceBunnyWithinItsDeclaredBounds)
{
    const std::vector<PointCloud> scans = io::readE57Scans(kE57Dir / "bunnyDouble.e57");
    ASSERT_EQ(scans.size(), 1u);
    const PointCloud& bunny = scans.front();
    EXPECT_EQ(bunny.name, "bunny");
    ASSERT_EQ(bunny.size(), 30571u);
    // The header's cartesianBounds were computed by the writer from the same
    // doubles: the decoded extremes must be those values to the float.
    const BoundingBox box = bunny.bounds();
    EXPECT_EQ(static_cast<float>(box.min.x()), static_cast<float>(-9.4688999999999995e-002));
    EXPECT_EQ(static_cast<float>(box.max.x()), static_cast<float>(6.1008999999999994e-002));
    EXPECT_EQ(static_cast<float>(box.min.y()), static_cast<float>(4.0010999999999998e-002));
    EXPECT_EQ(static_cast<float>(box.max.y()), static_cast<float>(1.8732099999999999e-001));
    EXPECT_EQ(static_cast<float>(box.min.z()), static_cast<float>(-6.1872999999999997e-002));
    EXPECT_EQ(static_cast<float>(box.max.z()), static_cast<float>(5.8798999999999997e-002));

    // The first record, read straight from the bytes: the first packet starts
    // at byte 80 with a 6-byte header and four 2-byte stream lengths, then x's stream.
    const std::string bytes = readBytes(kE57Dir / "bunnyDouble.e57");
    double x0 = 0;
    std::memcpy(&x0, bytes.data() + 80 + 6 + 8, 8);
    EXPECT_EQ(bunny.positions()[0].x(), static_cast<float>(x0));
}

TEST(E57Format, ReadsFloatCoordinatesAndColoursOfTheCube)
{
    const PointCloud cube = io::readPointCloud(builtinFormats(), kE57Dir / "ColouredCubeFloat.e57");
    ASSERT_EQ(cube.size(), 7680u);
    ASSERT_TRUE(cube.hasColors());
    std::size_t onFace = 0, coloured = 0;
    for (std::size_t i = 0; i < cube.size(); ++i) {
        onFace += cube.positions()[i].cwiseAbs().maxCoeff() == 0.5f;
        const Rgb8& c = cube.colors()[i];
        coloured += (c.r | c.g | c.b) != 0;
    }
    EXPECT_EQ(onFace, cube.size());
    EXPECT_EQ(coloured, cube.size());
}

TEST(E57Format, DecodesBitPackedScaledIntegersAndColourLimits)
{
    // las2e57's file: coordinates as 10-bit scaled integers (millimetres in
    // -0.5..0.5), 16-bit colours, 1-bit return fields, a LAS extension field.
    const PointCloud cloud = io::readPointCloud(builtinFormats(), kE57Dir / "ColourRepresentation.e57");
    ASSERT_EQ(cloud.size(), 153u);
    for (std::size_t i = 0; i < cloud.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            const double v = cloud.globalPosition(i)[k];
            ASSERT_LE(std::abs(v), 0.5 + 1e-7);
            ASSERT_NEAR(v * 1000.0, std::round(v * 1000.0), 1e-4) << "point " << i;
        }
    ASSERT_NE(cloud.field("return_index"), nullptr);
    ASSERT_NE(cloud.field("las_pointSourceId"), nullptr);
    EXPECT_EQ(cloud.field("return_count")->range().validCount, 153u);
    ASSERT_TRUE(cloud.hasColors());
}

TEST(E57Format, ListsAndExtractsImages)
{
    const io::E57Summary summary = io::inspectE57(kE57Dir / "PinholeImageWithDistortionParameters.e57");
    EXPECT_TRUE(summary.scans.empty());
    ASSERT_EQ(summary.images.size(), 3u);
    EXPECT_EQ(summary.images[0].name, "JPEG Image Test 1");
    EXPECT_EQ(summary.images[0].representation, "pinhole");
    EXPECT_EQ(summary.images[0].format, "jpeg");
    EXPECT_EQ(summary.images[0].byteLength, 375u);

    const fs::path folder = tempDir() / "e57-images";
    fs::create_directories(folder);
    const std::vector<fs::path> written = io::extractE57Images(kE57Dir / "PinholeImageWithDistortionParameters.e57", folder);
    ASSERT_EQ(written.size(), 3u);
    for (const fs::path& file : written) {
        const std::string jpeg = readBytes(file);
        ASSERT_EQ(jpeg.size(), 375u);
        EXPECT_EQ(static_cast<unsigned char>(jpeg[0]), 0xFF); // JPEG start-of-image marker
        EXPECT_EQ(static_cast<unsigned char>(jpeg[1]), 0xD8);
    }
    // A file of images only is not a cloud: a clear error rather than an empty one.
    EXPECT_NE(errorOf([&] { io::readFile(builtinFormats(), kE57Dir / "PinholeImageWithDistortionParameters.e57"); }).find("no 3D scan"),
              std::string::npos);
}

TEST(E57Format, EmptyAndBrokenSamplesGiveClearAnswers)
{
    const std::vector<PointCloud> zero = io::readE57Scans(kE57Dir / "ZeroPoints.e57");
    ASSERT_EQ(zero.size(), 1u);
    EXPECT_EQ(zero.front().size(), 0u);
    EXPECT_NE(errorOf([&] { io::readFile(builtinFormats(), kE57Dir / "empty.e57"); }).find("holds no 3D scan"), std::string::npos);
    EXPECT_NE(errorOf([&] { io::readFile(builtinFormats(), kE57Dir / "bad-crc.e57"); }).find("checksum of page 0"), std::string::npos);
    EXPECT_NE(errorOf([&] { io::readFile(builtinFormats(), kE57Dir / "InvalidCVHeader.e57"); }).find("not a compressed vector"),
              std::string::npos);
}

//! A station of a survey far from the origin: UTM coordinates, a posed
//! scanner, colours, normals, intensities with invalid ones, GPS times, row
//! indices, and a field whose name XML cannot hold as it is.
PointCloud surveyStation(std::size_t count)
{
    PointCloud cloud;
    cloud.name = "station <1> & \"north\"";
    cloud.setOrigin(Eigen::Vector3d(512000.0, 5401000.0, 200.0));
    cloud.resize(count);
    cloud.enableColors();
    cloud.enableNormals();
    for (const char* name : {"intensity", "time_stamp", "row_index", "distance (m) ]]> _x41_"})
        cloud.addField(name);
    // References once every field exists: adding one moves the others.
    ScalarField& intensity = *cloud.field("intensity");
    ScalarField& time = *cloud.field("time_stamp");
    ScalarField& row = *cloud.field("row_index");
    ScalarField& odd = *cloud.field("distance (m) ]]> _x41_");
    time.setOffset(1.3e9);
    time.keepDoubles();
    std::mt19937 random(7);
    std::uniform_real_distribution<float> spread(-40.0f, 40.0f);
    for (std::size_t i = 0; i < count; ++i) {
        cloud.positions()[i] = Eigen::Vector3f(spread(random), spread(random), spread(random) / 4);
        cloud.enableColors()[i] = Rgb8{static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(i * 7), static_cast<std::uint8_t>(255 - i % 256)};
        cloud.enableNormals()[i] = Eigen::Vector3f(spread(random), spread(random), spread(random)).normalized();
        intensity.values()[i] = i % 17 == 0 ? NAN : static_cast<float>(i % 4096);
        time.setValue(i, 1.3e9 + 0.000001 * static_cast<double>(i) + 1.0 / 3.0);
        row.values()[i] = static_cast<float>(i / 100);
        odd.values()[i] = i % 5 == 0 ? NAN : spread(random);
    }
    SensorPose scanner;
    scanner.position = Eigen::Vector3d(512010.25, 5401020.5, 201.75);
    scanner.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.6, Eigen::Vector3d(0.1, 0.2, 1.0).normalized()));
    cloud.sensors().push_back(scanner);
    cloud.setCrsWkt("PROJCS[\"WGS 84 / UTM zone 31N\",GEOGCS[\"WGS 84\"]]");
    return cloud;
}

TEST(E57Format, RoundTripKeepsEveryValueOfSeveralScans)
{
    // 20,000 points span about ten packets: the 1-bit invalid-intensity stream
    // carries values across packet boundaries.
    const PointCloud station = surveyStation(20000);
    PointCloud plain;
    plain.name = "plain";
    plain.setOrigin(station.origin()); // scans of one file share the site's origin
    plain.resize(3);
    plain.positions() = {Eigen::Vector3f(0.1f, 0.2f, 0.3f), Eigen::Vector3f(-1e-3f, 5.0f, 7.25f), Eigen::Vector3f(0, 0, 0)};
    const fs::path path = tempDir() / "two-scans.e57";
    io::writeE57({&station, &plain}, path);

    const io::E57Summary summary = io::inspectE57(path);
    ASSERT_EQ(summary.scans.size(), 2u);
    EXPECT_EQ(summary.scans[0].recordCount, 20000u);
    ASSERT_TRUE(summary.scans[0].pose.has_value());
    EXPECT_FALSE(summary.scans[1].pose.has_value());

    io::ReadOptions options;
    options.origin = station.origin();
    const std::vector<PointCloud> back = io::readE57Scans(path, options);
    ASSERT_EQ(back.size(), 2u);
    const PointCloud& a = back[0];
    EXPECT_EQ(a.name, station.name);
    EXPECT_EQ(a.crsWkt(), station.crsWkt());
    ASSERT_EQ(a.size(), station.size());
    ASSERT_EQ(a.sensors().size(), 1u);
    EXPECT_LT((a.sensors()[0].position - station.sensors()[0].position).norm(), 1e-9);
    EXPECT_LT(a.sensors()[0].orientation.angularDistance(station.sensors()[0].orientation), 1e-12);
    double worst = 0, worstNormal = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        worst = std::max(worst, (a.globalPosition(i) - station.globalPosition(i)).cwiseAbs().maxCoeff());
        worstNormal = std::max(worstNormal, static_cast<double>((a.normals()[i] - station.normals()[i]).cwiseAbs().maxCoeff()));
        ASSERT_EQ(a.colors()[i], station.colors()[i]);
    }
    // Written in the scanner's frame, read back through its pose in double.
    EXPECT_LT(worst, 1e-9);
    EXPECT_LT(worstNormal, 1e-6);
    for (const char* name : {"intensity", "time_stamp", "row_index", "distance (m) ]]> _x41_"}) {
        const ScalarField* original = station.field(name);
        const ScalarField* read = a.field(name);
        ASSERT_NE(read, nullptr) << name;
        for (std::size_t i = 0; i < a.size(); ++i) {
            ASSERT_EQ(original->hasValue(i), read->hasValue(i)) << name << " " << i;
            if (original->hasValue(i)) {
                ASSERT_EQ(original->value(i), read->value(i)) << name << " " << i; // a double stays a double
            }
        }
    }

    const PointCloud& b = back[1];
    ASSERT_EQ(b.size(), 3u);
    EXPECT_TRUE(b.sensors().empty());
    for (std::size_t i = 0; i < 3; ++i)
        EXPECT_EQ(b.globalPosition(i), plain.globalPosition(i));

    // One cloud for the tools, with the scan each point came from.
    const PointCloud merged = io::readPointCloud(builtinFormats(), path, options);
    ASSERT_EQ(merged.size(), 20003u);
    ASSERT_NE(merged.field("scan_index"), nullptr);
    EXPECT_EQ(merged.field("scan_index")->value(0), 0.0);
    EXPECT_EQ(merged.field("scan_index")->value(20002), 1.0);
    EXPECT_EQ(merged.sensors().size(), 1u);
    const std::vector<Entity> parts = io::readEntities(builtinFormats(), path, options);
    ASSERT_EQ(parts.size(), 2u);
    EXPECT_EQ(std::get<PointCloud>(parts[1]).name, "plain");
}

TEST(E57Format, DamagedCopiesOfOurFileAreRefusedByName)
{
    const PointCloud station = surveyStation(3000);
    const fs::path path = tempDir() / "station.e57";
    io::writeE57({&station}, path);
    const std::string good = readBytes(path);
    const fs::path broken = tempDir() / "broken.e57";

    std::string flipped = good;
    flipped[5 * 1024 + 100] ^= 0x20;
    writeBytes(broken, flipped);
    EXPECT_NE(errorOf([&] { io::readE57Scans(broken); }).find("checksum of page 5"), std::string::npos);

    writeBytes(broken, good.substr(0, good.size() - 1024));
    EXPECT_NE(errorOf([&] { io::readE57Scans(broken); }).find("truncated"), std::string::npos);

    // The XML claims ten times the records the section holds: refused before allocating.
    std::string lying = good;
    const std::size_t at = lying.find("recordCount=\"3000\"");
    ASSERT_NE(at, std::string::npos);
    lying.replace(at, 18, "recordCount=\"9999\"");
    resealPages(lying);
    writeBytes(broken, lying);
    EXPECT_NE(errorOf([&] { io::readE57Scans(broken); }).find("claims 9999 records"), std::string::npos);

    // A record field of a type no record may have.
    std::string badType = good;
    const std::size_t field = badType.find("<cartesianY type=\"Float\"/>");
    ASSERT_NE(field, std::string::npos);
    badType.replace(field, 26, "<cartesianY type=\"Blob\"/> ");
    resealPages(badType);
    writeBytes(broken, badType);
    EXPECT_NE(errorOf([&] { io::readE57Scans(broken); }).find("'cartesianY' has type 'Blob'"), std::string::npos);

    // Malformed XML.
    std::string malformed = good;
    const std::size_t root = malformed.rfind("</e57Root>");
    ASSERT_NE(root, std::string::npos);
    malformed.replace(root, 10, "</e57Rot> ");
    resealPages(malformed);
    writeBytes(broken, malformed);
    EXPECT_NE(errorOf([&] { io::readE57Scans(broken); }).find("XML section is malformed"), std::string::npos);
}

TEST(E57Format, TheXmlParserRefusesHostileSectionsAndKeepsNamespacesAndText)
{
    auto parse = [](const std::string& text) { return io::e57::parseTree(std::vector<char>(text.begin(), text.end()), "x.e57"); };
    const std::string open = "<e57Root type=\"Structure\" xmlns=\"http://www.astm.org/COMMIT/E57/2010-e57-v1.0\" "
                             "xmlns:nor=\"http://www.libe57.org/E57_NOR_surface_normals.txt\">";
    // Names, namespaces, the type attribute apart from the others, strings
    // keeping their spaces, numbers trimmed, CDATA as text.
    const io::e57::Node tree = parse(open + "<guid type=\"String\"> a b </guid><nor:normalX type=\"Float\" minimum=\"-1\"> 0.5 "
                                            "</nor:normalX><n type=\"Integer\"><![CDATA[42]]></n></e57Root>");
    ASSERT_EQ(tree.children.size(), 3u);
    EXPECT_EQ(tree.localName, "e57Root");
    EXPECT_EQ(tree.namespaceUri, io::e57::kE57Namespace);
    EXPECT_EQ(tree.children[0].text, " a b ");
    const io::e57::Node& normal = tree.children[1];
    EXPECT_EQ(normal.qualifiedName(), "nor:normalX");
    EXPECT_EQ(normal.namespaceUri, io::e57::kNormalsNamespace);
    EXPECT_EQ(normal.type, "Float");
    EXPECT_EQ(normal.text, "0.5");
    ASSERT_EQ(normal.attributes.size(), 1u);
    EXPECT_EQ(normal.attributes[0].first, "minimum");
    EXPECT_EQ(io::e57::integerValue(tree.children[2], "x.e57"), 42);

    // A "billion laughs": ten levels of ten references, 10^10 copies if expanded.
    std::string laughs = "<?xml version=\"1.0\"?><!DOCTYPE e57Root [<!ENTITY l0 \"ha\">";
    for (int i = 1; i <= 10; ++i) {
        laughs += "<!ENTITY l" + std::to_string(i) + " \"";
        for (int j = 0; j < 10; ++j)
            laughs += "&l" + std::to_string(i - 1) + ";";
        laughs += "\">";
    }
    laughs += "]>" + open + "<guid type=\"String\">&l10;</guid></e57Root>";
    EXPECT_NE(errorOf([&] { parse(laughs); }).find("declares the entity 'l0'"), std::string::npos) << errorOf([&] { parse(laughs); });
    // An external entity is never fetched: its declaration is refused.
    const std::string external = "<?xml version=\"1.0\"?><!DOCTYPE e57Root [<!ENTITY secret SYSTEM \"/etc/passwd\">]>" + open +
                                 "<guid type=\"String\">&secret;</guid></e57Root>";
    EXPECT_NE(errorOf([&] { parse(external); }).find("declares the entity 'secret'"), std::string::npos);
    // A DOCTYPE without entities is harmless and read.
    EXPECT_EQ(parse("<?xml version=\"1.0\"?><!DOCTYPE e57Root>" + open + "</e57Root>").localName, "e57Root");
    // Nesting deeper than E57 files go.
    std::string deep = open;
    for (int i = 0; i < 100; ++i)
        deep += "<s type=\"Structure\">";
    for (int i = 0; i < 100; ++i)
        deep += "</s>";
    EXPECT_NE(errorOf([&] { parse(deep + "</e57Root>"); }).find("nests deeper than 64 levels"), std::string::npos);
    // Not XML at all, and no element.
    EXPECT_NE(errorOf([&] { parse("\x01\x02garbage"); }).find("XML section is malformed (line 1"), std::string::npos);
    EXPECT_NE(errorOf([&] { parse(""); }).find("XML section"), std::string::npos);
}

TEST(E57Format, NamesXmlCannotHoldAreMadeSafeAndScansMayNotShareASection)
{
    // A name read from a file in another encoding, with a control character:
    // written as '?' where XML 1.0 has no character, so the file reads back.
    PointCloud a, b;
    a.name = std::string("bad\x01name\xff");
    a.resize(5);
    b.name = "b";
    b.resize(4);
    for (std::size_t i = 0; i < 5; ++i)
        a.positions()[i] = Eigen::Vector3f(float(i), 0, 0);
    const fs::path path = tempDir() / "names.e57";
    io::writeE57({&a, &b}, path);
    const std::vector<PointCloud> back = io::readE57Scans(path);
    ASSERT_EQ(back.size(), 2u);
    EXPECT_EQ(back[0].name, "bad?name?");

    // The second scan made to read the first one's points: refused, not read twice.
    std::string bytes = readBytes(path);
    const std::size_t first = bytes.find("fileOffset=\"");
    const std::size_t second = bytes.find("fileOffset=\"", first + 1);
    ASSERT_NE(second, std::string::npos);
    const std::size_t valueStart = first + 12, valueEnd = bytes.find('"', valueStart);
    const std::size_t secondStart = second + 12, secondEnd = bytes.find('"', secondStart);
    std::string firstValue = bytes.substr(valueStart, valueEnd - valueStart);
    ASSERT_LE(firstValue.size(), secondEnd - secondStart);
    firstValue.resize(secondEnd - secondStart, ' '); // the same length: trailing spaces are trimmed
    bytes.replace(secondStart, secondEnd - secondStart, firstValue);
    resealPages(bytes);
    const fs::path shared = tempDir() / "shared.e57";
    writeBytes(shared, bytes);
    EXPECT_NE(errorOf([&] { io::readE57Scans(shared); }).find("same points section"), std::string::npos);
}

//! The file with its XML section replaced by `edit(xml)`: the pages'
//! payloads joined, the XML swapped, the whole cut into checksummed pages again.
std::string withXml(const std::string& file, const std::function<std::string(std::string)>& edit)
{
    std::uint64_t xmlPhysical = 0, xmlLength = 0;
    std::memcpy(&xmlPhysical, file.data() + 24, 8);
    std::memcpy(&xmlLength, file.data() + 32, 8);
    std::string logical;
    for (std::size_t page = 0; page + 1024 <= file.size(); page += 1024)
        logical.append(file, page, 1020);
    const std::size_t xmlLogical = xmlPhysical / 1024 * 1020 + xmlPhysical % 1024;
    const std::string xml = edit(logical.substr(xmlLogical, xmlLength));
    logical.resize(xmlLogical);
    logical += xml;
    logical.resize((logical.size() + 1019) / 1020 * 1020, '\0');
    const std::uint64_t newLength = xml.size(), physical = logical.size() / 1020 * 1024;
    std::memcpy(logical.data() + 16, &physical, 8);
    std::memcpy(logical.data() + 32, &newLength, 8);
    std::string out;
    for (std::size_t page = 0; page < logical.size(); page += 1020) {
        out.append(logical, page, 1020);
        out.append(4, '\0');
    }
    resealPages(out);
    return out;
}

TEST(E57Format, SphericalCoordinatesAreConvertedAndMakeASensor)
{
    // A scan stored as range, azimuth and elevation (what scanners record):
    // our writer's doubles relabelled as the spherical fields.
    PointCloud polar;
    polar.name = "station";
    polar.resize(200);
    for (std::size_t i = 0; i < polar.size(); ++i)
        polar.positions()[i] = Eigen::Vector3f(5.0f + 0.1f * float(i % 17), -3.0f + 0.03f * float(i), -0.5f + 0.005f * float(i));
    const fs::path written = tempDir() / "polar.e57";
    io::writeE57({&polar}, written);
    const std::string spherical = withXml(readBytes(written), [](std::string xml) {
        for (const auto& [from, to] : {std::pair<std::string, std::string>{"<cartesianX ", "<sphericalRange "},
                                       {"<cartesianY ", "<sphericalAzimuth "},
                                       {"<cartesianZ ", "<sphericalElevation "}})
            xml.replace(xml.find(from), from.size(), to);
        xml.replace(xml.find("<cartesianBounds"), xml.find("</cartesianBounds>") + 18 - xml.find("<cartesianBounds"), "");
        return xml;
    });
    const fs::path path = tempDir() / "spherical.e57";
    writeBytes(path, spherical);
    const io::E57Summary summary = io::inspectE57(path);
    ASSERT_EQ(summary.scans.size(), 1u);
    EXPECT_TRUE(summary.scans[0].spherical);
    const std::vector<PointCloud> scans = io::readE57Scans(path);
    ASSERT_EQ(scans.size(), 1u);
    ASSERT_EQ(scans[0].size(), polar.size());
    EXPECT_EQ(scans[0].sensors().size(), 1u); // a spherical scan is a station at its frame's origin
    for (std::size_t i = 0; i < polar.size(); ++i) {
        const double r = polar.positions()[i].x(), azimuth = polar.positions()[i].y(), elevation = polar.positions()[i].z();
        const Eigen::Vector3d expected(r * std::cos(elevation) * std::cos(azimuth), r * std::cos(elevation) * std::sin(azimuth),
                                       r * std::sin(elevation));
        ASSERT_LT((scans[0].globalPosition(i) - expected).norm(), 1e-5) << i;
    }
}

TEST(E57Format, ConvertsBetweenE57AndPly)
{
    const io::FormatRegistry registry = builtinFormats();
    const PointCloud cube = io::readPointCloud(registry, kE57Dir / "ColouredCubeFloat.e57");
    const fs::path e57 = tempDir() / "cube.e57", ply = tempDir() / "cube.ply";
    io::writePointCloud(registry, cube, e57);
    const PointCloud again = io::readPointCloud(registry, e57);
    ASSERT_EQ(again.size(), cube.size());
    for (std::size_t i = 0; i < cube.size(); ++i) {
        ASSERT_EQ(again.positions()[i], cube.positions()[i]);
        ASSERT_EQ(again.colors()[i], cube.colors()[i]);
    }
    io::writePointCloud(registry, again, ply);
    EXPECT_EQ(io::readPointCloud(registry, ply).size(), cube.size());
    // Two clouds into a format of one cloud: refused, not merged silently.
    const PointCloud* both[] = {&cube, &again};
    EXPECT_EQ(errorCodeOf([&] { io::writePointClouds(registry, {both[0], both[1]}, ply); }), ErrorCode::Unsupported);
}

} // namespace
