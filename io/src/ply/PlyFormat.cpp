// SPDX-License-Identifier: GPL-3.0-or-later
//! PLY (Stanford polygon format): ascii, binary_little_endian and binary_big_endian.
//!
//! Reading maps the vertex element's properties to the cloud: x y z (any numeric
//! type), red green blue (or diffuse_*; integers 0-255, 16-bit integers scaled,
//! floats 0-1 scaled), nx ny nz (or normal_*), alpha ignored, list properties
//! skipped, and every other scalar property becomes a scalar field (a leading
//! "scalar_", as CloudCompare writes it, is removed). A "face" element with a
//! vertex_indices (or vertex_index) list gives triangles, polygons being fan
//! triangulated; the file is then a Mesh. Every other element is skipped.
//!
//! Writing (PlyWriter.cpp) uses float x y z when the origin is zero and double global
//! coordinates otherwise, uchar colours, float normals, and one float property
//! per scalar field (double when the field has an offset, so GPS times survive).

#include "internal/Formats.h"
#include "ply/PlyCommon.h"
#include "ply/PlyWriter.h"
#include "internal/FieldOffset.h"
#include "internal/MappedFile.h"
#include "internal/TextUtil.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/AtomicFile.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <memory>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace scandiff::io::detail {

namespace {

using namespace ply;

namespace fs = std::filesystem;

// The types, encodings and byte order both sides share: ply/PlyCommon.h.

struct PlyProperty
{
    std::string name;
    PlyType type = PlyType::Float32; //!< the item type for a list
    bool isList = false;
    PlyType countType = PlyType::UInt8;
};

struct PlyElement
{
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;

    bool fixedSize() const
    {
        return std::none_of(properties.begin(), properties.end(), [](const PlyProperty& p) { return p.isList; });
    }
    //! Exact size of a fixed-size record; the smallest possible one otherwise (empty lists).
    std::size_t minRecordSize() const
    {
        std::size_t size = 0;
        for (const auto& p : properties)
            size += typeSize(p.isList ? p.countType : p.type);
        return size;
    }
};

struct PlyHeader
{
    PlyEncoding encoding = PlyEncoding::Ascii;
    std::vector<PlyElement> elements;
    std::size_t dataOffset = 0; //!< first byte after end_header's line
    std::size_t lineCount = 0;  //!< lines in the header, for ASCII line numbers
    std::string crsWkt;         //!< from a "comment crs_wkt WKT" line (scandiff's own)
};

// PLY has no place for a coordinate reference system: scandiff writes it as a
// comment line of its own, "comment crs_wkt " + the WKT on one line.


bool isBlank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

//! Splits off the next whitespace-separated token of `rest`; false at the end.
bool nextToken(std::string_view& rest, std::string_view& token)
{
    std::size_t i = 0;
    while (i < rest.size() && isBlank(rest[i]))
        ++i;
    if (i == rest.size()) {
        rest = {};
        return false;
    }
    std::size_t j = i;
    while (j < rest.size() && !isBlank(rest[j]))
        ++j;
    token = rest.substr(i, j - i);
    rest.remove_prefix(j);
    return true;
}

std::vector<std::string_view> tokenize(std::string_view line)
{
    std::vector<std::string_view> tokens;
    std::string_view token;
    while (nextToken(line, token))
        tokens.push_back(token);
    return tokens;
}

bool parseDouble(std::string_view token, double& value)
{
    const char* first = token.data();
    const char* last = first + token.size();
    // from_chars rejects the '+' sign that some writers emit.
    if (first != last && *first == '+')
        ++first;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    return ec == std::errc() && ptr == last && first != last;
}

bool parseInteger(std::string_view token, std::int64_t& value)
{
    const char* first = token.data();
    const char* last = first + token.size();
    if (first != last && *first == '+')
        ++first;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    return ec == std::errc() && ptr == last && first != last;
}

class Context
{
public:
    explicit Context(const fs::path& path) : fileName_(path.string()) {}
    const std::string& fileName() const { return fileName_; }

    [[noreturn]] void fail(const std::string& message) const
    {
        throw Error(ErrorCode::InvalidData, fileName_ + ": " + message);
    }
    [[noreturn]] void failAtLine(std::size_t line, const std::string& message) const
    {
        throw Error(ErrorCode::InvalidData, fileName_ + ":" + std::to_string(line) + ": " + message);
    }
    [[noreturn]] void truncated(const PlyElement& e, std::uint64_t index) const
    {
        fail("truncated: " + e.name + " " + std::to_string(index + 1) + " of " + std::to_string(e.count) +
             " ends beyond the end of the file");
    }

private:
    std::string fileName_;
};

PlyHeader parseHeader(const MappedFile& file, const Context& ctx)
{
    const char* data = file.data();
    const std::size_t size = file.size();
    if (size == 0)
        ctx.fail("empty file");

    PlyHeader header;
    std::size_t pos = 0;
    std::size_t lineNo = 0;
    auto nextLine = [&](std::string_view& line) {
        if (pos >= size)
            return false;
        const void* nl = std::memchr(data + pos, '\n', size - pos);
        const std::size_t stop = nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - data) : size;
        line = std::string_view(data + pos, stop - pos);
        if (!line.empty() && line.back() == '\r')
            line.remove_suffix(1);
        pos = nl ? stop + 1 : size;
        ++lineNo;
        return true;
    };

    std::string_view line;
    nextLine(line);
    if (line != "ply" && tokenize(line) != std::vector<std::string_view>{"ply"})
        ctx.fail("not a PLY file (the first line is not 'ply')");

    bool sawFormat = false;
    while (true) {
        if (!nextLine(line))
            ctx.fail("missing end_header: the header ends with the file");
        const auto tokens = tokenize(line);
        if (tokens.empty())
            continue;
        const std::string_view keyword = tokens[0];
        if (keyword == "end_header") {
            break;
        } else if (keyword == "comment" || keyword == "obj_info") {
            if (line.substr(0, kCrsComment.size()) == kCrsComment)
                header.crsWkt = std::string(line.substr(kCrsComment.size()));
            continue;
        } else if (keyword == "format") {
            if (tokens.size() != 3)
                ctx.failAtLine(lineNo, "malformed format line (expected 'format <encoding> 1.0')");
            if (tokens[1] == "ascii")
                header.encoding = PlyEncoding::Ascii;
            else if (tokens[1] == "binary_little_endian")
                header.encoding = PlyEncoding::BinaryLittleEndian;
            else if (tokens[1] == "binary_big_endian")
                header.encoding = PlyEncoding::BinaryBigEndian;
            else
                ctx.failAtLine(lineNo, "unknown format " + quoted(tokens[1]) +
                                           " (expected ascii, binary_little_endian or binary_big_endian)");
            if (tokens[2].substr(0, 1) != "1")
                ctx.failAtLine(lineNo, "unsupported PLY version " + quoted(tokens[2]));
            sawFormat = true;
        } else if (keyword == "element") {
            std::int64_t count = 0;
            if (tokens.size() != 3 || !parseInteger(tokens[2], count) || count < 0)
                ctx.failAtLine(lineNo, "malformed element line (expected 'element <name> <count>')");
            PlyElement e;
            e.name = std::string(tokens[1]);
            e.count = static_cast<std::uint64_t>(count);
            header.elements.push_back(std::move(e));
        } else if (keyword == "property") {
            if (header.elements.empty())
                ctx.failAtLine(lineNo, "property before any element");
            PlyProperty p;
            if (tokens.size() >= 2 && tokens[1] == "list") {
                if (tokens.size() != 5)
                    ctx.failAtLine(lineNo, "malformed list property (expected 'property list <count type> <item type> <name>')");
                if (!parseType(tokens[2], p.countType))
                    ctx.failAtLine(lineNo, "unknown property type " + quoted(tokens[2]));
                if (isFloatType(p.countType))
                    ctx.failAtLine(lineNo, "a list count must have an integer type, not " + quoted(tokens[2]));
                if (!parseType(tokens[3], p.type))
                    ctx.failAtLine(lineNo, "unknown property type " + quoted(tokens[3]));
                p.isList = true;
                p.name = std::string(tokens[4]);
            } else {
                if (tokens.size() != 3)
                    ctx.failAtLine(lineNo, "malformed property line (expected 'property <type> <name>')");
                if (!parseType(tokens[1], p.type))
                    ctx.failAtLine(lineNo, "unknown property type " + quoted(tokens[1]));
                p.name = std::string(tokens[2]);
            }
            header.elements.back().properties.push_back(std::move(p));
        } else {
            ctx.failAtLine(lineNo, "unexpected " + quoted(keyword) + " in the PLY header");
        }
    }
    if (!sawFormat)
        ctx.fail("the PLY header has no format line");
    header.dataOffset = pos;
    header.lineCount = lineNo;
    return header;
}

