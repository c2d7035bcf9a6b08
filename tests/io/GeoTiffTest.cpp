// SPDX-License-Identifier: GPL-3.0-or-later
// A DEM of difference written as GeoTIFF and read back through GDAL: the
// grid's geotransform, its bands, nodata and values.
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/DemOfDifference.h>
#include <scandiff/io/FileIO.h>

#include "TestSupport.h"

#include <gdal.h>

#include <gtest/gtest.h>

#include <cmath>
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
    int differenceBand = 0;
    for (int b = 1; b <= 5; ++b)
        if (std::string(GDALGetDescription(GDALGetRasterBand(dataset, b))) == fields::kDodDifference)
            differenceBand = b;
    ASSERT_GT(differenceBand, 0);
    GDALRasterBandH band = GDALGetRasterBand(dataset, differenceBand);
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
