// SPDX-License-Identifier: GPL-3.0-or-later
// E57 writing (ASTM E2807): the points of every cloud as one compressed
// vector section of bit-packed packets, then the XML section that describes
// them, all in 1 KiB pages each closed by its CRC-32C; the file header is
// written last, once the XML's place and the file's length are known.
#include <scandiff/io/E57.h>

#include "e57/E57Fields.h"
#include "e57/E57Pages.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Progress.h>
#include <scandiff/io/AtomicFile.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <cmath>
#include <cstring>
#include <random>
#include <sstream>

// E57's binary sections are little endian (ASTM E2807 §9): values are moved with
// memcpy, which is only right on a little-endian host.
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "E57Writer.cpp assumes a little-endian host"
#endif

namespace scandiff::io {

namespace fs = std::filesystem;
using namespace e57;

namespace {

constexpr std::uint64_t kPageSize = 1024;
constexpr std::uint64_t kPayload = kPageSize - 4;
constexpr std::size_t kMaxPacket = 65536; // a packet's length is stored minus one in 16 bits

//! Appends logical bytes to the file, page by page, each page closed by its checksum.
class PagedWriter
{
public:
    explicit PagedWriter(std::ofstream& out) : out_(out), page_(kPageSize, 0) {}

    std::uint64_t physicalPosition() const { return pages_ * kPageSize + fill_; }
    std::uint64_t logicalPosition() const { return pages_ * kPayload + fill_; }

    void write(const void* data, std::size_t length)
    {
        const auto* p = static_cast<const char*>(data);
        while (length > 0) {
            const std::size_t take = std::min<std::size_t>(kPayload - fill_, length);
            std::memcpy(page_.data() + fill_, p, take);
            fill_ += take;
            p += take;
            length -= take;
            if (fill_ == kPayload)
                flushPage();
        }
    }

    void padTo(std::uint64_t alignment)
    {
        static const char zeros[8] = {};
        while (logicalPosition() % alignment != 0)
            write(zeros, 1);
    }

    //! Closes the last page; returns the file's physical length.
    std::uint64_t finish()
    {
        if (fill_ > 0) {
            std::fill(page_.begin() + static_cast<std::ptrdiff_t>(fill_), page_.end(), 0);
            fill_ = kPayload;
            flushPage();
        }
        return pages_ * kPageSize;
    }

    //! Puts the 48-byte file header at the start of page 0 (kept since it was written) and rewrites that page.
    void rewriteHeader(const char (&header)[48])
    {
        std::memcpy(firstPage_.data(), header, 48);
        sealPage(firstPage_);
        out_.seekp(0);
        out_.write(firstPage_.data(), static_cast<std::streamsize>(kPageSize));
    }

private:
    static void sealPage(std::vector<char>& page)
    {
        const std::uint32_t crc = crc32c(page.data(), kPayload);
        // The checksum is stored big-endian (as libE57Format and the reference implementation do).
        page[kPayload + 0] = static_cast<char>(crc >> 24);
        page[kPayload + 1] = static_cast<char>(crc >> 16);
        page[kPayload + 2] = static_cast<char>(crc >> 8);
        page[kPayload + 3] = static_cast<char>(crc);
    }

    void flushPage()
    {
        sealPage(page_);
        if (pages_ == 0)
            firstPage_ = page_;
        out_.write(page_.data(), static_cast<std::streamsize>(kPageSize));
        ++pages_;
        fill_ = 0;
    }

    std::ofstream& out_;
    std::vector<char> page_;
    std::vector<char> firstPage_;
    std::size_t fill_ = 0;
    std::uint64_t pages_ = 0;
};

//! One field of the records written: how it is stored and where its values come from.
struct WrittenField
{
    enum class Kind { Integer, Float32, Float64 };
    std::string element;  //!< "cartesianX", "nor:normalX", "sdf:distance"
    Kind kind = Kind::Float64;
    int bits = 64;
    std::int64_t minimum = 0, maximum = 0;
    std::function<double(std::size_t)> value;

