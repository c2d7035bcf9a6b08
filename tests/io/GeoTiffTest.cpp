// SPDX-License-Identifier: GPL-3.0-or-later
// A DEM of difference written as GeoTIFF and read back through GDAL: the
// grid's geotransform, its bands, nodata and values.
#include <scandiff/core/ColourScale.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/DemOfDifference.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/CoordinateSystem.h>
#include <scandiff/io/FileIO.h>

#include "TestSupport.h"

#include <gdal.h>
#include <ogr_srs_api.h>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

using namespace scandiff;

TEST(GeoTiff, ADemOfDifferenceReadsBackWithItsGridBandsAndNodata)
{
    // Reference over [0, 4] x [0, 3] m, compared over [0, 4] x [0, 2] m raised
    // 0.25 m, UTM-like: 8 x 6 cells of 0.5 m, the top two rows without a
    // compared height (nodata in the difference).
    auto plane = [](double height, double ymax) {
        PointCloud c;
        c.setOrigin({512000, 5400000, 0});
        for (int i = 0; i < 40; ++i)
            for (int j = 0; j < ymax * 10; ++j)
                c.positions().emplace_back(static_cast<float>((i + 0.5) * 0.1), static_cast<float>((j + 0.5) * 0.1),
                                           static_cast<float>(height));
        return c;
    };
    const PointCloud reference = plane(100.0, 3.0), compared = plane(100.25, 2.0);
    DemOfDifferenceParams params;
    params.cell = 0.5;
    const DemOfDifferenceResult dod = demOfDifference(&reference, compared, params);
    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    const auto path = test::tempDir() / "dod.tif";
    io::writePointCloud(formats, dod.cells, path);

    GDALAllRegister();
    GDALDatasetH dataset = GDALOpen(path.string().c_str(), GA_ReadOnly);
    ASSERT_NE(dataset, nullptr);
    EXPECT_EQ(GDALGetRasterXSize(dataset), 8);
    EXPECT_EQ(GDALGetRasterYSize(dataset), 6);
    double transform[6];
    ASSERT_EQ(GDALGetGeoTransform(dataset, transform), CE_None);
    EXPECT_DOUBLE_EQ(transform[0], 512000.0);
    EXPECT_DOUBLE_EQ(transform[1], 0.5);
    EXPECT_DOUBLE_EQ(transform[3], 5400003.0); // the top edge, north up
    EXPECT_DOUBLE_EQ(transform[5], -0.5);
    ASSERT_EQ(GDALGetRasterCount(dataset), 5);
    // Band 1 is the difference: what QGIS and gdaldem show without being told.
    const std::vector<std::string> bandNames = {fields::kDodDifference, fields::kDodLod, fields::kDodSignificant, fields::kZReference,
                                                fields::kZCompared};
    for (int b = 1; b <= 5; ++b)
        EXPECT_EQ(std::string(GDALGetDescription(GDALGetRasterBand(dataset, b))), bandNames[static_cast<std::size_t>(b - 1)]);
    GDALRasterBandH band = GDALGetRasterBand(dataset, 1);
    int hasNoData = 0;
    EXPECT_TRUE(std::isnan(GDALGetRasterNoDataValue(band, &hasNoData)));
    EXPECT_TRUE(hasNoData);
    std::vector<double> image(8 * 6);
    ASSERT_EQ(GDALRasterIO(band, GF_Read, 0, 0, 8, 6, image.data(), 8, 6, GDT_Float64, 0, 0), CE_None);
    for (int row = 0; row < 6; ++row)
        for (int col = 0; col < 8; ++col) {
            const double v = image[static_cast<std::size_t>(row * 8 + col)];
            if (row < 2) // y from 2 to 3 m: no compared height
                EXPECT_TRUE(std::isnan(v)) << row << " " << col;
            else
                EXPECT_NEAR(v, 0.25, 1e-6) << row << " " << col;
        }
    GDALClose(dataset);

    // Only a grid can be a GeoTIFF.
    EXPECT_EQ(test::errorCodeOf([&] { io::writePointCloud(formats, reference, test::tempDir() / "cloud.tif"); }),
              ErrorCode::InvalidArgument);
    EXPECT_FALSE(std::filesystem::exists(test::tempDir() / "cloud.tif"));
}