// ---------------------------------------------------------------- binary values

template <typename T, bool Swap>
inline T load(const char* p)
{
    T value;
    if constexpr (!Swap) {
        std::memcpy(&value, p, sizeof(T));
    } else {
        char bytes[sizeof(T)];
        for (std::size_t i = 0; i < sizeof(T); ++i)
            bytes[i] = p[sizeof(T) - 1 - i];
        std::memcpy(&value, bytes, sizeof(T));
    }
    return value;
}

template <bool Swap>
inline double loadDouble(const char* p, PlyType type)
{
    switch (type) {
    case PlyType::Int8: return load<std::int8_t, Swap>(p);
    case PlyType::UInt8: return load<std::uint8_t, Swap>(p);
    case PlyType::Int16: return load<std::int16_t, Swap>(p);
    case PlyType::UInt16: return load<std::uint16_t, Swap>(p);
    case PlyType::Int32: return load<std::int32_t, Swap>(p);
    case PlyType::UInt32: return load<std::uint32_t, Swap>(p);
    case PlyType::Float32: return load<float, Swap>(p);
    case PlyType::Float64: return load<double, Swap>(p);
    }
    return 0.0;
}

//! Integer value of a list count or index; floating-point indices (seen in the
//! wild) are truncated, NaN maps to -1 so that it is rejected as out of range.
template <bool Swap>
inline std::int64_t loadInteger(const char* p, PlyType type)
{
    switch (type) {
    case PlyType::Int8: return load<std::int8_t, Swap>(p);
    case PlyType::UInt8: return load<std::uint8_t, Swap>(p);
    case PlyType::Int16: return load<std::int16_t, Swap>(p);
    case PlyType::UInt16: return load<std::uint16_t, Swap>(p);
    case PlyType::Int32: return load<std::int32_t, Swap>(p);
    case PlyType::UInt32: return load<std::uint32_t, Swap>(p);
    case PlyType::Float32:
    case PlyType::Float64: {
        const double v = loadDouble<Swap>(p, type);
        return (v >= 0.0 && v < 9e18) ? static_cast<std::int64_t>(v) : -1;
    }
    }
    return -1;
}

// ---------------------------------------------------------------- vertex layout

enum class Role : std::uint8_t { Ignore, X, Y, Z, Red, Green, Blue, Nx, Ny, Nz, Field };

struct Slot
{
    Role role = Role::Ignore;
    PlyType type = PlyType::Float32;
    std::uint32_t index = 0;  //!< position in VertexLayout::slots
    std::uint32_t field = 0;  //!< index among the layout's fields for Role::Field
    std::size_t offset = 0;   //!< byte offset inside a fixed-size binary record
    double colorScale = 1.0;  //!< brings the stored colour to 0-255
};

struct VertexLayout
{
    std::vector<Slot> slots;          //!< the properties that carry data, in file order
    std::vector<int> slotOfProperty;  //!< per property of the element, -1 when skipped
    std::vector<std::string> fieldNames;
    //! Fields whose values may not fit a float around zero (double, 32-bit integers):
    //! their offset is chosen from their range before conversion.
    std::vector<bool> fieldIsWide;
    bool hasColors = false;
    bool hasNormals = false;
    bool coordinatesAreDouble = false;
};

VertexLayout makeVertexLayout(const PlyElement& e, const Context& ctx)
{
    VertexLayout layout;
    layout.slotOfProperty.assign(e.properties.size(), -1);
    bool hasAxis[3] = {false, false, false};
    std::unordered_set<std::string> usedNames;          // the field names so far
    std::unordered_map<std::string, int> nextSuffix;    // per base name, the next "_k" to try
    std::size_t offset = 0;
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        const std::size_t size = typeSize(p.isList ? p.countType : p.type);
        const std::size_t propertyOffset = offset;
        offset += size;
        if (p.isList)
            continue;
        const std::string name = lower(p.name);
        Slot slot;
        slot.type = p.type;
        slot.offset = propertyOffset;
        if (name == "x" || name == "y" || name == "z") {
            const int axis = name[0] - 'x';
            slot.role = static_cast<Role>(static_cast<int>(Role::X) + axis);
            hasAxis[axis] = true;
            if (p.type == PlyType::Float64)
                layout.coordinatesAreDouble = true;
        } else if (name == "red" || name == "diffuse_red" || name == "green" || name == "diffuse_green" ||
                   name == "blue" || name == "diffuse_blue") {
            const std::string base = name.rfind("diffuse_", 0) == 0 ? name.substr(8) : name;
            slot.role = base == "red" ? Role::Red : base == "green" ? Role::Green : Role::Blue;
            if (isFloatType(p.type))
                slot.colorScale = 255.0;
            else if (p.type == PlyType::UInt16 || p.type == PlyType::Int16)
                slot.colorScale = 255.0 / 65535.0;
            layout.hasColors = true;
        } else if (name == "alpha" || name == "diffuse_alpha") {
            continue;
        } else if (name == "nx" || name == "ny" || name == "nz" || name == "normal_x" || name == "normal_y" ||
                   name == "normal_z") {
            const int axis = name.back() - 'x';
            slot.role = static_cast<Role>(static_cast<int>(Role::Nx) + axis);
            layout.hasNormals = true;
        } else {
            std::string fieldName = p.name;
            if (name.rfind("scalar_", 0) == 0 && fieldName.size() > 7)
                fieldName.erase(0, 7);
            // Two properties may map to one name ("scalar_a" and "a"): keep
            // both. In constant time per property: a hostile header repeating
            // one name thousands of times took 44 s with a search per suffix.
            const std::string base = fieldName;
            int& next = nextSuffix[base];
            next = std::max(next, 2);
            while (usedNames.count(fieldName) != 0)
                fieldName = base + "_" + std::to_string(next++);
            usedNames.insert(fieldName);
            slot.role = Role::Field;
            slot.field = static_cast<std::uint32_t>(layout.fieldNames.size());
            layout.fieldNames.push_back(fieldName);
            layout.fieldIsWide.push_back(p.type == PlyType::Float64 || p.type == PlyType::Int32 ||
                                         p.type == PlyType::UInt32);
        }
        slot.index = static_cast<std::uint32_t>(layout.slots.size());
        layout.slotOfProperty[i] = static_cast<int>(slot.index);
        layout.slots.push_back(slot);
    }
    if (!hasAxis[0] || !hasAxis[1] || !hasAxis[2])
        ctx.fail("the " + e.name + " element has no x, y and z properties");
    return layout;
}

//! Keeps the slots `keep` accepts, renumbered, and the map from properties
//! to slots with them (records of variable size are visited through it).
template <class Keep>
void keepSlots(VertexLayout& layout, Keep&& keep)
{
    std::vector<int> newIndex(layout.slots.size(), -1);
    std::vector<Slot> kept;
    for (const Slot& s : layout.slots)
        if (keep(s)) {
            newIndex[s.index] = static_cast<int>(kept.size());
            kept.push_back(s);
            kept.back().index = static_cast<std::uint32_t>(newIndex[s.index]);
        }
    for (int& slot : layout.slotOfProperty)
        if (slot >= 0)
            slot = newIndex[static_cast<std::size_t>(slot)];
    layout.slots = std::move(kept);
    layout.fieldNames.clear();
    layout.fieldIsWide.clear();
    layout.hasColors = false;
}

bool isCoordinate(const Slot& s) { return s.role >= Role::X && s.role <= Role::Z; }

