// SPDX-License-Identifier: GPL-3.0-or-later
// Merge, transform, crop and scalar-field operations.
#include "SyntheticClouds.h"
#include "TestSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/processing/CloudEditing.h>
#include <scandiff/core/processing/CrossSections.h>
#include <scandiff/core/processing/FieldOperations.h>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <gtest/gtest.h>

#include <random>

using namespace scandiff;

TEST(Transform, TransformAndInverseGiveThePointsBack)
{
    // A georeferenced cloud (UTM-like shift) with normals, a field and a sensor.
    PointCloud cloud = test::randomPlaneCloud(2000, 50.0, 5);
    cloud.setOrigin(Eigen::Vector3d(512000, 5403000, 120));
    for (std::size_t i = 0; i < cloud.size(); ++i)
        cloud.positions()[i].z() = static_cast<float>(0.1 * i / 2000.0);
    cloud.enableNormals().assign(cloud.size(), Eigen::Vector3f::UnitZ());
    SensorPose pose;
    pose.position = Eigen::Vector3d(512010, 5403010, 125);
    cloud.sensors().push_back(pose);
    const Eigen::Vector3d centre(512025, 5403025, 120);
    const Eigen::Matrix4d m = rotationAbout(Eigen::Vector3d(0.2, 0.3, 1), 37.5, centre) * scaleAbout(1.7, centre) *
                              translation(Eigen::Vector3d(3, -2, 0.5));
    const PointCloud moved = transformCloud(cloud, m, "test");
    const PointCloud back = transformCloud(moved, m.inverse(), "inverse");
    const double shift = cloud.origin().norm();
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        // The moved point is where the matrix says, to the float32 step of a
        // local coordinate within a kilometre of its origin (0.06 mm).
        const Eigen::Vector4d g(cloud.globalPosition(i).x(), cloud.globalPosition(i).y(), cloud.globalPosition(i).z(), 1);
        EXPECT_LT((moved.globalPosition(i) - (m * g).head<3>()).norm(), 1.2e-4) << i;
        EXPECT_LT((back.globalPosition(i) - cloud.globalPosition(i)).norm(), 1e-9 * shift) << i;
        EXPECT_LT((back.normals()[i] - cloud.normals()[i]).norm(), 1e-6f) << i;
    }
    // Normals follow the rotation (the scale and the translation do not turn them).
    const Eigen::Vector3d turned = (m.topLeftCorner<3, 3>().inverse().transpose() * Eigen::Vector3d::UnitZ()).normalized();
    EXPECT_LT((moved.normals()[0].cast<double>() - turned).norm(), 1e-6);
    EXPECT_LT((moved.sensors()[0].position - (m * Eigen::Vector4d(512010, 5403010, 125, 1)).head<3>()).norm(), 1e-6);
    // The history keeps both steps.
    ASSERT_EQ(back.transformHistory().size(), 2u);
    EXPECT_EQ(back.transformHistory()[0].matrix, m);
    EXPECT_EQ(back.transformHistory()[1].description, "inverse");

    Eigen::Matrix4d projective = Eigen::Matrix4d::Identity();
    projective(3, 0) = 0.1;
    EXPECT_EQ(test::errorCodeOf([&] { transformCloud(cloud, projective, ""); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { transformCloud(cloud, scaleAbout(1, centre) * 0.0, ""); }), ErrorCode::InvalidArgument);
}

TEST(Transform, UndoMovesBackAndForgetsTheStep)
{
    PointCloud cloud = test::randomPlaneCloud(1000, 50.0, 7);
    cloud.setOrigin(Eigen::Vector3d(512000, 5403000, 120));
    const Eigen::Matrix4d first = translation(Eigen::Vector3d(1, 2, 3));
    const Eigen::Matrix4d second = rotationAbout(Eigen::Vector3d::UnitZ(), 25, Eigen::Vector3d(512020, 5403020, 120));
    const PointCloud once = transformCloud(cloud, first, "first");
    const PointCloud twice = transformCloud(once, second, "registration");
    const PointCloud undone = undoLastTransform(twice);
    ASSERT_EQ(undone.transformHistory().size(), 1u);
    EXPECT_EQ(undone.transformHistory()[0].description, "first");
    // Back to the float steps of the local coordinates of both moves (each
    // 0.06 mm within a kilometre of the origin).
    for (std::size_t i = 0; i < cloud.size(); ++i)
        ASSERT_LT((undone.globalPosition(i) - once.globalPosition(i)).norm(), 2.5e-4) << i;
    const PointCloud original = undoLastTransform(undone);
    EXPECT_TRUE(original.transformHistory().empty());
    EXPECT_EQ(test::errorCodeOf([&] { undoLastTransform(original); }), ErrorCode::InvalidArgument);
}

