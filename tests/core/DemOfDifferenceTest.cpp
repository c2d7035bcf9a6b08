// SPDX-License-Identifier: GPL-3.0-or-later
// DEM of difference and 2.5D volume against closed forms: a raised block's
// volume, thresholds, propagated errors, cell statistics, filling.
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/DemOfDifference.h>

#include "TestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

using namespace scandiff;

namespace {

//! Points 0.1 m apart over [0, 10]², at the centres of a 0.1 m lattice (never
//! on the edge of a 0.5 m cell), at the height `z(x, y)`.
PointCloud lattice(const std::function<double(double, double)>& z, const Eigen::Vector3d& origin = Eigen::Vector3d::Zero())
{
    PointCloud cloud;
    cloud.setOrigin(origin);
    for (int i = 0; i < 100; ++i)
        for (int j = 0; j < 100; ++j) {
            const double x = (i + 0.5) * 0.1, y = (j + 0.5) * 0.1;
            cloud.positions().push_back((Eigen::Vector3d(x, y, z(x, y)) - origin).cast<float>());
        }
    return cloud;
}

//! The value of `field` at the cell whose centre is (x, y).
double at(const DemOfDifferenceResult& r, const char* field, double x, double y)
{
    for (std::size_t i = 0; i < r.cells.size(); ++i) {
        const Eigen::Vector3d p = r.cells.globalPosition(i);
        if (std::abs(p.x() - x) < 1e-3 && std::abs(p.y() - y) < 1e-3)
            return r.cells.field(field)->value(i);
    }
    ADD_FAILURE() << "no cell at " << x << ", " << y;
    return 0.0;
}

} // namespace

TEST(DemOfDifference, ARaisedBlockGivesItsVolumeExactly)
{
    // A 2 x 3 m block raised 0.5 m, its sides on cell edges: 24 cells of
    // 0.25 m², 3 m³ of deposition, nothing else.
    // The epochs have different global shifts; the grid is in global coordinates.
    const PointCloud ground = lattice([](double, double) { return 100.0; }, {5, -3, 90});
    const PointCloud raised = lattice([](double x, double y) { return x > 2 && x < 4 && y > 3 && y < 6 ? 100.5 : 100.0; });
    DemOfDifferenceParams params;
    params.cell = 0.5;
    params.propagated = true;
    const DemOfDifferenceResult r = demOfDifference(&ground, raised, params);
    EXPECT_EQ(r.columns, 20u);
    EXPECT_EQ(r.rows, 20u);
    EXPECT_EQ(r.matchingCells, 400u);
    EXPECT_EQ(r.significantCells, 24u);
    EXPECT_NEAR(r.deposition, 3.0, 1e-9);
    EXPECT_EQ(r.erosion, 0.0);
    EXPECT_NEAR(r.added, 3.0, 1e-9);
    EXPECT_EQ(r.removed, 0.0);
    EXPECT_NEAR(r.depositionError, 0.0, 1e-12); // no roughness in either epoch
    EXPECT_NEAR(at(r, fields::kDodDifference, 2.25, 3.25), 0.5, 1e-9);
    EXPECT_EQ(at(r, fields::kDodSignificant, 2.25, 3.25), 1.0);
    EXPECT_EQ(at(r, fields::kDodSignificant, 1.75, 3.25), 0.0);
    EXPECT_EQ(at(r, fields::kRasterCol, 2.25, 3.25), 4.0);
    EXPECT_EQ(at(r, fields::kRasterRow, 2.25, 3.25), 6.0);
    // The report says the same.
    const Table report = r.report();
    ASSERT_EQ(report.rows.size(), 13u);
    EXPECT_EQ(std::get<std::string>(report.rows[6][0]), "deposition");
    EXPECT_NEAR(std::get<double>(report.rows[6][1]), 3.0, 1e-9);
}

