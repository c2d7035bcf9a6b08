// SPDX-License-Identifier: GPL-3.0-or-later
// M3C2 against its definition evaluated by brute force, closed forms on
// planes, the calibration of its level of detection, orientation and Cancel.
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/M3C2.h>
#include <scandiff/core/processing/ProcessingTools.h>
#include <scandiff/core/segmentation/SegmentationParameters.h>

#include "StageWatcher.h"
#include "TestSupport.h"

#include <Eigen/Eigenvalues>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace scandiff;

namespace {

//! A rough, wavy surface over [0, size]², its points relative to `origin`.
PointCloud roughSurface(std::size_t n, double size, double lift, double noise, unsigned seed, const Eigen::Vector3d& origin)
{
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> along(0.0, size);
    std::normal_distribution<double> rough(0.0, noise);
    PointCloud cloud;
    cloud.setOrigin(origin);
    cloud.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const double x = along(random), y = along(random);
        const double z = 0.3 * std::sin(0.7 * x) * std::cos(0.5 * y) + 0.05 * x + lift + rough(random);
        cloud.positions()[i] = (Eigen::Vector3d(500000 + x, 4000000 + y, 120 + z) - origin).cast<float>();
    }
    return cloud;
}

//! A square grid of points `spacing` apart at height z, (2k+1)² points.
PointCloud grid(int k, double spacing, double z)
{
    PointCloud cloud;
    for (int i = -k; i <= k; ++i)
        for (int j = -k; j <= k; ++j)
            cloud.positions().emplace_back(static_cast<float>(i * spacing), static_cast<float>(j * spacing), static_cast<float>(z));
    return cloud;
}

//! The definition of M3C2.h, point by point over every point: the normal from
//! a self-adjoint eigen solver, the cylinder test on each point, mean and σ in
//! index order. Same float inputs as m3c2() (the compared points taken into
//! the reference frame the same way).
struct BruteForce
{
    std::vector<Eigen::Vector3d> normal;
    std::vector<std::size_t> n1, n2;
    std::vector<double> mean1, mean2, std1, std2;
};

BruteForce bruteForce(const PointCloud& reference, const PointCloud& compared, const PointCloud& cores, const M3c2Params& p)
{
    auto frame = [&](const PointCloud& c) {
        std::vector<Eigen::Vector3f> out;
        for (const Eigen::Vector3f& q : c.positions())
            out.push_back((q.cast<double>() + (c.origin() - reference.origin())).cast<float>());
        return out;
    };
    const std::vector<Eigen::Vector3f> ref = frame(reference), cmp = frame(compared), core = frame(cores);
    BruteForce b;
    const double r = p.projectionScale / 2;
    for (const Eigen::Vector3f& cf : core) {
        const Eigen::Vector3d c = cf.cast<double>();
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        std::vector<Eigen::Vector3d> near;
        const float radius = static_cast<float>(p.normalScales.front() / 2);
        for (const Eigen::Vector3f& q : ref)
            if ((q - cf).squaredNorm() <= radius * radius)
                near.push_back((q - cf).cast<double>());
        Eigen::Vector3d normal = Eigen::Vector3d::Zero();
        if (near.size() >= 3) {
            for (const auto& v : near)
                mean += v;
            mean /= static_cast<double>(near.size());
            Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
            for (const auto& v : near)
                cov += (v - mean) * (v - mean).transpose();
            normal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0).normalized();
            if (normal.z() < 0)
                normal = -normal;
        }
        b.normal.push_back(normal);
        auto cylinder = [&](const std::vector<Eigen::Vector3f>& cloud, std::size_t& count, double& m, double& s) {
            std::vector<double> t;
            for (const Eigen::Vector3f& q : cloud) {
                const Eigen::Vector3d v = q.cast<double>() - c;
                const double along = v.dot(normal);
                if (std::abs(along) <= p.maxDepth && v.squaredNorm() - along * along <= r * r)
                    t.push_back(along);
            }
            count = t.size();
            m = s = std::numeric_limits<double>::quiet_NaN();
            if (t.empty())
                return;
            double sum = 0;
            for (double v : t)
                sum += v;
            m = sum / static_cast<double>(t.size());
            double squares = 0;
            for (double v : t)
                squares += (v - m) * (v - m);
            s = std::sqrt(squares / static_cast<double>(t.size()));
        };
        std::size_t a = 0, z = 0;
        double m1, m2, s1, s2;
        cylinder(ref, a, m1, s1);
        cylinder(cmp, z, m2, s2);
        b.n1.push_back(a);
        b.n2.push_back(z);
        b.mean1.push_back(m1);
        b.mean2.push_back(m2);
        b.std1.push_back(s1);
        b.std2.push_back(s2);
    }
    return b;
}

