// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The PLY reader's first step: the header's elements and properties, and the
//! text helpers the header and the ASCII data share. Errors name the file
//! (and the line) through Context.

#include "internal/MappedFile.h"
#include "internal/TextUtil.h"
#include "ply/PlyCommon.h"

#include <scandiff/core/Error.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace scandiff::io::detail::ply {

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

inline bool isBlank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

//! Splits off the next whitespace-separated token of `rest`; false at the end.
bool nextToken(std::string_view& rest, std::string_view& token);
std::vector<std::string_view> tokenize(std::string_view line);

class Context
{
public:
    explicit Context(const std::filesystem::path& path) : fileName_(path.string()) {}
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

//! Parses the header of a mapped PLY file; throws an InvalidData Error naming the line.
PlyHeader parseHeader(const MappedFile& file, const Context& ctx);

} // namespace scandiff::io::detail::ply
