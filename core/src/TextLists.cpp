// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/TextLists.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

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
        try {
            std::size_t used = 0;
            values.push_back(std::stod(part, &used));
            if (used != part.size() || !std::isfinite(values.back()))
                throw std::invalid_argument(part);
        } catch (const std::exception&) {
            throw Error(ErrorCode::InvalidArgument, what + ": '" + part + "' is not a finite number");
        }
    }
    return values;
}

} // namespace scandiff
