// SPDX-License-Identifier: GPL-3.0-or-later
#include "e57/E57Fields.h"

#include <scandiff/io/AtomicFile.h>

#include <cctype>
#include <cstdio>
#include <utility>

namespace scandiff::io::e57 {

namespace {

// The standard's per-point elements (ASTM E2807 Tab. 20) beside the names scandiff's fields use.
const std::pair<const char*, const char*> kStandardFields[] = {
    {"intensity", "intensity"},     {"timeStamp", "time_stamp"},     {"rowIndex", "row_index"},
    {"columnIndex", "column_index"}, {"returnIndex", "return_index"}, {"returnCount", "return_count"},
};

bool isNameChar(unsigned char c, bool first)
{
    if (std::isalpha(c))
        return true;
    return !first && (std::isdigit(c) || c == '-' || c == '.');
}

int hexValue(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    return -1;
}

} // namespace

std::string fieldNameFor(const Node& field)
{
    if (field.namespaceUri == kE57Namespace) {
        for (const auto& [element, name] : kStandardFields)
            if (field.localName == element)
                return name;
        return field.localName;
    }
    if (field.namespaceUri == kScalarFieldNamespace)
        return decodeXmlName(field.localName);
    return field.prefix.empty() ? field.localName : field.prefix + "_" + field.localName;
}

std::optional<std::string> standardElementFor(const std::string& fieldName)
{
    for (const auto& [element, name] : kStandardFields)
        if (fieldName == name)
            return std::string(element);
    return std::nullopt;
}

std::string encodeXmlName(const std::string& name)
{
    std::string out;
    for (std::size_t i = 0; i < name.size(); ++i) {
        const auto c = static_cast<unsigned char>(name[i]);
        // '_' is kept unless it could be read back as the start of an escape.
        const bool plainUnderscore = c == '_' && !(i + 1 < name.size() && name[i + 1] == 'x');
        if (isNameChar(c, out.empty()) || plainUnderscore) {
            out += static_cast<char>(c);
        } else {
            char escape[8];
            std::snprintf(escape, sizeof escape, "_x%02X_", c);
            out += escape;
        }
    }
    return out.empty() ? "_x00_" : out;
}

std::string decodeXmlName(const std::string& name)
{
    std::string out;
    for (std::size_t i = 0; i < name.size(); ++i) {
        if (name[i] == '_' && i + 4 < name.size() && name[i + 1] == 'x' && name[i + 4] == '_') {
            const int hi = hexValue(name[i + 2]), lo = hexValue(name[i + 3]);
            if (hi >= 0 && lo >= 0) {
                if (hi != 0 || lo != 0)
                    out += static_cast<char>(hi * 16 + lo);
                i += 4;
                continue;
            }
        }
        out += name[i];
    }
    return out;
}

std::string safeFileStem(const std::string& name)
{
    std::string out;
    for (const char ch : name) {
        const auto c = static_cast<unsigned char>(ch);
        out += (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == ' ' || c >= 0x80) ? ch : '_';
    }
    while (!out.empty() && (out.front() == '.' || out.front() == ' '))
        out.erase(out.begin());
    return out.empty() ? "image" : out.substr(0, 120);
}

void writeBytesAtomically(const std::filesystem::path& path, const std::vector<char>& bytes)
{
    AtomicFile file(path);
    file.stream().write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    file.commit();
}

} // namespace scandiff::io::e57
