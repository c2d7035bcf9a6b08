// SPDX-License-Identifier: GPL-3.0-or-later
//! The PLY header's parser and the text helpers (ply/PlyHeader.h).

#include "ply/PlyHeader.h"

#include "internal/TextUtil.h"

#include <cstring>

namespace scandiff::io::detail::ply {

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

} // namespace scandiff::io::detail::ply