//! Drops colours and scalar fields from a layout (ReadOptions::geometryOnly):
//! their values are then never decoded.
void keepGeometryOnly(VertexLayout& layout)
{
    keepSlots(layout, [](const Slot& s) { return isCoordinate(s) || (s.role >= Role::Nx && s.role <= Role::Nz); });
}

//! The layout's x, y and z alone (the passes over coordinates).
VertexLayout coordinatesOnly(const VertexLayout& layout)
{
    VertexLayout coordinates = layout;
    keepSlots(coordinates, isCoordinate);
    coordinates.hasNormals = false;
    return coordinates;
}

//! Where decoded vertex values go. Coordinates and wide fields go to double
//! staging buffers when their origin/offset can only be chosen after reading.
//! Set the members, call compile(), then put() every value.
struct VertexSink
{
    Eigen::Vector3f* positions = nullptr;
    Rgb8* colors = nullptr;
    Eigen::Vector3f* normals = nullptr;
    std::vector<float*> fieldValues;
    //! Per field, null unless the field keeps float residuals (its exact form),
    //! with a flag raised by a value they cannot give back.
    std::vector<float*> fieldResiduals;
    std::vector<std::atomic<bool>*> fieldResidualsFailed;
    std::vector<double> fieldOffsets;
    std::vector<double*> stagedFields; //!< per field, null when written directly
    double* stagedXyz = nullptr;
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();

    static std::uint8_t colorByte(double v, double scale)
    {
        v *= scale;
        if (!(v > 0.0))
            return 0;
        if (v >= 255.0)
            return 255;
        return static_cast<std::uint8_t>(std::lround(v));
    }

    //! Turns every slot into a strided destination, so that put() is a small
    //! switch the compiler inlines in the per-value loop.
    void compile(const VertexLayout& layout)
    {
        static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "positions must be packed xyz floats");
        static_assert(sizeof(Rgb8) == 3, "colours must be packed rgb bytes");
        targets_.clear();
        // An empty element (`element vertex 0`) has no arrays: pointer
        // arithmetic on their null data would be undefined, and nothing is put.
        if (!positions && !stagedXyz)
            return;
        for (const Slot& s : layout.slots) {
            Target t;
            switch (s.role) {
            case Role::X:
            case Role::Y:
            case Role::Z: {
                const int axis = static_cast<int>(s.role) - static_cast<int>(Role::X);
                t.stride = 3;
                if (stagedXyz) {
                    t.kind = Target::Staged;
                    t.doubles = stagedXyz + axis;
                } else {
                    t.kind = Target::Float;
                    t.floats = reinterpret_cast<float*>(positions) + axis;
                    t.offset = origin[axis];
                }
                break;
            }
            case Role::Red:
            case Role::Green:
            case Role::Blue:
                t.kind = Target::Color;
                t.stride = 3;
                t.bytes = reinterpret_cast<std::uint8_t*>(colors) + (static_cast<int>(s.role) - static_cast<int>(Role::Red));
                t.colorScale = s.colorScale;
                break;
            case Role::Nx:
            case Role::Ny:
            case Role::Nz:
                t.kind = Target::Float;
                t.stride = 3;
                t.floats = reinterpret_cast<float*>(normals) + (static_cast<int>(s.role) - static_cast<int>(Role::Nx));
                break;
            case Role::Field:
                if (stagedFields[s.field]) {
                    t.kind = Target::Staged;
                    t.doubles = stagedFields[s.field];
                } else {
                    t.kind = fieldResiduals[s.field] ? Target::FloatAndResidual : Target::Float;
                    t.floats = fieldValues[s.field];
                    t.residuals = fieldResiduals[s.field];
                    t.failed = fieldResidualsFailed[s.field];
                    t.offset = fieldOffsets[s.field];
                }
                break;
            case Role::Ignore: break;
            }
            targets_.push_back(t);
        }
    }

    void put(std::size_t i, const Slot& s, double v) const
    {
        const Target& t = targets_[s.index];
        switch (t.kind) {
        case Target::Float: t.floats[i * t.stride] = static_cast<float>(v - t.offset); break;
        case Target::Color: t.bytes[i * t.stride] = colorByte(v, t.colorScale); break;
        case Target::Staged: t.doubles[i * t.stride] = v; break;
        case Target::FloatAndResidual: {
            const auto f = static_cast<float>(v - t.offset);
            t.floats[i] = f;
            t.residuals[i] = std::isnan(v) ? 0.0f : ScalarField::residualOf(v, t.offset, f);
            if (!ScalarField::residualHolds(v, t.offset))
                t.failed->store(true, std::memory_order_relaxed);
            break;
        }
        case Target::None: break;
        }
    }

private:
    struct Target
    {
        enum Kind : std::uint8_t { None, Float, Color, Staged, FloatAndResidual } kind = None;
        std::size_t stride = 1;
        float* floats = nullptr;
        std::uint8_t* bytes = nullptr;
        double* doubles = nullptr;
        float* residuals = nullptr;
        std::atomic<bool>* failed = nullptr;
        double offset = 0.0;
        double colorScale = 1.0;
    };
    std::vector<Target> targets_;
};


struct RangeAccumulator
{
    double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                    std::numeric_limits<double>::infinity()};
    double hi[3] = {-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                    -std::numeric_limits<double>::infinity()};
    std::vector<double> fieldLo, fieldHi;

    explicit RangeAccumulator(std::size_t fieldCount)
        : fieldLo(fieldCount, std::numeric_limits<double>::infinity()),
          fieldHi(fieldCount, -std::numeric_limits<double>::infinity())
    {
    }

    //! Each axis's range keeps its finite values only.
    void addCoordinate(int axis, double v)
    {
        if (std::isfinite(v)) {
            lo[axis] = std::min(lo[axis], v);
            hi[axis] = std::max(hi[axis], v);
        }
    }

    void add(const Slot& s, double v)
    {
        if (s.role >= Role::X && s.role <= Role::Z) {
            addCoordinate(static_cast<int>(s.role) - static_cast<int>(Role::X), v);
        } else if (s.role == Role::Field && std::isfinite(v)) {
            fieldLo[s.field] = std::min(fieldLo[s.field], v);
            fieldHi[s.field] = std::max(fieldHi[s.field], v);
        }
    }

    void merge(const RangeAccumulator& other)
    {
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], other.lo[a]);
            hi[a] = std::max(hi[a], other.hi[a]);
        }
        for (std::size_t f = 0; f < fieldLo.size(); ++f) {
            fieldLo[f] = std::min(fieldLo[f], other.fieldLo[f]);
            fieldHi[f] = std::max(fieldHi[f], other.fieldHi[f]);
        }
    }

    BoundingBox box() const
    {
        BoundingBox b;
        b.empty = !(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]);
        if (!b.empty) {
            b.min = Eigen::Vector3d(lo[0], lo[1], lo[2]);
            b.max = Eigen::Vector3d(hi[0], hi[1], hi[2]);
        }
        return b;
    }
};

// ---------------------------------------------------------------- binary elements

template <bool Swap>
const char* skipBinaryList(const PlyElement& e, const PlyProperty& p, std::uint64_t record, const char* ptr,
                           const char* end, const Context& ctx)
{
    const std::size_t countSize = typeSize(p.countType);
    if (static_cast<std::size_t>(end - ptr) < countSize)
        ctx.truncated(e, record);
    const std::int64_t count = loadInteger<Swap>(ptr, p.countType);
    if (count < 0)
        ctx.fail(e.name + " " + std::to_string(record + 1) + ": negative length " + std::to_string(count) +
                 " for list '" + p.name + "'");
    ptr += countSize;
    const std::size_t itemSize = typeSize(p.type);
    if (static_cast<std::uint64_t>(end - ptr) / itemSize < static_cast<std::uint64_t>(count))
        ctx.truncated(e, record);
    return ptr + static_cast<std::size_t>(count) * itemSize;
}

