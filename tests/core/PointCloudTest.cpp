// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/core/FieldRange.h>
#include <scandiff/core/Mesh.h>
#include <scandiff/core/PointCloud.h>
#include <scandiff/core/TextLists.h>

#include "TestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <type_traits>

using namespace scandiff;

static_assert(!std::is_copy_constructible_v<PointCloud>, "a cloud is never copied by accident");
static_assert(std::is_nothrow_move_constructible_v<PointCloud>, "a cloud moves cheaply");
static_assert(!std::is_copy_constructible_v<Mesh>, "a mesh is never copied by accident");

namespace {

PointCloud threePoints()
{
    PointCloud c;
    c.name = "three";
    c.resize(3);
    c.positions()[0] = {0, 0, 0};
    c.positions()[1] = {1, 2, 3};
    c.positions()[2] = {-1, 5, 2};
    c.enableColors()[1] = Rgb8{10, 20, 30};
    c.enableNormals()[2] = {0, 0, 1};
    ScalarField& f = c.addField("intensity");
    f.values() = {1.0f, std::nanf(""), 3.0f};
    return c;
}

} // namespace

TEST(PointCloud, GlobalCoordinatesKeepMillimetresWithAnOrigin)
{
    PointCloud c;
    c.setOrigin({512000.0, 5423000.0, 0.0});
    c.resize(1);
    c.positions()[0] = {345.678f, 456.789f, 123.456f};
    const Eigen::Vector3d g = c.globalPosition(0);
    EXPECT_NEAR(g.x(), 512345.678, 1e-4);
    EXPECT_NEAR(g.y(), 5423456.789, 1e-4);
    c.shiftOrigin({512300.0, 5423400.0, 100.0});
    EXPECT_NEAR(c.globalPosition(0).x(), 512345.678, 1e-4);
    EXPECT_NEAR(c.globalPosition(0).z(), 123.456, 1e-4);
}

TEST(PointCloud, SuggestedOriginForGeoreferencedBounds)
{
    BoundingBox local;
    local.min = {-10, -10, 0};
    local.max = {100, 100, 5};
    local.empty = false;
    EXPECT_TRUE(suggestOrigin(local).isZero());
    BoundingBox utm;
    utm.min = {512345.6, 5423456.7, 80};
    utm.max = {513000, 5424000, 120};
    utm.empty = false;
    EXPECT_EQ(suggestOrigin(utm), Eigen::Vector3d(512000, 5423000, 0));
}

TEST(PointCloud, BoundsIgnoreNonFinitePoints)
{
    PointCloud c = threePoints();
    c.positions()[0] = {std::nanf(""), 0, 0};
    const BoundingBox b = c.bounds();
    ASSERT_FALSE(b.empty);
    EXPECT_EQ(b.min, Eigen::Vector3d(-1, 2, 2));
    EXPECT_EQ(b.max, Eigen::Vector3d(1, 5, 3));
    EXPECT_TRUE(PointCloud().bounds().empty);
}

TEST(PointCloud, RemoveNonFinitePointsKeepsAttributesAligned)
{
    PointCloud c = threePoints();
    c.positions()[1] = {INFINITY, 0, 0};
    EXPECT_EQ(c.removeNonFinitePoints(), 1u);
    ASSERT_EQ(c.size(), 2u);
    EXPECT_EQ(c.positions()[1], Eigen::Vector3f(-1, 5, 2));
    EXPECT_EQ(c.normals()[1], Eigen::Vector3f(0, 0, 1));
    EXPECT_EQ(c.field("intensity")->values()[1], 3.0f);
    EXPECT_EQ(c.colors().size(), 2u);
    c.checkConsistency();
}

TEST(PointCloud, SubsetAndCloneCopyEverything)
{
    const PointCloud c = threePoints();
    const PointCloud s = c.subset({2, 1});
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(s.positions()[0], c.positions()[2]);
    EXPECT_EQ(s.colors()[1], (Rgb8{10, 20, 30}));
    EXPECT_EQ(s.normals()[0], Eigen::Vector3f(0, 0, 1));
    EXPECT_TRUE(std::isnan(s.field("intensity")->values()[1]));
    EXPECT_THROW(c.subset({3}), Error);
    const PointCloud copy = c.clone();
    EXPECT_EQ(copy.positions(), c.positions());
    EXPECT_EQ(copy.fields().size(), 1u);
}

