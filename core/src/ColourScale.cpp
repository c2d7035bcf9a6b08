// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/ColourScale.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string_view>

namespace scandiff {

namespace {

std::uint8_t lerpChannel(std::uint8_t a, std::uint8_t b, double f)
{
    const double v = a + (static_cast<double>(b) - a) * f;
    return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
}

constexpr std::string_view kTextHeader = "scandiff-colour-scale 1;symmetric=";

// The name is free text and comes last; only the characters that would break
// the single line (and the escape itself) are escaped.
std::string escapeName(const std::string& name)
{
    std::string out;
    out.reserve(name.size());
    for (char c : name) {
        switch (c) {
        case '\\': out += "\\\\"; break;
        case '\n': out += "\\n"; break;
        case '\r': out += "\\r"; break;
        default: out += c;
        }
    }
    return out;
}

std::optional<std::string> unescapeName(std::string_view text)
{
    std::string out;
    for (std::size_t i = 0; i < text.size(); ++i) {
        if (text[i] != '\\') {
            out += text[i];
            continue;
        }
        if (++i == text.size())
            return std::nullopt;
        switch (text[i]) {
        case '\\': out += '\\'; break;
        case 'n': out += '\n'; break;
        case 'r': out += '\r'; break;
        default: return std::nullopt;
        }
    }
    return out;
}

int hexDigit(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

// One stop as "position:rrggbb".
std::optional<ColourStop> parseStop(std::string_view text)
{
    const auto colon = text.find(':');
    if (colon == std::string_view::npos || text.size() - colon - 1 != 6)
        return std::nullopt;
    ColourStop stop{};
    const char* first = text.data();
    const char* last = text.data() + colon;
    const auto [end, ec] = std::from_chars(first, last, stop.position);
    if (ec != std::errc() || end != last)
        return std::nullopt;
    std::uint8_t* channels[3] = {&stop.r, &stop.g, &stop.b};
    for (int c = 0; c < 3; ++c) {
        const int hi = hexDigit(text[colon + 1 + 2 * c]);
        const int lo = hexDigit(text[colon + 2 + 2 * c]);
        if (hi < 0 || lo < 0)
            return std::nullopt;
        *channels[c] = static_cast<std::uint8_t>(hi * 16 + lo);
    }
    return stop;
}

} // namespace

ColourScale::ColourScale(std::string name, std::vector<ColourStop> stops, bool symmetric)
    : name_(std::move(name)), stops_(std::move(stops)), symmetric_(symmetric)
{
    if (stops_.size() < 2)
        throw std::invalid_argument("a colour scale needs at least two stops");
    for (const ColourStop& s : stops_) {
        if (!(s.position >= 0.0 && s.position <= 1.0))
            throw std::invalid_argument("colour stop positions must lie in [0, 1]");
    }
    std::stable_sort(stops_.begin(), stops_.end(),
                     [](const ColourStop& a, const ColourStop& b) { return a.position < b.position; });
    if (stops_.front().position != 0.0)
        throw std::invalid_argument("the first colour stop must be at position 0");
    if (stops_.back().position != 1.0)
        throw std::invalid_argument("the last colour stop must be at position 1");
}

const std::vector<ColourScale>& ColourScale::presets()
{
    static const std::vector<ColourScale> all = [] {
        std::vector<ColourScale> list;
        list.emplace_back("Blue-Green-Yellow-Red",
                          std::vector<ColourStop>{{0.0, 0, 0, 255},
                                                  {1.0 / 3.0, 0, 255, 0},
                                                  {2.0 / 3.0, 255, 255, 0},
                                                  {1.0, 255, 0, 0}});
        list.emplace_back("Grey", std::vector<ColourStop>{{0.0, 0, 0, 0}, {1.0, 255, 255, 255}});
        // ColorBrewer's RdBu ends with a neutral white at the centre (value 0).
        list.emplace_back("Diverging Blue-White-Red",
                          std::vector<ColourStop>{{0.0, 33, 102, 172}, {0.5, 247, 247, 247}, {1.0, 178, 24, 43}},
                          true);
        // matplotlib's viridis sampled at tenths; linear between them is within a
        // level or two of the full 256-entry table.
        list.emplace_back("Viridis", std::vector<ColourStop>{{0.0, 68, 1, 84},
                                                             {0.1, 72, 36, 117},
                                                             {0.2, 65, 68, 135},
                                                             {0.3, 53, 95, 141},
                                                             {0.4, 42, 120, 142},
                                                             {0.5, 33, 145, 140},
                                                             {0.6, 34, 168, 132},
                                                             {0.7, 68, 191, 112},
                                                             {0.8, 122, 209, 81},
                                                             {0.9, 189, 223, 38},
                                                             {1.0, 253, 231, 37}});
        return list;
    }();
    return all;
}

std::optional<ColourScale> ColourScale::preset(const std::string& name)
{
    for (const ColourScale& s : presets()) {
        if (s.name() == name)
            return s;
    }
    return std::nullopt;
}

std::array<std::uint8_t, 3> ColourScale::colourAt(double t) const
{
    if (!(t > 0.0))
        t = 0.0; // also NaN
    if (t > 1.0)
        t = 1.0;
    // The first stop above t ends the segment; at t = 1 that is past the end.
    const auto upper = std::upper_bound(stops_.begin(), stops_.end(), t,
                                        [](double v, const ColourStop& s) { return v < s.position; });
    if (upper == stops_.end()) {
        const ColourStop& s = stops_.back();
        return {s.r, s.g, s.b};
    }
    const ColourStop& b = *upper;
    const ColourStop& a = *(upper - 1); // exists: stops_[0] is at 0 <= t
    const double width = b.position - a.position;
    const double f = width > 0.0 ? (t - a.position) / width : 0.0;
    return {lerpChannel(a.r, b.r, f), lerpChannel(a.g, b.g, f), lerpChannel(a.b, b.b, f)};
}

std::string ColourScale::toText() const
{
    std::string text(kTextHeader);
    text += symmetric_ ? '1' : '0';
    text += ";stops=";
    static const char* hex = "0123456789abcdef";
    for (std::size_t i = 0; i < stops_.size(); ++i) {
        const ColourStop& s = stops_[i];
        if (i > 0)
            text += ',';
        // to_chars writes the shortest form that reads back to the same double.
        char buffer[64];
        const auto result = std::to_chars(buffer, buffer + sizeof buffer, s.position);
        text.append(buffer, result.ptr);
        text += ':';
        for (std::uint8_t c : {s.r, s.g, s.b}) {
            text += hex[c >> 4];
            text += hex[c & 15];
        }
    }
    text += ";name=";
    text += escapeName(name_);
    return text;
}

std::optional<ColourScale> ColourScale::fromText(const std::string& text)
{
    std::string_view rest(text);
    if (rest.substr(0, kTextHeader.size()) != kTextHeader)
        return std::nullopt;
    rest.remove_prefix(kTextHeader.size());
    if (rest.empty() || (rest[0] != '0' && rest[0] != '1'))
        return std::nullopt;
    const bool symmetric = rest[0] == '1';
    rest.remove_prefix(1);
    constexpr std::string_view stopsKey = ";stops=";
    if (rest.substr(0, stopsKey.size()) != stopsKey)
        return std::nullopt;
    rest.remove_prefix(stopsKey.size());
    constexpr std::string_view nameKey = ";name=";
    const auto nameAt = rest.find(nameKey);
    if (nameAt == std::string_view::npos)
        return std::nullopt;
    std::string_view stopsText = rest.substr(0, nameAt);
    const auto name = unescapeName(rest.substr(nameAt + nameKey.size()));
    if (!name)
        return std::nullopt;

    std::vector<ColourStop> stops;
    while (!stopsText.empty()) {
        const auto comma = stopsText.find(',');
        const auto stop = parseStop(stopsText.substr(0, comma));
        if (!stop)
            return std::nullopt;
        stops.push_back(*stop);
        if (comma == std::string_view::npos)
            break;
        stopsText.remove_prefix(comma + 1);
        if (stopsText.empty())
            return std::nullopt; // a trailing comma
    }
    try {
        return ColourScale(*name, std::move(stops), symmetric);
    } catch (const std::invalid_argument&) {
        return std::nullopt;
    }
}

bool operator==(const ColourScale& a, const ColourScale& b)
{
    if (a.name_ != b.name_ || a.symmetric_ != b.symmetric_ || a.stops_.size() != b.stops_.size())
        return false;
    for (std::size_t i = 0; i < a.stops_.size(); ++i) {
        const ColourStop& s = a.stops_[i];
        const ColourStop& t = b.stops_[i];
        if (s.position != t.position || s.r != t.r || s.g != t.g || s.b != t.b)
            return false;
    }
    return true;
}

} // namespace scandiff
