// SPDX-License-Identifier: GPL-3.0-or-later
// E57 reading (ASTM E2807): the XML section says what each scan holds, the
// binary sections hold its records as compressed vectors: packets that each
// carry a piece of every field's bit-packed byte stream (§9).
#include <scandiff/io/E57.h>

#include "e57/E57Fields.h"
#include "e57/E57Pages.h"
#include "e57/E57Tree.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/Progress.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>

// E57's binary sections are little endian (ASTM E2807 §9): values are moved with
// memcpy, which is only right on a little-endian host.
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "E57Reader.cpp assumes a little-endian host"
#endif

namespace scandiff::io {

namespace fs = std::filesystem;
using namespace e57;

namespace {

//! How one field of a record is stored in its byte stream.
struct FieldCodec
{
    enum class Kind { Integer, ScaledInteger, Float32, Float64 };
    std::string name;  //!< qualified name, as in the file
    const Node* node = nullptr;
    Kind kind = Kind::Float64;
    int bits = 64;
    std::int64_t minimum = 0, maximum = 0;
    double scale = 1.0, offset = 0.0;

    // Decoding state: the stream's bytes not consumed yet (padded with 16
    // zero bytes so an unaligned 64-bit load never leaves the buffer), and
    // the values decoded but not yet assembled into records.
    std::vector<unsigned char> pending;
    std::size_t pendingBytes = 0;
    std::uint64_t bitPosition = 0;
    std::vector<double> decoded;
    std::size_t decodedFront = 0;
    std::uint64_t produced = 0;