TEST(PointCloud, FieldsByName)
{
    PointCloud c = threePoints();
    EXPECT_EQ(c.field("missing"), nullptr);
    ScalarField& d = c.addField("distance");
    EXPECT_EQ(d.size(), 3u);
    EXPECT_TRUE(std::isnan(d.values()[0]));
    EXPECT_EQ(&c.addField("distance"), c.field("distance"));
    EXPECT_THROW(c.addField(ScalarField("wrong", 2)), Error);
    EXPECT_TRUE(c.removeField("distance"));
    EXPECT_FALSE(c.removeField("distance"));
    c.resize(5);
    EXPECT_EQ(c.field("intensity")->size(), 5u);
    EXPECT_EQ(c.colors().size(), 5u);
}

TEST(PointCloud, FieldsAddedAtAPositionKeepTheOrderAroundThem)
{
    PointCloud c = threePoints(); // intensity
    c.addField("distance");
    ScalarField& first = c.addField(ScalarField("first", 3), 0);
    EXPECT_EQ(first.name(), "first");
    c.addField(ScalarField("middle", 3), 2);
    c.addField(ScalarField("last", 3), 99);
    std::vector<std::string> names;
    for (const ScalarField& f : c.fields())
        names.push_back(f.name());
    EXPECT_EQ(names, (std::vector<std::string>{"first", "intensity", "middle", "distance", "last"}));
    // A field of a name already there replaces it where it is.
    ScalarField replacement("middle", 3);
    replacement.setValue(1, 7.0);
    EXPECT_EQ(c.addField(std::move(replacement), 0).value(1), 7.0);
    EXPECT_EQ(c.fields()[2].name(), "middle");
    EXPECT_EQ(c.fields().size(), 5u);
    EXPECT_THROW(c.addField(ScalarField("wrong", 2), 1), Error);
}

TEST(ScalarField, RangeWithOffsetKeepsLargeValuesPrecise)
{
    ScalarField gps("gps_time", 3);
    gps.setOffset(1.2e9);
    gps.setValue(0, 1.2e9 + 0.25);
    gps.setValue(2, 1.2e9 + 10.5);
    const ValueRange r = gps.range();
    EXPECT_EQ(r.validCount, 2u);
    EXPECT_DOUBLE_EQ(r.min, 1.2e9 + 0.25);
    EXPECT_DOUBLE_EQ(r.max, 1.2e9 + 10.5);
    EXPECT_TRUE(std::isnan(ScalarField("empty", 4).range().min));
}

// range() reads a field in blocks on every core, eight lanes at a time: a
// field of several blocks, NaN here and there, the extremes in a middle block
// and in the tail that is not a multiple of eight, against a plain loop.
TEST(ScalarField, RangeOfALargeFieldEqualsAPlainLoop)
{
    const std::size_t n = 5 * 65536 + 13;
    auto bruteForce = [](const ScalarField& f) {
        ValueRange r;
        double lo = INFINITY, hi = -INFINITY;
        for (std::size_t i = 0; i < f.size(); ++i) {
            const double v = f.value(i);
            if (std::isnan(v))
                continue;
            lo = std::min(lo, v);
            hi = std::max(hi, v);
            ++r.validCount;
        }
        if (r.validCount > 0) {
            r.min = lo;
            r.max = hi;
        }
        return r;
    };
    auto expectSame = [](const ValueRange& got, const ValueRange& want) {
        EXPECT_EQ(got.validCount, want.validCount);
        EXPECT_EQ(got.min, want.min);
        EXPECT_EQ(got.max, want.max);
    };

    ScalarField floats("height", n);
    floats.setOffset(100.0);
    std::uint32_t state = 12345;
    for (std::size_t i = 0; i < n; ++i) {
        state = state * 1664525u + 1013904223u;
        floats.setValue(i, i % 7 == 3 ? NAN : 100.0 + (state >> 8) * 1e-3);
    }
    floats.setValue(2 * 65536 + 5, 99.0);    // the lowest, in the third block
    floats.setValue(n - 2, 1e6);             // the highest, in the tail
    ASSERT_FALSE(floats.isDouble());
    const ValueRange r = floats.range();
    expectSame(r, bruteForce(floats));
    EXPECT_EQ(r.min, 99.0);
    EXPECT_EQ(r.max, 100.0 + static_cast<double>(static_cast<float>(1e6 - 100.0)));
    EXPECT_EQ(r.validCount, n - (n + 3) / 7);

    floats.setValue(7, -INFINITY); // infinities are values
    EXPECT_EQ(floats.range().min, -INFINITY);

    // Values only doubles hold: the exact extremes, not the floats'.
    ScalarField ids("pulse", n);
    ids.setOffset(4e9);
    ids.keepDoubles();
    for (std::size_t i = 0; i < n; ++i)
        ids.setValue(i, i % 5 == 0 ? NAN : 4e9 + 1e6 * static_cast<double>((i * 7919) % n) + 1.0);
    ASSERT_TRUE(ids.isDouble());
    expectSame(ids.range(), bruteForce(ids));
    EXPECT_EQ(ids.range().max, 4e9 + 1e6 * static_cast<double>(n - 1) + 1.0);

    const ValueRange none = ScalarField("nothing", n).range();
    EXPECT_EQ(none.validCount, 0u);
    EXPECT_TRUE(std::isnan(none.min) && std::isnan(none.max));
}

