// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What PLY's reader (PlyFormat.cpp) and writer (PlyWriter.cpp) share: the
//! property types, the encodings, the host's byte order.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace scandiff::io::detail::ply {

#if defined(__BYTE_ORDER__)
constexpr bool kHostLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;
#else
constexpr bool kHostLittleEndian = true; // compilers without __BYTE_ORDER__ (MSVC) only target little-endian CPUs
#endif

//! Records per progress step: frequent enough for a smooth bar, rare enough to cost nothing.
constexpr std::uint64_t kChunk = 1u << 16;

enum class PlyType : std::uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

inline std::size_t typeSize(PlyType type)
{
    switch (type) {
    case PlyType::Int8:
    case PlyType::UInt8: return 1;
    case PlyType::Int16:
    case PlyType::UInt16: return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
    }
    return 1;
}

inline bool parseType(std::string_view name, PlyType& type)
{
    struct Entry
    {
        const char* name;
        PlyType type;
    };
    static const Entry entries[] = {
        {"char", PlyType::Int8},     {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},   {"short", PlyType::Int16},     {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16}, {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
        {"int32", PlyType::Int32},   {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64},
        {"float64", PlyType::Float64},
    };
    for (const Entry& e : entries)
        if (name == e.name) {
            type = e.type;
            return true;
        }
    return false;
}

inline bool isFloatType(PlyType type)
{
    return type == PlyType::Float32 || type == PlyType::Float64;
}

enum class PlyEncoding { Ascii, BinaryLittleEndian, BinaryBigEndian };

// PLY has no place for a coordinate reference system: scandiff writes it as a
// comment line of its own, "comment crs_wkt " + the WKT on one line.
inline constexpr std::string_view kCrsComment = "comment crs_wkt ";

//! ASCII lower case (property names are compared without case).
inline std::string lower(std::string_view s)
{
    std::string out(s);
    for (char& c : out)
        if (c >= 'A' && c <= 'Z')
            c = static_cast<char>(c - 'A' + 'a');
    return out;
}

} // namespace scandiff::io::detail::ply