// A typed or dragged motion (about a UTM centre) and its matrix give each
// other back on 40 seeded draws over every heading, pitch within (-90, 90)
// and any roll; the matrix moves the centre by the offset alone and turns
// about it as Rz Ry Rx would.
TEST(RigidMotion, MatrixAndMotionGiveEachOtherBack)
{
    std::mt19937 random(11);
    std::uniform_real_distribution<double> angle(-180, 180), tilt(-89, 89), offset(-50, 50);
    const Eigen::Vector3d centre(512345.678, 5403210.987, 312.5);
    for (int draw = 0; draw < 40; ++draw) {
        RigidMotion motion;
        motion.offset = Eigen::Vector3d(offset(random), offset(random), offset(random));
        motion.heading = angle(random);
        motion.pitch = tilt(random);
        motion.roll = angle(random);
        const Eigen::Matrix4d m = rigidMotionMatrix(motion, centre);
        EXPECT_NEAR((m.topLeftCorner<3, 3>() * m.topLeftCorner<3, 3>().transpose() - Eigen::Matrix3d::Identity()).norm(), 0, 1e-12);
        const Eigen::Vector3d movedCentre = (m * centre.homogeneous()).head<3>();
        EXPECT_LT((movedCentre - centre - motion.offset).norm(), 1e-8) << draw;
        const Eigen::Vector3d p = centre + Eigen::Vector3d(3, -2, 1);
        const Eigen::Vector3d expected = centre + motion.offset +
                                         (Eigen::AngleAxisd(motion.heading * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                                          Eigen::AngleAxisd(motion.pitch * M_PI / 180, Eigen::Vector3d::UnitY()) *
                                          Eigen::AngleAxisd(motion.roll * M_PI / 180, Eigen::Vector3d::UnitX())) *
                                             Eigen::Vector3d(3, -2, 1);
        EXPECT_LT(((m * p.homogeneous()).head<3>() - expected).norm(), 1e-8) << draw;
        const RigidMotion back = rigidMotionOf(m, centre);
        EXPECT_LT((back.offset - motion.offset).norm(), 1e-8) << draw;
        EXPECT_NEAR(back.heading, motion.heading, 1e-9) << draw;
        EXPECT_NEAR(back.pitch, motion.pitch, 1e-9) << draw;
        EXPECT_NEAR(back.roll, motion.roll, 1e-9) << draw;
    }
    // No motion: the identity.
    EXPECT_EQ(rigidMotionMatrix(RigidMotion{}, centre), Eigen::Matrix4d::Identity());
}

TEST(Merge, CloudsWithDifferentShiftsKeepTheirMillimetres)
{
    PointCloud a = test::randomPlaneCloud(1000, 20.0, 1), b = test::randomPlaneCloud(500, 20.0, 2);
    a.setOrigin(Eigen::Vector3d(512000, 5403000, 0));
    b.setOrigin(Eigen::Vector3d(513000, 5402000, 100)); // another shift, 1.4 km away
    a.addField("intensity");
    for (std::size_t i = 0; i < a.size(); ++i)
        a.field("intensity")->setValue(i, static_cast<double>(i));
    ScalarField& time = b.addField("gps_time");
    time.setOffset(1.3e9);
    for (std::size_t i = 0; i < b.size(); ++i)
        time.setValue(i, 1.3e9 + 0.001 * static_cast<double>(i));
    b.enableColors().assign(b.size(), Rgb8{10, 20, 30});
    const PointCloud merged = mergeClouds({&a, &b});
    ASSERT_EQ(merged.size(), 1500u);
    for (std::size_t i = 0; i < a.size(); ++i)
        EXPECT_LT((merged.globalPosition(i) - a.globalPosition(i)).norm(), 1e-3) << i;
    for (std::size_t i = 0; i < b.size(); ++i)
        EXPECT_LT((merged.globalPosition(a.size() + i) - b.globalPosition(i)).norm(), 1e-3) << i;
    const ScalarField& source = *merged.field(fields::kSourceIndex);
    EXPECT_EQ(source.value(0), 0.0);
    EXPECT_EQ(source.value(1499), 1.0);
    EXPECT_EQ(merged.field("intensity")->value(999), 999.0);
    EXPECT_FALSE(merged.field("intensity")->hasValue(1000)); // b has no intensity
    EXPECT_FALSE(merged.field("gps_time")->hasValue(0));
    EXPECT_NEAR(merged.field("gps_time")->value(1000 + 400), 1.3e9 + 0.4, 1e-4);
    EXPECT_EQ(merged.colors()[0], (Rgb8{255, 255, 255})); // a had none
    EXPECT_EQ(merged.colors()[1000], (Rgb8{10, 20, 30}));
    // Merging the merged cloud again numbers the inputs anew.
    const PointCloud again = mergeClouds({&merged, &a});
    EXPECT_EQ(again.field(fields::kSourceIndex)->value(1400), 0.0);
    EXPECT_EQ(again.field(fields::kSourceIndex)->value(1500), 1.0);
    EXPECT_EQ(test::errorCodeOf([&] { mergeClouds({}); }), ErrorCode::InvalidArgument);
}

TEST(DoubleFields, SubsetMergeAndDroppedPointsKeepEveryDouble)
{
    // A field kept in double: GPS times 37.1234567 s apart, over half an
    // hour, which its float view around the offset keeps to 0.1 ms only.
    auto makeCloud = [](double start, std::size_t n) {
        PointCloud cloud;
        cloud.resize(n);
        ScalarField time("gps_time", n);
        time.setOffset(std::floor(start));
        time.keepDoubles();
        for (std::size_t i = 0; i < n; ++i) {
            cloud.positions()[i] = Eigen::Vector3f(static_cast<float>(i), 0.0f, 0.0f);
            time.setValue(i, start + static_cast<double>(i) * 37.1234567);
        }
        cloud.addField(std::move(time));
        return cloud;
    };
    const PointCloud a = makeCloud(1.4e9 + 0.5, 50);
    const PointCloud b = makeCloud(1.5e9 + 0.25, 30);
    const ScalarField& ta = *a.field("gps_time");
    ASSERT_NE(ta.offset() + static_cast<double>(ta.values()[40]), ta.value(40)); // the float view alone loses it
    EXPECT_EQ(ta.value(40), 1.4e9 + 0.5 + 40 * 37.1234567);

    const PointCloud some = a.subset({7, 3, 49});
    EXPECT_EQ(some.field("gps_time")->value(0), ta.value(7));
    EXPECT_EQ(some.field("gps_time")->value(2), ta.value(49));

    // Merged around one offset, 1e8 s from b's times: still every bit.
    const PointCloud merged = mergeClouds({&a, &b});
    const ScalarField& tm = *merged.field("gps_time");
    ASSERT_TRUE(tm.isDouble());
    for (std::size_t i = 0; i < 50; ++i)
        EXPECT_EQ(tm.value(i), ta.value(i)) << i;
    for (std::size_t i = 0; i < 30; ++i)
        EXPECT_EQ(tm.value(50 + i), b.field("gps_time")->value(i)) << i;

    PointCloud holed = a.clone();
    holed.positions()[4].y() = std::numeric_limits<float>::infinity();
    ASSERT_EQ(holed.removeNonFinitePoints(), 1u);
    EXPECT_EQ(holed.field("gps_time")->value(4), ta.value(5));
    EXPECT_EQ(holed.field("gps_time")->size(), 49u);

    // A value written through the float view wins over its stale double, and
    // the range is the doubles' own.
    ScalarField& edited = *holed.field("gps_time");
    edited.values()[0] = 100000.0f;
    EXPECT_EQ(edited.value(0), edited.offset() + 100000.0);
    EXPECT_EQ(edited.value(1), ta.value(1));
    EXPECT_EQ(edited.range().min, ta.value(1));
    EXPECT_EQ(edited.range().max, edited.offset() + 100000.0);
    // The smallest exact form: none when the float holds every value, float
    // residuals when they do (GPS times), else doubles.
    ScalarField small("small", 3);
    small.keepDoubles();
    small.setValue(0, 0.5);
    small.setValue(1, 2.0);
    EXPECT_FALSE(small.compact());
    EXPECT_FALSE(small.isDouble());
    EXPECT_EQ(small.value(0), 0.5);
    ScalarField times = ta.subset({0, 40, 49});
    times.keepDoubles();
    EXPECT_TRUE(times.compact());
    EXPECT_TRUE(times.doubles().empty());
    EXPECT_EQ(times.residuals().size(), 3u);
    EXPECT_EQ(times.value(1), ta.value(40));
    ScalarField tenths("tenths", 2);
    tenths.keepDoubles();
    tenths.setValue(0, 0.1 + 1e-12); // 53 bits: no float pair holds it
    EXPECT_TRUE(tenths.compact());
    EXPECT_FALSE(tenths.doubles().empty());
    EXPECT_EQ(tenths.value(0), 0.1 + 1e-12);
    // A residual field given a value its residual cannot hold turns to doubles.
    times.setValue(2, 0.1 + 1e-12);
    EXPECT_FALSE(times.doubles().empty());
    EXPECT_EQ(times.value(2), 0.1 + 1e-12);
    EXPECT_EQ(times.value(1), ta.value(40));
}

TEST(Crop, ScreenPolygonsEqualBruteForceInTopAndPerspectiveViews)
{
    PointCloud cloud = test::randomPlaneCloud(3000, 10.0, 9);
    cloud.setOrigin(Eigen::Vector3d(600000, 4000000, 10));
    for (std::size_t i = 0; i < cloud.size(); ++i)
        cloud.positions()[i].z() = static_cast<float>(i % 7);
    // A top view, 50 pixels per metre, screen y downwards, the scan's corner at pixel (100, 600).
    Eigen::Matrix4d top = Eigen::Matrix4d::Identity();
    top(0, 0) = 50, top(0, 3) = 100 - 50 * 600000.0;
    top(1, 1) = -50, top(1, 3) = 600 + 50 * 4000000.0;
    const std::vector<Eigen::Vector2d> lShape{{100, 600}, {400, 600}, {400, 500}, {200, 500}, {200, 300}, {100, 300}};
    const std::vector<std::size_t> inside = pointsInScreenPolygon(cloud, top, lShape);
    std::vector<std::size_t> expected;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const double x = cloud.globalPosition(i).x() - 600000, y = cloud.globalPosition(i).y() - 4000000;
        if ((x > 0 && x < 6 && y > 0 && y < 2) || (x > 0 && x < 2 && y > 0 && y < 6))
            expected.push_back(i);
    }
    EXPECT_EQ(inside, expected); // the same L as the crop's, drawn on the screen
    EXPECT_FALSE(inside.empty());

    // A perspective view looking down from 20 m above the scan's middle:
    // (x, y, z) -> (f x / d, f y / d) with d = 30 - z the depth; points behind it are out.
    Eigen::Matrix4d perspective = Eigen::Matrix4d::Zero();
    const double f = 500;
    perspective(0, 0) = f, perspective(0, 3) = -f * 600005.0;
    perspective(1, 1) = f, perspective(1, 3) = -f * 4000005.0;
    perspective(3, 2) = -1, perspective(3, 3) = 30 + 10; // w = 30 - (z - 10): the eye at global z 40
    const std::vector<Eigen::Vector2d> square{{-100, -100}, {100, -100}, {100, 100}, {-100, 100}};
    const std::vector<std::size_t> seen = pointsInScreenPolygon(cloud, perspective, square);
    expected.clear();
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d g = cloud.globalPosition(i);
        const double depth = 40 - g.z();
        const double u = f * (g.x() - 600005) / depth, v = f * (g.y() - 4000005) / depth;
        if (u > -100 && u < 100 && v > -100 && v < 100)
            expected.push_back(i);
    }
    EXPECT_EQ(seen, expected);
    perspective(3, 3) = 10 - 100; // the eye below everything, looking the other way: nothing is in front
    EXPECT_TRUE(pointsInScreenPolygon(cloud, perspective, square).empty());
    EXPECT_EQ(test::errorCodeOf([&] { pointsInScreenPolygon(cloud, top, {{0, 0}, {1, 1}}); }), ErrorCode::InvalidArgument);
}