    std::size_t available() const { return decoded.size() - decodedFront; }
};

FieldCodec makeCodec(const Node& node, const std::string& context)
{
    FieldCodec codec;
    codec.name = node.qualifiedName();
    codec.node = &node;
    if (node.type == "Float") {
        const std::string* precision = node.attribute("precision");
        const bool single = precision && *precision == "single";
        codec.kind = single ? FieldCodec::Kind::Float32 : FieldCodec::Kind::Float64;
        codec.bits = single ? 32 : 64;
        return codec;
    }
    if (node.type != "Integer" && node.type != "ScaledInteger")
        throw Error(ErrorCode::InvalidData, context + ": the record field '" + codec.name + "' has type '" + node.type +
                                                "'; scandiff reads Integer, ScaledInteger and Float fields");
    codec.kind = node.type == "Integer" ? FieldCodec::Kind::Integer : FieldCodec::Kind::ScaledInteger;
    codec.minimum = integerAttribute(node, "minimum", std::numeric_limits<std::int64_t>::min(), context);
    codec.maximum = integerAttribute(node, "maximum", std::numeric_limits<std::int64_t>::max(), context);
    if (codec.maximum < codec.minimum)
        throw Error(ErrorCode::InvalidData, context + ": the record field '" + codec.name + "' has a maximum below its minimum");
    // The stream holds value - minimum in just enough bits for the range (§9.5).
    const std::uint64_t range = static_cast<std::uint64_t>(codec.maximum) - static_cast<std::uint64_t>(codec.minimum);
    codec.bits = range == 0 ? 0 : 64 - __builtin_clzll(range);
    if (codec.kind == FieldCodec::Kind::ScaledInteger) {
        codec.scale = floatAttribute(node, "scale", 1.0, context);
        codec.offset = floatAttribute(node, "offset", 0.0, context);
    }
    return codec;
}

//! Decodes the whole values the field's pending bytes hold, up to `records` in all.
void decodePending(FieldCodec& f, std::uint64_t records)
{
    if (f.bits == 0)
        return;
    // Values already assembled leave the queue once they are half of it: a
    // field far ahead of another is not shifted at every packet.
    if (f.decodedFront > 0 && 2 * f.decodedFront >= f.decoded.size()) {
        f.decoded.erase(f.decoded.begin(), f.decoded.begin() + static_cast<std::ptrdiff_t>(f.decodedFront));
        f.decodedFront = 0;
    }
    const std::uint64_t totalBits = static_cast<std::uint64_t>(f.pendingBytes) * 8;
    const unsigned bits = static_cast<unsigned>(f.bits);
    const std::uint64_t mask = bits == 64 ? ~0ull : (1ull << bits) - 1;
    const unsigned char* data = f.pending.data();
    while (f.produced < records && totalBits - f.bitPosition >= bits) {
        const std::uint64_t byte = f.bitPosition >> 3;
        const unsigned shift = static_cast<unsigned>(f.bitPosition & 7);
        std::uint64_t low;
        std::memcpy(&low, data + byte, 8);
        std::uint64_t raw = low >> shift;
        if (shift + bits > 64)
            raw |= static_cast<std::uint64_t>(data[byte + 8]) << (64 - shift);
        raw &= mask;
        double value;
        switch (f.kind) {
        case FieldCodec::Kind::Float32: {
            const auto word = static_cast<std::uint32_t>(raw);
            float v;
            std::memcpy(&v, &word, 4);
            value = v;
            break;
        }
        case FieldCodec::Kind::Float64:
            std::memcpy(&value, &raw, 8);
            break;
        case FieldCodec::Kind::Integer:
            value = static_cast<double>(static_cast<std::int64_t>(raw + static_cast<std::uint64_t>(f.minimum)));
            break;
        case FieldCodec::Kind::ScaledInteger:
            value = static_cast<double>(static_cast<std::int64_t>(raw + static_cast<std::uint64_t>(f.minimum))) * f.scale + f.offset;
            break;
        }
        f.decoded.push_back(value);
        f.bitPosition += bits;
        ++f.produced;
    }
    // Whole bytes consumed leave the buffer; a value's first bits stay for the next packet.
    const std::size_t consumed = static_cast<std::size_t>(f.bitPosition >> 3);
    std::memmove(f.pending.data(), f.pending.data() + consumed, f.pendingBytes - consumed);
    f.pendingBytes -= consumed;
    std::fill(f.pending.begin() + static_cast<std::ptrdiff_t>(f.pendingBytes), f.pending.end(), 0);
    f.bitPosition &= 7;
}

void appendStream(FieldCodec& f, const char* bytes, std::size_t length)
{
    if (f.pending.size() < f.pendingBytes + length + 16)
        f.pending.resize(f.pendingBytes + length + 16, 0);
    std::memcpy(f.pending.data() + f.pendingBytes, bytes, length);
    f.pendingBytes += length;
}

template <typename T> T loadLittle(const char* p)
{
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

E57Pose poseOf(const Node& pose, const std::string& context)
{
    E57Pose out;
    if (const Node* r = pose.child("rotation")) {
        Eigen::Quaterniond q(numberOr(r, "w", 1.0, context), numberOr(r, "x", 0.0, context), numberOr(r, "y", 0.0, context),
                             numberOr(r, "z", 0.0, context));
        const double norm = q.norm();
        if (!(norm > 0.5 && norm < 2.0) || !std::isfinite(norm))
            throw Error(ErrorCode::InvalidData, context + ": a pose's rotation quaternion has norm " + std::to_string(norm) +
                                                    " (a rotation needs 1)");
        out.rotation = q.normalized();
    }
    if (const Node* t = pose.child("translation"))
        out.translation = Eigen::Vector3d(numberOr(t, "x", 0.0, context), numberOr(t, "y", 0.0, context), numberOr(t, "z", 0.0, context));
    if (!out.translation.allFinite())
        throw Error(ErrorCode::InvalidData, context + ": a pose's translation is not finite");
    return out;
}

//! The XML of a file, parsed, with the reader that gives its binary sections.
struct OpenFile
{
    PagedReader pages;
    Node root;
    std::string context;

    explicit OpenFile(const fs::path& path) : pages(path), context(path.string())
    {
        const std::vector<char> xml = pages.read(pages.header().xmlPhysicalOffset, pages.header().xmlLogicalLength);
        root = parseTree(xml, context);
    }

    std::vector<const Node*> vectorChildren(std::string_view name) const
    {
        std::vector<const Node*> out;
        if (const Node* v = root.child(name))
            for (const Node& c : v->children)
                if (c.type == "Structure")
                    out.push_back(&c);
        return out;
    }
};

const Node& pointsOf(const Node& scan, const std::string& context, std::size_t index)
{
    const Node* points = scan.child("points");
    if (!points || points->type != "CompressedVector")
        throw Error(ErrorCode::InvalidData, context + ": scan " + std::to_string(index) + " has no 'points' compressed vector");
    const Node* prototype = points->child("prototype");
    if (!prototype || prototype->type != "Structure")
        throw Error(ErrorCode::InvalidData, context + ": the points of scan " + std::to_string(index) + " have no record prototype");
    return *points;
}

std::uint64_t recordCountOf(const Node& points, const std::string& context)
{
    const std::int64_t count = integerAttribute(points, "recordCount", -1, context);
    if (count < 0)
        throw Error(ErrorCode::InvalidData, context + ": a compressed vector has no valid recordCount");
    return static_cast<std::uint64_t>(count);
}

E57ScanSummary summarise(const Node& scan, std::size_t index, const std::string& context)
{
    E57ScanSummary s;
    s.name = stringOr(&scan, "name");
    s.guid = stringOr(&scan, "guid");
    s.description = stringOr(&scan, "description");
    if (const Node* pose = scan.child("pose"))
        s.pose = poseOf(*pose, context);
    const Node& points = pointsOf(scan, context, index);
    s.recordCount = recordCountOf(points, context);
    for (const Node& field : points.child("prototype")->children)
        s.fields.push_back(field.qualifiedName());
    const auto has = [&](const char* n) { return points.child("prototype")->child(n) != nullptr; };
    s.spherical = !has("cartesianX") && has("sphericalRange");
    if (const Node* limits = scan.child("intensityLimits"))
        s.intensityLimits = std::make_pair(numberOr(limits, "intensityMinimum", 0.0, context),
                                           numberOr(limits, "intensityMaximum", 0.0, context));
    return s;
}

//! A box around the scan in file coordinates, for choosing the origin before any point is decoded.
BoundingBox scanBox(const Node& scan, const std::optional<E57Pose>& pose, const std::string& context)
{
    const E57Pose p = pose.value_or(E57Pose{});
    BoundingBox box;
    auto extend = [&](const Eigen::Vector3d& q) {
        const Eigen::Vector3d w = p.rotation * q + p.translation;
        if (!w.allFinite() || w.cwiseAbs().maxCoeff() > 1e12)
            return;
        box.min = box.empty ? w : box.min.cwiseMin(w);
        box.max = box.empty ? w : box.max.cwiseMax(w);
        box.empty = false;
    };
    const Node* bounds = scan.child("cartesianBounds");
    const double lo[3] = {numberOr(bounds, "xMinimum", NAN, context), numberOr(bounds, "yMinimum", NAN, context),
                          numberOr(bounds, "zMinimum", NAN, context)};
    const double hi[3] = {numberOr(bounds, "xMaximum", NAN, context), numberOr(bounds, "yMaximum", NAN, context),
                          numberOr(bounds, "zMaximum", NAN, context)};
    bool usable = bounds != nullptr;
    for (int k = 0; k < 3; ++k)
        usable = usable && std::isfinite(lo[k]) && std::isfinite(hi[k]) && lo[k] <= hi[k] && std::abs(lo[k]) < 1e12 && std::abs(hi[k]) < 1e12;
    if (usable) {
        for (int corner = 0; corner < 8; ++corner)
            extend(Eigen::Vector3d(corner & 1 ? hi[0] : lo[0], corner & 2 ? hi[1] : lo[1], corner & 4 ? hi[2] : lo[2]));
    } else {
        // The scanner's own position: points lie within its range of it.
        extend(Eigen::Vector3d::Zero());
    }
    return box;
}

SensorPose sensorOf(const Node& scan, const E57Pose& pose, const std::string& context)
{
    SensorPose sensor;
    sensor.position = pose.translation;
    sensor.orientation = pose.rotation;
    if (const Node* s = scan.child("sphericalBounds")) {
        sensor.maxRange = numberOr(s, "rangeMaximum", sensor.maxRange, context);
        sensor.pitchMin = numberOr(s, "elevationMinimum", sensor.pitchMin, context);
        sensor.pitchMax = numberOr(s, "elevationMaximum", sensor.pitchMax, context);
        sensor.yawMin = numberOr(s, "azimuthStart", sensor.yawMin, context);
        sensor.yawMax = numberOr(s, "azimuthEnd", sensor.yawMax, context);
        if (const Node* index = scan.child("indexBounds")) {
            const double rows = numberOr(index, "rowMaximum", 0, context) - numberOr(index, "rowMinimum", 0, context);
            const double columns = numberOr(index, "columnMaximum", 0, context) - numberOr(index, "columnMinimum", 0, context);
            if (rows > 0)
                sensor.pitchStep = (sensor.pitchMax - sensor.pitchMin) / rows;
            if (columns > 0)
                sensor.yawStep = (sensor.yawMax - sensor.yawMin) / columns;
        }
    }
    return sensor;
}

//! Where each decoded field goes in the cloud.
struct RecordLayout
{
    bool spherical = false;
    int coordinate[3] = {-1, -1, -1};  //!< x y z, or range azimuth elevation
    int invalidState = -1;              //!< cartesianInvalidState / sphericalInvalidState
    int colour[3] = {-1, -1, -1};
    int colourInvalid = -1;
    double colourMin[3] = {0, 0, 0}, colourMax[3] = {255, 255, 255};
    int normal[3] = {-1, -1, -1};
    //! Fields copied into scalar fields: codec index, field name, and the codec index of its invalid flag.
    struct Copied
    {
        int codec;
        std::string fieldName;
        int invalidFlag = -1;
        bool exact = false;  //!< the file stores more than a float holds
    };
    std::vector<Copied> copied;
};

RecordLayout layoutOf(const Node& scan, const std::vector<FieldCodec>& codecs, const std::string& context, std::size_t index)
{
    RecordLayout layout;
    auto find = [&](std::string_view name, std::string_view uri = kE57Namespace) {
        for (std::size_t i = 0; i < codecs.size(); ++i)
            if (codecs[i].node->localName == name && codecs[i].node->namespaceUri == uri)
                return static_cast<int>(i);
        return -1;
    };
    const int cx = find("cartesianX"), cy = find("cartesianY"), cz = find("cartesianZ");
    const int sr = find("sphericalRange"), sa = find("sphericalAzimuth"), se = find("sphericalElevation");
    if (cx >= 0 && cy >= 0 && cz >= 0) {
        layout.coordinate[0] = cx, layout.coordinate[1] = cy, layout.coordinate[2] = cz;
        layout.invalidState = find("cartesianInvalidState");
    } else if (sr >= 0 && sa >= 0 && se >= 0) {
        layout.spherical = true;
        layout.coordinate[0] = sr, layout.coordinate[1] = sa, layout.coordinate[2] = se;
        layout.invalidState = find("sphericalInvalidState");
    } else {
        throw Error(ErrorCode::InvalidData, context + ": scan " + std::to_string(index) +
                                                " has neither cartesian (cartesianX/Y/Z) nor spherical coordinates");
    }
    const char* colourNames[3] = {"colorRed", "colorGreen", "colorBlue"};
    const char* limitNames[3][2] = {{"colorRedMinimum", "colorRedMaximum"},
                                    {"colorGreenMinimum", "colorGreenMaximum"},
                                    {"colorBlueMinimum", "colorBlueMaximum"}};
    const Node* limits = scan.child("colorLimits");
    for (int k = 0; k < 3; ++k) {
        layout.colour[k] = find(colourNames[k]);
        if (layout.colour[k] < 0)
            continue;
        const FieldCodec& c = codecs[static_cast<std::size_t>(layout.colour[k])];
        const bool integer = c.kind == FieldCodec::Kind::Integer;
        layout.colourMin[k] = numberOr(limits, limitNames[k][0], integer ? static_cast<double>(c.minimum) : 0.0, context);
        layout.colourMax[k] = numberOr(limits, limitNames[k][1], integer ? static_cast<double>(c.maximum) : 1.0, context);
    }
    if (layout.colour[0] < 0 || layout.colour[1] < 0 || layout.colour[2] < 0)
        layout.colour[0] = layout.colour[1] = layout.colour[2] = -1;
    layout.colourInvalid = find("isColorInvalid");
    layout.normal[0] = find("normalX", kNormalsNamespace);
    layout.normal[1] = find("normalY", kNormalsNamespace);
    layout.normal[2] = find("normalZ", kNormalsNamespace);
    if (layout.normal[0] < 0 || layout.normal[1] < 0 || layout.normal[2] < 0)
        layout.normal[0] = layout.normal[1] = layout.normal[2] = -1;

    std::set<int> used(std::begin(layout.coordinate), std::end(layout.coordinate));
    for (int k = 0; k < 3; ++k)
        used.insert({layout.colour[k], layout.normal[k]});
    used.insert({layout.invalidState, layout.colourInvalid});
    // The other coordinate system, when both are stored, is not a field.
    for (const char* other : {"cartesianX", "cartesianY", "cartesianZ", "cartesianInvalidState", "sphericalRange",
                              "sphericalAzimuth", "sphericalElevation", "sphericalInvalidState"})
        used.insert(find(other));
    const int intensityInvalid = find("isIntensityInvalid"), timeInvalid = find("isTimeStampInvalid");
    used.insert({intensityInvalid, timeInvalid});
    for (std::size_t i = 0; i < codecs.size(); ++i) {
        if (used.count(static_cast<int>(i)))
            continue;
        const FieldCodec& c = codecs[i];
        RecordLayout::Copied copied{static_cast<int>(i), fieldNameFor(*c.node)};
        // Two record fields of one name (a repeated element, intensity beside sdf:intensity) stay two fields.
        for (int k = 2; std::any_of(layout.copied.begin(), layout.copied.end(),
                                    [&](const RecordLayout::Copied& other) { return other.fieldName == copied.fieldName; });
             ++k)
            copied.fieldName = fieldNameFor(*c.node) + "_" + std::to_string(k);
        if (c.node->localName == "intensity" && c.node->namespaceUri == kE57Namespace)
            copied.invalidFlag = intensityInvalid;
        if (c.node->localName == "timeStamp" && c.node->namespaceUri == kE57Namespace)
            copied.invalidFlag = timeInvalid;
        copied.exact = c.kind == FieldCodec::Kind::Float64 || c.kind == FieldCodec::Kind::ScaledInteger ||
                       (c.kind == FieldCodec::Kind::Integer && c.bits > 24);
        layout.copied.push_back(std::move(copied));
    }
    return layout;
}

//! Decodes one scan's records into `cloud` (whose origin is set).
class ScanDecoder
{
public:
    ScanDecoder(PagedReader& pages, const Node& scan, std::size_t index, const std::string& context, PointCloud& cloud,
                ProgressTicker& ticker)
        : pages_(pages), context_(context), index_(index), cloud_(cloud), ticker_(ticker)
    {
        const Node& points = pointsOf(scan, context, index);
        records_ = recordCountOf(points, context);
        for (const Node& field : points.child("prototype")->children)
            codecs_.push_back(makeCodec(field, context));
        // An empty codec list means bit-packing; a list may also name it explicitly.
        if (const Node* codecs = points.child("codecs"))
            for (const Node& codec : codecs->children)
                if (!codec.child("bitPackCodec"))
                    throw Error(ErrorCode::Unsupported, context + ": scan " + std::to_string(index) +
                                                            " names a codec other than the standard bit-pack codec");
        layout_ = layoutOf(scan, codecs_, context, index);
        if (const Node* pose = scan.child("pose"))
            pose_ = poseOf(*pose, context);
        sectionOffset_ = static_cast<std::uint64_t>(integerAttribute(points, "fileOffset", -1, context));
    }

    void run()
    {
        // The section is checked even for an empty scan: a broken header is a broken file.
        const SectionBounds section = readSectionHeader();
        if (records_ == 0)
            return;
        checkRecordCount(section);
        allocate();
        std::uint64_t position = section.dataLogical;
        std::vector<char> packet;
        while (assembled_ < records_) {
            if (position + 4 > section.endLogical)
                pages_.fail("the points of scan " + std::to_string(index_) + " end after " + std::to_string(assembled_) + " of " +
                            std::to_string(records_) + " records");
            char head[4];
            pages_.read(pages_.toPhysical(position), head, 4);
            const auto type = static_cast<unsigned char>(head[0]);
            const std::uint64_t length = std::uint64_t(loadLittle<std::uint16_t>(head + 2)) + 1;
            if (position + length > section.endLogical)
                pages_.fail("a packet of scan " + std::to_string(index_) + " runs past the end of its section");
            if (type == 1) {
                packet.resize(length);
                pages_.read(pages_.toPhysical(position), packet.data(), length);
                takeDataPacket(packet);
            } else if (type != 0 && type != 2) {
                pages_.fail("unknown packet type " + std::to_string(type) + " in the points of scan " + std::to_string(index_));
            }
            position += length;
        }
        finish();
    }

private:
    struct SectionBounds
    {
        std::uint64_t dataLogical = 0, endLogical = 0, length = 0;
    };

    SectionBounds readSectionHeader()
    {
        char header[32];
        pages_.read(sectionOffset_, header, 32);
        if (header[0] != 1)
            pages_.fail("the points of scan " + std::to_string(index_) + " point at a section of type " +
                        std::to_string(static_cast<unsigned char>(header[0])) + ", not a compressed vector (1)");
        SectionBounds s;
        s.length = loadLittle<std::uint64_t>(header + 8);
        const std::uint64_t dataPhysical = loadLittle<std::uint64_t>(header + 16);
        const std::uint64_t start = pages_.toLogical(sectionOffset_);
        if (s.length < 32 || s.length > pages_.logicalLength() - start)
            pages_.fail("the compressed vector of scan " + std::to_string(index_) + " claims " + std::to_string(s.length) +
                        " bytes, which the file does not hold");
        s.endLogical = start + s.length;
        if (dataPhysical >= pages_.header().physicalLength || dataPhysical % pages_.header().pageSize >= pages_.header().pageSize - 4)
            pages_.fail("the first packet of scan " + std::to_string(index_) + " is outside the file");
        s.dataLogical = pages_.toLogical(dataPhysical);
        if (s.dataLogical < start + 32 || s.dataLogical > s.endLogical || (s.dataLogical == s.endLogical && records_ > 0))
            pages_.fail("the first packet of scan " + std::to_string(index_) + " is outside its section");
        return s;
    }

    //! A record count the section cannot hold is refused before anything is allocated.
    void checkRecordCount(const SectionBounds& section) const
    {
        std::uint64_t bitsPerRecord = 0;
        // A field of one constant value takes no bit in the file but a value
        // per point in memory: counted as one bit, so the memory a file can
        // ask for stays proportional to its size.
        for (const FieldCodec& c : codecs_)
            bitsPerRecord += static_cast<std::uint64_t>(std::max(c.bits, 1));
        const long double capacity = static_cast<long double>(section.length) * 8.0L / static_cast<long double>(std::max<std::uint64_t>(bitsPerRecord, 1));
        if (static_cast<long double>(records_) > capacity)
            pages_.fail("scan " + std::to_string(index_) + " claims " + std::to_string(records_) + " records, but its section of " +
                        std::to_string(section.length) + " bytes holds at most " + std::to_string(static_cast<std::uint64_t>(capacity)));
    }

    void allocate()
    {
        const std::size_t n = static_cast<std::size_t>(records_);
        // The kernel zeroes a new array's pages as they are first touched, a
        // sixth of a read on one core: the arrays are made on both.
        std::vector<ScalarField> made(layout_.copied.size());
        try {
            tbb::parallel_invoke(
                [&] {
                    cloud_.resize(n);
                    if (layout_.colour[0] >= 0)
                        cloud_.enableColors();
                    if (layout_.normal[0] >= 0)
                        cloud_.enableNormals();
                },
                [&] {
                    tbb::parallel_for(std::size_t(0), made.size(), [&](std::size_t f) {
                        made[f] = ScalarField(layout_.copied[f].fieldName, n);
                        if (layout_.copied[f].exact)
                            made[f].keepDoubles();
                    });
                });
            for (ScalarField& field : made)
                cloud_.addField(std::move(field));
        } catch (const std::bad_alloc&) {
            throw Error(ErrorCode::Io, context_ + ": not enough memory to load " + std::to_string(records_) + " points");
        } catch (const std::length_error&) {
            throw Error(ErrorCode::Io, context_ + ": not enough memory to load " + std::to_string(records_) + " points");
        }
        for (const auto& copied : layout_.copied)
            fields_.push_back(cloud_.field(copied.fieldName));
        offsetSet_.assign(fields_.size(), false);
    }

    void takeDataPacket(const std::vector<char>& packet)
    {
        if (packet.size() < 6)
            pages_.fail("a data packet of scan " + std::to_string(index_) + " is shorter than its header");
        const std::size_t streams = loadLittle<std::uint16_t>(packet.data() + 4);
        if (streams != codecs_.size())
            pages_.fail("a data packet of scan " + std::to_string(index_) + " has " + std::to_string(streams) +
                        " byte streams for " + std::to_string(codecs_.size()) + " fields");
        std::size_t at = 6 + 2 * streams;
        if (at > packet.size())
            pages_.fail("a data packet of scan " + std::to_string(index_) + " is shorter than its stream table");
        for (std::size_t s = 0; s < streams; ++s) {
            const std::size_t length = loadLittle<std::uint16_t>(packet.data() + 6 + 2 * s);
            if (length > packet.size() - at)
                pages_.fail("a data packet of scan " + std::to_string(index_) + " has streams longer than the packet");
            appendStream(codecs_[s], packet.data() + at, length);
            at += length;
            decodePending(codecs_[s], records_);
        }
        assemble();
    }

    void assemble()
    {
        std::uint64_t ready = records_ - assembled_;
        for (const FieldCodec& c : codecs_)
            if (c.bits > 0)
                ready = std::min<std::uint64_t>(ready, c.available());
        const auto value = [&](int codec, std::size_t k) -> double {
            const FieldCodec& c = codecs_[static_cast<std::size_t>(codec)];
            return c.bits == 0 ? (c.kind == FieldCodec::Kind::ScaledInteger ? double(c.minimum) * c.scale + c.offset : double(c.minimum))
                               : c.decoded[c.decodedFront + k];
        };
        const Eigen::Vector3d origin = cloud_.origin();
        const E57Pose pose = pose_.value_or(E57Pose{});
        const Eigen::Matrix3d rotation = pose.rotation.toRotationMatrix();
        for (std::size_t k = 0; k < ready; ++k) {
            if (layout_.invalidState >= 0 && value(layout_.invalidState, k) != 0.0) {
                ++skipped_;
                continue;
            }
            Eigen::Vector3d p(value(layout_.coordinate[0], k), value(layout_.coordinate[1], k), value(layout_.coordinate[2], k));
            if (layout_.spherical) {
                const double range = p.x(), azimuth = p.y(), elevation = p.z();
                p = Eigen::Vector3d(range * std::cos(elevation) * std::cos(azimuth), range * std::cos(elevation) * std::sin(azimuth),
                                    range * std::sin(elevation));
            }
            if (pose_)
                p = rotation * p + pose.translation;
            const std::size_t w = written_++;
            cloud_.positions()[w] = (p - origin).cast<float>();
            if (layout_.colour[0] >= 0) {
                Rgb8& rgb = cloud_.enableColors()[w];
                if (layout_.colourInvalid >= 0 && value(layout_.colourInvalid, k) != 0.0) {
                    rgb = Rgb8{};
                    ++invalidColours_;
                } else {
                    std::uint8_t* channel[3] = {&rgb.r, &rgb.g, &rgb.b};
                    for (int c = 0; c < 3; ++c) {
                        const double span = layout_.colourMax[c] - layout_.colourMin[c];
                        const double scaled = span > 0 ? (value(layout_.colour[c], k) - layout_.colourMin[c]) * 255.0 / span : 0.0;
                        // Into [0, 255] (NaN: 0), then rounded half up: a
                        // call of llround per channel was a twentieth of a read.
                        const double clamped = std::isnan(scaled) ? 0.0 : std::clamp(scaled, 0.0, 255.0);
                        *channel[c] = static_cast<std::uint8_t>(clamped + 0.5);
                    }
                }
            }
            if (layout_.normal[0] >= 0) {
                Eigen::Vector3d n(value(layout_.normal[0], k), value(layout_.normal[1], k), value(layout_.normal[2], k));
                if (pose_)
                    n = rotation * n;
                cloud_.enableNormals()[w] = n.cast<float>();
            }
            for (std::size_t f = 0; f < fields_.size(); ++f) {
                const RecordLayout::Copied& copied = layout_.copied[f];
                if (copied.invalidFlag >= 0 && value(copied.invalidFlag, k) != 0.0)
                    continue; // stays NaN
                const double v = value(copied.codec, k);
                if (!offsetSet_[f] && std::isfinite(v)) {
                    // Large values (a time stamp of ~1e9 s) around their first one, so the float view keeps detail.
                    if (std::abs(v) > 1e5)
                        fields_[f]->setOffset(std::floor(v));
                    offsetSet_[f] = true;
                }
                fields_[f]->setValue(w, v);
            }
        }
        for (FieldCodec& c : codecs_)
            if (c.bits > 0)
                c.decodedFront += ready;
        assembled_ += ready;
        ticker_.step(ready);
    }

    void finish()
    {
        if (written_ < cloud_.size())
            cloud_.resize(written_);
        for (std::size_t f = 0; f < fields_.size(); ++f)
            if (layout_.copied[f].exact)
                fields_[f]->compact(codecs_[static_cast<std::size_t>(layout_.copied[f].codec)].kind == FieldCodec::Kind::Float64);
        if (skipped_ > 0)
            logWarning(context_ + ": scan " + std::to_string(index_) + ": " + std::to_string(skipped_) +
                       " points whose coordinates the file marks invalid were skipped");
        if (invalidColours_ > 0)
            logWarning(context_ + ": scan " + std::to_string(index_) + ": " + std::to_string(invalidColours_) +
                       " points whose colour the file marks invalid are black");
    }

    PagedReader& pages_;
    std::string context_;
    std::size_t index_;
    PointCloud& cloud_;
    ProgressTicker& ticker_;
    std::vector<FieldCodec> codecs_;
    RecordLayout layout_;
    std::optional<E57Pose> pose_;
    std::uint64_t sectionOffset_ = 0;
    std::uint64_t records_ = 0, assembled_ = 0;
    std::size_t written_ = 0, skipped_ = 0, invalidColours_ = 0;
    std::vector<ScalarField*> fields_;
    std::vector<bool> offsetSet_;
};

const char* kRepresentations[] = {"pinholeRepresentation", "sphericalRepresentation", "cylindricalRepresentation",
                                  "visualReferenceRepresentation"};

struct ImageBlob
{
    E57ImageSummary summary;
    const Node* blob = nullptr;
};

ImageBlob imageOf(const Node& image, const std::string& context)
{
    ImageBlob out;
    E57ImageSummary& s = out.summary;
    s.name = stringOr(&image, "name");
    s.guid = stringOr(&image, "guid");
    if (const Node* pose = image.child("pose"))
        s.pose = poseOf(*pose, context);
    for (const char* representation : kRepresentations) {
        const Node* r = image.child(representation);
        if (!r)
            continue;
        s.representation = std::string(representation).substr(0, std::strlen(representation) - std::strlen("Representation"));
        auto pixels = [&](const char* name) {
            const double v = numberOr(r, name, 0, context);
            return std::isfinite(v) && v >= 0 && v < 1e15 ? static_cast<std::int64_t>(v) : std::int64_t{-1};
        };
        s.width = pixels("imageWidth");
        s.height = pixels("imageHeight");
        if (const Node* jpeg = r->child("jpegImage"); jpeg && jpeg->type == "Blob") {
            s.format = "jpeg";
            out.blob = jpeg;
        } else if (const Node* png = r->child("pngImage"); png && png->type == "Blob") {
            s.format = "png";
            out.blob = png;
        }
        if (out.blob)
            s.byteLength = static_cast<std::uint64_t>(std::max<std::int64_t>(0, integerAttribute(*out.blob, "length", 0, context)));
        break;
    }
    return out;
}

std::vector<char> readBlob(PagedReader& pages, const Node& blob, const std::string& context)
{
    const std::int64_t offset = integerAttribute(blob, "fileOffset", -1, context);
    const std::int64_t length = integerAttribute(blob, "length", -1, context);
    if (offset < 0 || length < 0)
        pages.fail("a blob has no valid fileOffset and length");
    char header[16];
    pages.read(static_cast<std::uint64_t>(offset), header, 16);
    if (header[0] != 0)
        pages.fail("a blob points at a section of type " + std::to_string(static_cast<unsigned char>(header[0])) + ", not a blob (0)");
    const std::uint64_t sectionLength = loadLittle<std::uint64_t>(header + 8);
    if (sectionLength < 16 || static_cast<std::uint64_t>(length) > sectionLength - 16)
        pages.fail("a blob of " + std::to_string(length) + " bytes does not fit its section");
    return pages.read(pages.advance(static_cast<std::uint64_t>(offset), 16), static_cast<std::uint64_t>(length));
}

} // namespace

E57Summary inspectE57(const fs::path& path)
{
    OpenFile file(path);
    E57Summary summary;
    summary.guid = stringOr(&file.root, "guid");
    summary.libraryVersion = stringOr(&file.root, "e57LibraryVersion");
    summary.coordinateMetadata = stringOr(&file.root, "coordinateMetadata");
    const std::vector<const Node*> scans = file.vectorChildren("data3D");
    for (std::size_t i = 0; i < scans.size(); ++i)
        summary.scans.push_back(summarise(*scans[i], i, file.context));
    for (const Node* image : file.vectorChildren("images2D"))
        summary.images.push_back(imageOf(*image, file.context).summary);
    return summary;
}

std::vector<PointCloud> readE57Scans(const fs::path& path, const ReadOptions& options)
{
    OpenFile file(path);
    const std::vector<const Node*> scans = file.vectorChildren("data3D");
    std::vector<E57ScanSummary> summaries;
    std::uint64_t total = 0;
    BoundingBox all;
    for (std::size_t i = 0; i < scans.size(); ++i) {
        summaries.push_back(summarise(*scans[i], i, file.context));
        total += summaries.back().recordCount;
        const BoundingBox box = scanBox(*scans[i], summaries.back().pose, file.context);
        if (!box.empty) {
            all.min = all.empty ? box.min : all.min.cwiseMin(box.min);
            all.max = all.empty ? box.max : all.max.cwiseMax(box.max);
            all.empty = false;
        }
    }
    const Eigen::Vector3d origin = options.origin ? *options.origin : (all.empty ? Eigen::Vector3d::Zero() : suggestOrigin(all));
    const std::string crs = stringOr(&file.root, "coordinateMetadata");
    ProgressTicker ticker(options.progress, "Reading " + path.filename().string(), total);
    std::vector<PointCloud> clouds;
    // Two scans may not read one section: a file of many scans pointing at one
    // would otherwise ask for its points many times over.
    std::set<std::int64_t> sections;
    for (std::size_t i = 0; i < scans.size(); ++i)
        if (summaries[i].recordCount > 0 &&
            !sections.insert(integerAttribute(*scans[i]->child("points"), "fileOffset", -1, file.context)).second)
            file.pages.fail("scans " + std::to_string(i) + " and another read the same points section");
    for (std::size_t i = 0; i < scans.size(); ++i) {
        PointCloud cloud;
        cloud.setOrigin(origin);
        const E57ScanSummary& s = summaries[i];
        cloud.name = !s.name.empty() ? s.name : path.stem().string() + (scans.size() > 1 ? " scan " + std::to_string(i) : "");
        if (crs.rfind("PROJCS", 0) == 0 || crs.rfind("GEOGCS", 0) == 0 || crs.rfind("PROJCRS", 0) == 0 || crs.rfind("GEOGCRS", 0) == 0 ||
            crs.rfind("COMPD_CS", 0) == 0 || crs.rfind("COMPOUNDCRS", 0) == 0)
            cloud.setCrsWkt(crs);
        ScanDecoder(file.pages, *scans[i], i, file.context, cloud, ticker).run();
        if (s.pose || s.spherical)
            cloud.sensors().push_back(sensorOf(*scans[i], s.pose.value_or(E57Pose{}), file.context));
        if (const std::size_t dropped = cloud.removeNonFinitePoints())
            logWarning(file.context + ": scan " + std::to_string(i) + ": " + std::to_string(dropped) +
                       " points with NaN or infinite coordinates were dropped");
        clouds.push_back(std::move(cloud));
    }
    return clouds;
}

std::vector<fs::path> extractE57Images(const fs::path& path, const fs::path& folder)
{
    OpenFile file(path);
    std::vector<fs::path> written;
    std::set<std::string> names;
    std::size_t index = 0;
    for (const Node* image : file.vectorChildren("images2D")) {
        const ImageBlob found = imageOf(*image, file.context);
        ++index;
        if (!found.blob)
            continue;
        const std::vector<char> bytes = readBlob(file.pages, *found.blob, file.context);
        std::string stem = safeFileStem(found.summary.name.empty() ? "image" + std::to_string(index) : found.summary.name);
        std::string name = stem + (found.summary.format == "png" ? ".png" : ".jpg");
        for (int k = 2; names.count(name); ++k)
            name = stem + "-" + std::to_string(k) + (found.summary.format == "png" ? ".png" : ".jpg");
        names.insert(name);
        const fs::path target = folder / name;
        writeBytesAtomically(target, bytes);
        written.push_back(target);
    }
    return written;
}

} // namespace scandiff::io