TEST(Mesh, ConsistencyAndDegenerateTriangles)
{
    Mesh m;
    m.vertices.resize(4);
    m.vertices.positions() = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}};
    m.triangles = {{0, 1, 2}, {0, 0, 1}, {0, 1, 3}};
    EXPECT_EQ(m.countDegenerateTriangles(), 2u); // a repeated vertex, and three collinear ones
    m.checkConsistency();
    m.triangles.push_back({0, 1, 9});
    EXPECT_THROW(m.checkConsistency(), Error);
}

TEST(FieldRange, SplitKeepsOrderAttributesAndSendsNaNOutside)
{
    PointCloud cloud;
    cloud.resize(6);
    cloud.setOrigin({1000.0, 0.0, 0.0});
    ScalarField& f = cloud.addField("d");
    f.setOffset(100.0);
    const double values[6] = {100.5, 99.0, 101.0, std::nan(""), 100.0, 102.0};
    for (std::size_t i = 0; i < 6; ++i) {
        cloud.positions()[i] = {float(i), 0.0f, 0.0f};
        f.setValue(i, values[i]);
    }
    const FieldRangeSplit split = splitByFieldRange(cloud, "d", 100.0, 101.0);
    ASSERT_EQ(split.inside.size(), 3u);
    ASSERT_EQ(split.outside.size(), 3u);
    EXPECT_EQ(split.inside.positions()[0].x(), 0.0f);
    EXPECT_EQ(split.inside.positions()[1].x(), 2.0f);
    EXPECT_EQ(split.inside.positions()[2].x(), 4.0f);
    EXPECT_EQ(split.outside.positions()[1].x(), 3.0f);
    EXPECT_TRUE(std::isnan(split.outside.field("d")->values()[1]));
    EXPECT_DOUBLE_EQ(split.inside.origin().x(), 1000.0);
    EXPECT_DOUBLE_EQ(split.inside.field("d")->value(0), 100.5);
    EXPECT_EQ(countInRange(*cloud.field("d"), 100.0, 101.0), 3u);
    EXPECT_EQ(test::errorCodeOf([&] { splitByFieldRange(cloud, "none", 0, 1); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(test::errorCodeOf([&] { splitByFieldRange(cloud, "d", 2, 1); }), ErrorCode::InvalidArgument);
}

TEST(TextLists, NumbersWithSpacesAndSignsInAnyLocale)
{
    EXPECT_EQ(parseNumberList(" 1.5, +2 ,-3e2", "test"), (std::vector<double>{1.5, 2, -300}));
    EXPECT_THROW(parseNumberList("1,,2", "test"), Error);
    EXPECT_THROW(parseNumberList("1,2x", "test"), Error);
    EXPECT_THROW(parseNumberList("nan", "test"), Error);
    EXPECT_THROW(parseNumberList("1;2", "test"), Error);
}
