// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Table.h>

#include <charconv>
#include <cmath>

namespace scandiff {

namespace {

void appendCell(std::string& out, const TableCell& cell)
{
    if (const auto* number = std::get_if<double>(&cell)) {
        if (std::isnan(*number)) {
            out += "nan";
            return;
        }
        char buffer[32];
        const auto result = std::to_chars(buffer, buffer + sizeof buffer, *number);
        out.append(buffer, result.ptr);
        return;
    }
    const std::string& text = std::get<std::string>(cell);
    if (text.find_first_of(",\"\r\n") == std::string::npos) {
        out += text;
        return;
    }
    out += '"';
    for (char c : text) {
        if (c == '"')
            out += '"';
        out += c;
    }
    out += '"';
}

} // namespace

std::string Table::toCsv() const
{
    std::string out;
    for (std::size_t c = 0; c < columns.size(); ++c) {
        if (c)
            out += ',';
        appendCell(out, columns[c]);
    }
    out += '\n';
    for (const auto& row : rows) {
        for (std::size_t c = 0; c < row.size(); ++c) {
            if (c)
                out += ',';
            appendCell(out, row[c]);
        }
        out += '\n';
    }
    return out;
}

std::string Table::toText() const
{
    if (!plainNumbers)
        return toCsv();
    std::string out;
    for (const auto& row : rows) {
        for (std::size_t c = 0; c < row.size(); ++c) {
            if (c)
                out += ' ';
            appendCell(out, row[c]);
        }
        out += '\n';
    }
    return out;
}

} // namespace scandiff
