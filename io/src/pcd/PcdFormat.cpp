// SPDX-License-Identifier: GPL-3.0-or-later
//! PCD (Point Cloud Library) files: ascii, binary and binary_compressed (LZF,
//! through Debian's liblzf, the same algorithm PCL ships a copy of).
//!
//! Written here rather than through PCL's io for two reasons. PCL 1.13's
//! PCDReader is not safe on hostile input (fuzzing found crashes and a
//! use-after-free inside it, multi-gigabyte allocations from 150-byte files, a
//! quadratic header parse); and libpcl_io pulls VTK, OpenNI and Boost into
//! every process that links it (about 40 ms of start-up and 26 MB of resident
//! memory, measured on scandiff-cli). The whole header is validated against
//! the file's size before anything is allocated, and every loop is linear.
//!
//! Mapping: x y z -> positions (any numeric type), rgb/rgba (4 bytes, packed
//! 0x00RRGGBB / 0xAARRGGBB) -> colours, normal_x/y/z -> normals, "_" (padding)
//! skipped, every other field -> a scalar field (a field with COUNT c > 1
//! becomes name_0 .. name_{c-1}). The VIEWPOINT becomes a sensor pose when it
//! is not the default one or the cloud is organised (a depth-camera frame,
//! whose viewpoint is the camera). Points with a non-finite coordinate
//! (organised clouds' missing returns) are dropped, as by every reader.
//! Writing: x y z as float, or double when the cloud has a non-zero origin so
//! georeferenced coordinates keep their precision; a scalar field with an
//! offset as double; ascii numbers in their shortest exact form.

#include "internal/FieldOffset.h"
#include "internal/Formats.h"
#include "internal/MappedFile.h"
#include "internal/TextUtil.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/AtomicFile.h>

#include <lzf.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <unordered_map>
#include <unordered_set>

namespace scandiff::io::detail {
namespace {

namespace fs = std::filesystem;

//! Bounds that no real file reaches and that keep a hostile header cheap.
constexpr std::size_t kMaxHeaderLines = 256;
constexpr std::size_t kMaxFields = 4096;      //!< names on the FIELDS line
constexpr std::uint64_t kMaxCount = 1 << 16;  //!< COUNT of one field
//! Scalar fields a file may create: above PCL's largest descriptor (SHOT with
//! colour, 1344 numbers), far below what a hostile COUNT asks for.
constexpr std::size_t kMaxScalarFields = 2048;
//! LZF codes at most 264 bytes with a 3-byte back reference: no block
//! expands more than about 88 times, so a larger claim is a corrupt file.
constexpr std::uint64_t kMaxLzfRatio = 100;

enum class DataKind { Ascii, Binary, Compressed };

struct PcdField
{
    std::string name;
    char type = 'F';         //!< F, I or U
    unsigned size = 4;       //!< bytes of one value
    std::uint64_t count = 1; //!< values of this field per point
    std::uint64_t offset = 0; //!< in a binary record
};

struct PcdHeader
{
    std::vector<PcdField> fields;
    std::uint64_t width = 0, height = 1;
    std::uint64_t points = 0; //!< WIDTH x HEIGHT (POINTS, when given, must agree)
    double viewpoint[7] = {0, 0, 0, 1, 0, 0, 0}; //!< tx ty tz qw qx qy qz
    DataKind data = DataKind::Ascii;
    std::size_t dataStart = 0;   //!< first byte after the DATA line
    std::uint64_t pointStep = 0; //!< bytes of one binary record
    std::uint64_t values = 0;    //!< numbers of one ascii line
};

[[noreturn]] void fail(const fs::path& path, const std::string& why)
{
    throw Error(ErrorCode::InvalidData, path.string() + ": not a valid PCD file: " + why);
}

std::vector<std::string_view> words(std::string_view line)
{
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t'))
            ++i;
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t')
            ++i;
        if (i > start)
            out.push_back(line.substr(start, i - start));
    }
    return out;
}

template <typename T>
bool parseWhole(std::string_view word, T& value)
{
    const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), value);
    return ec == std::errc() && end == word.data() + word.size();
}

bool multiplyFits(std::uint64_t a, std::uint64_t b, std::uint64_t& product)
{
    if (a != 0 && b > std::numeric_limits<std::uint64_t>::max() / a)
        return false;
    product = a * b;
    return true;
}