//! Calls visit(i, record) for each record of an element of fixed-size
//! records, after checking the file holds them all; returns the end of the
//! records. Records are visited in chunks on both cores, from one thread per
//! chunk, so the visitor must only write what belongs to record i (or to its
//! chunk, i / kChunk); each chunk's pages are released once read.
template <class Visit>
const char* visitFixedRecords(const PlyElement& e, const char* ptr, const char* end, const Context& ctx,
                              ProgressTicker& ticker, Visit&& visit)
{
    const std::uint64_t n = e.count;
    const std::size_t recordSize = e.minRecordSize();
    const std::uint64_t available = static_cast<std::uint64_t>(end - ptr) / recordSize;
    if (available < n)
        ctx.truncated(e, available);
    const std::uint64_t chunks = (n + kChunk - 1) / kChunk;
    tbb::parallel_for(tbb::blocked_range<std::uint64_t>(0, chunks, 1), [&](const tbb::blocked_range<std::uint64_t>& range) {
        for (std::uint64_t chunk = range.begin(); chunk != range.end(); ++chunk) {
            const std::uint64_t start = chunk * kChunk, stop = std::min(n, start + kChunk);
            const char* record = ptr + start * recordSize;
            const char* chunkBegin = record;
            for (std::uint64_t i = start; i < stop; ++i, record += recordSize)
                visit(i, record);
            MappedFile::releaseConsumed(chunkBegin, record);
            ticker.step(stop - start);
        }
    });
    return ptr + n * recordSize;
}

//! Calls visit(index, slot, value) for every used vertex property: in file
//! order for records of variable size, by chunks on several threads for
//! fixed-size records (see below).
template <bool Swap, class Visit>
const char* visitBinaryVertices(const PlyElement& e, const VertexLayout& layout, const char* ptr, const char* end,
                                const Context& ctx, ProgressTicker& ticker, Visit&& visit)
{
    const std::uint64_t n = e.count;
    if (e.fixedSize()) {
        const Slot* slotsBegin = layout.slots.data();
        const Slot* slotsEnd = slotsBegin + layout.slots.size();
        return visitFixedRecords(e, ptr, end, ctx, ticker, [&](std::uint64_t i, const char* record) {
            for (const Slot* s = slotsBegin; s != slotsEnd; ++s)
                visit(i, *s, loadDouble<Swap>(record + s->offset, s->type));
        });
    }
    for (std::uint64_t i = 0; i < n; ++i) {
        for (std::size_t j = 0; j < e.properties.size(); ++j) {
            const PlyProperty& p = e.properties[j];
            if (p.isList) {
                ptr = skipBinaryList<Swap>(e, p, i, ptr, end, ctx);
                continue;
            }
            const std::size_t size = typeSize(p.type);
            if (static_cast<std::size_t>(end - ptr) < size)
                ctx.truncated(e, i);
            if (const int slot = layout.slotOfProperty[j]; slot >= 0)
                visit(i, layout.slots[static_cast<std::size_t>(slot)], loadDouble<Swap>(ptr, p.type));
            ptr += size;
        }
        if ((i + 1) % kChunk == 0)
            ticker.step(kChunk);
    }
    ticker.step(n % kChunk);
    return ptr;
}

//! Where a record's x, y and z lie when they are three values of one
//! floating type: the layout every common writer uses (scandiff, CloudCompare,
//! PDAL). Coordinates-only passes (the box, a geometry-only read) then load
//! them directly instead of dispatching on every value's type and role.
struct PlainCoordinates
{
    PlyType type = PlyType::Float32;
    std::size_t offset[3] = {0, 0, 0};
};

//! The plain coordinates of `e`'s records, where they can be loaded
//! directly: fixed-size records in the machine's byte order.
template <bool Swap>
std::optional<PlainCoordinates> plainCoordinates(const VertexLayout& layout, const PlyElement& e)
{
    if (Swap || !e.fixedSize())
        return std::nullopt;
    PlainCoordinates plain;
    int found = 0;
    for (const Slot& s : layout.slots)
        if (s.role >= Role::X && s.role <= Role::Z) {
            if (found > 0 && s.type != plain.type)
                return std::nullopt;
            plain.type = s.type;
            plain.offset[static_cast<int>(s.role) - static_cast<int>(Role::X)] = s.offset;
            ++found;
        }
    if (found != 3 || (plain.type != PlyType::Float32 && plain.type != PlyType::Float64))
        return std::nullopt;
    return plain;
}

//! Calls visit(i, x, y, z) for every record of a fixed-size element in
//! native byte order whose coordinates are plain (see visitFixedRecords).
template <class Visit>
const char* visitPlainCoordinates(const PlyElement& e, const PlainCoordinates& plain, const char* ptr, const char* end,
                                  const Context& ctx, ProgressTicker& ticker, Visit&& visit)
{
    const std::size_t ox = plain.offset[0], oy = plain.offset[1], oz = plain.offset[2];
    const auto visitAs = [&](auto type) {
        using T = decltype(type);
        return visitFixedRecords(e, ptr, end, ctx, ticker, [&](std::uint64_t i, const char* record) {
            T x, y, z;
            std::memcpy(&x, record + ox, sizeof x);
            std::memcpy(&y, record + oy, sizeof y);
            std::memcpy(&z, record + oz, sizeof z);
            visit(i, static_cast<double>(x), static_cast<double>(y), static_cast<double>(z));
        });
    };
    return plain.type == PlyType::Float64 ? visitAs(double()) : visitAs(float());
}

template <bool Swap>
const char* skipBinaryElement(const PlyElement& e, const char* ptr, const char* end, const Context& ctx)
{
    if (e.fixedSize()) {
        const std::size_t recordSize = e.minRecordSize();
        if (recordSize == 0)
            return ptr;
        const std::uint64_t available = static_cast<std::uint64_t>(end - ptr) / recordSize;
        if (available < e.count)
            ctx.truncated(e, available);
        return ptr + e.count * recordSize;
    }
    for (std::uint64_t i = 0; i < e.count; ++i)
        for (const PlyProperty& p : e.properties) {
            if (p.isList) {
                ptr = skipBinaryList<Swap>(e, p, i, ptr, end, ctx);
            } else {
                const std::size_t size = typeSize(p.type);
                if (static_cast<std::size_t>(end - ptr) < size)
                    ctx.truncated(e, i);
                ptr += size;
            }
        }
    return ptr;
}

//! Adds the fan triangulation of one polygon, checking every index.
class FaceBuilder
{
public:
    FaceBuilder(const PlyElement& faces, std::uint64_t vertexCount, const Context& ctx, std::vector<Triangle>& out)
        : faces_(faces), vertexCount_(vertexCount), ctx_(ctx), out_(out)
    {
    }

    void begin(std::uint64_t face)
    {
        face_ = face;
        corners_ = 0;
    }
    void add(std::int64_t index)
    {
        if (index < 0 || static_cast<std::uint64_t>(index) >= vertexCount_)
            ctx_.fail("face " + std::to_string(face_ + 1) + " of " + std::to_string(faces_.count) + " uses vertex " +
                      std::to_string(index) + ", but there are only " + std::to_string(vertexCount_) + " vertices");
        const auto v = static_cast<std::uint32_t>(index);
        if (corners_ == 0)
            first_ = v;
        else if (corners_ >= 2)
            out_.push_back({first_, previous_, v});
        previous_ = v;
        ++corners_;
    }

private:
    const PlyElement& faces_;
    std::uint64_t vertexCount_;
    const Context& ctx_;
    std::vector<Triangle>& out_;
    std::uint64_t face_ = 0;
    std::size_t corners_ = 0;
    std::uint32_t first_ = 0;
    std::uint32_t previous_ = 0;
};

template <bool Swap>
const char* readBinaryFaces(const PlyElement& e, std::size_t indexProperty, FaceBuilder& builder, const char* ptr,
                            const char* end, const Context& ctx, ProgressTicker& ticker)
{
    for (std::uint64_t i = 0; i < e.count; ++i) {
        for (std::size_t j = 0; j < e.properties.size(); ++j) {
            const PlyProperty& p = e.properties[j];
            if (!p.isList) {
                const std::size_t size = typeSize(p.type);
                if (static_cast<std::size_t>(end - ptr) < size)
                    ctx.truncated(e, i);
                ptr += size;
                continue;
            }
            const char* next = skipBinaryList<Swap>(e, p, i, ptr, end, ctx);
            const char* items = ptr + typeSize(p.countType);
            if (j == indexProperty) {
                builder.begin(i);
                const std::size_t itemSize = typeSize(p.type);
                for (const char* item = items; item < next; item += itemSize)
                    builder.add(loadInteger<Swap>(item, p.type));
            }
            ptr = next;
        }
        if ((i + 1) % kChunk == 0)
            ticker.step(kChunk);
    }
    ticker.step(e.count % kChunk);
    return ptr;
}