double value(const PointCloud& cloud, const char* field, std::size_t i) { return cloud.field(field)->value(i); }

} // namespace

TEST(M3C2, EqualsTheDefinitionEvaluatedByBruteForceAtEveryCorePoint)
{
    // Two rough epochs with different global shifts; cylinders five times
    // longer than wide (H = 5 r).
    const PointCloud reference = roughSurface(6000, 12.0, 0.0, 0.01, 1, {500000, 4000000, 100});
    PointCloud compared = roughSurface(5000, 12.0, 0.04, 0.015, 2, {500010, 4000003, 90});
    PointCloud cores = reference.subset([] {
        std::vector<std::size_t> every;
        for (std::size_t i = 0; i < 6000; i += 23)
            every.push_back(i);
        return every;
    }());
    M3c2Params params;
    params.normalScales = {1.2};
    params.projectionScale = 0.8;
    params.maxDepth = 2.0;
    params.registrationError = 0.002;
    const M3c2Result result = m3c2(reference, compared, cores, params);
    const BruteForce truth = bruteForce(reference, compared, cores, params);
    const PointCloud& out = result.corePoints;
    ASSERT_EQ(out.size(), cores.size());
    std::size_t significant = 0, measured = 0;
    for (std::size_t i = 0; i < out.size(); ++i) {
        ASSERT_FALSE(truth.normal[i].isZero()) << i;
        EXPECT_LT((out.normals()[i].cast<double>() - truth.normal[i]).norm(), 1e-6) << i;
        ASSERT_EQ(value(out, fields::kM3c2N1, i), static_cast<double>(truth.n1[i])) << i;
        ASSERT_EQ(value(out, fields::kM3c2N2, i), static_cast<double>(truth.n2[i])) << i;
        EXPECT_NEAR(value(out, fields::kM3c2Std1, i), truth.std1[i], 1e-6) << i;
        EXPECT_NEAR(value(out, fields::kM3c2Std2, i), truth.std2[i], 1e-6) << i;
        const double distance = truth.mean2[i] - truth.mean1[i];
        EXPECT_NEAR(value(out, fields::kM3c2Distance, i), distance, 1e-6) << i;
        const double lod = 1.96 * (std::sqrt(truth.std1[i] * truth.std1[i] / truth.n1[i] + truth.std2[i] * truth.std2[i] / truth.n2[i]) +
                                   params.registrationError);
        if (truth.n1[i] < params.minPoints || truth.n2[i] < params.minPoints) {
            EXPECT_TRUE(std::isnan(value(out, fields::kM3c2Uncertainty, i))) << i;
            EXPECT_TRUE(std::isnan(value(out, fields::kM3c2Significant, i))) << i;
            ++measured;
            continue;
        }
        EXPECT_NEAR(value(out, fields::kM3c2Uncertainty, i), lod, 1e-6) << i;
        if (std::abs(std::abs(distance) - lod) > 1e-6) {
            EXPECT_EQ(value(out, fields::kM3c2Significant, i), std::abs(distance) > lod ? 1.0 : 0.0) << i;
        }
        significant += value(out, fields::kM3c2Significant, i) == 1.0;
        measured += 1;
        EXPECT_NEAR(value(out, fields::kM3c2NormalScale, i), 1.2, 1e-6);
    }
    EXPECT_EQ(result.significantCount, significant);
    EXPECT_EQ(result.measuredCount, measured);
    // The compared epoch is 4 cm higher: most core points see it.
    EXPECT_GT(significant, out.size() / 2);
}

