// SPDX-License-Identifier: GPL-3.0-or-later
//! PNG preview of a gridded cloud (a DEM of difference, an M3C2 raster, a
//! rasterised cloud): one field drawn cell by cell in a colour scale, nodata
//! transparent, with a colour bar and its values on the right. The field is
//! the first present of dod_difference, m3c2_distance and height, else the
//! first field; signed changes use the diverging blue-white-red scale
//! symmetric about 0, the rest CloudCompare's blue-green-yellow-red, both
//! over the 2nd to 98th percentile so that a few outliers do not wash the
//! picture out. Written through GDAL's PNG driver, to a temporary file
//! renamed at the end.
//!
//! The labels are drawn with a 3 x 5 pixel font of the characters numbers
//! need, written here: io has no GUI toolkit, and GDAL draws no text.

#include "internal/Formats.h"
#include "raster/GdalDataset.h"
#include "raster/GriddedCloud.h"

#include <scandiff/core/ColourScale.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/DemOfDifference.h>
#include <scandiff/core/distance/M3C2.h>
#include <scandiff/io/AtomicFile.h>


#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace scandiff::io::detail {

namespace {

// Rows of 3 bits, top first, for the characters of a "%.3g m" label.
struct Glyph
{
    char c;
    std::array<std::uint8_t, 5> rows;
};
constexpr Glyph kGlyphs[] = {
    {'0', {7, 5, 5, 5, 7}}, {'1', {2, 6, 2, 2, 7}}, {'2', {7, 1, 7, 4, 7}}, {'3', {7, 1, 7, 1, 7}}, {'4', {5, 5, 7, 1, 1}},
    {'5', {7, 4, 7, 1, 7}}, {'6', {7, 4, 7, 5, 7}}, {'7', {7, 1, 1, 1, 1}}, {'8', {7, 5, 7, 5, 7}}, {'9', {7, 5, 7, 1, 7}},
    {'-', {0, 0, 7, 0, 0}}, {'+', {0, 2, 7, 2, 0}}, {'.', {0, 0, 0, 0, 2}}, {'e', {7, 4, 7, 4, 7}}, {'m', {5, 7, 7, 5, 5}},
    {' ', {0, 0, 0, 0, 0}},
};
constexpr int kFontScale = 2; // each font pixel is 2 x 2 image pixels

struct Rgba
{
    std::vector<std::uint8_t> r, g, b, a;
    int width = 0, height = 0;
    Rgba(int w, int h) : r(std::size_t(w) * h, 255), g(r), b(r), a(std::size_t(w) * h, 0), width(w), height(h) {}
    void set(int x, int y, std::array<std::uint8_t, 3> c, std::uint8_t alpha = 255)
    {
        if (x < 0 || y < 0 || x >= width || y >= height)
            return;
        const std::size_t i = std::size_t(y) * width + x;
        r[i] = c[0], g[i] = c[1], b[i] = c[2], a[i] = alpha;
    }
};

void drawText(Rgba& image, int x, int y, const std::string& text)
{
    for (char c : text) {
        const Glyph* glyph = std::find_if(std::begin(kGlyphs), std::end(kGlyphs), [c](const Glyph& g) { return g.c == c; });
        if (glyph != std::end(kGlyphs))
            for (int row = 0; row < 5; ++row)
                for (int col = 0; col < 3; ++col)
                    if (glyph->rows[row] & (4 >> col))
                        for (int dy = 0; dy < kFontScale; ++dy)
                            for (int dx = 0; dx < kFontScale; ++dx)
                                image.set(x + col * kFontScale + dx, y + row * kFontScale + dy, {0, 0, 0});
        x += 4 * kFontScale;
    }
}

std::string label(double value)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.3g m", value);
    return text;
}