TEST(DemOfDifference, ThresholdsAndPropagatedErrors)
{
    const PointCloud ground = lattice([](double, double) { return 0.0; });
    const PointCloud up5 = lattice([](double, double) { return 0.05; });
    const PointCloud up6 = lattice([](double, double) { return 0.06; });
    DemOfDifferenceParams params;
    params.cell = 0.5;
    params.lod = 0.1;
    EXPECT_EQ(demOfDifference(&ground, up5, params).significantCells, 0u);
    params.lod = 0.01;
    const DemOfDifferenceResult all = demOfDifference(&ground, up5, params);
    EXPECT_EQ(all.significantCells, 400u);
    EXPECT_NEAR(all.deposition, 0.05 * 100.0, 1e-6);
    // Propagated: δz = 0.02 in each epoch, LoD = 1.96 √2 0.02 = 0.0554 m.
    params.lod.reset();
    params.propagated = true;
    params.heightError = 0.02;
    EXPECT_EQ(demOfDifference(&ground, up5, params).significantCells, 0u);
    const DemOfDifferenceResult six = demOfDifference(&ground, up6, params);
    EXPECT_EQ(six.significantCells, 400u);
    EXPECT_NEAR(at(six, fields::kDodLod, 0.25, 0.25), 1.96 * std::sqrt(2.0) * 0.02, 1e-7); // a float field
    // 400 independent cells of 0.25 m², each σ = √2 0.02: √400 x 0.25 x σ.
    EXPECT_NEAR(six.depositionError, 20 * 0.25 * std::sqrt(2.0) * 0.02, 1e-9);
    // Roughness as δz: in a cell, 3 columns of 5 points at +0.01 and 2 at
    // -0.01: mean 0.002, δz = √(0.0001 - 0.002²) (the flat epoch adds none).
    const PointCloud rough = lattice([](double x, double) { return std::fmod(std::floor(x * 10), 2.0) == 0 ? 0.01 : -0.01; });
    params.heightError.reset();
    EXPECT_NEAR(at(demOfDifference(&rough, up6, params), fields::kDodLod, 0.25, 0.25), 1.96 * std::sqrt(0.0001 - 0.002 * 0.002), 1e-6);
}

TEST(DemOfDifference, CellStatisticsFillingAndAConstantReference)
{
    // One cell holds heights 1, 2, 3 and 10.
    PointCloud cell;
    for (double z : {1.0, 2.0, 3.0, 10.0})
        cell.positions().emplace_back(0.1f, 0.1f, static_cast<float>(z));
    cell.positions().emplace_back(0.9f, 0.1f, 0.0f); // a second cell, so the grid is 2 wide
    DemOfDifferenceParams params;
    params.cell = 0.5;
    params.referenceHeight = 0.0;
    const std::pair<CellStatistic, double> expected[] = {
        {CellStatistic::Min, 1.0}, {CellStatistic::Mean, 4.0}, {CellStatistic::Max, 10.0}, {CellStatistic::Median, 2.5}};
    for (const auto& [statistic, z] : expected) {
        params.statistic = statistic;
        EXPECT_NEAR(at(demOfDifference(nullptr, cell, params), fields::kDodDifference, 0.25, 0.25), z, 1e-6);
    }
    EXPECT_EQ(parseCellStatistic("median"), CellStatistic::Median);

    // A hole of one cell at (2.25, 2.25): empty, then filled from its 8
    // neighbours (all at 1 m) by one pass.
    const PointCloud holed = [] {
        PointCloud c = lattice([](double, double) { return 1.0; });
        std::vector<std::size_t> keep;
        for (std::size_t i = 0; i < c.size(); ++i) {
            const Eigen::Vector3f& p = c.positions()[i];
            if (!(p.x() > 2 && p.x() < 2.5 && p.y() > 2 && p.y() < 2.5))
                keep.push_back(i);
        }
        return c.subset(keep);
    }();
    params.statistic = CellStatistic::Mean;
    EXPECT_EQ(demOfDifference(nullptr, holed, params).matchingCells, 399u);
    params.fillPasses = 1;
    const DemOfDifferenceResult filled = demOfDifference(nullptr, holed, params);
    EXPECT_EQ(filled.matchingCells, 400u);
    EXPECT_NEAR(at(filled, fields::kDodDifference, 2.25, 2.25), 1.0, 1e-9);
    EXPECT_NEAR(filled.added, 100.0, 1e-6); // 1 m over 10 x 10 m
}

TEST(DemOfDifference, BadParametersAreClearErrors)
{
    const PointCloud ground = lattice([](double, double) { return 0.0; });
    DemOfDifferenceParams params;
    params.cell = 0.0;
    EXPECT_EQ(test::errorCodeOf([&] { demOfDifference(&ground, ground, params); }), ErrorCode::InvalidArgument);
    params.cell = 1e-5; // 10^12 cells
    EXPECT_EQ(test::errorCodeOf([&] { demOfDifference(&ground, ground, params); }), ErrorCode::InvalidArgument);
    params.cell = 1.0;
    EXPECT_EQ(test::errorCodeOf([&] { demOfDifference(nullptr, ground, params); }), ErrorCode::InvalidArgument);
    params.lod = 0.1;
    params.propagated = true;
    EXPECT_EQ(test::errorCodeOf([&] { demOfDifference(&ground, ground, params); }), ErrorCode::InvalidArgument);
    params.lod.reset();
    EXPECT_EQ(test::errorCodeOf([&] { demOfDifference(&ground, PointCloud(), params); }), ErrorCode::InvalidData);
    EXPECT_EQ(test::errorCodeOf([&] { parseCellStatistic("mode"); }), ErrorCode::InvalidArgument);
}