TEST(CrossSections, SlabsHoldExactlyTheirPointsAndOutlineTheSection)
{
    // A solid block 4 x 2 x 1 m sampled every 5 cm, at UTM coordinates.
    PointCloud block;
    block.setOrigin({512000, 5403000, 300});
    for (int i = 0; i <= 80; ++i)
        for (int j = 0; j <= 40; ++j)
            for (int k = 0; k <= 20; ++k)
                block.positions().emplace_back(0.05f * i, 0.05f * j, 0.05f * k);
    CrossSectionParams params;
    params.axis = 0;
    params.thickness = 0.06; // one layer of points per slab
    params.step = 1.0;
    params.first = 512000.5;
    params.last = 512003.5;
    const std::vector<CrossSection> sections = crossSections(block, params);
    ASSERT_EQ(sections.size(), 4u);
    for (std::size_t s = 0; s < sections.size(); ++s) {
        EXPECT_DOUBLE_EQ(sections[s].position, 512000.5 + static_cast<double>(s));
        std::vector<std::size_t> expected;
        for (std::size_t i = 0; i < block.size(); ++i)
            if (std::abs(block.globalPosition(i).x() - sections[s].position) <= 0.03)
                expected.push_back(i);
        ASSERT_EQ(sections[s].indices, expected);
        EXPECT_EQ(expected.size(), 41u * 21u);
        // The section of the block: a 2 x 1 m rectangle, in the slab's middle plane.
        EXPECT_NEAR(sections[s].area, 2.0, 1e-4);
        ASSERT_EQ(sections[s].outlines.size(), 1u);
        for (const Eigen::Vector3d& v : sections[s].outlines[0])
            ASSERT_DOUBLE_EQ(v.x(), sections[s].position);
    }
    // Slabs thicker than the step share points; a range of no slab and a bad axis are refused.
    params.thickness = 1.5;
    EXPECT_GT(crossSections(block, params)[1].indices.size(), 41u * 21u * 20u);
    params.axis = 3;
    EXPECT_EQ(test::errorCodeOf([&] { crossSections(block, params); }), ErrorCode::InvalidArgument);
    params.axis = 0;
    params.step = 1e-9;
    EXPECT_EQ(test::errorCodeOf([&] { crossSections(block, params); }), ErrorCode::InvalidArgument);
}

