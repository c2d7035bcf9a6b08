// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/ColourScale.h>

#include <algorithm>
#include <initializer_list>
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

namespace {

using Rgb = std::array<std::uint8_t, 3>;

// Stops at even steps from 0 to 1 through the given colours.
std::vector<ColourStop> evenStops(std::initializer_list<Rgb> colours)
{
    std::vector<ColourStop> stops;
    const double last = static_cast<double>(colours.size() - 1);
    std::size_t i = 0;
    for (const Rgb& c : colours) {
        const double position = i + 1 == colours.size() ? 1.0 : static_cast<double>(i) / last;
        stops.push_back({position, c[0], c[1], c[2]});
        ++i;
    }
    return stops;
}

} // namespace

const std::vector<ColourScale>& ColourScale::presets()
{
    // Perceptually uniform scales first (their lightness rises evenly, so a
    // step of the value is a step the eye sees the same everywhere, and they
    // read in grey and to colour-blind eyes), then the diverging ones for
    // signed distances, then CloudCompare's classics. The matplotlib and
    // ColorBrewer scales are their published tables (matplotlib 3.6's
    // _cm_listed.py and _cm.py, Brewer's ColorBrewer 2.0): matplotlib's
    // sampled at 17 or 33 even steps (linear between the samples is within 5
    // levels of 255 of the full 256-entry tables), ColorBrewer's as its own
    // classes (11 for the diverging ones, 9 for Yellow-Brown).
    static const std::vector<ColourScale> all = [] {
        std::vector<ColourScale> list;
        list.emplace_back("Viridis", evenStops({
                               {68, 1, 84}, {72, 24, 106}, {71, 45, 123}, {66, 64, 134}, {59, 82, 139}, {51, 99, 141},
                               {44, 114, 142}, {38, 130, 142}, {33, 145, 140}, {31, 160, 136}, {40, 174, 128}, {63, 188, 115},
                               {94, 201, 98}, {132, 212, 75}, {173, 220, 48}, {216, 226, 25}, {253, 231, 37}
                           }));
        list.emplace_back("Cividis", evenStops({
                               {0, 34, 78}, {0, 40, 91}, {0, 46, 106}, {5, 51, 113}, {26, 56, 111}, {39, 62, 110},
                               {50, 67, 109}, {59, 73, 108}, {67, 78, 108}, {75, 84, 108}, {83, 90, 109}, {90, 95, 110},
                               {97, 101, 111}, {104, 106, 113}, {111, 112, 115}, {118, 118, 118}, {125, 124, 120}, {132, 130, 121},
                               {140, 136, 120}, {147, 142, 120}, {155, 148, 118}, {163, 154, 116}, {171, 160, 114}, {180, 167, 111},
                               {188, 174, 108}, {196, 180, 104}, {205, 187, 99}, {213, 194, 94}, {222, 201, 88}, {231, 209, 80},
                               {240, 216, 70}, {249, 224, 58}, {254, 232, 56}
                           }));
        list.emplace_back("Magma", evenStops({
                               {0, 0, 4}, {10, 8, 34}, {29, 17, 71}, {54, 16, 107}, {81, 18, 124}, {106, 28, 129},
                               {131, 38, 129}, {156, 46, 127}, {183, 55, 121}, {208, 65, 111}, {231, 82, 99}, {245, 107, 92},
                               {252, 137, 97}, {254, 167, 114}, {254, 196, 136}, {253, 226, 163}, {252, 253, 191}
                           }));
        list.emplace_back("Inferno", evenStops({
                               {0, 0, 4}, {11, 7, 36}, {33, 12, 74}, {61, 9, 101}, {87, 16, 110}, {113, 25, 110},
                               {138, 34, 106}, {163, 44, 97}, {188, 55, 84}, {210, 70, 68}, {228, 90, 49}, {241, 115, 29},
                               {249, 142, 9}, {252, 172, 17}, {249, 203, 53}, {242, 234, 105}, {252, 255, 164}
                           }));
        list.emplace_back("Plasma", evenStops({
                               {13, 8, 135}, {49, 5, 151}, {76, 2, 161}, {102, 0, 167}, {126, 3, 168}, {149, 17, 161},
                               {170, 35, 149}, {188, 53, 135}, {204, 71, 120}, {218, 90, 106}, {230, 108, 92}, {240, 128, 78},
                               {248, 149, 64}, {253, 172, 51}, {253, 197, 39}, {248, 223, 37}, {240, 249, 33}
                           }));
        // Diverging: a neutral centre at the value 0 of a symmetric range.
        // ColorBrewer's RdBu ends with a neutral white at the centre.
        list.emplace_back("Diverging Blue-White-Red",
                          std::vector<ColourStop>{{0.0, 33, 102, 172}, {0.5, 247, 247, 247}, {1.0, 178, 24, 43}}, true);
        list.emplace_back("Diverging Blue-White-Red, 11 steps", evenStops({
                               {5, 48, 97}, {33, 102, 172}, {67, 147, 195}, {146, 197, 222}, {209, 229, 240}, {247, 247, 247},
                               {253, 219, 199}, {244, 165, 130}, {214, 96, 77}, {178, 24, 43}, {103, 0, 31}
                           }), true);
        // Moreland's cool-warm (2009), ParaView's default: grey at the centre.
        list.emplace_back("Diverging Cool-Warm", evenStops({
                               {59, 76, 192}, {78, 104, 216}, {98, 130, 234}, {119, 154, 247}, {141, 176, 254}, {163, 194, 254},
                               {185, 208, 249}, {204, 217, 237}, {221, 220, 220}, {236, 211, 197}, {245, 196, 172}, {247, 176, 147},
                               {244, 152, 122}, {235, 125, 98}, {221, 95, 75}, {202, 59, 55}, {180, 4, 38}
                           }), true);
        list.emplace_back("Diverging Brown-White-Teal", evenStops({
                               {84, 48, 5}, {140, 81, 10}, {191, 129, 45}, {223, 194, 125}, {246, 232, 195}, {245, 245, 245},
                               {199, 234, 229}, {128, 205, 193}, {53, 151, 143}, {1, 102, 94}, {0, 60, 48}
                           }), true);
        list.emplace_back("Diverging Green-White-Purple", evenStops({
                               {0, 68, 27}, {27, 120, 55}, {90, 174, 97}, {166, 219, 160}, {217, 240, 211}, {247, 247, 247},
                               {231, 212, 232}, {194, 165, 207}, {153, 112, 171}, {118, 42, 131}, {64, 0, 75}
                           }), true);
        list.emplace_back("Diverging Blue-Yellow-Red", evenStops({
                               {49, 54, 149}, {69, 117, 180}, {116, 173, 209}, {171, 217, 233}, {224, 243, 248}, {255, 255, 191},
                               {254, 224, 144}, {253, 174, 97}, {244, 109, 67}, {215, 48, 39}, {165, 0, 38}
                           }), true);
        // CloudCompare's default look: loss and gain read at once, but its
        // yellow band is brighter than its ends (a false edge at 2/3).
        list.emplace_back("Blue-Green-Yellow-Red",
                          std::vector<ColourStop>{{0.0, 0, 0, 255}, {1.0 / 3.0, 0, 255, 0}, {2.0 / 3.0, 255, 255, 0}, {1.0, 255, 0, 0}});
        list.emplace_back("Turbo", evenStops({
                               {48, 18, 59}, {57, 42, 115}, {64, 64, 162}, {68, 86, 199}, {70, 107, 227}, {70, 128, 246},
                               {66, 148, 255}, {55, 168, 250}, {40, 188, 235}, {28, 205, 216}, {24, 221, 194}, {31, 233, 175},
                               {50, 242, 152}, {78, 249, 125}, {109, 254, 98}, {139, 255, 75}, {164, 252, 60}, {185, 246, 53},
                               {205, 236, 52}, {223, 223, 55}, {238, 207, 58}, {248, 190, 57}, {253, 172, 52}, {254, 150, 43},
                               {251, 126, 33}, {244, 102, 23}, {235, 80, 14}, {223, 63, 8}, {208, 47, 5}, {190, 33, 2},
                               {169, 22, 1}, {146, 11, 1}, {122, 4, 3}
                           }));
        list.emplace_back("Grey", std::vector<ColourStop>{{0.0, 0, 0, 0}, {1.0, 255, 255, 255}});
        list.emplace_back("Red-Yellow", std::vector<ColourStop>{{0.0, 255, 0, 0}, {1.0, 255, 255, 0}});
        list.emplace_back("Red-White", std::vector<ColourStop>{{0.0, 255, 0, 0}, {1.0, 255, 255, 255}});
        list.emplace_back("Yellow-Brown", evenStops({
                               {255, 255, 229}, {255, 247, 188}, {254, 227, 145}, {254, 196, 79}, {254, 153, 41}, {236, 112, 20},
                               {204, 76, 2}, {153, 52, 4}, {102, 37, 6}
                           }));
        // matplotlib's terrain: its own six breakpoints (sea blue, green, sand, brown, snow).
        list.emplace_back("Terrain", std::vector<ColourStop>{{0.0, 51, 51, 153},
                                                             {0.15, 0, 153, 255},
                                                             {0.25, 0, 204, 102},
                                                             {0.5, 255, 255, 153},
                                                             {0.75, 128, 92, 84},
                                                             {1.0, 255, 255, 255}});
        // The hue circle (angles, dip directions): its ends meet.
        list.emplace_back("HSV 360", evenStops({
                               {255, 0, 0}, {255, 255, 0}, {0, 255, 0}, {0, 255, 255}, {0, 0, 255}, {255, 0, 255},
                               {255, 0, 0}
                           }));
        return list;
    }();
    return all;
}

const ColourScale& ColourScale::defaultScale()
{
    static const ColourScale scale = *preset("Blue-Green-Yellow-Red");
    return scale;
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