//! Reads and checks the whole header, and the data's size against the file.
PcdHeader parseHeader(std::string_view file, const fs::path& path)
{
    if (file.empty())
        fail(path, "the file is empty");
    PcdHeader header;
    std::set<std::string, std::less<>> seen;
    std::vector<std::string_view> names, sizes, types, counts;
    bool haveWidth = false, havePoints = false, haveData = false;
    std::uint64_t pointsLine = 0;
    std::size_t at = 0, lineNumber = 0;
    while (!haveData) {
        if (at >= file.size())
            fail(path, "the header has no DATA line");
        if (++lineNumber > kMaxHeaderLines)
            fail(path, "no DATA line in the first " + std::to_string(kMaxHeaderLines) + " lines");
        const std::size_t newline = file.find('\n', at);
        std::string_view line = file.substr(at, newline == std::string_view::npos ? std::string_view::npos : newline - at);
        at = newline == std::string_view::npos ? file.size() : newline + 1;
        if (!line.empty() && line.back() == '\r')
            line.remove_suffix(1);
        const std::vector<std::string_view> w = words(line);
        if (w.empty() || w[0][0] == '#')
            continue;
        const std::string where = "line " + std::to_string(lineNumber) + ": ";
        const std::string_view key = w[0];
        const std::vector<std::string_view> rest(w.begin() + 1, w.end());
        if (!seen.insert(std::string(key)).second)
            fail(path, where + quoted(key) + " appears twice in the header");
        auto one = [&](std::uint64_t& into) {
            if (rest.size() != 1 || !parseWhole(rest[0], into))
                fail(path, where + std::string(key) + " needs one whole number");
        };
        if (key == "VERSION")
            continue;
        if (key == "FIELDS") {
            if (rest.size() > kMaxFields)
                fail(path, where + "more than " + std::to_string(kMaxFields) + " fields");
            names = rest;
        } else if (key == "SIZE")
            sizes = rest;
        else if (key == "TYPE")
            types = rest;
        else if (key == "COUNT")
            counts = rest;
        else if (key == "WIDTH") {
            one(header.width);
            haveWidth = true;
        } else if (key == "HEIGHT")
            one(header.height);
        else if (key == "POINTS") {
            one(pointsLine);
            havePoints = true;
        } else if (key == "VIEWPOINT") {
            if (rest.size() != 7)
                fail(path, where + "VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz)");
            for (int k = 0; k < 7; ++k)
                if (!parseWhole(rest[static_cast<std::size_t>(k)], header.viewpoint[k]) || !std::isfinite(header.viewpoint[k]))
                    fail(path, where + quoted(rest[static_cast<std::size_t>(k)]) + " is not a finite number");
        } else if (key == "DATA") {
            if (rest.size() != 1)
                fail(path, where + "DATA needs one word: ascii, binary or binary_compressed");
            if (rest[0] == "ascii")
                header.data = DataKind::Ascii;
            else if (rest[0] == "binary")
                header.data = DataKind::Binary;
            else if (rest[0] == "binary_compressed")
                header.data = DataKind::Compressed;
            else
                fail(path, where + "unknown DATA encoding " + quoted(rest[0]));
            haveData = true;
        } else
            fail(path, where + "unknown header keyword " + quoted(key));
    }
    header.dataStart = at;

    if (names.empty() || sizes.size() != names.size() || types.size() != names.size() ||
        (!counts.empty() && counts.size() != names.size()))
        fail(path, "FIELDS, SIZE, TYPE and COUNT do not describe the same fields");
    if (!haveWidth)
        fail(path, "the header has no WIDTH");
    if (!multiplyFits(header.width, header.height, header.points))
        fail(path, "WIDTH x HEIGHT is too large");
    if (havePoints && pointsLine != header.points)
        fail(path, "WIDTH x HEIGHT (" + std::to_string(header.points) + ") differs from POINTS (" + std::to_string(pointsLine) + ")");

    std::unordered_set<std::string_view> fieldNames;
    std::size_t scalarFields = 0;
    for (std::size_t f = 0; f < names.size(); ++f) {
        PcdField field;
        field.name = std::string(names[f]);
        if (field.name != "_" && !fieldNames.insert(names[f]).second)
            fail(path, "the field " + quoted(names[f]) + " appears twice");
        std::uint64_t size = 0;
        if (!parseWhole(sizes[f], size) || types[f].size() != 1)
            fail(path, "field " + quoted(names[f]) + ": SIZE " + quoted(sizes[f]) + ", TYPE " + quoted(types[f]));
        field.type = types[f][0];
        field.size = static_cast<unsigned>(size);
        const bool valid = (field.type == 'F' && (size == 4 || size == 8)) ||
                           ((field.type == 'I' || field.type == 'U') && (size == 1 || size == 2 || size == 4 || size == 8));
        if (!valid)
            fail(path, "field " + quoted(names[f]) + ": TYPE " + quoted(types[f]) + " of SIZE " + quoted(sizes[f]) +
                           " is not a PCD type (F 4/8, I or U 1/2/4/8)");
        if (!counts.empty() && (!parseWhole(counts[f], field.count) || field.count < 1 || field.count > kMaxCount))
            fail(path, "field " + quoted(names[f]) + ": COUNT " + quoted(counts[f]) + " is not a whole number from 1 to " +
                           std::to_string(kMaxCount));
        field.offset = header.pointStep;
        header.pointStep += field.size * field.count;
        header.values += field.count;
        const bool special = field.name == "_" || field.name == "x" || field.name == "y" || field.name == "z" ||
                             field.name == "normal_x" || field.name == "normal_y" || field.name == "normal_z" ||
                             field.name == "rgb" || field.name == "rgba";
        // x, y, z, normals and colour of COUNT 1 are no scalar fields; with a
        // larger COUNT each of their values is one (a z of COUNT 55,555 made
        // 55,555 fields and took 2.6 s to name them).
        const std::uint64_t asFields = field.name == "_" || (special && field.count == 1) ? 0 : field.count;
        if ((scalarFields += asFields) > kMaxScalarFields)
            fail(path, "more than " + std::to_string(kMaxScalarFields) + " scalar values per point");
        header.fields.push_back(std::move(field));
    }

    // Nothing is allocated that the file's length cannot justify.
    const std::uint64_t remaining = file.size() - header.dataStart;
    std::uint64_t bytes = 0;
    if (!multiplyFits(header.points, header.pointStep, bytes))
        fail(path, std::to_string(header.points) + " points of " + std::to_string(header.pointStep) + " bytes cannot fit in a file");
    if (header.data == DataKind::Binary && remaining < bytes)
        fail(path, "truncated: " + std::to_string(header.points) + " points need " + std::to_string(bytes) +
                       " bytes of data, the file has " + std::to_string(remaining));
    if (header.data == DataKind::Ascii) {
        // Each number takes at least one character and one separator.
        std::uint64_t least = 0;
        if (!multiplyFits(header.points, 2 * header.values, least) || remaining + 1 < least)
            fail(path, "truncated: " + std::to_string(header.points) + " points of " + std::to_string(header.values) +
                           " numbers cannot fit in the " + std::to_string(remaining) + " bytes of data");
    }
    if (header.data == DataKind::Compressed) {
        std::uint32_t blockSizes[2] = {0, 0};
        if (remaining < 8)
            fail(path, "truncated compressed data");
        std::memcpy(blockSizes, file.data() + header.dataStart, 8);
        if (blockSizes[0] > remaining - 8)
            fail(path, "truncated: the compressed block is " + std::to_string(blockSizes[0]) + " bytes, the file has " +
                           std::to_string(remaining - 8));
        if (blockSizes[1] != bytes)
            fail(path, "the uncompressed size (" + std::to_string(blockSizes[1]) + " bytes) disagrees with " +
                           std::to_string(header.points) + " points of " + std::to_string(header.pointStep) + " bytes");
        if (bytes > kMaxLzfRatio * blockSizes[0] + 1024)
            fail(path, "a compressed block of " + std::to_string(blockSizes[0]) + " bytes cannot hold " + std::to_string(bytes));
    }
    return header;
}