TEST(M3C2, APlaneRaisedByHGivesHWithTheCountsOfTheDisc)
{
    // Grids 0.1 m apart, the compared one 0.2 m above: a cylinder of diameter
    // 0.5 holds the grid points (i, j) with i² + j² <= 6.25, 21 of them, in
    // each epoch, with no spread: distance 0.2 and LoD95 = 1.96 x 0.01.
    const PointCloud reference = grid(20, 0.1, 0.0);
    const PointCloud compared = grid(20, 0.1, 0.2);
    const PointCloud cores = grid(5, 0.3, 0.0);
    M3c2Params params;
    params.normalScales = {1.0};
    params.projectionScale = 0.5;
    params.maxDepth = 1.0;
    params.registrationError = 0.01;
    const M3c2Result result = m3c2(reference, compared, cores, params);
    const PointCloud& out = result.corePoints;
    for (std::size_t i = 0; i < out.size(); ++i) {
        EXPECT_LT((out.normals()[i] - Eigen::Vector3f(0, 0, 1)).norm(), 1e-6f) << i;
        EXPECT_NEAR(value(out, fields::kM3c2Distance, i), 0.2, 1e-6) << i;
        EXPECT_EQ(value(out, fields::kM3c2N1, i), 21.0) << i;
        EXPECT_EQ(value(out, fields::kM3c2N2, i), 21.0) << i;
        EXPECT_NEAR(value(out, fields::kM3c2Std1, i), 0.0, 1e-6) << i;
        EXPECT_NEAR(value(out, fields::kM3c2Uncertainty, i), 1.96 * 0.01, 1e-6) << i;
        EXPECT_EQ(value(out, fields::kM3c2Significant, i), 1.0) << i;
    }
    EXPECT_EQ(result.significantCount, out.size());

    // The side of the normal sets the sign; the maximum depth bounds what is seen.
    params.orientation = parseNormalOrientation("-z");
    EXPECT_NEAR(value(m3c2(reference, compared, cores, params).corePoints, fields::kM3c2Distance, 0), -0.2, 1e-6);
    params.orientation = parseNormalOrientation("+z");
    params.maxDepth = 0.15;
    const PointCloud shallow = m3c2(reference, compared, cores, params).corePoints;
    EXPECT_EQ(value(shallow, fields::kM3c2N2, 0), 0.0);
    EXPECT_TRUE(std::isnan(value(shallow, fields::kM3c2Distance, 0)));
    EXPECT_TRUE(std::isnan(value(shallow, fields::kM3c2Significant, 0)));

    // Below the minimum points: a distance, but no LoD nor significance.
    params.maxDepth = 1.0;
    params.minPoints = 22;
    const PointCloud few = m3c2(reference, compared, cores, params).corePoints;
    EXPECT_NEAR(value(few, fields::kM3c2Distance, 0), 0.2, 1e-6);
    EXPECT_TRUE(std::isnan(value(few, fields::kM3c2Uncertainty, 0)));
    EXPECT_TRUE(std::isnan(value(few, fields::kM3c2Significant, 0)));
}

