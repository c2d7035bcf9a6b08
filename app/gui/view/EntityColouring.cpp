// SPDX-License-Identifier: GPL-3.0-or-later
#include "view/EntityColouring.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <set>

namespace scandiff::gui {

std::pair<double, double> colourRange(const ScalarField& field, const FieldDisplay& display)
{
    const ValueRange r = field.range();
    double lo = std::isfinite(display.colourLow) ? display.colourLow : r.validCount > 0 ? r.min : 0.0;
    double hi = std::isfinite(display.colourHigh) ? display.colourHigh : r.validCount > 0 ? r.max : 1.0;
    if (lo > hi)
        std::swap(lo, hi);
    if (display.symmetric || display.scale.symmetric()) {
        const double m = std::max(std::abs(lo), std::abs(hi));
        lo = -m;
        hi = m;
    }
    if (!(hi > lo)) {
        lo -= 0.5;
        hi += 0.5;
    }
    return {lo, hi};
}

std::string wrappedTitle(const std::string& title, std::size_t width)
{
    // Words end after an underscore (kept, so the name reads whole) or at a space (dropped).
    std::vector<std::string> words;
    std::string word;
    for (char c : title) {
        if (c == ' ') {
            if (!word.empty())
                words.push_back(word);
            word.clear();
            continue;
        }
        word += c;
        if (c == '_') {
            words.push_back(word);
            word.clear();
        }
    }
    if (!word.empty())
        words.push_back(word);
    std::string out, line;
    for (const std::string& w : words) {
        const bool space = !line.empty() && line.back() != '_';
        if (!line.empty() && line.size() + (space ? 1 : 0) + w.size() > width) {
            out += (out.empty() ? "" : "\n") + line;
            line.clear();
        }
        line += (line.empty() || line.back() == '_' ? "" : " ") + w;
    }
    if (!line.empty())
        out += (out.empty() ? "" : "\n") + line;
    return out;
}

bool isLabelField(const ScalarField& field)
{
    static const char* const kLabelNames[] = {"region_id", "primitive_id", "primitive_type", "classification", "class", "label",
                                              "cluster", "segment"};
    const std::string& name = field.name();
    const bool labelName = std::find(std::begin(kLabelNames), std::end(kLabelNames), name) != std::end(kLabelNames) ||
                           (name.size() > 3 && name.compare(name.size() - 3, 3, "_id") == 0);
    if (!labelName)
        return false;
    for (std::size_t i = 0; i < field.size(); ++i)
        if (field.hasValue(i)) {
            const double v = field.value(i);
            if (v != std::floor(v) || std::abs(v) > 1e9)
                return false;
        }
    return true;
}

bool isFlagField(const ScalarField& field)
{
    bool any = false;
    for (std::size_t i = 0; i < field.size(); ++i)
        if (field.hasValue(i)) {
            const double v = field.value(i);
            if (v != 0.0 && v != 1.0)
                return false;
            any = true;
        }
    return any;
}

bool isCategoricalField(const ScalarField& field) { return isLabelField(field) || isFlagField(field); }

std::array<std::uint8_t, 3> categoryColour(bool isLabel, long value)
{
    // Two of Kelly's colours, the farthest apart for most colour visions.
    static constexpr std::array<std::uint8_t, 3> kNo{0, 103, 165}, kYes{190, 0, 50};
    if (!isLabel && (value == 0 || value == 1))
        return value == 1 ? kYes : kNo;
    return labelColour(value);
}

std::array<std::uint8_t, 3> labelColour(long value)
{
    static constexpr std::array<std::uint8_t, 3> kKelly[] = {
        {243, 195, 0},   {135, 86, 146}, {243, 132, 0},  {161, 202, 241}, {190, 0, 50},   {194, 178, 128}, {0, 136, 86},
        {230, 143, 172}, {0, 103, 165},  {249, 147, 121}, {96, 78, 151},  {246, 166, 0},  {179, 68, 108},  {220, 211, 0},
        {136, 45, 23},   {141, 182, 0},  {101, 69, 34},  {226, 88, 34},   {43, 61, 38}};
    constexpr long kCount = static_cast<long>(std::size(kKelly));
    return kKelly[((value % kCount) + kCount) % kCount];
}

namespace {

//! The values of a label field present, ascending (at most `limit`, for the legend).
std::vector<long> labelsPresent(const ScalarField& field, std::size_t limit)
{
    std::set<long> values;
    for (std::size_t i = 0; i < field.size() && values.size() <= limit; ++i)
        if (field.hasValue(i))
            values.insert(std::lround(field.value(i)));
    return {values.begin(), values.end()};
}

//! Colours a categorical field's points begin + first, then every stride-th
//! before end: each value its categoryColour, the thresholds as for any field.
void colourLabels(const ScalarField& field, const FieldDisplay& display, FieldColouring::Outside outside, bool label,
                  std::uint8_t* rgba, std::size_t begin, std::size_t end, std::size_t stride, std::size_t first)
{
    const FieldColouring how;
    for (std::size_t i = begin + first; i < end; i += stride) {
        std::uint8_t* c = rgba + 4 * i;
        if (!field.hasValue(i)) {
            c[0] = how.nanColour[0], c[1] = how.nanColour[1], c[2] = how.nanColour[2], c[3] = 255;
            continue;
        }
        const double v = field.value(i);
        if (v < display.low || v > display.high) {
            if (outside == FieldColouring::Outside::Hide)
                c[0] = c[1] = c[2] = c[3] = 0;
            else
                c[0] = how.greyColour[0], c[1] = how.greyColour[1], c[2] = how.greyColour[2], c[3] = 255;
            continue;
        }
        const long value = std::lround(v);
        const auto colour = categoryColour(label, value);
        c[0] = colour[0], c[1] = colour[1], c[2] = colour[2], c[3] = 255;
    }
}

//! A field's colours shaded by the cloud's own (see colourEntity), over the same part.
void blendPart(const PointCloud& points, std::uint8_t* rgba, std::size_t begin, std::size_t end, std::size_t stride, std::size_t first)
{
    if (!points.hasColors())
        return;
    const std::vector<Rgb8>& own = points.colors();
    for (std::size_t i = begin + first; i < end; i += stride) {
        std::uint8_t* c = rgba + 4 * i;
        if (c[3] == 0)
            continue;
        const double lightness = (0.2126 * own[i].r + 0.7152 * own[i].g + 0.0722 * own[i].b) / 255.0;
        const double shade = 0.35 + 0.65 * lightness;
        for (int k = 0; k < 3; ++k)
            c[k] = static_cast<std::uint8_t>(std::lround(c[k] * shade));
    }
}

void setColour(std::uint8_t* c, std::uint8_t r, std::uint8_t g, std::uint8_t b)
{
    c[0] = r, c[1] = g, c[2] = b, c[3] = 255;
}

constexpr std::size_t kLegendCategories = 24;

} // namespace

ColourLegend legendOf(const PointCloud& points, const DisplayState& display)
{
    ColourLegend legend;
    const ScalarField* field = display.activeField.empty() ? nullptr : points.field(display.activeField);
    if (!field)
        return legend;
    const auto it = display.fields.find(field->name());
    legend.shown = true;
    legend.title = field->name();
    const FieldDisplay fieldDisplay = it == display.fields.end() ? FieldDisplay{} : it->second;
    legend.scale = fieldDisplay.scale;
    std::tie(legend.min, legend.max) = colourRange(*field, fieldDisplay);
    if (isCategoricalField(*field))
        for (long value : labelsPresent(*field, kLegendCategories))
            legend.categories.emplace_back(value, categoryColour(*field, value));
    return legend;
}

EntityColourer::EntityColourer(const PointCloud& points, const DisplayState& display)
    : points_(&points), outside_(display.outside), blend_(display.blendColours)
{
    const ScalarField* field = display.activeField.empty() ? nullptr : points.field(display.activeField);
    if (field) {
        fieldName_ = field->name();
        const auto it = display.fields.find(field->name());
        fieldDisplay_ = it == display.fields.end() ? FieldDisplay{} : it->second;
        if (isCategoricalField(*field)) {
            kind_ = Kind::Categories;
            label_ = isLabelField(*field);
            return;
        }
        kind_ = Kind::Ramp;
        std::tie(how_.colourMin, how_.colourMax) = colourRange(*field, fieldDisplay_);
        how_.visibleMin = fieldDisplay_.low;
        how_.visibleMax = fieldDisplay_.high;
        how_.outside = display.outside;
        table_ = std::make_shared<const ColourTable>(colourTable(fieldDisplay_.scale));
        return;
    }
    blend_ = false;
    if (display.neutral) {
        kind_ = Kind::Neutral;
        return;
    }
    if (points.hasColors()) {
        kind_ = Kind::OwnColours;
        return;
    }
    // Height: what a user expects of a cloud with nothing else to show.
    kind_ = Kind::Height;
    float zmin = std::numeric_limits<float>::max(), zmax = -zmin;
    for (const Eigen::Vector3f& p : points.positions())
        if (std::isfinite(p.z())) {
            zmin = std::min(zmin, p.z());
            zmax = std::max(zmax, p.z());
        }
    how_.colourMin = zmin <= zmax ? zmin : 0.0;
    how_.colourMax = zmin < zmax ? zmax : how_.colourMin + 1.0;
    table_ = std::make_shared<const ColourTable>(colourTable(ColourScale::defaultScale()));
}

bool EntityColourer::colouredInParts() const { return kind_ == Kind::Ramp || kind_ == Kind::Categories; }

ColourLegend EntityColourer::heightLegend() const
{
    if (kind_ != Kind::Height)
        return {};
    return {true, "height", ColourScale::defaultScale(), how_.colourMin + points_->origin().z(), how_.colourMax + points_->origin().z(), {}};
}

void EntityColourer::colour(std::uint8_t* rgba, std::size_t begin, std::size_t end, std::size_t stride, std::size_t first) const
{
    switch (kind_) {
    case Kind::Ramp:
    case Kind::Categories: {
        const ScalarField* field = points_->field(fieldName_);
        if (!field) // removed since: the entity's next refresh colours it anew
            return;
        if (kind_ == Kind::Ramp)
            colourise(field->values().data() + begin, end - begin, field->offset(), *table_, how_, rgba + 4 * begin, stride, first);
        else
            colourLabels(*field, fieldDisplay_, outside_, label_, rgba, begin, end, stride, first);
        if (blend_)
            blendPart(*points_, rgba, begin, end, stride, first);
        return;
    }
    case Kind::Neutral:
        for (std::size_t i = begin + first; i < end; i += stride)
            setColour(rgba + 4 * i, kNeutralGrey[0], kNeutralGrey[1], kNeutralGrey[2]);
        return;
    case Kind::OwnColours:
        for (std::size_t i = begin + first; i < end; i += stride) {
            const Rgb8 c = points_->colors()[i];
            setColour(rgba + 4 * i, c.r, c.g, c.b);
        }
        return;
    case Kind::Height: {
        std::vector<float> heights(end - begin);
        for (std::size_t i = begin; i < end; ++i)
            heights[i - begin] = points_->positions()[i].z();
        colourise(heights.data(), heights.size(), 0.0, *table_, how_, rgba + 4 * begin, stride, first);
        return;
    }
    }
}

ColourLegend colourEntity(const PointCloud& points, const DisplayState& display, std::uint8_t* rgba)
{
    const EntityColourer colourer(points, display);
    colourer.colourAll(rgba);
    ColourLegend height = colourer.heightLegend();
    return height.shown ? height : legendOf(points, display);
}

} // namespace scandiff::gui