double decode(const unsigned char* p, char type, unsigned size)
{
    switch (type) {
    case 'F':
        if (size == 4) {
            float v;
            std::memcpy(&v, p, 4);
            return v;
        } else {
            double v;
            std::memcpy(&v, p, 8);
            return v;
        }
    case 'I':
        switch (size) {
        case 1: return static_cast<std::int8_t>(p[0]);
        case 2: { std::int16_t v; std::memcpy(&v, p, 2); return v; }
        case 4: { std::int32_t v; std::memcpy(&v, p, 4); return v; }
        default: { std::int64_t v; std::memcpy(&v, p, 8); return static_cast<double>(v); }
        }
    default:
        switch (size) {
        case 1: return p[0];
        case 2: { std::uint16_t v; std::memcpy(&v, p, 2); return v; }
        case 4: { std::uint32_t v; std::memcpy(&v, p, 4); return v; }
        default: { std::uint64_t v; std::memcpy(&v, p, 8); return static_cast<double>(v); }
        }
    }
}

//! Where each number of a point goes.
enum class Target { Skip, X, Y, Z, NormalX, NormalY, NormalZ, Colour, Field };

struct Slot
{
    Target target = Target::Skip;
    std::size_t field = 0; //!< index of the PCD field
    std::uint64_t component = 0;
    std::size_t scalar = 0; //!< Target::Field: index among the cloud's fields
    //! Target::Field: a double or a 32/64-bit integer, staged in double until
    //! the field's offset is chosen from its range (GPS times, ids).
    bool wide = false;
};

//! Gives each field a name no other has: `name`, or `name_2`... when one has it
//! (a field "a" of COUNT 2 gives a_0 and a_1, and the file may also hold an
//! a_0). In constant time per field: a set of the names taken and, per name,
//! the next suffix to try.
class UniqueFieldNames
{
public:
    UniqueFieldNames(PointCloud& cloud, const std::filesystem::path& path) : cloud_(cloud), path_(path) {}