TEST(M3C2, TheLevelOfDetectionIsCalibratedOnNoiseAndSeesAFiveCentimetreShift)
{
    // Two independent samplings of one plane with 4 mm noise. Without any
    // registration error about 5 % of core points pass LoD95 by chance (its
    // definition); with a 1 mm registration error, far fewer. The same plane
    // 5 cm higher is significant almost everywhere.
    auto noisyPlane = [](std::size_t n, double lift, unsigned seed) {
        std::mt19937 random(seed);
        std::uniform_real_distribution<double> along(0.0, 20.0);
        std::normal_distribution<double> noise(0.0, 0.004);
        PointCloud cloud;
        cloud.resize(n);
        for (std::size_t i = 0; i < n; ++i)
            cloud.positions()[i] = Eigen::Vector3d(along(random), along(random), lift + noise(random)).cast<float>();
        return cloud;
    };
    const PointCloud reference = noisyPlane(80000, 0.0, 11);
    const PointCloud same = noisyPlane(80000, 0.0, 12);
    const PointCloud raised = noisyPlane(80000, 0.05, 13);
    PointCloud cores;
    for (int i = 0; i < 40; ++i)
        for (int j = 0; j < 40; ++j)
            cores.positions().emplace_back(1.0f + 0.45f * static_cast<float>(i), 1.0f + 0.45f * static_cast<float>(j), 0.0f);
    M3c2Params params;
    params.normalScales = {1.0};
    params.projectionScale = 0.4;
    params.maxDepth = 0.5;
    const double chance = static_cast<double>(m3c2(reference, same, cores, params).significantCount) / 1600.0;
    EXPECT_GT(chance, 0.02);
    EXPECT_LT(chance, 0.09);
    params.registrationError = 0.001;
    EXPECT_LT(static_cast<double>(m3c2(reference, same, cores, params).significantCount) / 1600.0, 0.05);
    EXPECT_GT(static_cast<double>(m3c2(reference, raised, cores, params).significantCount) / 1600.0, 0.95);
}

TEST(M3C2, MultiScaleKeepsTheMostPlanarScaleAndRobustStatisticsResistOutliers)
{
    // A plane with a 0.5 m step at x = 0: near the step the small scale is
    // planar, the large one straddles it. A few far outliers in the compared
    // epoch pull the mean, not the median.
    PointCloud reference, compared;
    for (int i = -30; i <= 30; ++i)
        for (int j = -30; j <= 30; ++j) {
            const float x = 0.05f * static_cast<float>(i), y = 0.05f * static_cast<float>(j);
            reference.positions().emplace_back(x, y, x < 0 ? 0.0f : 0.5f);
            compared.positions().emplace_back(x, y, (x < 0 ? 0.0f : 0.5f) + 0.1f);
        }
    compared.positions().emplace_back(-0.6f, 0.0f, 0.9f);
    compared.positions().emplace_back(-0.6f, 0.01f, 0.9f);
    PointCloud cores;
    cores.positions().emplace_back(-0.6f, 0.0f, 0.0f);
    M3c2Params params;
    params.normalScales = {0.5, 2.0};
    params.projectionScale = 0.2;
    params.maxDepth = 1.0;
    const PointCloud mean = m3c2(reference, compared, cores, params).corePoints;
    EXPECT_NEAR(value(mean, fields::kM3c2NormalScale, 0), 0.5, 1e-6);
    EXPECT_GT(value(mean, fields::kM3c2Distance, 0), 0.15); // the outliers pull the mean up
    params.robust = true;
    const PointCloud median = m3c2(reference, compared, cores, params).corePoints;
    EXPECT_NEAR(value(median, fields::kM3c2Distance, 0), 0.1, 1e-6);
}