TEST(Rasterise, EachCellGetsItsHeightStatisticCountAndFieldMeans)
{
    // Five points in two 1 m cells of a UTM-like area, one with a NaN value.
    PointCloud cloud;
    cloud.setOrigin({512000, 5400000, 200});
    cloud.positions() = {{0.2f, 0.2f, 1.0f}, {0.7f, 0.4f, 2.0f}, {0.5f, 0.9f, 6.0f}, {1.5f, 0.5f, 3.0f}, {1.6f, 0.6f, 5.0f}};
    ScalarField& distance = cloud.addField("m3c2_distance");
    for (std::size_t i = 0; i < 5; ++i)
        distance.setValue(i, 0.1 * static_cast<double>(i + 1));
    distance.setValue(2, std::numeric_limits<double>::quiet_NaN());
    ScalarField& flag = cloud.addField("m3c2_significant");
    for (std::size_t i = 0; i < 5; ++i)
        flag.setValue(i, i == 0 || i == 3 ? 1.0 : 0.0);
    cloud.setCrsWkt("LOCAL_CS[\"site\"]");

    RasteriseParams params;
    params.cell = 1.0;
    for (CellStatistic statistic : {CellStatistic::Min, CellStatistic::Mean, CellStatistic::Max, CellStatistic::Median}) {
        params.statistic = statistic;
        const PointCloud cells = rasteriseCloud(cloud, params);
        ASSERT_EQ(cells.size(), 2u);
        EXPECT_EQ(cells.crsWkt(), cloud.crsWkt());
        const double expectedFirst[] = {201.0, 203.0, 206.0, 202.0}, expectedSecond[] = {203.0, 204.0, 205.0, 204.0};
        const auto s = static_cast<std::size_t>(statistic);
        for (std::size_t c = 0; c < 2; ++c) {
            const Eigen::Vector3d p = cells.globalPosition(c);
            EXPECT_DOUBLE_EQ(p.x(), 512000.5 + static_cast<double>(c));
            EXPECT_DOUBLE_EQ(p.y(), 5400000.5);
            EXPECT_NEAR(p.z(), c == 0 ? expectedFirst[s] : expectedSecond[s], 1e-4);
            EXPECT_DOUBLE_EQ(cells.field(fields::kCellHeight)->value(c), c == 0 ? expectedFirst[s] : expectedSecond[s]);
            EXPECT_EQ(cells.field(fields::kRasterCol)->value(c), static_cast<double>(c));
            EXPECT_EQ(cells.field(fields::kRasterRow)->value(c), 0.0);
        }
        EXPECT_EQ(cells.field(fields::kPointCount)->value(0), 3.0);
        EXPECT_EQ(cells.field(fields::kPointCount)->value(1), 2.0);
        // The NaN of point 2 is left out of the first cell's mean.
        EXPECT_NEAR(cells.field("m3c2_distance")->value(0), 0.15, 1e-7);
        EXPECT_NEAR(cells.field("m3c2_distance")->value(1), 0.45, 1e-7);
        EXPECT_NEAR(cells.field("m3c2_significant")->value(0), 1.0 / 3.0, 1e-7);
        EXPECT_NEAR(cells.field("m3c2_significant")->value(1), 0.5, 1e-7);
    }
    // A grid is shown by its change, else its height; a plain cloud is no grid.
    params.statistic = CellStatistic::Mean;
    EXPECT_EQ(mainGridField(rasteriseCloud(cloud, params))->name(), "m3c2_distance");
    EXPECT_EQ(mainGridField(cloud), nullptr);
    EXPECT_FALSE(gridCellSize(cloud).has_value());
    EXPECT_DOUBLE_EQ(gridCellSize(rasteriseCloud(cloud, params)).value(), 1.0);

    // Chosen fields only; bad input.
    params.fields = {"m3c2_significant"};
    EXPECT_EQ(rasteriseCloud(cloud, params).field("m3c2_distance"), nullptr);
    EXPECT_EQ(mainGridField(rasteriseCloud(cloud, params))->name(), fields::kCellHeight);
    params.fields = {"nothing"};
    EXPECT_EQ(test::errorCodeOf([&] { rasteriseCloud(cloud, params); }), ErrorCode::InvalidArgument);
    params.fields.clear();
    params.cell = 0;
    EXPECT_EQ(test::errorCodeOf([&] { rasteriseCloud(cloud, params); }), ErrorCode::InvalidArgument);
    params.cell = 1;
    EXPECT_EQ(test::errorCodeOf([&] { rasteriseCloud(PointCloud(), params); }), ErrorCode::InvalidData);
}