    std::size_t add(const std::string& name)
    {
        if (cloud_.fields().size() >= kMaxScalarFields) // the header check counts them first
            fail(path_, "more than " + std::to_string(kMaxScalarFields) + " scalar fields per point");
        std::string candidate = name;
        int& next = nextSuffix_[name];
        next = std::max(next, 2);
        while (taken_.count(candidate) != 0)
            candidate = name + "_" + std::to_string(next++);
        taken_.insert(candidate);
        cloud_.addField(candidate);
        return cloud_.fields().size() - 1;
    }

private:
    PointCloud& cloud_;
    const std::filesystem::path& path_;
    std::unordered_set<std::string> taken_;
    std::unordered_map<std::string, int> nextSuffix_;
};

//! One slot per number of a point, in file order, and the cloud's fields made.
std::vector<Slot> makeSlots(const PcdHeader& header, PointCloud& cloud, bool& hasNormals, bool& hasColours, const fs::path& path)
{
    std::vector<Slot> slots;
    UniqueFieldNames names(cloud, path);
    int axes = 0, normalAxes = 0;
    for (std::size_t f = 0; f < header.fields.size(); ++f) {
        const PcdField& field = header.fields[f];
        for (std::uint64_t c = 0; c < field.count; ++c) {
            Slot slot;
            slot.field = f;
            slot.component = c;
            const std::string& n = field.name;
            if (c == 0 && field.count == 1) {
                if (n == "x" || n == "y" || n == "z") {
                    slot.target = n == "x" ? Target::X : n == "y" ? Target::Y : Target::Z;
                    ++axes;
                } else if (n == "normal_x" || n == "normal_y" || n == "normal_z") {
                    slot.target = n == "normal_x" ? Target::NormalX : n == "normal_y" ? Target::NormalY : Target::NormalZ;
                    ++normalAxes;
                } else if ((n == "rgb" || n == "rgba") && field.size == 4 && !hasColours) {
                    slot.target = Target::Colour;
                    hasColours = true;
                }
            }
            if (slot.target == Target::Skip && n != "_" && n != "x" && n != "y" && n != "z") {
                slot.target = Target::Field;
                slot.scalar = names.add(field.count == 1 ? n : n + "_" + std::to_string(c));
                slot.wide = field.size >= 4 && !(field.type == 'F' && field.size == 4);
            }
            slots.push_back(slot);
        }
    }
    if (axes != 3)
        fail(path, "no x, y and z fields (one value each)");
    hasNormals = normalAxes == 3;
    if (!hasNormals)
        for (Slot& slot : slots)
            if (slot.target == Target::NormalX || slot.target == Target::NormalY || slot.target == Target::NormalZ) {
                slot.target = Target::Field;
                slot.scalar = names.add(header.fields[slot.field].name);
                slot.wide = header.fields[slot.field].size == 8;
            }
    return slots;
}

//! Stores one number of point i. Positions go to `global` (double) first,
//! until the origin is known.
class PointSink
{
public:
    PointSink(PointCloud& cloud, std::vector<Eigen::Vector3d>& global, std::vector<std::vector<double>>& staged)
        : global_(global), staged_(staged)
    {
        if (cloud.hasNormals())
            normals_ = &cloud.enableNormals();
        if (cloud.hasColors())
            colours_ = &cloud.enableColors();
        for (const ScalarField& f : cloud.fields())
            scalars_.push_back(cloud.field(f.name()));
    }
    void store(const Slot& slot, std::size_t i, double value, std::uint32_t packedColour) const
    {
        switch (slot.target) {
        case Target::X: global_[i].x() = value; break;
        case Target::Y: global_[i].y() = value; break;
        case Target::Z: global_[i].z() = value; break;
        case Target::NormalX: (*normals_)[i].x() = static_cast<float>(value); break;
        case Target::NormalY: (*normals_)[i].y() = static_cast<float>(value); break;
        case Target::NormalZ: (*normals_)[i].z() = static_cast<float>(value); break;
        case Target::Colour:
            (*colours_)[i] = Rgb8{static_cast<std::uint8_t>(packedColour >> 16), static_cast<std::uint8_t>(packedColour >> 8),
                                  static_cast<std::uint8_t>(packedColour)};
            break;
        case Target::Field:
            if (slot.wide)
                staged_[slot.scalar][i] = value;
            else
                scalars_[slot.scalar]->setValue(i, value);
            break;
        case Target::Skip: break;
        }
    }

private:
    std::vector<Eigen::Vector3d>& global_;
    std::vector<std::vector<double>>& staged_;
    std::vector<Eigen::Vector3f>* normals_ = nullptr;
    std::vector<Rgb8>* colours_ = nullptr;
    std::vector<ScalarField*> scalars_;
};