TEST(Crop, OrientedBoxTextRoundTrips)
{
    const CropBox box = parseOrientedBox("512345.5,5403210.25,312.75,40,25,300,30,5,-10");
    EXPECT_NEAR(box.size.y(), 25.0, 1e-12);
    const CropBox back = parseOrientedBox(orientedBoxText(box));
    EXPECT_LT((back.centre - box.centre).norm(), 1e-4);
    EXPECT_LT((back.size - box.size).norm(), 1e-4);
    EXPECT_LT((back.rotation - box.rotation).norm(), 1e-6);
    EXPECT_EQ(test::errorCodeOf([] { parseOrientedBox("1,2,3,4,5"); }), ErrorCode::InvalidArgument);
}

TEST(Crop, BoxesAndPolygonsEqualBruteForce)
{
    PointCloud cloud = test::randomPlaneCloud(3000, 10.0, 9);
    cloud.setOrigin(Eigen::Vector3d(600000, 4000000, 10));
    for (std::size_t i = 0; i < cloud.size(); ++i)
        cloud.positions()[i].z() = static_cast<float>(i % 7);
    CropBox box;
    box.centre = Eigen::Vector3d(600004, 4000005, 13);
    box.size = Eigen::Vector3d(3, 4, 2);
    box.rotation = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const std::vector<std::size_t> inBox = pointsInBox(cloud, box);
    std::vector<std::size_t> expected;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d local = box.rotation.transpose() * (cloud.globalPosition(i) - box.centre);
        if ((local.array().abs() <= (box.size / 2).array()).all())
            expected.push_back(i);
    }
    EXPECT_EQ(inBox, expected);
    EXPECT_FALSE(inBox.empty());

    // A concave L-shaped polygon seen along z.
    CropPolygon polygon;
    polygon.axis = 2;
    for (const auto& [x, y] : std::vector<std::pair<double, double>>{{0, 0}, {6, 0}, {6, 2}, {2, 2}, {2, 6}, {0, 6}})
        polygon.vertices.emplace_back(600000 + x, 4000000 + y);
    const std::vector<std::size_t> inPolygon = pointsInPolygon(cloud, polygon);
    expected.clear();
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const double x = cloud.globalPosition(i).x() - 600000, y = cloud.globalPosition(i).y() - 4000000;
        if ((x > 0 && x < 6 && y > 0 && y < 2) || (x > 0 && x < 2 && y > 0 && y < 6))
            expected.push_back(i);
    }
    EXPECT_EQ(inPolygon, expected);
    const std::vector<std::size_t> outside = complementOf(inPolygon, cloud.size());
    EXPECT_EQ(outside.size() + inPolygon.size(), cloud.size());
    polygon.vertices.resize(2);
    EXPECT_EQ(test::errorCodeOf([&] { pointsInPolygon(cloud, polygon); }), ErrorCode::InvalidArgument);
}