// ---------------------------------------------------------------- ASCII elements

//! Walks the data section line by line (one record per line, as every writer
//! does), skipping blank lines and keeping the line number for messages.
class AsciiLines
{
public:
    AsciiLines(const char* begin, const char* end, std::size_t firstLine)
        : ptr_(begin), end_(end), nextLineNumber_(firstLine)
    {
    }

    bool next(std::string_view& line)
    {
        while (ptr_ < end_) {
            const void* nl = std::memchr(ptr_, '\n', static_cast<std::size_t>(end_ - ptr_));
            const char* stop = nl ? static_cast<const char*>(nl) : end_;
            line = std::string_view(ptr_, static_cast<std::size_t>(stop - ptr_));
            ptr_ = nl ? stop + 1 : end_;
            lineNumber_ = nextLineNumber_++;
            for (char c : line)
                if (!isBlank(c))
                    return true;
        }
        return false;
    }
    std::size_t lineNumber() const { return lineNumber_; }
    //! The line the file ends on, for "the file ends at line N".
    std::size_t lastLine() const { return nextLineNumber_ - 1; }
    std::size_t remainingBytes() const { return static_cast<std::size_t>(end_ - ptr_); }

private:
    const char* ptr_;
    const char* end_;
    std::size_t nextLineNumber_;
    std::size_t lineNumber_ = 0;
};

class AsciiRecordReader
{
public:
    AsciiRecordReader(AsciiLines& lines, const PlyElement& e, const Context& ctx) : lines_(lines), e_(e), ctx_(ctx)
    {
        // A record holds at least one character and one separator or newline per
        // property: an upper bound on the records left, so that a corrupt count
        // cannot trigger a huge allocation.
        const std::size_t tokens = std::max<std::size_t>(e.properties.size(), 1);
        maxRecords_ = (lines.remainingBytes() + 1) / (2 * tokens);
    }

    //! Records that can be parsed before the data must run out (with a precise message).
    std::uint64_t capacity() const { return std::min<std::uint64_t>(e_.count, maxRecords_ + 1); }

    void beginRecord(std::uint64_t index)
    {
        index_ = index;
        if (!lines_.next(rest_))
            ctx_.fail("truncated: " + e_.name + " " + std::to_string(index + 1) + " of " + std::to_string(e_.count) +
                      " is missing (the file ends at line " + std::to_string(lines_.lastLine()) + ")");
    }
    std::string_view token(const PlyProperty& p)
    {
        std::string_view t;
        if (!nextToken(rest_, t))
            ctx_.failAtLine(lines_.lineNumber(), e_.name + " " + std::to_string(index_ + 1) + " has fewer values than the " +
                                                     std::to_string(e_.properties.size()) +
                                                     " properties of the header (no value for '" + p.name + "')");
        return t;
    }
    double number(const PlyProperty& p)
    {
        const std::string_view t = token(p);
        double v = 0.0;
        if (!parseDouble(t, v))
            ctx_.failAtLine(lines_.lineNumber(), quoted(t) + " is not a number (property '" + p.name + "' of " + e_.name +
                                                     " " + std::to_string(index_ + 1) + ")");
        return v;
    }
    std::int64_t integer(const PlyProperty& p)
    {
        const std::string_view t = token(p);
        std::int64_t v = 0;
        if (!parseInteger(t, v))
            ctx_.failAtLine(lines_.lineNumber(), quoted(t) + " is not an integer (property '" + p.name + "' of " +
                                                     e_.name + " " + std::to_string(index_ + 1) + ")");
        return v;
    }
    std::int64_t listCount(const PlyProperty& p)
    {
        const std::int64_t count = integer(p);
        if (count < 0)
            ctx_.failAtLine(lines_.lineNumber(), "negative length for list '" + p.name + "'");
        return count;
    }
    void endRecord()
    {
        std::string_view t;
        if (nextToken(rest_, t))
            ctx_.failAtLine(lines_.lineNumber(), e_.name + " " + std::to_string(index_ + 1) + " has more values than the " +
                                                     std::to_string(e_.properties.size()) + " properties of the header");
    }

private:
    AsciiLines& lines_;
    const PlyElement& e_;
    const Context& ctx_;
    std::string_view rest_;
    std::uint64_t index_ = 0;
    std::uint64_t maxRecords_ = 0;
};

void readAsciiVertices(const PlyElement& e, const VertexLayout& layout, AsciiRecordReader& reader, const VertexSink& sink,
                       ProgressTicker& ticker)
{
    const std::uint64_t capacity = reader.capacity();
    for (std::uint64_t i = 0; i < e.count; ++i) {
        if (i == capacity) // cannot happen (see capacity()), but the arrays end here
            throw Error(ErrorCode::Internal, "PLY reader: ASCII record bound exceeded");
        reader.beginRecord(i);
        for (std::size_t j = 0; j < e.properties.size(); ++j) {
            const PlyProperty& p = e.properties[j];
            if (p.isList) {
                for (std::int64_t k = reader.listCount(p); k > 0; --k)
                    reader.token(p);
            } else if (const int slot = layout.slotOfProperty[j]; slot >= 0) {
                sink.put(i, layout.slots[static_cast<std::size_t>(slot)], reader.number(p));
            } else {
                reader.token(p);
            }
        }
        reader.endRecord();
        if ((i + 1) % kChunk == 0)
            ticker.step(kChunk);
    }
    ticker.step(e.count % kChunk);
}

void readAsciiFaces(const PlyElement& e, std::size_t indexProperty, FaceBuilder& builder, AsciiLines& lines,
                    const Context& ctx, ProgressTicker& ticker)
{
    AsciiRecordReader reader(lines, e, ctx);
    for (std::uint64_t i = 0; i < e.count; ++i) {
        reader.beginRecord(i);
        for (std::size_t j = 0; j < e.properties.size(); ++j) {
            const PlyProperty& p = e.properties[j];
            if (!p.isList) {
                reader.token(p);
                continue;
            }
            const std::int64_t count = reader.listCount(p);
            if (j == indexProperty)
                builder.begin(i);
            for (std::int64_t k = 0; k < count; ++k) {
                if (j == indexProperty)
                    builder.add(reader.integer(p));
                else
                    reader.token(p);
            }
        }
        reader.endRecord();
        if ((i + 1) % kChunk == 0)
            ticker.step(kChunk);
    }
    ticker.step(e.count % kChunk);
}

void skipAsciiElement(const PlyElement& e, AsciiLines& lines, const Context& ctx)
{
    AsciiRecordReader reader(lines, e, ctx);
    for (std::uint64_t i = 0; i < e.count; ++i)
        reader.beginRecord(i);
}

// ---------------------------------------------------------------- reading

bool isVertexElement(const PlyElement& e)
{
    return e.name == "vertex";
}

//! Index of the face element's vertex list, or -1 when the element gives no triangles.
int faceIndexProperty(const PlyElement& e)
{
    if (e.name != "face")
        return -1;
    for (std::size_t j = 0; j < e.properties.size(); ++j)
        if (e.properties[j].isList && (e.properties[j].name == "vertex_indices" || e.properties[j].name == "vertex_index"))
            return static_cast<int>(j);
    return -1;
}

class PlyReader
{
public:
    PlyReader(const fs::path& path, const ReadOptions& options, std::optional<RecordRange> range = std::nullopt)
        : path_(path), options_(options), range_(range), ctx_(path), file_(path), header_(parseHeader(file_, ctx_))
    {
    }

    //! The number of vertex records the header announces.
    std::uint64_t vertexRecordCount() const { return vertexCountFromHeader(); }

