// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What colour each point of an entity gets on screen, from its display state:
//! the active scalar field through its colour scale, hidden or greyed outside
//! the thresholds; else the entity's own colours; else its height. Plain C++
//! (no VTK), so it is tested without a window.

#include "document/Document.h"

#include <cstdint>
#include <string>
#include <vector>

namespace scandiff::gui {

//! The colour-scale bar that goes with a colouring.
struct ColourLegend
{
    bool shown = false;
    std::string title;
    ColourScale scale = *ColourScale::preset("Blue-Green-Yellow-Red");
    double min = 0, max = 1;
};

//! The value range a field's colour scale spans: the display's colour range,
//! each infinite end replaced by the field's finite end; made symmetric about 0
//! when asked or for a symmetric (diverging) scale; a constant field gets a
//! unit-wide range so it still maps to a colour.
std::pair<double, double> colourRange(const ScalarField& field, const FieldDisplay& display);

//! The legend of the active field (not shown for colours or height).
ColourLegend legendOf(const PointCloud& points, const DisplayState& display);

//! Fills rgba (4 bytes per point, alpha 0 = hidden; room for 4 x points.size())
//! and returns the legend.
ColourLegend colourEntity(const PointCloud& points, const DisplayState& display, std::uint8_t* rgba);

} // namespace scandiff::gui