TEST(FieldOperations, ExpressionsOverFieldsCoordinatesAndColours)
{
    PointCloud cloud = test::randomPlaneCloud(5000, 1.0, 4);
    cloud.setOrigin(Eigen::Vector3d(512000, 5403000, 0));
    ScalarField& d = cloud.addField("C2C absolute distances");
    for (std::size_t i = 0; i < cloud.size(); ++i)
        d.setValue(i, i % 10 == 0 ? std::nan("") : 0.001 * static_cast<double>(i));
    cloud.enableColors().assign(cloud.size(), Rgb8{100, 50, 0});
    const auto [name, expression] = parseFieldAssignment("change = C2C_absolute_distances > 2 ? 1 : -x + x + r / 50");
    EXPECT_EQ(name, "change");
    const ScalarField result = evaluateFieldExpression(cloud, expression, name);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (i % 10 == 0) {
            EXPECT_FALSE(result.hasValue(i)) << i; // no value in, no value out
            continue;
        }
        EXPECT_NEAR(result.value(i), 0.001 * i > 2 ? 1.0 : 2.0, 1e-6) << i;
    }
    // Global coordinates in double: x - 512000 keeps the millimetres.
    const ScalarField x = evaluateFieldExpression(cloud, "x - 512000", "dx");
    for (std::size_t i = 0; i < cloud.size(); i += 101)
        EXPECT_NEAR(x.value(i), cloud.positions()[i].x(), 1e-6);
    // A large result is the double the expression gives, exactly: kept in
    // float residuals or doubles where the floats around the offset are not.
    const ScalarField big = evaluateFieldExpression(cloud, "y", "y");
    for (std::size_t i = 0; i < cloud.size(); ++i)
        ASSERT_EQ(big.value(i), cloud.globalPosition(i).y()) << i;
    ScalarField& id = cloud.addField("id");
    for (std::size_t i = 0; i < cloud.size(); ++i)
        id.setValue(i, static_cast<double>(i));
    const ScalarField pulse = evaluateFieldExpression(cloud, "id * 1000000 + 4000000000", "pulse");
    EXPECT_TRUE(pulse.isDouble());
    for (std::size_t i = 0; i < cloud.size(); ++i)
        ASSERT_EQ(pulse.value(i), 1e6 * static_cast<double>(i) + 4e9) << i;
    // What floats hold stays float only.
    EXPECT_FALSE(evaluateFieldExpression(cloud, "id / 4", "quarter").isDouble());
    // Comparisons are not assignments.
    EXPECT_EQ(parseFieldAssignment("a = b >= 2").second, "b >= 2");
    EXPECT_EQ(test::errorCodeOf([&] { parseFieldAssignment("a == b"); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { evaluateFieldExpression(cloud, "unknown_field * 2", "z"); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { evaluateFieldExpression(cloud, "x +* 2", "z"); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(expressionName("3d dist."), "_3d_dist_");
    // Two fields with one expression name, or a field named like a coordinate:
    // refused when the expression uses the name, harmless otherwise.
    PointCloud clash = cloud.clone();
    clash.addField("a b");
    clash.addField("a_b");
    clash.addField("x");
    EXPECT_EQ(test::errorCodeOf([&] { evaluateFieldExpression(clash, "a_b * 2", "t"); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { evaluateFieldExpression(clash, "x + 1", "t"); }), ErrorCode::InvalidArgument);
    EXPECT_NO_THROW(evaluateFieldExpression(clash, "y + 1", "t"));
}

TEST(FieldOperations, GaussianSmoothingKeepsAConstantAndReducesNoise)
{
    PointCloud cloud = test::randomPlaneCloud(20000, 5.0, 8);
    cloud.addField("constant");
    cloud.addField("noise"); // both added before either is held: adding one may move the other
    ScalarField& constant = *cloud.field("constant");
    ScalarField& noise = *cloud.field("noise");
    std::mt19937 rng(1);
    std::normal_distribution<double> g(0.0, 1.0);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        constant.setValue(i, 7.25);
        noise.setValue(i, g(rng));
    }
    const ScalarField smoothConstant = gaussianSmoothing(cloud, "constant", 0.1, "s");
    for (std::size_t i = 0; i < cloud.size(); ++i)
        ASSERT_NEAR(smoothConstant.value(i), 7.25, 1e-5) << i;
    const ScalarField smoothNoise = gaussianSmoothing(cloud, "noise", 0.1, "s");
    double before = 0, after = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        before += noise.value(i) * noise.value(i);
        after += smoothNoise.value(i) * smoothNoise.value(i);
    }
    EXPECT_LT(after, 0.2 * before);
    EXPECT_EQ(test::errorCodeOf([&] { gaussianSmoothing(cloud, "missing", 0.1, "s"); }), ErrorCode::InvalidArgument);
}

TEST(FieldOperations, ColoursHistogramAndChannels)
{
    PointCloud cloud;
    cloud.resize(11);
    ScalarField& f = cloud.addField("v");
    for (std::size_t i = 0; i < 10; ++i)
        f.setValue(i, static_cast<double>(i));
    const ColourScale grey = *ColourScale::preset("Grey");
    const std::vector<Rgb8> colours = coloursFromField(f, grey, 0, 9);
    const auto first = grey.colourAt(0.0), last = grey.colourAt(1.0);
    EXPECT_EQ(colours[0], (Rgb8{first[0], first[1], first[2]}));
    EXPECT_EQ(colours[10], (Rgb8{150, 150, 150})); // no value
    EXPECT_EQ(colours[9], (Rgb8{last[0], last[1], last[2]}));

    const Table histogram = fieldHistogram(f, 5);
    ASSERT_EQ(histogram.rows.size(), 5u);
    double total = 0;
    for (const auto& row : histogram.rows)
        total += std::get<double>(row[2]);
    EXPECT_EQ(total, 10.0); // NaN is not counted
    EXPECT_EQ(std::get<double>(histogram.rows.front()[0]), 0.0);
    EXPECT_EQ(std::get<double>(histogram.rows.back()[1]), 9.0);
    const Table ranged = fieldHistogram(f, 2, std::make_pair(0.0, 4.0));
    EXPECT_EQ(std::get<double>(ranged.rows[0][2]), 2.0); // 0, 1
    EXPECT_EQ(std::get<double>(ranged.rows[1][2]), 3.0); // 2, 3, 4
    EXPECT_EQ(test::errorCodeOf([&] { fieldHistogram(f, 0); }), ErrorCode::InvalidArgument);

    cloud.enableColors().assign(cloud.size(), Rgb8{200, 100, 50});
    EXPECT_NEAR(fieldFromColours(cloud, ColourChannel::Luminance, "l").value(0), 0.2126 * 200 + 0.7152 * 100 + 0.0722 * 50, 1e-4);
    EXPECT_EQ(fieldFromColours(cloud, ColourChannel::Green, "g").value(0), 100.0);
    EXPECT_NEAR(fieldFromColours(cloud, ColourChannel::Mean, "m").value(0), 350.0 / 3, 1e-4);
    PointCloud plain;
    plain.resize(2);
    EXPECT_EQ(test::errorCodeOf([&] { fieldFromColours(plain, ColourChannel::Red, "r"); }), ErrorCode::InvalidArgument);
}
