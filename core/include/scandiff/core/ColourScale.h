// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Colour scales for scalar fields: named gradients through colour stops, the
//! presets users know from CloudCompare, and a one-line text form for sessions
//! and settings. Used by the workbench's view and by the "field to colours" tool.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace scandiff {

struct ColourStop
{
    double position; // in [0,1]
    std::uint8_t r, g, b;
};

//! A named gradient through two or more colour stops, from position 0 to 1.
class ColourScale
{
public:
    //! Sorts the stops by position (stable, so equal positions make a hard edge
    //! in the given order). Throws std::invalid_argument when there are fewer
    //! than two stops, a position is outside [0,1] or not finite, or the first
    //! and last positions are not exactly 0 and 1.
    ColourScale(std::string name, std::vector<ColourStop> stops, bool symmetric = false);

    //! The named scales of the workbench and the field-to-colours tool:
    //! perceptually uniform ones first (Viridis, Cividis, Magma, Inferno,
    //! Plasma), the diverging ones (symmetric), then the classic ones
    //! (CloudCompare's default, Grey, Red-Yellow..., Turbo, Terrain, HSV).
    static const std::vector<ColourScale>& presets();
    //! The scale a field is first shown with: "Blue-Green-Yellow-Red", the
    //! look CloudCompare users know (the list puts the perceptual ones first).
    static const ColourScale& defaultScale();
    static std::optional<ColourScale> preset(const std::string& name);

    const std::string& name() const { return name_; }
    const std::vector<ColourStop>& stops() const { return stops_; }
    //! A symmetric scale is meant to be centred on 0: its users pick a colour
    //! range [-a, a]. The scale itself does not enforce it.
    bool symmetric() const { return symmetric_; }

    //! Linear interpolation between the stops around t; t is clamped to [0,1]
    //! and NaN is treated as 0. Channels are rounded to the nearest integer.
    std::array<std::uint8_t, 3> colourAt(double t) const;

    //! One line of text (no newline) that fromText turns back into an equal
    //! scale; positions keep every bit. Meant for sessions and QSettings.
    std::string toText() const;
    //! Empty if the text is not something toText wrote, or describes an invalid scale.
    static std::optional<ColourScale> fromText(const std::string& text);

    friend bool operator==(const ColourScale& a, const ColourScale& b);
    friend bool operator!=(const ColourScale& a, const ColourScale& b) { return !(a == b); }

private:
    std::string name_;
    std::vector<ColourStop> stops_;
    bool symmetric_ = false;
};

} // namespace scandiff