    Entity read()
    {
        const PlyElement* vertexElement = &findVertexElement();
        layout_ = makeVertexLayout(*vertexElement, ctx_);
        if (options_.geometryOnly)
            keepGeometryOnly(layout_);
        cloud_.setCrsWkt(header_.crsWkt);
        if (range_)
            return readRecordRange(*vertexElement);

        const bool binary = header_.encoding != PlyEncoding::Ascii;
        const bool needsRanges =
            binary && ((layout_.coordinatesAreDouble && !options_.origin) ||
                       std::find(layout_.fieldIsWide.begin(), layout_.fieldIsWide.end(), true) != layout_.fieldIsWide.end());
        std::uint64_t totalSteps = vertexElement->count * (needsRanges ? 2 : 1);
        for (const auto& e : header_.elements)
            if (faceIndexProperty(e) >= 0)
                totalSteps += e.count;
        ProgressTicker ticker(options_.progress, "Reading " + path_.filename().string(), totalSteps);

        const bool swap = binary && ((header_.encoding == PlyEncoding::BinaryBigEndian) == kHostLittleEndian);
        if (!binary)
            readAll(ticker, false);
        else if (swap)
            readAll<true>(ticker, needsRanges);
        else
            readAll<false>(ticker, needsRanges);
        return finish();
    }

private:
    template <bool Swap = false>
    void readAll(ProgressTicker& ticker, bool needsRanges)
    {
        const bool binary = header_.encoding != PlyEncoding::Ascii;
        const char* ptr = file_.data() + header_.dataOffset;
        const char* end = file_.data() + file_.size();
        AsciiLines lines(ptr, end, header_.lineCount + 1);
        bool vertexDone = false;
        bool facesDone = false;
        for (const auto& e : header_.elements) {
            const int indexProperty = faceIndexProperty(e);
            if (isVertexElement(e) && !vertexDone) {
                vertexDone = true;
                if (binary)
                    ptr = readBinaryVertexElement<Swap>(e, ptr, end, ticker, needsRanges);
                else
                    readAsciiVertexElement(e, lines, ticker);
            } else if (indexProperty >= 0 && !facesDone) {
                facesDone = true;
                const std::uint64_t vertexCount = vertexCountFromHeader();
                reserveTriangles(e, binary ? static_cast<std::size_t>(end - ptr) : lines.remainingBytes());
                FaceBuilder builder(e, vertexCount, ctx_, triangles_);
                if (binary)
                    ptr = readBinaryFaces<Swap>(e, static_cast<std::size_t>(indexProperty), builder, ptr, end, ctx_, ticker);
                else
                    readAsciiFaces(e, static_cast<std::size_t>(indexProperty), builder, lines, ctx_, ticker);
            } else {
                if (binary)
                    ptr = skipBinaryElement<Swap>(e, ptr, end, ctx_);
                else
                    skipAsciiElement(e, lines, ctx_);
            }
        }
    }

    //! Records [first, first + count) of the vertex element, through the
    //! parallel decoder of fixed-size records. The origin is the whole file's
    //! (a pass over every record's coordinates) unless the options give one.
    Entity readRecordRange(const PlyElement& vertexElement)
    {
        if (swapsBytes(vertexElement))
            readBinaryRange<true>(vertexElement);
        else
            readBinaryRange<false>(vertexElement);
        // Faces are not read: a range of vertices cannot keep their indices.
        return finish();
    }

    //! Throws Error(Unsupported) unless records can be read by ranges; then
    //! whether their bytes must be swapped.
    bool swapsBytes(const PlyElement& vertexElement) const
    {
        if (header_.encoding == PlyEncoding::Ascii || !vertexElement.fixedSize())
            throw Error(ErrorCode::Unsupported, path_.string() +
                                                    ": a range of records can only be read from a binary PLY whose vertex "
                                                    "records have a fixed size");
        return (header_.encoding == PlyEncoding::BinaryBigEndian) == kHostLittleEndian;
    }

    //! Where the vertex records start; throws when the file holds fewer than announced.
    template <bool Swap>
    const char* vertexRecords(const PlyElement& vertexElement, const char* end)
    {
        const char* ptr = file_.data() + header_.dataOffset;
        for (const auto& e : header_.elements) {
            if (&e == &vertexElement)
                break;
            ptr = skipBinaryElement<Swap>(e, ptr, end, ctx_);
        }
        const std::size_t recordSize = vertexElement.minRecordSize();
        if (recordSize == 0 || static_cast<std::uint64_t>(end - ptr) / recordSize < vertexElement.count)
            ctx_.truncated(vertexElement, recordSize == 0 ? 0 : static_cast<std::uint64_t>(end - ptr) / recordSize);
        return ptr;
    }

    //! Where the range's records lie: the vertex element's records, the
    //! range's first one, the file's end, and the range (cut at the
    //! element's end) as an element of its own.
    struct RangeRecords
    {
        const char* all = nullptr;
        const char* first = nullptr;
        const char* end = nullptr;
        PlyElement part;
    };
    template <bool Swap>
    RangeRecords rangeRecords(const PlyElement& vertexElement)
    {
        RangeRecords r;
        r.end = file_.data() + file_.size();
        r.all = vertexRecords<Swap>(vertexElement, r.end);
        const std::uint64_t first = std::min(range_->first, vertexElement.count);
        r.first = r.all + first * vertexElement.minRecordSize();
        r.part = vertexElement;
        r.part.count = std::min(range_->count, vertexElement.count - first);
        return r;
    }

    //! The box of the coordinates of `part`'s records, which start at `ptr`
    //! (non-finite values left out, axis by axis, as a whole read does).
    template <bool Swap>
    BoundingBox coordinateBox(const PlyElement& part, const char* ptr, const char* end, ProgressTicker& ticker)
    {
        return coordinateRanges<Swap>(part, ptr, end, ticker).box();
    }

    //! Each axis's range of finite values (+inf/-inf where it has none).
    template <bool Swap>
    RangeAccumulator coordinateRanges(const PlyElement& part, const char* ptr, const char* end, ProgressTicker& ticker)
    {
        std::vector<RangeAccumulator> perChunk(static_cast<std::size_t>(part.count / kChunk + 1), RangeAccumulator(0));
        if (const std::optional<PlainCoordinates> plain = plainCoordinates<Swap>(layout_, part)) {
            const auto add = [&perChunk](std::uint64_t i, double x, double y, double z) {
                RangeAccumulator& r = perChunk[static_cast<std::size_t>(i / kChunk)];
                r.addCoordinate(0, x);
                r.addCoordinate(1, y);
                r.addCoordinate(2, z);
            };
            visitPlainCoordinates(part, *plain, ptr, end, ctx_, ticker, add);
        } else {
            visitCoordinates<Swap>(part, ptr, end, ticker, perChunk);
        }
        RangeAccumulator whole(0);
        for (const RangeAccumulator& chunk : perChunk)
            whole.merge(chunk);
        return whole;
    }

    template <bool Swap>
    void visitCoordinates(const PlyElement& part, const char* ptr, const char* end, ProgressTicker& ticker,
                          std::vector<RangeAccumulator>& perChunk)
    {
        visitBinaryVertices<Swap>(part, coordinatesOnly(layout_), ptr, end, ctx_, ticker,
                                  [&perChunk](std::uint64_t i, const Slot& s, double v) {
                                      perChunk[static_cast<std::size_t>(i / kChunk)].add(s, v);
                                  });
    }