TEST(M3C2, ToolRunsFromTheRegistryAndCancelStopsItAtAnyPoll)
{
    ToolRegistry registry;
    registerProcessingTools(registry);
    const ToolSpec& tool = *registry.find("m3c2");
    const PointCloud reference = roughSurface(20000, 12.0, 0.0, 0.01, 3, {500000, 4000000, 100});
    const PointCloud compared = roughSurface(20000, 12.0, 0.05, 0.01, 4, {500000, 4000000, 100});
    const PointCloud before = reference.clone();
    const ParameterValues values = tool.resolve(
        {{"normal-scale", "1"}, {"projection-scale", "0.5"}, {"max-depth", "1"}, {"core-spacing", "0.3"}});
    const ToolInputs inputs = ToolInputs().add("reference", reference).add("compared", compared);
    test::PollCounter counting;
    const ToolResult result = tool.execute(inputs, values, &counting);
    const PointCloud& out = result.cloud();
    EXPECT_LT(out.size(), reference.size() / 5);
    EXPECT_NE(out.field(fields::kM3c2Distance), nullptr);
    EXPECT_NE(result.summary.find("significant"), std::string::npos);
    const std::size_t polls = counting.polls();
    ASSERT_GE(polls, 3u);
    // The last poll too: the count is the same from run to run.
    for (const std::size_t at : {std::size_t(1), polls / 3, 2 * polls / 3, polls}) {
        test::PollCounter cancel(std::max<std::size_t>(at, 1));
        EXPECT_EQ(test::errorCodeOf([&] { tool.execute(inputs, values, &cancel); }), ErrorCode::Cancelled) << at;
    }
    EXPECT_EQ(reference.positions(), before.positions());
    EXPECT_EQ(reference.fields().size(), before.fields().size());

    // Required scales, no MST orientation, no empty epoch.
    EXPECT_EQ(test::errorCodeOf([&] { tool.resolve({{"normal-scale", "1"}}); }), ErrorCode::InvalidArgument);
    M3c2Params params;
    params.orientation = parseNormalOrientation("mst");
    EXPECT_EQ(test::errorCodeOf([&] { m3c2(reference, compared, reference, params); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { m3c2(reference, PointCloud(), reference, M3c2Params()); }), ErrorCode::InvalidData);
}

TEST(M3C2, SignificantChangeBecomesRegionsWithTheirMeanDistance)
{
    // A 2 x 2 m patch raised 0.3 m in the compared epoch: M3C2 flags it, the
    // segmentation groups the flagged core points into one region, and the
    // region report gives the M3C2 distance, not the flag.
    const PointCloud reference = grid(30, 0.1, 0.0);
    PointCloud compared = grid(30, 0.1, 0.0);
    for (Eigen::Vector3f& p : compared.positions())
        if (p.x() > 0.0f && p.x() < 2.0f && p.y() > 0.0f && p.y() < 2.0f)
            p.z() = 0.3f;
    M3c2Params params;
    params.normalScales = {0.5};
    params.projectionScale = 0.3;
    params.maxDepth = 0.5;
    params.registrationError = 0.01;
    PointCloud cores = m3c2(reference, compared, reference, params).corePoints;
    const ParameterValues values = resolveParameters(
        segmentationParameters(),
        {{"field", fields::kM3c2Significant}, {"above", "0.5"}, {"components", "true"}, {"min-points", "20"},
         {"report-field", fields::kM3c2Distance}},
        "segment");
    attachFields(cores, runSegmentation(cores, values));
    const std::vector<RegionStatistics> regions = regionReport(cores, regionReportSettings(values, nullptr));
    ASSERT_EQ(regions.size(), 1u);
    // The patch's inner points see 0.3; those within the cylinder's radius of
    // its edge see part of it: the mean lies between.
    EXPECT_GT(regions.front().meanDistance, 0.2);
    EXPECT_LE(regions.front().meanDistance, 0.3 + 1e-6);
    EXPECT_NEAR(regions.front().maxDistance, 0.3, 1e-6);

    // The volume along the distances: the region's area in its plane times its
    // mean distance, ± that area times its mean LoD95 (m3c2_uncertainty, taken
    // by default with m3c2_distance), both recomputed here from the points.
    const RegionStatistics& region = regions.front();
    ASSERT_TRUE(region.distanceVolume && region.distanceVolumeUncertainty);
    const ScalarField& ids = *cores.field("region_id");
    const ScalarField& lod = *cores.field(fields::kM3c2Uncertainty);
    double lodSum = 0;
    std::size_t members = 0;
    for (std::size_t i = 0; i < cores.size(); ++i)
        if (ids.hasValue(i) && ids.value(i) == region.id) {
            lodSum += lod.value(i);
            ++members;
        }
    ASSERT_EQ(members, region.pointCount);
    EXPECT_DOUBLE_EQ(*region.distanceVolume, region.outlineArea * region.meanDistance);
    EXPECT_NEAR(*region.distanceVolumeUncertainty, region.outlineArea * lodSum / static_cast<double>(members), 1e-12);
    // Below the true raised volume, 2 x 2 x 0.3 = 1.2 m3, and not far: the
    // outline runs through the outermost flagged core points (inside the
    // patch's edge), and core points near the edge see only part of the rise.
    EXPECT_GT(*region.distanceVolume, 0.6);
    EXPECT_LT(*region.distanceVolume, 1.2);
    EXPECT_GT(*region.distanceVolumeUncertainty, 0.0);

    // An explicit uncertainty field must exist.
    RegionReportParams explicitField = regionReportSettings(values, nullptr);
    explicitField.uncertaintyField = "nothing";
    EXPECT_EQ(test::errorCodeOf([&] { regionReport(cores, explicitField); }), ErrorCode::InvalidArgument);
}

namespace {

//! The points of `cloud` within `reach` (in X and Y) of the box [lo, hi], in order.
PointCloud cropAround(const PointCloud& cloud, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, double reach)
{
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d p = cloud.globalPosition(i);
        if (p.x() >= lo.x() - reach && p.x() <= hi.x() + reach && p.y() >= lo.y() - reach && p.y() <= hi.y() + reach)
            kept.push_back(i);
    }
    return cloud.subset(kept);
}

} // namespace