TEST(GeoTiff, TheSystemOfTheEpochsGoesThroughPlyAndTheDodIntoTheGeoTiff)
{
    const std::string lambert93 = io::crsFromUserInput("EPSG:2154");
    auto plane = [&](double height) {
        PointCloud c;
        c.setOrigin({651000, 6862000, 0});
        for (int i = 0; i < 20; ++i)
            for (int j = 0; j < 20; ++j)
                c.positions().emplace_back(static_cast<float>((i + 0.5) * 0.1), static_cast<float>((j + 0.5) * 0.1),
                                           static_cast<float>(height));
        return c;
    };
    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    const auto dir = test::tempDir();

    // PLY keeps the system in a comment line, in every encoding.
    PointCloud reference = plane(50.0);
    reference.setCrsWkt(lambert93);
    for (io::Encoding encoding : {io::Encoding::Ascii, io::Encoding::BinaryLittleEndian}) {
        io::WriteOptions options;
        options.encoding = encoding;
        io::writePointCloud(formats, reference, dir / "reference.ply", options);
        EXPECT_EQ(io::readPointCloud(formats, dir / "reference.ply").crsWkt(), lambert93);
    }

    // A file without one takes the system the user gives; a file's own wins,
    // with a warning.
    io::writePointCloud(formats, plane(50.5), dir / "compared.xyz");
    io::ReadOptions given;
    given.crsWkt = lambert93;
    const PointCloud compared = io::readPointCloud(formats, dir / "compared.xyz", given);
    EXPECT_EQ(compared.crsWkt(), lambert93);
    std::vector<std::string> warnings;
    const LogSink previous = setLogSink([&](LogLevel level, const std::string& m) {
        if (level == LogLevel::Warning)
            warnings.push_back(m);
    });
    given.crsWkt = io::crsFromUserInput("EPSG:4326");
    EXPECT_EQ(io::readPointCloud(formats, dir / "reference.ply", given).crsWkt(), lambert93);
    setLogSink(previous);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("kept"), std::string::npos) << warnings[0];

    DemOfDifferenceParams params;
    params.cell = 0.5;
    const DemOfDifferenceResult dod = demOfDifference(&reference, compared, params);
    EXPECT_EQ(dod.cells.crsWkt(), lambert93);
    io::writePointCloud(formats, dod.cells, dir / "dod.tif");
    GDALAllRegister();
    GDALDatasetH dataset = GDALOpen((dir / "dod.tif").string().c_str(), GA_ReadOnly);
    ASSERT_NE(dataset, nullptr);
    OGRSpatialReferenceH written = OSRNewSpatialReference(GDALGetProjectionRef(dataset));
    OGRSpatialReferenceH expected = OSRNewSpatialReference(nullptr);
    OSRImportFromEPSG(expected, 2154);
    ASSERT_NE(written, nullptr);
    EXPECT_TRUE(OSRIsSame(written, expected)) << GDALGetProjectionRef(dataset);
    EXPECT_STREQ(OSRGetAuthorityCode(written, nullptr), "2154");
    OSRDestroySpatialReference(written);
    OSRDestroySpatialReference(expected);
    GDALClose(dataset);
}

TEST(PngPreview, TheDifferenceIsDrawnInItsScaleWithNodataTransparentAndABar)
{
    // 10 x 5 cells of 1 m: the left half sank 0.2 m, the right half rose 0.2 m,
    // and cell (0, 0) holds no difference.
    PointCloud grid;
    grid.setOrigin({512000, 5400000, 0});
    ScalarField col(fields::kRasterCol), row(fields::kRasterRow), difference(fields::kDodDifference);
    for (int r = 0; r < 5; ++r)
        for (int c = 0; c < 10; ++c) {
            grid.positions().emplace_back(static_cast<float>(c + 0.5), static_cast<float>(r + 0.5), 0.0f);
            col.values().push_back(static_cast<float>(c));
            row.values().push_back(static_cast<float>(r));
            difference.values().push_back(r == 0 && c == 0 ? std::numeric_limits<float>::quiet_NaN() : c < 5 ? -0.2f : 0.2f);
        }
    grid.addField(std::move(col));
    grid.addField(std::move(row));
    grid.addField(std::move(difference));
    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    const auto path = test::tempDir() / "dod.png";
    io::writePointCloud(formats, grid, path);

    GDALAllRegister();
    GDALDatasetH png = GDALOpen(path.string().c_str(), GA_ReadOnly);
    ASSERT_NE(png, nullptr);
    ASSERT_EQ(GDALGetRasterCount(png), 4);
    const int width = GDALGetRasterXSize(png), height = GDALGetRasterYSize(png);
    // 10 cells over 800 pixels: 80 pixels a cell, the map 800 x 400 from y = 12.
    ASSERT_GT(width, 800);
    ASSERT_EQ(height, 400 + 24);
    auto pixel = [&](int x, int y) {
        std::array<std::uint8_t, 4> rgba{};
        for (int b = 0; b < 4; ++b)
            EXPECT_EQ(GDALRasterIO(GDALGetRasterBand(png, b + 1), GF_Read, x, y, 1, 1, &rgba[static_cast<std::size_t>(b)], 1, 1, GDT_Byte,
                                   0, 0),
                      CE_None);
        return rgba;
    };
    const ColourScale scale = *ColourScale::preset("Diverging Blue-White-Red");
    const auto blue = scale.colourAt(0.0), red = scale.colourAt(1.0);
    // Symmetric range [-0.2, 0.2]: the sunk half at the scale's low end, the risen half at its high end.
    const auto sunk = pixel(200, 12 + 40), risen = pixel(600, 12 + 200);
    EXPECT_EQ((std::array<std::uint8_t, 3>{sunk[0], sunk[1], sunk[2]}), blue);
    EXPECT_EQ(sunk[3], 255);
    EXPECT_EQ((std::array<std::uint8_t, 3>{risen[0], risen[1], risen[2]}), red);
    // Row 0 is the southernmost: cell (0, 0) is the bottom-left block, transparent.
    EXPECT_EQ(pixel(40, 12 + 400 - 40)[3], 0);
    // The bar: its top is the high end, its bottom the low end.
    const auto barTop = pixel(820 + 12, 12), barBottom = pixel(820 + 12, height - 13);
    EXPECT_EQ((std::array<std::uint8_t, 3>{barTop[0], barTop[1], barTop[2]}), red);
    EXPECT_EQ((std::array<std::uint8_t, 3>{barBottom[0], barBottom[1], barBottom[2]}), blue);
    GDALClose(png);

    // Only a grid has a preview; nothing is left behind.
    PointCloud plain;
    plain.positions().emplace_back(0.0f, 0.0f, 0.0f);
    EXPECT_EQ(test::errorCodeOf([&] { io::writePointCloud(formats, plain, test::tempDir() / "plain.png"); }), ErrorCode::InvalidArgument);
}