    template <bool Swap>
    void readBinaryRange(const PlyElement& vertexElement)
    {
        const RangeRecords r = rangeRecords<Swap>(vertexElement);
        std::optional<Eigen::Vector3d> origin = options_.origin;
        ProgressTicker ticker(options_.progress, "Reading " + path_.filename().string(),
                              r.part.count + (!origin && layout_.coordinatesAreDouble ? vertexElement.count : 0));
        if (!origin && layout_.coordinatesAreDouble)
            origin = suggestOrigin(coordinateBox<Swap>(vertexElement, r.all, r.end, ticker));
        const bool wideFields =
            std::find(layout_.fieldIsWide.begin(), layout_.fieldIsWide.end(), true) != layout_.fieldIsWide.end();
        readBinaryVertexElement<Swap>(r.part, r.first, r.end, ticker, wideFields,
                                      origin ? origin : std::optional<Eigen::Vector3d>(Eigen::Vector3d::Zero()));
    }

public:
    //! See FormatHandler::recordBounds: the box of the range's coordinates
    //! when they are doubles (the origin then comes from every point's box),
    //! else none (the origin is zero, whatever the points).
    std::optional<BoundingBox> recordBounds()
    {
        const PlyElement& vertexElement = findVertexElement();
        layout_ = makeVertexLayout(vertexElement, ctx_);
        const bool swap = swapsBytes(vertexElement);
        if (!layout_.coordinatesAreDouble)
            return std::nullopt;
        return swap ? rangeBox<true>(vertexElement) : rangeBox<false>(vertexElement);
    }

    //! See FormatHandler::recordPositions: the range's coordinates as the
    //! file holds them, when they are doubles; else none.
    std::optional<std::vector<Eigen::Vector3d>> recordPositions()
    {
        const PlyElement& vertexElement = findVertexElement();
        layout_ = makeVertexLayout(vertexElement, ctx_);
        const bool swap = swapsBytes(vertexElement);
        if (!layout_.coordinatesAreDouble)
            return std::nullopt;
        return swap ? rangePositions<true>(vertexElement) : rangePositions<false>(vertexElement);
    }

private:
    template <bool Swap>
    std::vector<Eigen::Vector3d> rangePositions(const PlyElement& vertexElement)
    {
        // rangeRecords has checked that the file holds every record.
        const RangeRecords r = rangeRecords<Swap>(vertexElement);
        std::vector<Eigen::Vector3d> positions(static_cast<std::size_t>(r.part.count));
        ProgressTicker ticker(nullptr, "", r.part.count);
        if (const std::optional<PlainCoordinates> plain = plainCoordinates<Swap>(layout_, r.part)) {
            const auto store = [&positions](std::uint64_t i, double x, double y, double z) { positions[i] = {x, y, z}; };
            visitPlainCoordinates(r.part, *plain, r.first, r.end, ctx_, ticker, store);
            return positions;
        }
        visitBinaryVertices<Swap>(r.part, coordinatesOnly(layout_), r.first, r.end, ctx_, ticker,
                                  [&positions](std::uint64_t i, const Slot& s, double v) {
                                      positions[i][static_cast<int>(s.role) - static_cast<int>(Role::X)] = v;
                                  });
        return positions;
    }

    template <bool Swap>
    BoundingBox rangeBox(const PlyElement& vertexElement)
    {
        const RangeRecords r = rangeRecords<Swap>(vertexElement);
        ProgressTicker ticker(nullptr, "", r.part.count);
        const RangeAccumulator ranges = coordinateRanges<Swap>(r.part, r.first, r.end, ticker);
        // Every axis's range, even where another has none: the parts of a
        // file join axis by axis, as a whole read's ranges do.
        BoundingBox box = ranges.box();
        box.min = Eigen::Vector3d(ranges.lo[0], ranges.lo[1], ranges.lo[2]);
        box.max = Eigen::Vector3d(ranges.hi[0], ranges.hi[1], ranges.hi[2]);
        return box;
    }

    const PlyElement& findVertexElement() const
    {
        for (const auto& e : header_.elements)
            if (isVertexElement(e))
                return e;
        ctx_.fail("no vertex element in the PLY header");
    }

    std::uint64_t vertexCountFromHeader() const
    {
        for (const auto& e : header_.elements)
            if (isVertexElement(e))
                return e.count;
        return 0;
    }

    void reserveTriangles(const PlyElement& e, std::size_t remainingBytes)
    {
        // Most faces are triangles; the bound keeps a lying count from allocating wildly.
        const std::size_t bound = remainingBytes / std::max<std::size_t>(e.minRecordSize(), 2);
        triangles_.reserve(static_cast<std::size_t>(std::min<std::uint64_t>(e.count, bound)));
    }

    //! Allocates the cloud and points the sink at its arrays.
    VertexSink prepareCloud(std::uint64_t count)
    {
        const auto n = static_cast<std::size_t>(count);
        cloud_.resize(n);
        VertexSink sink;
        sink.positions = cloud_.positions().data();
        sink.colors = layout_.hasColors ? cloud_.enableColors().data() : nullptr;
        sink.normals = layout_.hasNormals ? cloud_.enableNormals().data() : nullptr;
        for (const auto& name : layout_.fieldNames)
            cloud_.addField(name);
        // Pointers are taken once every field exists: addField may reallocate the field vector.
        for (const auto& name : layout_.fieldNames)
            sink.fieldValues.push_back(cloud_.field(name)->values().data());
        sink.fieldResiduals.assign(layout_.fieldNames.size(), nullptr);
        sink.fieldResidualsFailed.assign(layout_.fieldNames.size(), nullptr);
        sink.fieldOffsets.assign(layout_.fieldNames.size(), 0.0);
        sink.stagedFields.assign(layout_.fieldNames.size(), nullptr);
        return sink;
    }

    template <bool Swap>
    const char* readBinaryVertexElement(const PlyElement& e, const char* ptr, const char* end, ProgressTicker& ticker,
                                        bool needsRanges, const std::optional<Eigen::Vector3d>& wholeFileOrigin = std::nullopt)
    {
        // Check the size before allocating: a corrupt count must not allocate gigabytes.
        const std::size_t minSize = std::max<std::size_t>(e.minRecordSize(), 1);
        if (static_cast<std::uint64_t>(end - ptr) / minSize < e.count) {
            if (e.fixedSize())
                ctx_.truncated(e, static_cast<std::uint64_t>(end - ptr) / minSize);
            ctx_.fail("truncated: the header announces " + std::to_string(e.count) + " vertices but only " +
                      std::to_string(end - ptr) + " bytes of data remain");
        }
        RangeAccumulator ranges(layout_.fieldNames.size());
        if (needsRanges && layout_.fieldNames.empty()) {
            ranges = coordinateRanges<Swap>(e, ptr, end, ticker);
        } else if (needsRanges) {
            // One accumulator per chunk (the decoding is parallel by chunk), merged after.
            std::vector<RangeAccumulator> perChunk(static_cast<std::size_t>(e.count / kChunk + 1), ranges);
            visitBinaryVertices<Swap>(e, layout_, ptr, end, ctx_, ticker, [&perChunk](std::uint64_t i, const Slot& s, double v) {
                perChunk[static_cast<std::size_t>(i / kChunk)].add(s, v);
            });
            for (const RangeAccumulator& chunk : perChunk)
                ranges.merge(chunk);
        }
        VertexSink sink = prepareCloud(e.count);
        if (options_.origin)
            sink.origin = *options_.origin;
        else if (wholeFileOrigin)
            sink.origin = *wholeFileOrigin;
        else if (layout_.coordinatesAreDouble)
            sink.origin = suggestOrigin(ranges.box());
        cloud_.setOrigin(sink.origin);
        // Wide values keep an exact form: float residuals as they are decoded
        // (4 bytes a value), doubles for a field they fail on (a second pass).
        const auto failed = std::make_unique<std::atomic<bool>[]>(layout_.fieldNames.size());
        for (std::size_t f = 0; f < layout_.fieldNames.size(); ++f) {
            failed[f].store(false);
            if (layout_.fieldIsWide[f]) {
                sink.fieldOffsets[f] = chooseFieldOffset(ranges.fieldLo[f], ranges.fieldHi[f]);
                ScalarField& field = *cloud_.field(layout_.fieldNames[f]);
                field.keepResiduals();
                sink.fieldResiduals[f] = field.residuals().data();
                sink.fieldResidualsFailed[f] = &failed[f];
            }
        }
        applyFieldOffsets(sink);
        sink.compile(layout_);
        const char* next = nullptr;
        const std::optional<PlainCoordinates> plain = plainCoordinates<Swap>(layout_, e);
        if (plain && layout_.slots.size() == 3 && e.count > 0) {
            // Coordinates only (a geometry-only read): each one as put() would store it.
            Eigen::Vector3f* positions = sink.positions;
            const Eigen::Vector3d origin = sink.origin;
            const auto store = [positions, origin](std::uint64_t i, double x, double y, double z) {
                positions[i] = Eigen::Vector3f(static_cast<float>(x - origin.x()), static_cast<float>(y - origin.y()),
                                               static_cast<float>(z - origin.z()));
            };
            next = visitPlainCoordinates(e, *plain, ptr, end, ctx_, ticker, store);
        } else {
            next = visitBinaryVertices<Swap>(
                e, layout_, ptr, end, ctx_, ticker, [&sink](std::uint64_t i, const Slot& s, double v) { sink.put(i, s, v); });
        }
        for (std::size_t f = 0; f < layout_.fieldNames.size(); ++f) {
            if (!failed[f].load())
                continue;
            ScalarField& field = *cloud_.field(layout_.fieldNames[f]);
            field.keepDoubles();
            double* doubles = field.doubles().data();
            visitBinaryVertices<Swap>(e, layout_, ptr, end, ctx_, ticker, [doubles, f](std::uint64_t i, const Slot& s, double v) {
                if (s.role == Role::Field && s.field == f)
                    doubles[i] = v;
            });
        }
        keepWideFieldsExact();
        return next;
    }