void writePngPreview(const PointCloud& cloud, const std::filesystem::path& path, const WriteOptions&)
{
    const ScalarField* col = cloud.field(fields::kRasterCol);
    const ScalarField* row = cloud.field(fields::kRasterRow);
    if (!col || !row || cloud.empty())
        throw Error(ErrorCode::InvalidArgument,
                    path.string() + ": only a gridded cloud (a DEM of difference, an M3C2 raster, a rasterised cloud) has a PNG preview");
    const ScalarField* field = mainGridField(cloud);
    if (!field)
        throw Error(ErrorCode::InvalidArgument, path.string() + ": the grid has no field to draw");
    const GridOfCloud g = gridOf(cloud, *col, *row, path);

    std::vector<double> values;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (std::isfinite(field->value(i)))
            values.push_back(field->value(i));
    std::sort(values.begin(), values.end());
    const bool signedChange = field->name() == fields::kDodDifference || field->name() == fields::kM3c2Distance;
    double lo = 0, hi = 1;
    if (!values.empty()) {
        lo = values[values.size() * 2 / 100];
        hi = values[std::min(values.size() - 1, values.size() * 98 / 100)];
    }
    if (signedChange) {
        hi = std::max(std::abs(lo), std::abs(hi));
        lo = -hi;
    }
    if (!(hi > lo)) { // one value: a range around it
        lo -= 0.5;
        hi += 0.5;
    }
    const ColourScale scale = *ColourScale::preset(signedChange ? "Diverging Blue-White-Red" : "Blue-Green-Yellow-Red");

    // About 800 pixels on the long side (at most 80 a cell, so a small grid
    // stays a picture of cells); a larger grid is sampled, one cell a pixel.
    const std::size_t longSide = std::max(g.cols, g.rows);
    const double pixelsPerCell = std::min(800.0 / static_cast<double>(longSide), 80.0);
    const int mapWidth = std::max(1, static_cast<int>(std::lround(static_cast<double>(g.cols) * pixelsPerCell)));
    const int mapHeight = std::max(1, static_cast<int>(std::lround(static_cast<double>(g.rows) * pixelsPerCell)));
    const int barX = mapWidth + 20, barWidth = 24, margin = 12;
    const int labelWidth = 4 * kFontScale * 10;
    const int height = std::max(mapHeight, 200) + 2 * margin;
    Rgba image(barX + barWidth + 8 + labelWidth, height);

    std::vector<double> cells(g.cols * g.rows, std::numeric_limits<double>::quiet_NaN());
    for (std::size_t i = 0; i < cloud.size(); ++i)
        cells[static_cast<std::size_t>(row->value(i)) * g.cols + static_cast<std::size_t>(col->value(i))] = field->value(i);
    for (int y = 0; y < mapHeight; ++y)
        for (int x = 0; x < mapWidth; ++x) {
            const auto c = std::min(g.cols - 1, static_cast<std::size_t>(x / pixelsPerCell));
            const auto r = std::min(g.rows - 1, static_cast<std::size_t>((mapHeight - 1 - y) / pixelsPerCell)); // north up
            const double v = cells[r * g.cols + c];
            if (std::isfinite(v))
                image.set(x, y + margin, scale.colourAt((v - lo) / (hi - lo)));
        }
    // The bar, white behind its labels, highest value at the top.
    for (int y = 0; y < height; ++y)
        for (int x = barX - 4; x < image.width; ++x)
            image.set(x, y, {255, 255, 255});
    const int barTop = margin, barBottom = height - margin;
    for (int y = barTop; y < barBottom; ++y)
        for (int x = barX; x < barX + barWidth; ++x)
            image.set(x, y, scale.colourAt(1.0 - static_cast<double>(y - barTop) / (barBottom - barTop - 1)));
    drawText(image, barX + barWidth + 6, barTop, label(hi));
    drawText(image, barX + barWidth + 6, (barTop + barBottom) / 2 - 5, label(0.5 * (lo + hi)));
    drawText(image, barX + barWidth + 6, barBottom - 10, label(lo));

    GDALDriverH memory = gdalDriver("MEM", path);
    GDALDriverH png = gdalDriver("PNG", path);
    const GdalDataset picture(gdal().GDALCreate(memory, "", image.width, image.height, 4, GDT_Byte, nullptr));
    if (!picture)
        throw Error(ErrorCode::Io, path.string() + ": GDAL cannot make the picture: " + gdal().CPLGetLastErrorMsg());
    std::vector<std::uint8_t>* channels[] = {&image.r, &image.g, &image.b, &image.a};
    for (int b = 0; b < 4; ++b)
        if (gdal().GDALRasterIO(gdal().GDALGetRasterBand(picture.get(), b + 1), GF_Write, 0, 0, image.width, image.height, channels[b]->data(),
                         image.width, image.height, GDT_Byte, 0, 0) != CE_None)
            throw Error(ErrorCode::Io, path.string() + ": GDAL failed to draw: " + gdal().CPLGetLastErrorMsg());
    AtomicFile file(path);
    GdalDataset written(gdal().GDALCreateCopy(png, file.tempPath().string().c_str(), picture.get(), FALSE, nullptr, nullptr, nullptr));
    if (!written)
        throw Error(ErrorCode::Io, path.string() + ": GDAL failed to write the PNG: " + gdal().CPLGetLastErrorMsg());
    written.close();
    // GDAL's PNG driver leaves an .aux.xml beside the file only when asked for
    // georeferencing it cannot store; none is asked here.
    file.commit();
}

} // namespace

FormatHandler pngPreviewFormat()
{
    FormatHandler h;
    h.name = "PNG preview (gridded clouds)";
    h.extensions = {"png"};
    h.writeCloud = writePngPreview;
    return h;
}

} // namespace scandiff::io::detail
