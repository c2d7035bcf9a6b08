// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>

#include <charconv>
#include <cmath>
#include <sstream>

namespace scandiff {

std::vector<std::string> splitList(const std::string& text, char separator)
{
    std::vector<std::string> parts;
    std::stringstream stream(text);
    std::string part;
    while (std::getline(stream, part, separator))
        parts.push_back(part);
    return parts;
}

std::vector<double> parseNumberList(const std::string& text, const std::string& what)
{
    std::vector<double> values;
    for (const std::string& part : splitList(text, ',')) {
        // from_chars, not stod: the decimal point must not depend on the
        // process's locale (the workbench's Qt sets it from the environment).
        std::size_t first = part.find_first_not_of(" \t"), last = part.find_last_not_of(" \t");
        if (first != std::string::npos && part[first] == '+')
            ++first;
        double value = 0;
        bool ok = first != std::string::npos && first <= last;
        if (ok) {
            const auto [end, ec] = std::from_chars(part.data() + first, part.data() + last + 1, value);
            ok = ec == std::errc() && end == part.data() + last + 1 && std::isfinite(value);
        }
        if (!ok)
            throw Error(ErrorCode::InvalidArgument, what + ": '" + part + "' is not a finite number");
        values.push_back(value);
    }
    return values;
}

std::vector<double> parseNumberWords(const std::string& text, const std::string& what)
{
    std::string commas = text;
    for (char& c : commas)
        if (c == ';' || c == ' ' || c == '\t')
            c = ',';
    std::string list;
    for (const std::string& part : splitList(commas, ','))
        if (!part.empty())
            list += (list.empty() ? "" : ",") + part;
    return parseNumberList(list, what);
}

} // namespace scandiff