//! Binary and compressed data: record-by-record or field-by-field bytes.
void decodeBinary(const PcdHeader& header, const unsigned char* data, bool fieldMajor, const std::vector<Slot>& slots,
                  const PointSink& sink, ProgressTicker& ticker)
{
    const std::size_t n = static_cast<std::size_t>(header.points);
    // Start and stride of every slot's numbers.
    std::vector<const unsigned char*> start(slots.size());
    std::vector<std::size_t> stride(slots.size());
    for (std::size_t s = 0; s < slots.size(); ++s) {
        const PcdField& field = header.fields[slots[s].field];
        const std::size_t fieldBytes = field.size * field.count;
        start[s] = fieldMajor ? data + field.offset * n + slots[s].component * field.size
                              : data + field.offset + slots[s].component * field.size;
        stride[s] = fieldMajor ? fieldBytes : header.pointStep;
    }
    for (std::size_t s = 0; s < slots.size(); ++s) {
        if (slots[s].target == Target::Skip)
            continue;
        const PcdField& field = header.fields[slots[s].field];
        for (std::size_t i = 0; i < n; ++i) {
            const unsigned char* p = start[s] + i * stride[s];
            std::uint32_t packed = 0;
            if (slots[s].target == Target::Colour)
                std::memcpy(&packed, p, 4);
            sink.store(slots[s], i, slots[s].target == Target::Colour ? 0.0 : decode(p, field.type, field.size), packed);
        }
        ticker.checkCancel();
    }
}

void decodeAscii(const PcdHeader& header, std::string_view text, const std::vector<Slot>& slots, const PointSink& sink,
                 const fs::path& path, ProgressTicker& ticker)
{
    const std::size_t n = static_cast<std::size_t>(header.points);
    std::size_t at = 0, line = 0;
    for (std::size_t i = 0; i < n; ++i) {
        // The next non-empty line.
        std::string_view row;
        while (row.empty()) {
            if (at >= text.size())
                fail(path, "the data ends after " + std::to_string(i) + " of " + std::to_string(n) + " points");
            const std::size_t newline = text.find('\n', at);
            row = text.substr(at, newline == std::string_view::npos ? std::string_view::npos : newline - at);
            at = newline == std::string_view::npos ? text.size() : newline + 1;
            ++line;
            while (!row.empty() && (row.back() == '\r' || row.back() == ' ' || row.back() == '\t'))
                row.remove_suffix(1);
        }
        std::size_t pos = 0;
        for (std::size_t s = 0; s < slots.size(); ++s) {
            while (pos < row.size() && (row[pos] == ' ' || row[pos] == '\t'))
                ++pos;
            const std::size_t begin = pos;
            while (pos < row.size() && row[pos] != ' ' && row[pos] != '\t')
                ++pos;
            const std::string_view word = row.substr(begin, pos - begin);
            auto bad = [&](const std::string& why) {
                fail(path, "data line " + std::to_string(line) + ", number " + std::to_string(s + 1) + " (" +
                               quoted(word) + "): " + why);
            };
            if (word.empty())
                bad("missing: the header announces " + std::to_string(slots.size()) + " numbers a point");
            const Slot& slot = slots[s];
            if (slot.target == Target::Skip)
                continue;
            const PcdField& field = header.fields[slot.field];
            if (slot.target == Target::Colour) {
                // PCL writes a packed colour of TYPE F as the float of the same bits.
                std::uint32_t packed = 0;
                if (field.type == 'F') {
                    float asFloat = 0;
                    if (!parseWhole(word, asFloat))
                        bad("not a number");
                    std::memcpy(&packed, &asFloat, 4);
                } else if (!parseWhole(word, packed)) {
                    bad("not a packed colour");
                }
                sink.store(slot, i, 0.0, packed);
                continue;
            }
            double value = 0;
            const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), value);
            if (end != word.data() + word.size() || (ec != std::errc() && ec != std::errc::result_out_of_range))
                bad("not a number");
            sink.store(slot, i, value, 0);
        }
        while (pos < row.size() && (row[pos] == ' ' || row[pos] == '\t'))
            ++pos;
        if (pos < row.size())
            fail(path, "data line " + std::to_string(line) + " has more than the " + std::to_string(slots.size()) +
                           " numbers the header announces");
        if ((i & 0xffff) == 0)
            ticker.checkCancel();
    }
}

