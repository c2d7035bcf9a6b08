// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Small helpers shared by the readers (internal to io/): tokens quoted for
//! messages, numbers parsed from text, colour channels as bytes.

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <system_error>

namespace scandiff::io::detail {

//! A token of a file, quoted for an error message: control and non-ASCII bytes
//! become '?', and a long token is cut, so a binary blob cannot flood the message.
inline std::string quoted(std::string_view s)
{
    constexpr std::size_t kMax = 40;
    std::string out = "'";
    for (char c : s.substr(0, kMax))
        out += (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) >= 127) ? '?' : c;
    if (s.size() > kMax)
        out += "...";
    return out + "'";
}

//! A whole token as a number; false when anything is left over. A leading
//! '+' is accepted (std::from_chars rejects the sign some writers emit).
template <class Number>
bool parseNumber(std::string_view token, Number& value)
{
    const char* first = token.data();
    const char* last = first + token.size();
    if (first != last && *first == '+')
        ++first;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    return ec == std::errc() && ptr == last && first != last;
}

inline bool parseDouble(std::string_view token, double& value) { return parseNumber(token, value); }
inline bool parseInteger(std::string_view token, std::int64_t& value) { return parseNumber(token, value); }

//! A stored colour channel (times `scale` to bring it to 0-255) as a byte:
//! rounded, clamped, NaN as 0.
inline std::uint8_t colourByte(double v, double scale)
{
    v *= scale;
    if (!(v > 0.0))
        return 0;
    if (v >= 255.0)
        return 255;
    return static_cast<std::uint8_t>(std::lround(v));
}

} // namespace scandiff::io::detail