TEST(M3C2, OnPartsHoldingTheSearchReachGivesTheWholeResultToTheBit)
{
    // scandiff-mpi's tiles: the core points of one square, each epoch cropped
    // to the square grown by the search reach (another octree, other cells,
    // points in another order in memory): the values must not change at all.
    const Eigen::Vector3d origin(500000, 4000000, 100);
    const PointCloud reference = roughSurface(60000, 30, 0.0, 0.01, 11, origin);
    const PointCloud compared = roughSurface(50000, 30, 0.03, 0.01, 12, origin + Eigen::Vector3d(3, -2, 1));
    M3c2Params params;
    params.normalScales = {0.6, 1.5};
    params.projectionScale = 0.7;
    params.maxDepth = 0.8;
    params.orientation = parseNormalOrientation("centroid");
    const M3c2Result whole = m3c2(reference, compared, reference, params);

    const Eigen::Vector2d lo(500010, 4000010), hi(500017, 4000016);
    const double reach = std::max(1.5 / 2, std::hypot(0.7 / 2, 0.8)) + 1e-3;
    std::vector<std::size_t> coreIndex;
    for (std::size_t i = 0; i < reference.size(); ++i) {
        const Eigen::Vector3d p = reference.globalPosition(i);
        if (p.x() >= lo.x() && p.x() < hi.x() && p.y() >= lo.y() && p.y() < hi.y())
            coreIndex.push_back(i);
    }
    ASSERT_GT(coreIndex.size(), 1000u);
    // The centroid rule looks at every core point: the whole set's, given.
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3f& p : reference.positions())
        centroid += p.cast<double>();
    params.orientation.centroid = centroid / static_cast<double>(reference.size());
    const M3c2Result part = m3c2OnParts(cropAround(reference, lo, hi, reach), cropAround(compared, lo, hi, reach),
                                        reference.subset(coreIndex), params);
    const PointCloud& a = part.corePoints;
    const PointCloud& b = whole.corePoints;
    std::size_t measured = 0;
    for (std::size_t j = 0; j < coreIndex.size(); ++j) {
        const std::size_t i = coreIndex[j];
        ASSERT_EQ(a.normals()[j], b.normals()[i]) << j;
        for (const char* name : {fields::kM3c2Distance, fields::kM3c2Uncertainty, fields::kM3c2Significant, fields::kM3c2N1,
                                 fields::kM3c2N2, fields::kM3c2Std1, fields::kM3c2Std2, fields::kM3c2NormalScale}) {
            const float x = a.field(name)->values()[j], y = b.field(name)->values()[i];
            ASSERT_TRUE(x == y || (std::isnan(x) && std::isnan(y))) << name << " of core point " << j << ": " << x << " vs " << y;
        }
        measured += !std::isnan(a.field(fields::kM3c2Distance)->values()[j]);
    }
    EXPECT_GT(measured, coreIndex.size() * 9 / 10);

    // An empty compared part: normals all the same, no distance.
    const M3c2Result empty = m3c2OnParts(cropAround(reference, lo, hi, reach), PointCloud(), reference.subset(coreIndex), params);
    EXPECT_EQ(empty.measuredCount, 0u);
    EXPECT_EQ(empty.corePoints.normals()[0], b.normals()[coreIndex[0]]);
}