    std::uint64_t raw(std::size_t i) const
    {
        const double v = value(i);
        switch (kind) {
        case Kind::Float64: {
            std::uint64_t r;
            std::memcpy(&r, &v, 8);
            return r;
        }
        case Kind::Float32: {
            const float f = static_cast<float>(v);
            std::uint32_t r;
            std::memcpy(&r, &f, 4);
            return r;
        }
        case Kind::Integer:
            return static_cast<std::uint64_t>(static_cast<std::int64_t>(v)) - static_cast<std::uint64_t>(minimum);
        }
        return 0;
    }
};

WrittenField integerField(std::string element, std::int64_t minimum, std::int64_t maximum, std::function<double(std::size_t)> value)
{
    WrittenField f;
    f.element = std::move(element);
    f.kind = WrittenField::Kind::Integer;
    f.minimum = minimum;
    f.maximum = maximum;
    const std::uint64_t range = static_cast<std::uint64_t>(maximum) - static_cast<std::uint64_t>(minimum);
    f.bits = range == 0 ? 0 : 64 - __builtin_clzll(range);
    f.value = std::move(value);
    return f;
}

WrittenField floatField(std::string element, bool single, std::function<double(std::size_t)> value)
{
    WrittenField f;
    f.element = std::move(element);
    f.kind = single ? WrittenField::Kind::Float32 : WrittenField::Kind::Float64;
    f.bits = single ? 32 : 64;
    f.value = std::move(value);
    return f;
}

//! A bit-packed byte stream: values' low bits first, continuing from one packet to the next (§9.5).
struct BitStream
{
    unsigned __int128 accumulator = 0;
    int bits = 0;
    void put(std::uint64_t raw, int width, std::vector<char>& out)
    {
        if (width == 0)
            return;
        accumulator |= static_cast<unsigned __int128>(raw) << bits;
        bits += width;
        while (bits >= 8) {
            out.push_back(static_cast<char>(static_cast<std::uint8_t>(accumulator)));
            accumulator >>= 8;
            bits -= 8;
        }
    }
    void flush(std::vector<char>& out)
    {
        if (bits > 0)
            out.push_back(static_cast<char>(static_cast<std::uint8_t>(accumulator)));
        accumulator = 0;
        bits = 0;
    }
};

//! The text with what XML 1.0 cannot hold replaced by '?': control characters
//! (but tab, line feed, carriage return) and bytes that are not UTF-8 (a
//! name read from a file in another encoding), so every reader can parse it.
std::string xmlSafe(const std::string& text)
{
    std::string out;
    out.reserve(text.size());
    for (std::size_t i = 0; i < text.size();) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (c < 0x80) {
            out += (c < 0x20 && c != '\t' && c != '\n' && c != '\r') || c == 0x7F ? '?' : static_cast<char>(c);
            ++i;
            continue;
        }
        const std::size_t length = c >= 0xF0 && c <= 0xF4 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 && c <= 0xDF ? 2 : 0;
        bool valid = length > 0 && i + length <= text.size();
        for (std::size_t k = 1; valid && k < length; ++k)
            valid = (static_cast<unsigned char>(text[i + k]) & 0xC0) == 0x80;
        if (valid) {
            out.append(text, i, length);
            i += length;
        } else {
            out += '?';
            ++i;
        }
    }
    return out;
}

std::string cdata(const std::string& raw)
{
    const std::string text = xmlSafe(raw);
    std::string out = "<![CDATA[";
    std::size_t from = 0;
    for (std::size_t at; (at = text.find("]]>", from)) != std::string::npos; from = at + 2)
        out += text.substr(from, at + 2 - from) + "]]><![CDATA[";
    return out + text.substr(from) + "]]>";
}

std::string number(double v)
{
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", v);
    return text;
}

std::string newGuid()
{
    thread_local std::mt19937_64 generator(std::random_device{}() ^ static_cast<std::uint64_t>(
                                                                  std::chrono::steady_clock::now().time_since_epoch().count()));
    const std::uint64_t a = generator(), b = generator();
    char text[40];
    std::snprintf(text, sizeof text, "{%08X-%04X-%04X-%04X-%012llX}", static_cast<unsigned>(a >> 32), static_cast<unsigned>((a >> 16) & 0xFFFF),
                  static_cast<unsigned>(0x4000 | (a & 0x0FFF)), static_cast<unsigned>(0x8000 | ((b >> 48) & 0x3FFF)),
                  static_cast<unsigned long long>(b & 0xFFFFFFFFFFFFull));
    return text;
}

//! Whether every valid value of the field is an integer within 32 bits (then an E57 Integer holds it).
bool integerValued(const ScalarField& field, std::int64_t& minimum, std::int64_t& maximum)
{
    bool any = false;
    for (std::size_t i = 0; i < field.size(); ++i) {
        if (!field.hasValue(i))
            return false;
        const double v = field.value(i);
        if (v != std::floor(v) || std::abs(v) > 2147483647.0)
            return false;
        const auto n = static_cast<std::int64_t>(v);
        minimum = any ? std::min(minimum, n) : n;
        maximum = any ? std::max(maximum, n) : n;
        any = true;
    }
    return any;
}

//! One cloud's scan: its fields, its pose, and the XML that describes it.
struct ScanPlan
{
    const PointCloud* cloud = nullptr;
    bool posed = false;
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
    Eigen::Vector3d translation = Eigen::Vector3d::Zero();
    std::vector<WrittenField> fields;
    std::vector<std::pair<std::string, std::string>> limits; //!< extra XML blocks of the scan header
    std::uint64_t sectionPhysical = 0;
    Eigen::Vector3d boundsMin = Eigen::Vector3d::Zero(), boundsMax = Eigen::Vector3d::Zero();
};

ScanPlan planScan(const PointCloud& cloud)
{
    ScanPlan plan;
    plan.cloud = &cloud;
    // One station's cloud is written in its scanner's frame with the pose
    // (what the standard means by a scan); a merged cloud of several stations in world coordinates.
    if (cloud.sensors().size() == 1) {
        plan.posed = true;
        plan.rotation = cloud.sensors().front().orientation.normalized();
        plan.translation = cloud.sensors().front().position;
    }
    const Eigen::Matrix3d toScan = plan.rotation.toRotationMatrix().transpose();
    const Eigen::Vector3d shift = cloud.origin() - plan.translation;
    auto local = [&cloud, toScan, shift, posed = plan.posed](std::size_t i, int axis) {
        const Eigen::Vector3d p = cloud.positions()[i].cast<double>();
        if (!posed)
            return cloud.origin()[axis] + p[axis];
        return (toScan * (shift + p))[axis];
    };
    const char* axes[3] = {"cartesianX", "cartesianY", "cartesianZ"};
    for (int k = 0; k < 3; ++k)
        plan.fields.push_back(floatField(axes[k], false, [local, k](std::size_t i) { return local(i, k); }));
    for (std::size_t i = 0; i < cloud.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            const double v = local(i, k);
            plan.boundsMin[k] = i == 0 ? v : std::min(plan.boundsMin[k], v);
            plan.boundsMax[k] = i == 0 ? v : std::max(plan.boundsMax[k], v);
        }
    if (cloud.hasColors()) {
        const char* names[3] = {"colorRed", "colorGreen", "colorBlue"};
        for (int k = 0; k < 3; ++k)
            plan.fields.push_back(integerField(names[k], 0, 255, [&cloud, k](std::size_t i) {
                const Rgb8& c = cloud.colors()[i];
                return static_cast<double>(k == 0 ? c.r : k == 1 ? c.g : c.b);
            }));
        plan.limits.emplace_back("colorLimits",
                                 "<colorRedMinimum type=\"Integer\">0</colorRedMinimum><colorRedMaximum type=\"Integer\">255</colorRedMaximum>"
                                 "<colorGreenMinimum type=\"Integer\">0</colorGreenMinimum><colorGreenMaximum type=\"Integer\">255</colorGreenMaximum>"
                                 "<colorBlueMinimum type=\"Integer\">0</colorBlueMinimum><colorBlueMaximum type=\"Integer\">255</colorBlueMaximum>");
    }
    if (cloud.hasNormals()) {
        const char* names[3] = {"nor:normalX", "nor:normalY", "nor:normalZ"};
        for (int k = 0; k < 3; ++k)
            plan.fields.push_back(floatField(names[k], true, [&cloud, toScan, k, posed = plan.posed](std::size_t i) {
                const Eigen::Vector3d n = cloud.normals()[i].cast<double>();
                return posed ? (toScan * n)[k] : n[k];
            }));
    }
    for (const ScalarField& field : cloud.fields()) {
        const ScalarField* f = &field;
        const std::optional<std::string> standard = standardElementFor(field.name());
        const std::string element = standard ? *standard : std::string(kScalarFieldPrefix) + ":" + encodeXmlName(field.name());
        std::int64_t lo = 0, hi = 0;
        const bool integerElement = standard && *standard != "intensity" && *standard != "timeStamp";
        if (integerElement && integerValued(field, lo, hi)) {
            plan.fields.push_back(integerField(element, lo, hi, [f](std::size_t i) { return f->value(i); }));
            continue;
        }
        if (integerElement) {
            // The standard says Integer; values that are not go under scandiff's own name.
            plan.fields.push_back(floatField(std::string(kScalarFieldPrefix) + ":" + encodeXmlName(field.name()), !field.isDouble(),
                                             [f](std::size_t i) { return f->value(i); }));
            continue;
        }
        bool missing = false;
        for (std::size_t i = 0; i < field.size() && !missing; ++i)
            missing = !field.hasValue(i);
        const bool flagged = standard && missing; // intensity and time stamps say "invalid" with a flag, not NaN
        plan.fields.push_back(floatField(element, !field.isDouble(), [f, flagged](std::size_t i) {
            return flagged && !f->hasValue(i) ? 0.0 : f->value(i);
        }));
        if (flagged)
            plan.fields.push_back(integerField(*standard == "intensity" ? "isIntensityInvalid" : "isTimeStampInvalid", 0, 1,
                                               [f](std::size_t i) { return f->hasValue(i) ? 0.0 : 1.0; }));
        if (standard && *standard == "intensity") {
            const ValueRange range = field.range();
            if (range.validCount > 0)
                plan.limits.emplace_back("intensityLimits", "<intensityMinimum type=\"Float\">" + number(range.min) +
                                                                "</intensityMinimum><intensityMaximum type=\"Float\">" + number(range.max) +
                                                                "</intensityMaximum>");
        }
    }
    return plan;
}

std::uint64_t recordsPerPacket(const ScanPlan& plan)
{
    std::uint64_t bitsPerRecord = 0;
    for (const WrittenField& f : plan.fields)
        bitsPerRecord += static_cast<std::uint64_t>(f.bits);
    // Room for the header, the stream table, one carried byte per stream and the padding to 4 bytes.
    const std::uint64_t room = kMaxPacket - 6 - 3 * plan.fields.size() - 4;
    return std::max<std::uint64_t>(1, room * 8 / std::max<std::uint64_t>(bitsPerRecord, 1));
}

//! Bytes of a field's stream written once `records` records are encoded (the last partial byte only at the end).
std::uint64_t streamBytes(const WrittenField& f, std::uint64_t records, bool last)
{
    const std::uint64_t bits = records * static_cast<std::uint64_t>(f.bits);
    return last ? (bits + 7) / 8 : bits / 8;
}

std::uint64_t packetLength(const ScanPlan& plan, std::uint64_t begin, std::uint64_t end, std::uint64_t total)
{
    std::uint64_t length = 6 + 2 * plan.fields.size();
    for (const WrittenField& f : plan.fields)
        length += streamBytes(f, end, end == total) - streamBytes(f, begin, false);
    return (length + 3) / 4 * 4;
}

void writeScanSection(PagedWriter& writer, ScanPlan& plan, ProgressTicker& ticker)
{
    const std::uint64_t total = plan.cloud->size();
    const std::uint64_t perPacket = recordsPerPacket(plan);
    std::uint64_t sectionLength = 32;
    for (std::uint64_t begin = 0; begin < total; begin += perPacket)
        sectionLength += packetLength(plan, begin, std::min(total, begin + perPacket), total);

    writer.padTo(4);
    plan.sectionPhysical = writer.physicalPosition();
    // The first packet's physical offset: 32 logical bytes on, past any page checksum in between.
    const std::uint64_t dataLogical = writer.logicalPosition() + 32;
    const std::uint64_t dataPhysical = dataLogical / kPayload * kPageSize + dataLogical % kPayload;
    char header[32] = {};
    header[0] = 1; // compressed vector section
    std::memcpy(header + 8, &sectionLength, 8);
    std::memcpy(header + 16, &dataPhysical, 8);
    writer.write(header, 32);

    std::vector<BitStream> streams(plan.fields.size());
    std::vector<std::vector<char>> bytes(plan.fields.size());
    std::vector<char> packet;
    for (std::uint64_t begin = 0; begin < total; begin += perPacket) {
        const std::uint64_t end = std::min(total, begin + perPacket);
        for (std::size_t s = 0; s < plan.fields.size(); ++s) {
            const WrittenField& f = plan.fields[s];
            bytes[s].clear();
            if (f.bits % 8 == 0 && streams[s].bits == 0) {
                // Whole bytes (coordinates, floats, 8-bit colours): the value's
                // little-endian bytes as they are, without the bit shifting.
                const std::size_t width = static_cast<std::size_t>(f.bits) / 8;
                bytes[s].resize(width * static_cast<std::size_t>(end - begin));
                char* out = bytes[s].data();
                for (std::uint64_t i = begin; i < end; ++i, out += width) {
                    const std::uint64_t raw = f.raw(static_cast<std::size_t>(i));
                    std::memcpy(out, &raw, width);
                }
            } else {
                for (std::uint64_t i = begin; i < end; ++i)
                    streams[s].put(f.raw(static_cast<std::size_t>(i)), f.bits, bytes[s]);
            }
            if (end == total)
                streams[s].flush(bytes[s]);
        }
        std::size_t length = 6 + 2 * plan.fields.size();
        for (const auto& b : bytes)
            length += b.size();
        const std::size_t padded = (length + 3) / 4 * 4;
        packet.assign(padded, 0);
        packet[0] = 1; // data packet
        const auto lengthMinus1 = static_cast<std::uint16_t>(padded - 1);
        const auto count = static_cast<std::uint16_t>(plan.fields.size());
        std::memcpy(packet.data() + 2, &lengthMinus1, 2);
        std::memcpy(packet.data() + 4, &count, 2);
        std::size_t at = 6 + 2 * plan.fields.size();
        for (std::size_t s = 0; s < bytes.size(); ++s) {
            const auto streamLength = static_cast<std::uint16_t>(bytes[s].size());
            std::memcpy(packet.data() + 6 + 2 * s, &streamLength, 2);
            std::memcpy(packet.data() + at, bytes[s].data(), bytes[s].size());
            at += bytes[s].size();
        }
        writer.write(packet.data(), packet.size());
        ticker.step(end - begin);
    }
}

std::string fieldXml(const WrittenField& f)
{
    std::string xml = "<" + f.element;
    if (f.kind == WrittenField::Kind::Integer)
        xml += " type=\"Integer\" minimum=\"" + std::to_string(f.minimum) + "\" maximum=\"" + std::to_string(f.maximum) + "\"";
    else
        xml += f.kind == WrittenField::Kind::Float32 ? " type=\"Float\" precision=\"single\"" : " type=\"Float\"";
    return xml + "/>";
}

std::string scanXml(const ScanPlan& plan, std::size_t index)
{
    std::ostringstream xml;
    const PointCloud& cloud = *plan.cloud;
    xml << "<vectorChild type=\"Structure\">\n";
    xml << "<guid type=\"String\">" << cdata(newGuid()) << "</guid>\n";
    xml << "<name type=\"String\">" << cdata(cloud.name.empty() ? "scan " + std::to_string(index) : cloud.name) << "</name>\n";
    if (plan.posed) {
        const Eigen::Quaterniond& q = plan.rotation;
        xml << "<pose type=\"Structure\"><rotation type=\"Structure\"><w type=\"Float\">" << number(q.w()) << "</w><x type=\"Float\">"
            << number(q.x()) << "</x><y type=\"Float\">" << number(q.y()) << "</y><z type=\"Float\">" << number(q.z())
            << "</z></rotation><translation type=\"Structure\"><x type=\"Float\">" << number(plan.translation.x())
            << "</x><y type=\"Float\">" << number(plan.translation.y()) << "</y><z type=\"Float\">" << number(plan.translation.z())
            << "</z></translation></pose>\n";
    }
    if (cloud.size() > 0) {
        const char* names[3] = {"x", "y", "z"};
        xml << "<cartesianBounds type=\"Structure\">";
        for (int k = 0; k < 3; ++k)
            xml << "<" << names[k] << "Minimum type=\"Float\">" << number(plan.boundsMin[k]) << "</" << names[k] << "Minimum><"
                << names[k] << "Maximum type=\"Float\">" << number(plan.boundsMax[k]) << "</" << names[k] << "Maximum>";
        xml << "</cartesianBounds>\n";
    }
    for (const auto& [element, body] : plan.limits)
        xml << "<" << element << " type=\"Structure\">" << body << "</" << element << ">\n";
    xml << "<points type=\"CompressedVector\" fileOffset=\"" << plan.sectionPhysical << "\" recordCount=\"" << cloud.size() << "\">\n";
    xml << "<prototype type=\"Structure\">\n";
    for (const WrittenField& f : plan.fields)
        xml << fieldXml(f) << "\n";
    xml << "</prototype>\n<codecs type=\"Vector\" allowHeterogeneousChildren=\"1\"></codecs>\n</points>\n</vectorChild>\n";
    return xml.str();
}

} // namespace

