// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Small text helpers shared by the text-based readers (internal to io/).

#include <string>
#include <string_view>

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

} // namespace scandiff::io::detail