Entity readPcd(const fs::path& path, const ReadOptions& options)
{
    const MappedFile file(path);
    const PcdHeader header = parseHeader(file.view(), path);
    ProgressTicker ticker(options.progress, "Reading " + path.filename().string(), 3);
    const std::size_t n = static_cast<std::size_t>(header.points);

    PointCloud cloud;
    cloud.resize(n);
    bool hasNormals = false, hasColours = false;
    const std::vector<Slot> slots = makeSlots(header, cloud, hasNormals, hasColours, path);
    if (hasNormals)
        cloud.enableNormals();
    if (hasColours)
        cloud.enableColors();
    std::vector<Eigen::Vector3d> global(n, Eigen::Vector3d::Zero());
    std::vector<std::vector<double>> staged(cloud.fields().size());
    std::vector<bool> stagedFromDouble(cloud.fields().size(), false);
    for (const Slot& slot : slots)
        if (slot.target == Target::Field && slot.wide) {
            staged[slot.scalar].assign(n, std::numeric_limits<double>::quiet_NaN());
            const PcdField& source = header.fields[slot.field];
            stagedFromDouble[slot.scalar] = source.type == 'F' && source.size == 8;
        }
    const PointSink sink(cloud, global, staged);
    const auto* bytes = reinterpret_cast<const unsigned char*>(file.data()) + header.dataStart;
    if (header.data == DataKind::Ascii) {
        decodeAscii(header, file.view().substr(header.dataStart), slots, sink, path, ticker);
    } else if (header.data == DataKind::Binary) {
        decodeBinary(header, bytes, false, slots, sink, ticker);
    } else {
        std::uint32_t blockSizes[2];
        std::memcpy(blockSizes, bytes, 8);
        std::vector<unsigned char> unpacked(blockSizes[1]);
        if (blockSizes[1] > 0 &&
            lzf_decompress(bytes + 8, blockSizes[0], unpacked.data(), blockSizes[1]) != blockSizes[1])
            fail(path, "the compressed data is corrupt");
        decodeBinary(header, unpacked.data(), true, slots, sink, ticker);
    }
    for (std::size_t f = 0; f < staged.size(); ++f) {
        if (staged[f].empty())
            continue;
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (double v : staged[f])
            if (std::isfinite(v)) {
                lo = std::min(lo, v);
                hi = std::max(hi, v);
            }
        ScalarField& field = *cloud.field(cloud.fields()[f].name());
        field.setOffset(chooseFieldOffset(lo, hi));
        // A double stays a double to the bit; a 32/64-bit integer keeps an
        // exact form only where the float around the offset cannot hold it.
        field.keepDoubles();
        for (std::size_t i = 0; i < n; ++i)
            field.setValue(i, staged[f][i]);
        field.compact(stagedFromDouble[f]);
        staged[f] = {};
    }
    ticker.step();

    BoundingBox box;
    for (const Eigen::Vector3d& p : global)
        if (p.allFinite()) {
            box.min = box.empty ? p : box.min.cwiseMin(p);
            box.max = box.empty ? p : box.max.cwiseMax(p);
            box.empty = false;
        }
    const Eigen::Vector3d origin = options.origin ? *options.origin : suggestOrigin(box);
    cloud.setOrigin(origin);
    for (std::size_t i = 0; i < n; ++i)
        cloud.positions()[i] = (global[i] - origin).cast<float>();
    global = {};
    ticker.step();

    const bool defaultViewpoint = header.viewpoint[0] == 0 && header.viewpoint[1] == 0 && header.viewpoint[2] == 0 &&
                                  header.viewpoint[3] == 1 && header.viewpoint[4] == 0 && header.viewpoint[5] == 0 &&
                                  header.viewpoint[6] == 0;
    if (!defaultViewpoint || header.height > 1) {
        SensorPose pose;
        pose.position = {header.viewpoint[0], header.viewpoint[1], header.viewpoint[2]};
        Eigen::Quaterniond q(header.viewpoint[3], header.viewpoint[4], header.viewpoint[5], header.viewpoint[6]);
        pose.orientation = q.norm() > 0 ? q.normalized() : Eigen::Quaterniond::Identity();
        cloud.sensors().push_back(pose);
    }
    const std::size_t dropped = cloud.removeNonFinitePoints();
    if (dropped > 0)
        logWarning(path.string() + ": " + std::to_string(dropped) + " points with non-finite coordinates were skipped");
    ticker.step();
    return cloud;
}

// ---------------------------------------------------------------- writing

struct OutField
{
    std::string name;
    char type;
    unsigned size;
};

//! PCD names are words: blanks become '_', and a name already taken gets a suffix.
std::string uniqueName(std::string name, std::set<std::string>& taken)
{
    for (char& c : name)
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r')
            c = '_';
    if (name.empty())
        name = "field";
    std::string candidate = name;
    for (int k = 2; !taken.insert(candidate).second; ++k)
        candidate = name + "_" + std::to_string(k);
    return candidate;
}

void appendNumber(std::string& out, double value, bool single)
{
    char buffer[64];
    const auto result = single ? std::to_chars(buffer, buffer + sizeof buffer, static_cast<float>(value))
                               : std::to_chars(buffer, buffer + sizeof buffer, value);
    out.append(buffer, result.ptr);
}