    //! A double property stays exact, to the bit, and a double when written
    //! back. A 32-bit integer one keeps an exact form only when the float around
    //! the field's offset cannot hold every value (a range wider than 2^24).
    void keepWideFieldsExact()
    {
        for (const Slot& s : layout_.slots) {
            if (s.role != Role::Field || !layout_.fieldIsWide[s.field])
                continue;
            ScalarField& field = *cloud_.field(layout_.fieldNames[s.field]);
            // Residuals that held need no second look for a double property.
            // A range of records keeps every wide field exact, whatever its
            // values: the ranges of one file then all have the same types.
            if (s.type != PlyType::Float64 || !field.doubles().empty() || range_)
                field.compact(s.type == PlyType::Float64 || range_.has_value());
        }
    }

    void readAsciiVertexElement(const PlyElement& e, AsciiLines& lines, ProgressTicker& ticker)
    {
        // The text gives every coordinate in full: keep them in double until the
        // bounding box, hence the origin, is known.
        AsciiRecordReader reader(lines, e, ctx_);
        // Allocating for the records the data can hold: the count may lie, and
        // parsing then stops with a precise message before the arrays end.
        const auto n = static_cast<std::size_t>(reader.capacity());
        VertexSink sink = prepareCloud(n);
        std::vector<double> stagedXyz;
        if (options_.origin) {
            sink.origin = *options_.origin;
        } else {
            stagedXyz.resize(3 * n);
            sink.stagedXyz = stagedXyz.data();
        }
        std::vector<std::vector<double>> stagedFields(layout_.fieldNames.size());
        for (std::size_t f = 0; f < layout_.fieldNames.size(); ++f)
            if (layout_.fieldIsWide[f]) {
                stagedFields[f].assign(n, std::numeric_limits<double>::quiet_NaN());
                sink.stagedFields[f] = stagedFields[f].data();
            }
        sink.compile(layout_);
        readAsciiVertices(e, layout_, reader, sink, ticker);

        if (!options_.origin) {
            RangeAccumulator ranges(0);
            Slot axis[3];
            for (int a = 0; a < 3; ++a)
                axis[a].role = static_cast<Role>(static_cast<int>(Role::X) + a);
            for (std::size_t i = 0; i < n; ++i)
                for (int a = 0; a < 3; ++a)
                    ranges.add(axis[a], stagedXyz[3 * i + static_cast<std::size_t>(a)]);
            const Eigen::Vector3d origin = suggestOrigin(ranges.box());
            auto& positions = cloud_.positions();
            for (std::size_t i = 0; i < n; ++i)
                for (int a = 0; a < 3; ++a)
                    positions[i][a] = static_cast<float>(stagedXyz[3 * i + static_cast<std::size_t>(a)] - origin[a]);
            sink.origin = origin;
        }
        cloud_.setOrigin(sink.origin);
        for (std::size_t f = 0; f < layout_.fieldNames.size(); ++f) {
            if (!layout_.fieldIsWide[f])
                continue;
            const auto& staged = stagedFields[f];
            double lo = std::numeric_limits<double>::infinity();
            double hi = -lo;
            for (double v : staged)
                if (std::isfinite(v)) {
                    lo = std::min(lo, v);
                    hi = std::max(hi, v);
                }
            sink.fieldOffsets[f] = chooseFieldOffset(lo, hi);
            float* values = sink.fieldValues[f];
            for (std::size_t i = 0; i < n; ++i)
                values[i] = static_cast<float>(staged[i] - sink.fieldOffsets[f]);
            ScalarField& field = *cloud_.field(layout_.fieldNames[f]);
            field.keepDoubles();
            field.doubles().swap(stagedFields[f]);
        }
        applyFieldOffsets(sink);
        keepWideFieldsExact();
    }

    void applyFieldOffsets(const VertexSink& sink)
    {
        for (std::size_t f = 0; f < layout_.fieldNames.size(); ++f)
            cloud_.field(layout_.fieldNames[f])->setOffset(sink.fieldOffsets[f]);
    }

    Entity finish()
    {
        if (!triangles_.empty()) {
            const auto& positions = cloud_.positions();
            for (std::size_t i = 0; i < positions.size(); ++i)
                if (!positions[i].allFinite())
                    ctx_.fail("vertex " + std::to_string(i + 1) + " of " + std::to_string(positions.size()) +
                              " has a non-finite coordinate; a mesh cannot have one");
            Mesh mesh;
            mesh.vertices = std::move(cloud_);
            mesh.triangles = std::move(triangles_);
            return mesh;
        }
        if (const std::size_t dropped = cloud_.removeNonFinitePoints(); dropped > 0)
            logWarning(ctx_.fileName() + ": " + std::to_string(dropped) +
                       " points with non-finite coordinates were skipped");
        return std::move(cloud_);
    }

    fs::path path_;
    const ReadOptions& options_;
    std::optional<RecordRange> range_;
    Context ctx_;
    MappedFile file_;
    PlyHeader header_;
    VertexLayout layout_;
    PointCloud cloud_;
    std::vector<Triangle> triangles_;
};

} // namespace

FormatHandler plyFormat()
{
    FormatHandler handler;
    handler.name = "PLY";
    handler.extensions = {"ply"};
    handler.read = [](const fs::path& path, const ReadOptions& options) -> Entity {
        return PlyReader(path, options).read();
    };
    handler.countRecords = [](const fs::path& path) { return PlyReader(path, ReadOptions{}).vertexRecordCount(); };
    handler.readRecords = [](const fs::path& path, RecordRange range, const ReadOptions& options) -> PointCloud {
        Entity entity = PlyReader(path, options, range).read();
        return std::move(std::get<PointCloud>(entity));
    };
    handler.writeCloud = [](const PointCloud& cloud, const fs::path& path, const WriteOptions& options) {
        ply::writeCloud(cloud, path, options);
    };
    handler.writeMesh = [](const Mesh& mesh, const fs::path& path, const WriteOptions& options) {
        ply::writeMesh(mesh, path, options);
    };
    handler.openChunkWriter = [](const fs::path& path, const PointCloud& layout, std::uint64_t total,
                                 const WriteOptions& options) -> std::unique_ptr<PointChunkWriter> {
        return ply::openChunkWriter(path, layout, total, options);
    };
    handler.recordBounds = [](const fs::path& path, RecordRange range) {
        return PlyReader(path, ReadOptions{}, range).recordBounds();
    };
    handler.recordPositions = [](const fs::path& path, RecordRange range) {
        return PlyReader(path, ReadOptions{}, range).recordPositions();
    };
    handler.openPlacedWriter = [](const fs::path& destination, const fs::path& join, const PointCloud& layout,
                                  std::uint64_t total, const WriteOptions& options) -> std::unique_ptr<PlacedChunkWriter> {
        return ply::openPlacedWriter(destination, join, layout, total, options);
    };
    return handler;
}

} // namespace scandiff::io::detail