void writeE57(const std::vector<const PointCloud*>& clouds, const fs::path& path, const WriteOptions& options)
{
    for (const PointCloud* cloud : clouds)
        // A packet lists each field's stream length in its header (16 bits for its whole length).
        if (cloud->fields().size() > 10000)
            throw Error(ErrorCode::Unsupported, path.string() + ": E57 packets cannot hold the " + std::to_string(cloud->fields().size()) +
                                                    " fields of '" + cloud->name + "' (at most 10,000)");
    std::uint64_t total = 0;
    for (const PointCloud* cloud : clouds) {
        cloud->checkConsistency();
        total += cloud->size();
    }
    AtomicFile file(path);
    std::ofstream& out = file.stream();
    PagedWriter writer(out);
    const char placeholder[48] = {};
    writer.write(placeholder, 48);

    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), total);
    std::vector<ScanPlan> plans;
    for (const PointCloud* cloud : clouds) {
        plans.push_back(planScan(*cloud));
        writeScanSection(writer, plans.back(), ticker);
    }

    std::ostringstream xml;
    xml << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
        << "<e57Root type=\"Structure\" xmlns=\"" << kE57Namespace << "\" xmlns:" << kNormalsPrefix << "=\"" << kNormalsNamespace
        << "\" xmlns:" << kScalarFieldPrefix << "=\"" << kScalarFieldNamespace << "\">\n"
        << "<formatName type=\"String\">" << cdata("ASTM E57 3D Imaging Data File") << "</formatName>\n"
        << "<guid type=\"String\">" << cdata(newGuid()) << "</guid>\n"
        << "<versionMajor type=\"Integer\">1</versionMajor>\n<versionMinor type=\"Integer\">0</versionMinor>\n"
        << "<e57LibraryVersion type=\"String\">" << cdata("scandiff") << "</e57LibraryVersion>\n"
        << "<coordinateMetadata type=\"String\">" << cdata(clouds.empty() ? std::string() : clouds.front()->crsWkt())
        << "</coordinateMetadata>\n"
        << "<creationDateTime type=\"Structure\"><dateTimeValue type=\"Float\">"
        // GPS time: seconds since 1980-01-06, without leap seconds (18 since then).
        << number(static_cast<double>(std::chrono::duration_cast<std::chrono::seconds>(
                                          std::chrono::system_clock::now().time_since_epoch()).count()) - 315964800.0 + 18.0)
        << "</dateTimeValue><isAtomicClockReferenced type=\"Integer\">0</isAtomicClockReferenced></creationDateTime>\n"
        << "<data3D type=\"Vector\" allowHeterogeneousChildren=\"1\">\n";
    for (std::size_t i = 0; i < plans.size(); ++i)
        xml << scanXml(plans[i], i);
    xml << "</data3D>\n<images2D type=\"Vector\" allowHeterogeneousChildren=\"1\"></images2D>\n</e57Root>\n";
    const std::string text = xml.str();

    writer.padTo(4);
    const std::uint64_t xmlPhysical = writer.physicalPosition();
    writer.write(text.data(), text.size());
    const std::uint64_t length = writer.finish();

    char header[48] = {};
    std::memcpy(header, "ASTM-E57", 8);
    const std::uint32_t major = 1, minor = 0;
    const std::uint64_t xmlLength = text.size(), pageSize = kPageSize;
    std::memcpy(header + 8, &major, 4);
    std::memcpy(header + 12, &minor, 4);
    std::memcpy(header + 16, &length, 8);
    std::memcpy(header + 24, &xmlPhysical, 8);
    std::memcpy(header + 32, &xmlLength, 8);
    std::memcpy(header + 40, &pageSize, 8);
    writer.rewriteHeader(header);
    file.commit();
}

} // namespace scandiff::io