//! The fields a cloud is written with, in order: x y z (doubles when the
//! cloud has a global shift, so coordinates keep their millimetres), normals,
//! the packed colour, then one per scalar field (double when it has an offset
//! or is kept in double), under names unique in the file.
std::vector<OutField> pcdFields(const PointCloud& cloud)
{
    std::vector<OutField> fields;
    std::set<std::string> taken{"x", "y", "z", "normal_x", "normal_y", "normal_z", "rgb", "rgba", "_"};
    const unsigned coordinateSize = cloud.origin().isZero() ? 4 : 8;
    fields.push_back({"x", 'F', coordinateSize});
    fields.push_back({"y", 'F', coordinateSize});
    fields.push_back({"z", 'F', coordinateSize});
    if (cloud.hasNormals())
        for (const char* name : {"normal_x", "normal_y", "normal_z"})
            fields.push_back({name, 'F', 4});
    if (cloud.hasColors())
        fields.push_back({"rgb", 'F', 4}); // PCL's convention: the packed bytes declared as a float
    for (const ScalarField& f : cloud.fields())
        fields.push_back({uniqueName(f.name(), taken), 'F', f.offset() != 0.0 || f.isDouble() ? 8u : 4u});
    return fields;
}

//! The numbers of one point, in field order, as they are written; the colour
//! as its packed bytes beside them (its place in `values` holds 0).
class PcdPointValues
{
public:
    explicit PcdPointValues(const PointCloud& cloud) : cloud_(cloud), doubles_(!cloud.origin().isZero()) {}
    //! Where the packed colour goes among the fields (past the end without colours).
    std::size_t colourIndex(std::size_t fieldCount) const
    {
        return cloud_.hasColors() ? (cloud_.hasNormals() ? 6 : 3) : fieldCount;
    }
    void of(std::size_t i)
    {
        values.clear();
        const Eigen::Vector3d p = cloud_.globalPosition(i);
        for (int a = 0; a < 3; ++a)
            values.push_back(doubles_ ? p[a] : static_cast<double>(cloud_.positions()[i][a]));
        if (cloud_.hasNormals())
            for (int a = 0; a < 3; ++a)
                values.push_back(cloud_.normals()[i][a]);
        if (cloud_.hasColors()) {
            const Rgb8 c = cloud_.colors()[i];
            packed = (std::uint32_t(c.r) << 16) | (std::uint32_t(c.g) << 8) | c.b;
            values.push_back(0);
        }
        for (const ScalarField& f : cloud_.fields())
            values.push_back(f.offset() != 0.0 || f.isDouble() ? f.value(i) : static_cast<double>(f.values()[i]));
    }
    std::vector<double> values;
    std::uint32_t packed = 0;

private:
    const PointCloud& cloud_;
    bool doubles_;
};

std::string pcdHeader(const PointCloud& cloud, const std::vector<OutField>& fields, Encoding encoding)
{
    std::string header = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS";
    for (const OutField& f : fields)
        header += " " + f.name;
    header += "\nSIZE";
    for (const OutField& f : fields)
        header += " " + std::to_string(f.size);
    header += "\nTYPE";
    for (const OutField& f : fields)
        header += std::string(" ") + f.type;
    header += "\nCOUNT";
    for (std::size_t k = 0; k < fields.size(); ++k)
        header += " 1";
    header += "\nWIDTH " + std::to_string(cloud.size()) + "\nHEIGHT 1\nVIEWPOINT";
    double viewpoint[7] = {0, 0, 0, 1, 0, 0, 0};
    if (!cloud.sensors().empty()) {
        const SensorPose& pose = cloud.sensors().front();
        viewpoint[0] = pose.position.x();
        viewpoint[1] = pose.position.y();
        viewpoint[2] = pose.position.z();
        viewpoint[3] = pose.orientation.w();
        viewpoint[4] = pose.orientation.x();
        viewpoint[5] = pose.orientation.y();
        viewpoint[6] = pose.orientation.z();
    }
    for (double v : viewpoint) {
        header += ' ';
        appendNumber(header, v, false);
    }
    header += "\nPOINTS " + std::to_string(cloud.size()) + "\nDATA " +
              std::string(encoding == Encoding::Ascii ? "ascii" : encoding == Encoding::BinaryCompressed ? "binary_compressed" : "binary") + "\n";
    return header;
}

