// SPDX-License-Identifier: GPL-3.0-or-later
// Region measurements: outline, footprint, statistics, volume.

#include <scandiff/core/Error.h>
#include <scandiff/core/geometry/PlanarRings.h>
#include <scandiff/core/segmentation/RegionReport.h>

#include "TestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace scandiff;

namespace {

std::vector<Eigen::Vector2d> gridPoints(double x0, double y0, double x1, double y1, double step)
{
    std::vector<Eigen::Vector2d> p;
    for (double x = x0 + 0.5 * step; x < x1; x += step)
        for (double y = y0 + 0.5 * step; y < y1; y += step)
            p.emplace_back(x, y);
    return p;
}

} // namespace

TEST(Outline, SquareAndConcaveLShape)
{
    // A 1 m square sampled every 2 cm, outlined on 3 cm cells.
    const Outline2d square = concaveOutline(gridPoints(0, 0, 1, 1, 0.02), 0.03);
    ASSERT_EQ(square.rings.size(), 1u);
    // The outline runs through the outermost points (0.01 and 0.99), not up
    // to a cell beyond them: the area is that of the sampled square, exactly.
    EXPECT_NEAR(square.area, 0.98 * 0.98, 1e-9);
    EXPECT_EQ(square.rings[0].size(), 4u);         // straight sides collapse to 4 corners
    EXPECT_GT(signedArea(square.rings[0]), 0.0); // counter-clockwise

    // An L (the square minus its upper-right quarter): area 0.75, not the hull's 1.
    auto l = gridPoints(0, 0, 1, 0.5, 0.02);
    const auto top = gridPoints(0, 0.5, 0.5, 1, 0.02);
    l.insert(l.end(), top.begin(), top.end());
    const Outline2d shape = concaveOutline(l, 0.03);
    ASSERT_EQ(shape.rings.size(), 1u);
    EXPECT_NEAR(shape.area, 0.75, 0.1);
    EXPECT_EQ(shape.rings[0].size(), 6u);
}

TEST(Outline, SeparatePiecesGetSeparateRingsAndHolesAreFilled)
{
    auto points = gridPoints(0, 0, 1, 1, 0.02);
    const auto far = gridPoints(3, 0, 3.5, 0.5, 0.02);
    points.insert(points.end(), far.begin(), far.end());
    // A hole in the middle of the first square is not part of the outline.
    points.erase(std::remove_if(points.begin(), points.end(),
                                [](const Eigen::Vector2d& p) { return (p - Eigen::Vector2d(0.5, 0.5)).norm() < 0.2; }),
                 points.end());
    const Outline2d o = concaveOutline(points, 0.03);
    ASSERT_EQ(o.rings.size(), 2u);
    EXPECT_GT(signedArea(o.rings[0]), signedArea(o.rings[1]));
    EXPECT_NEAR(o.area, 1.25, 0.15);
    EXPECT_TRUE(concaveOutline({}, 1.0).rings.empty());
    EXPECT_EQ(concaveOutline({{0, 0}}, 1.0).rings.size(), 1u);
    EXPECT_EQ(test::errorCodeOf([] { concaveOutline({{0, 0}}, 0.0); }), ErrorCode::InvalidArgument);
}

