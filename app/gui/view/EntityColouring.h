// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What colour each point of an entity gets on screen, from its display state:
//! the active scalar field through its colour scale, hidden or greyed outside
//! the thresholds; else the entity's own colours; else its height. Plain C++
//! (no VTK), so it is tested without a window.

#include "document/Document.h"

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace scandiff::gui {

//! The colour-scale bar that goes with a colouring.
struct ColourLegend
{
    bool shown = false;
    std::string title;
    ColourScale scale = ColourScale::defaultScale();
    double min = 0, max = 1;
    //! For a label field: each value present (ascending) and its colour; the
    //! legend is then a list of swatches, not a ramp.
    std::vector<std::pair<long, std::array<std::uint8_t, 3>>> categories;
};

//! A colour bar's title on lines of at most `width` characters, broken after
//! an underscore or at a space (a word longer than the line stays whole):
//! the bar's frame is narrow, and VTK draws a longer title past the view's
//! edge ("height_above_grou").
std::string wrappedTitle(const std::string& title, std::size_t width = 13);

//! Whether a field holds labels rather than measures: its name says so
//! (region_id, primitive_id, primitive_type, classification, label, cluster,
//! or any name ending in "_id") and every value is an integer. Such a field
//! is drawn with distinct colours per value, not on a ramp where 1 and 2
//! would be two shades of blue.
bool isLabelField(const ScalarField& field);

//! Whether a field is a yes/no flag: it has values and every one is 0 or 1
//! (changed, m3c2_significant, dod_significant...). Drawn in two colours, not
//! on a ramp where 0.5 would mean something.
bool isFlagField(const ScalarField& field);

//! Labels or a flag: drawn, legended and histogrammed by category.
bool isCategoricalField(const ScalarField& field);

//! The colour of `value` of a categorical field: a flag's 0 blue and 1 red
//! (unchanged / changed), a label's labelColour.
std::array<std::uint8_t, 3> categoryColour(bool isLabel, long value);
inline std::array<std::uint8_t, 3> categoryColour(const ScalarField& field, long value)
{
    return categoryColour(isLabelField(field), value);
}

//! The colour of label `value`: 19 colours of high mutual contrast in turn
//! (Kelly's list of 1965, without its white, black and grey, which the
//! background, the greyed points and the no-value points use), so
//! neighbouring ids differ.
std::array<std::uint8_t, 3> labelColour(long value);

//! The neutral grey of a reference shown without its colours.
inline constexpr std::array<std::uint8_t, 3> kNeutralGrey{185, 185, 185};

//! The value range a field's colour scale spans: the display's colour range,
//! each infinite end replaced by the field's finite end; made symmetric about 0
//! when asked or for a symmetric (diverging) scale; a constant field gets a
//! unit-wide range so it still maps to a colour.
std::pair<double, double> colourRange(const ScalarField& field, const FieldDisplay& display);

//! The legend of the active field (not shown for colours or height).
ColourLegend legendOf(const PointCloud& points, const DisplayState& display);

//! An entity's colouring, decided once from its display state (which field,
//! its range and scale's table, labels or a ramp, its own colours, or its
//! height) and applied to all its points or to a part: every stride-th point
//! of [begin, end) from begin + first. The view colours a large cloud's
//! points as its frames draw them, so that a threshold drag on 60 M points
//! recolours the few the moving frame shows. Holds the cloud by address and
//! its field by name: valid while the cloud's data is (the view drops it
//! with the entity's arrays).
class EntityColourer
{
public:
    EntityColourer(const PointCloud& points, const DisplayState& display);
    //! rgba is the whole entity's (4 bytes per point, alpha 0 = hidden).
    void colour(std::uint8_t* rgba, std::size_t begin, std::size_t end, std::size_t stride = 1, std::size_t first = 0) const;
    void colourAll(std::uint8_t* rgba) const { colour(rgba, 0, points_->size()); }
    //! Whether colouring a part costs only that part (a field's colours);
    //! own colours, grey and height are coloured whole.
    bool colouredInParts() const;
    //! The legend of a colouring by height (not shown for the others: see legendOf).
    ColourLegend heightLegend() const;

private:
    enum class Kind { Ramp, Categories, Neutral, OwnColours, Height };
    const PointCloud* points_;
    Kind kind_ = Kind::Height;
    std::string fieldName_;
    FieldColouring how_;
    std::shared_ptr<const ColourTable> table_;
    FieldColouring::Outside outside_ = FieldColouring::Outside::Hide;
    FieldDisplay fieldDisplay_;
    bool label_ = false;
    bool blend_ = false;
};

//! Fills rgba (4 bytes per point, alpha 0 = hidden; room for 4 x points.size())
//! and returns the legend. With display.blendColours, an active field's
//! colours are shaded by the lightness of the cloud's own colour at each
//! point: c x (0.35 + 0.65 L), L the colour's luma (BT.709 weights on its
//! sRGB values) in [0, 1]; a white point keeps the field's colour, a black
//! one a third of it, so the texture reads and the field's hue stays.
//! Hidden points (alpha 0) and clouds without colours are left as they are.
ColourLegend colourEntity(const PointCloud& points, const DisplayState& display, std::uint8_t* rgba);

} // namespace scandiff::gui