//! DATA ascii: one line per point, floats with the digits that give them back.
void writePcdAscii(std::ofstream& out, const PointCloud& cloud, const std::vector<OutField>& fields, ProgressTicker& ticker)
{
    PcdPointValues point(cloud);
    const std::size_t colourIndex = point.colourIndex(fields.size());
    std::string line;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        point.of(i);
        line.clear();
        for (std::size_t k = 0; k < point.values.size(); ++k) {
            if (k > 0)
                line += ' ';
            if (k == colourIndex) {
                float asFloat;
                std::memcpy(&asFloat, &point.packed, 4);
                appendNumber(line, asFloat, true);
            } else {
                appendNumber(line, point.values[k], fields[k].size == 4);
            }
        }
        line += '\n';
        out.write(line.data(), static_cast<std::streamsize>(line.size()));
        if ((i & 0xffff) == 0)
            ticker.checkCancel();
    }
}

//! DATA binary (point after point, written by blocks of 65,536) or
//! binary_compressed (field after field, the whole LZF-compressed).
void writePcdBinary(std::ofstream& out, const PointCloud& cloud, const std::vector<OutField>& fields, bool compressed,
                    const fs::path& path, ProgressTicker& ticker)
{
    const std::size_t n = cloud.size();
    std::size_t pointStep = 0;
    for (const OutField& f : fields)
        pointStep += f.size;
    PcdPointValues point(cloud);
    const std::size_t colourIndex = point.colourIndex(fields.size());
    const auto putValue = [](unsigned char* at, double value, unsigned size) {
        if (size == 8) {
            std::memcpy(at, &value, 8);
        } else {
            const float v = static_cast<float>(value);
            std::memcpy(at, &v, 4);
        }
    };
    std::vector<unsigned char> records(compressed ? n * pointStep : pointStep * std::min<std::size_t>(n, 65536));
    std::vector<std::size_t> fieldOffset(fields.size());
    for (std::size_t k = 1; k < fields.size(); ++k)
        fieldOffset[k] = fieldOffset[k - 1] + fields[k - 1].size;
    for (std::size_t i = 0; i < n; ++i) {
        point.of(i);
        const std::size_t slot = compressed ? i : i % 65536;
        for (std::size_t k = 0; k < fields.size(); ++k) {
            unsigned char* at = compressed ? records.data() + fieldOffset[k] * n + slot * fields[k].size
                                           : records.data() + slot * pointStep + fieldOffset[k];
            if (k == colourIndex)
                std::memcpy(at, &point.packed, 4);
            else
                putValue(at, point.values[k], fields[k].size);
        }
        if (!compressed && (slot == 65535 || i + 1 == n)) {
            out.write(reinterpret_cast<const char*>(records.data()), static_cast<std::streamsize>((slot + 1) * pointStep));
            ticker.checkCancel();
        }
    }
    if (!compressed)
        return;
    if (records.size() > std::numeric_limits<std::uint32_t>::max() / 2)
        throw Error(ErrorCode::Unsupported, path.string() + ": binary_compressed PCD holds at most 2 GB of data; use binary");
    // Room for incompressible data: LZF adds at most one byte per 32.
    std::vector<unsigned char> packedData(records.size() + records.size() / 16 + 64);
    const unsigned length = records.empty() ? 0
                                            : lzf_compress(records.data(), static_cast<unsigned>(records.size()), packedData.data(),
                                                           static_cast<unsigned>(packedData.size()));
    if (!records.empty() && length == 0)
        throw Error(ErrorCode::Io, path.string() + ": LZF compression failed");
    const std::uint32_t blockSizes[2] = {length, static_cast<std::uint32_t>(records.size())};
    out.write(reinterpret_cast<const char*>(blockSizes), 8);
    out.write(reinterpret_cast<const char*>(packedData.data()), length);
}

void writePcd(const PointCloud& cloud, const fs::path& path, const WriteOptions& options)
{
    if (options.encoding == Encoding::BinaryBigEndian)
        throw Error(ErrorCode::Unsupported, path.string() + ": PCD has no big-endian encoding");
    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), 2);
    const std::vector<OutField> fields = pcdFields(cloud);
    AtomicFile file(path);
    std::ofstream out(file.tempPath(), std::ios::binary);
    if (!out)
        throw Error(ErrorCode::Io, path.string() + ": cannot write");
    out << pcdHeader(cloud, fields, options.encoding);
    if (options.encoding == Encoding::Ascii)
        writePcdAscii(out, cloud, fields, ticker);
    else
        writePcdBinary(out, cloud, fields, options.encoding == Encoding::BinaryCompressed, path, ticker);
    ticker.step();
    out.close();
    if (!out)
        throw Error(ErrorCode::Io, path.string() + ": write failed (disk full?)");
    file.commit();
    ticker.step();
}

} // namespace

FormatHandler pcdFormat()
{
    FormatHandler handler;
    handler.name = "PCD";
    handler.extensions = {"pcd"};
    handler.read = readPcd;
    handler.writeCloud = writePcd;
    return handler;
}

} // namespace scandiff::io::detail