TEST(RegionReport, MeasuresEachRegion)
{
    // Region 1: a 1 m square at z = 0.5 (a raised slab); region 2: a tilted
    // square; a point without a region. The reference is the ground z = 0.
    PointCloud cloud;
    cloud.setOrigin({1000, 2000, 0});
    std::vector<float> ids, distances;
    for (const auto& p : gridPoints(0, 0, 1, 1, 0.02)) {
        cloud.positions().emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), 0.5f);
        ids.push_back(1);
        distances.push_back(0.5f);
    }
    const Eigen::Vector3d tiltU(0.6, 0, 0.8), tiltV(0, 1, 0);
    for (const auto& p : gridPoints(0, 0, 0.5, 0.5, 0.02)) {
        const Eigen::Vector3d q = Eigen::Vector3d(5, 5, 0) + p.x() * tiltU + p.y() * tiltV;
        cloud.positions().push_back(q.cast<float>());
        ids.push_back(2);
        distances.push_back(static_cast<float>(-q.z()));
    }
    cloud.positions().emplace_back(9.0f, 9.0f, 9.0f);
    ids.push_back(std::nanf(""));
    distances.push_back(100.0f);
    cloud.addField("region_id").values() = ids;
    cloud.addField("distance").values() = distances;

    PointCloud reference;
    reference.setOrigin({1000, 2000, 0});
    for (const auto& p : gridPoints(-1, -1, 2, 2, 0.05))
        reference.positions().emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), 0.0f);

    RegionReportParams params;
    params.distanceField = "distance";
    params.reference = &reference;
    params.volumeCellSize = 0.1;
    const std::vector<RegionStatistics> report = regionReport(cloud, params);
    ASSERT_EQ(report.size(), 2u);

    const RegionStatistics& slab = report[0];
    EXPECT_EQ(slab.id, 1);
    EXPECT_EQ(slab.pointCount, 2500u);
    EXPECT_NEAR(slab.centroid.x(), 1000.5, 1e-4);
    EXPECT_NEAR(slab.centroid.y(), 2000.5, 1e-4);
    EXPECT_NEAR(slab.centroid.z(), 0.5, 1e-6);
    EXPECT_NEAR(slab.bounds.min.x(), 1000.01, 1e-4);
    EXPECT_NEAR(slab.bounds.max.y(), 2000.99, 1e-4);
    EXPECT_NEAR(std::abs(slab.planeNormal.z()), 1.0, 1e-9);
    EXPECT_NEAR(slab.footprintArea, 0.98 * 0.98, 1e-6); // the square through the outermost points
    EXPECT_NEAR(slab.outlineArea, 0.98 * 0.98, 1e-6);
    EXPECT_NEAR(slab.meanDistance, 0.5, 1e-6);
    EXPECT_NEAR(slab.maxDistance, 0.5, 1e-6);
    EXPECT_NEAR(slab.rmsDistance, 0.5, 1e-6);
    ASSERT_TRUE(slab.volume.has_value());
    EXPECT_NEAR(*slab.volume, 0.5 * 0.98 * 0.98, 1e-6); // 0.5 m over the footprint
    EXPECT_NEAR(slab.volumeCoverage, 1.0, 1e-9); // areas summed from clipped cells at 1e3 m coordinates
    ASSERT_EQ(slab.outlines.size(), 1u);
    for (const auto& v : slab.outlines[0])
        EXPECT_NEAR(v.z(), 0.5, 1e-6); // lifted back onto the slab's plane

    const RegionStatistics& tilted = report[1];
    EXPECT_EQ(tilted.id, 2);
    EXPECT_NEAR(std::abs(tilted.planeNormal.dot(tiltU.cross(tiltV).normalized())), 1.0, 1e-6);
    // 0.48 x 0.48 in its plane; seen from above, its width along x shrinks by cos = 0.6.
    EXPECT_NEAR(tilted.outlineArea, 0.48 * 0.48, 1e-4);
    EXPECT_NEAR(tilted.footprintArea, 0.48 * 0.6 * 0.48, 1e-4);
    ASSERT_FALSE(tilted.outlines.empty());
    const Eigen::Vector3d origin(1000, 2000, 0);
    for (const auto& v : tilted.outlines[0]) // the outline lies in the tilted plane
        EXPECT_NEAR((v - origin - Eigen::Vector3d(5, 5, 0)).dot(tiltU.cross(tiltV)), 0.0, 1e-4);
    EXPECT_LT(tilted.maxDistance, 0.0); // the sign of the largest value is kept
    EXPECT_FALSE(tilted.volumeCoverage > 0.0); // the reference does not reach it
}

namespace {

//! A horizontal square grid of points at height z, corners included.
void addGrid(PointCloud& cloud, double x0, double y0, double x1, double y1, double z, double step)
{
    for (double x = x0; x <= x1 + 1e-9; x += step)
        for (double y = y0; y <= y1 + 1e-9; y += step)
            cloud.positions().emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
}

//! The four vertical walls of the box [x0, x1] x [y0, y1] x [0, height].
void addWalls(PointCloud& cloud, double x0, double y0, double x1, double y1, double height, double step)
{
    for (double z = 0; z < height - 1e-9; z += step) {
        for (double x = x0; x <= x1 + 1e-9; x += step) {
            cloud.positions().emplace_back(static_cast<float>(x), static_cast<float>(y0), static_cast<float>(z));
            cloud.positions().emplace_back(static_cast<float>(x), static_cast<float>(y1), static_cast<float>(z));
        }
        for (double y = y0 + step; y < y1 - 1e-9; y += step) {
            cloud.positions().emplace_back(static_cast<float>(x0), static_cast<float>(y), static_cast<float>(z));
            cloud.positions().emplace_back(static_cast<float>(x1), static_cast<float>(y), static_cast<float>(z));
        }
    }
}

void markRegion(PointCloud& cloud, std::size_t from, float id)
{
    ScalarField* field = cloud.field("region_id");
    if (!field)
        field = &cloud.addField("region_id");
    field->values().resize(cloud.size(), std::nanf(""));
    for (std::size_t i = from; i < cloud.size(); ++i)
        field->values()[i] = id;
}

} // namespace

// The trial's scene in closed form: between two epochs of flat ground, an
// 8 x 8 x 4 m box appeared (roof and walls scanned) and a 20 x 20 x 2 m block
// went. The trial's report gave the box -10.2 m^3 and 80.1 m^2.
TEST(RegionReport, AppearedBoxAndRemovedBlockInClosedForm)
{
    constexpr double step = 0.25;
    PointCloud earlier, later;
    for (PointCloud* epoch : {&earlier, &later})
        epoch->setOrigin({512000, 5403000, 380});
    // Earlier: ground (not under the block) and the block, roof and walls.
    addGrid(earlier, -10, -10, 12, 30, 0, step);
    addGrid(earlier, 12.25, -10, 40, -0.25, 0, step);
    addGrid(earlier, 12.25, 20.25, 40, 30, 0, step);
    addGrid(earlier, 35.25, 0, 40, 20, 0, step);
    const std::size_t blockStart = earlier.size();
    addGrid(earlier, 15, 0, 35, 20, 2, step);
    addWalls(earlier, 15, 0, 35, 20, 2, step);
    markRegion(earlier, blockStart, 1);
    // Later: ground everywhere but under the box, and the box.
    addGrid(later, -10, -10, -0.25, 30, 0, step);
    addGrid(later, 8.25, -10, 40, 30, 0, step);
    addGrid(later, 0, -10, 8, -0.25, 0, step);
    addGrid(later, 0, 8.25, 8, 30, 0, step);
    const std::size_t boxStart = later.size();
    addGrid(later, 0, 0, 8, 8, 4, step);
    addWalls(later, 0, 0, 8, 8, 4, step);
    markRegion(later, boxStart, 1);

    RegionReportParams appeared;
    appeared.reference = &earlier; // the other epoch; the regions are in the later one
    const std::vector<RegionStatistics> box = regionReport(later, appeared);
    ASSERT_EQ(box.size(), 1u);
    EXPECT_NEAR(box[0].footprintArea, 64.0, 1e-3);
    ASSERT_TRUE(box[0].volume.has_value());
    EXPECT_NEAR(*box[0].volume, 256.0, 1e-2); // appearance counts positive
    EXPECT_NEAR(box[0].volumeAdded, 256.0, 1e-2);
    EXPECT_EQ(box[0].volumeRemoved, 0.0);
    EXPECT_NEAR(box[0].volumeCoverage, 1.0, 1e-9);
    // The same with columns of another size: the partial ones at the edge are weighed by their part inside.
    appeared.volumeCellSize = 0.7;
    EXPECT_NEAR(*regionReport(later, appeared)[0].volume, 256.0, 1e-2);

    RegionReportParams removed;
    removed.reference = &later;
    removed.regionInLaterEpoch = false; // the regions are in the earlier epoch
    const std::vector<RegionStatistics> block = regionReport(earlier, removed);
    ASSERT_EQ(block.size(), 1u);
    EXPECT_NEAR(block[0].footprintArea, 400.0, 1e-2);
    EXPECT_NEAR(*block[0].volume, -800.0, 1e-1); // removal counts negative
    EXPECT_NEAR(block[0].volumeRemoved, 800.0, 1e-1);
    EXPECT_EQ(block[0].volumeAdded, 0.0);
    // Mean column heights: the walls pull the block's edge columns down, so it is less, not more.
    removed.columnHeight = RegionReportParams::ColumnHeight::Mean;
    const double meanVolume = *regionReport(earlier, removed)[0].volume;
    EXPECT_LT(meanVolume, 0.0);
    EXPECT_GT(meanVolume, -800.0);
}

TEST(RegionReport, BadInput)
{
    PointCloud cloud;
    cloud.resize(3);
    EXPECT_EQ(test::errorCodeOf([&] { regionReport(cloud); }), ErrorCode::InvalidArgument);
    cloud.addField("region_id").values() = {1.0f, 1.5f, std::nanf("")};
    EXPECT_EQ(test::errorCodeOf([&] { regionReport(cloud); }), ErrorCode::InvalidData);
    cloud.field("region_id")->values() = {std::nanf(""), std::nanf(""), std::nanf("")};
    EXPECT_TRUE(regionReport(cloud).empty());
    RegionReportParams params;
    params.distanceField = "missing";
    EXPECT_EQ(test::errorCodeOf([&] { regionReport(cloud, params); }), ErrorCode::InvalidArgument);
    // A one-point region still gets an outline and no crash.
    cloud.field("region_id")->values() = {1.0f, std::nanf(""), std::nanf("")};
    const auto report = regionReport(cloud);
    ASSERT_EQ(report.size(), 1u);
    EXPECT_EQ(report[0].pointCount, 1u);
    EXPECT_EQ(report[0].outlines.size(), 1u);
}
