// SPDX-License-Identifier: GPL-3.0-or-later
// Contours (thesis 001 ch. 4) and stone walls (thesis 003): outlines of
// lattices whose Delaunay triangles are known, the inter-means threshold on
// symmetric data, and the synthetic wall and façade of tests/support/WallScenes.h
// measured against their true outlines.
#include <scandiff/core/Error.h>
#include <scandiff/io/DxfWriter.h>
#include <scandiff/plugins/PluginRegistry.h>
#include <scandiff/plugins/contours/PlanarContours.h>
#include <scandiff/plugins/contours/PolygonMeasures.h>
#include <scandiff/plugins/contours/StoneWall.h>
#include <scandiff/plugins/contours/Vectorisation.h>

#include "DxfCheck.h"
#include "TestSupport.h"
#include "WallScenes.h"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <random>
#include <set>

using namespace scandiff;
using namespace scandiff::plugins;

namespace {

//! Lattice points x0..x1 by y0..y1 (pitch 1).
void addLattice(std::vector<Eigen::Vector2d>& points, int x0, int x1, int y0, int y1)
{
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x)
            points.emplace_back(x, y);
}

OutlineParams alpha(double radius)
{
    OutlineParams p;
    p.method = OutlineMethod::Alpha;
    p.threshold = radius;
    return p;
}

bool hasRepeatedVertex(const Ring2d& ring)
{
    std::set<std::pair<double, double>> seen;
    for (const Eigen::Vector2d& q : ring)
        if (!seen.insert({q.x(), q.y()}).second)
            return true;
    return false;
}

//! A truth outline in the fitted plane's coordinates.
Ring2d inPlane(const test::Outline& outline, const test::WallFrame& frame, const PlaneFrame& plane)
{
    Ring2d out;
    for (const Eigen::Vector2d& q : outline)
        out.push_back(plane.toPlane(frame.world(q)));
    return out;
}

//! A 3D polyline in the wall's own (along, up) coordinates.
Ring2d inWall(const std::vector<Eigen::Vector3d>& polyline, const test::WallFrame& frame)
{
    Ring2d out;
    for (const Eigen::Vector3d& p : polyline)
        out.emplace_back((p - frame.origin).dot(frame.along()), (p - frame.origin).z());
    return out;
}

//! The stones found against the true ones, in the fitted wall plane.
struct StoneMatch
{
    std::vector<Polygon2d> model, truth;
    PolygonMatching matching;
};

StoneMatch matchStones(const StoneWallResult& wall, const test::StoneWallScene& scene)
{
    StoneMatch out;
    for (const Stone& stone : wall.stones)
        out.model.push_back({stone.outline2d, {}});
    for (const test::Outline& outline : scene.stones)
        out.truth.push_back({inPlane(outline, scene.frame, wall.wall), {}});
    out.matching = matchPolygons(out.model, out.truth);
    return out;
}

} // namespace

TEST(Outlines, ALatticeAboveItsCircumradiusIsOneSquare)
{
    // Every Delaunay triangle of a unit lattice has circumradius 1/sqrt(2) and
    // longest edge sqrt(2): just above, the outline is the 10 x 10 square
    // through the 40 border points; just below, nothing is kept.
    std::vector<Eigen::Vector2d> points;
    addLattice(points, 0, 10, 0, 10);
    for (const OutlineParams& params : {alpha(0.7072), [] {
             OutlineParams p;
             p.threshold = 1.4143;
             return p;
         }()}) {
        const OutlineResult result = extractOutlines(points, params);
        ASSERT_EQ(result.parts.size(), 1u);
        EXPECT_DOUBLE_EQ(result.parts[0].area, 100.0);
        EXPECT_DOUBLE_EQ(signedArea(result.parts[0].outer), 100.0);
        EXPECT_EQ(result.parts[0].outer.size(), 40u);
        EXPECT_TRUE(result.parts[0].holes.empty());
        EXPECT_EQ(result.parts[0].pointCount, points.size());
        EXPECT_EQ(result.keptTriangles, 200u);
    }
    EXPECT_TRUE(extractOutlines(points, alpha(0.7070)).parts.empty());
}

TEST(Outlines, AHoleIsAClockwiseRingAndTheKneeFindsIt)
{
    // The lattice without its 3 x 3 centre: at alpha 0.75 the lattice
    // triangles at the hole's corners stay, the hole is the octagon through
    // (4,3), (6,3), (7,4) ... (area 16 - 4 x 0.5).
    std::vector<Eigen::Vector2d> points;
    for (int y = 0; y <= 10; ++y)
        for (int x = 0; x <= 10; ++x)
            if (!(x >= 4 && x <= 6 && y >= 4 && y <= 6))
                points.emplace_back(x, y);
    const OutlineResult exact = extractOutlines(points, alpha(0.75));
    ASSERT_EQ(exact.parts.size(), 1u);
    ASSERT_EQ(exact.parts[0].holes.size(), 1u);
    EXPECT_DOUBLE_EQ(signedArea(exact.parts[0].holes[0]), -14.0);
    EXPECT_DOUBLE_EQ(exact.parts[0].area, 86.0);
    EXPECT_EQ(exact.parts[0].holes[0].size(), 12u);
    EXPECT_DOUBLE_EQ(exact.spacing, 1.0);
    // The knee (threshold 0) finds the hole with either criterion.
    for (OutlineMethod method : {OutlineMethod::LongEdges, OutlineMethod::Alpha}) {
        OutlineParams params;
        params.method = method;
        const OutlineResult result = extractOutlines(points, params);
        ASSERT_EQ(result.parts.size(), 1u);
        ASSERT_EQ(result.parts[0].holes.size(), 1u);
        EXPECT_LE(signedArea(result.parts[0].holes[0]), -4.0);
        EXPECT_GT(result.threshold, method == OutlineMethod::LongEdges ? std::sqrt(2.0) : std::sqrt(0.5));
    }
    // Without a gap, the knee keeps every triangle (its floor).
    std::vector<Eigen::Vector2d> full;
    addLattice(full, 0, 10, 0, 10);
    const OutlineResult whole = extractOutlines(full, OutlineParams{});
    ASSERT_EQ(whole.parts.size(), 1u);
    EXPECT_TRUE(whole.parts[0].holes.empty());
    EXPECT_DOUBLE_EQ(whole.parts[0].area, 100.0);
}

TEST(Outlines, TwoPatchesJoinedByOnePointStayTwoOutlines)
{
    // Thesis 003 §III.1.2.1: "two stones joined by a common point". Stones
    // [0,5]² and [8,13]x[0,5], one stray point in the middle of the joint: its
    // small triangles reach both stones, but it joins them by a vertex only,
    // so each stone keeps its own ring and the point is a vertex of both.
    std::vector<Eigen::Vector2d> points;
    addLattice(points, 0, 5, 0, 5);
    addLattice(points, 8, 13, 0, 5);
    const Eigen::Vector2d bridge(6.5, 2.5);
    points.push_back(bridge);
    const OutlineResult result = extractOutlines(points, alpha(0.9));
    ASSERT_EQ(result.parts.size(), 2u);
    for (const OutlinePart& part : result.parts) {
        EXPECT_DOUBLE_EQ(part.area, 25.75); // the stone and the triangle reaching the stray point
        EXPECT_FALSE(hasRepeatedVertex(part.outer));
        EXPECT_EQ(std::count(part.outer.begin(), part.outer.end(), bridge), 1);
    }
    for (std::size_t i = 0; i + 1 < points.size(); ++i)
        EXPECT_EQ(result.partOfPoint[i], result.partOfPoint[i < 36 ? 0 : 36]) << i;
}

TEST(Outlines, SeparatePatchesAndDuplicatesAndBadInput)
{
    std::vector<Eigen::Vector2d> points;
    addLattice(points, 0, 5, 0, 5);
    addLattice(points, 9, 14, 0, 5);
    points.push_back(points[7]); // a duplicate of a first-patch point
    const OutlineResult result = extractOutlines(points, alpha(0.75));
    ASSERT_EQ(result.parts.size(), 2u);
    EXPECT_NE(result.partOfPoint[0], result.partOfPoint[36]);
    EXPECT_EQ(result.partOfPoint.back(), result.partOfPoint[7]);
    EXPECT_GE(result.partOfPoint.back(), 0);

    EXPECT_TRUE(extractOutlines({{0, 0}, {1, 1}}, OutlineParams{}).parts.empty());
    EXPECT_TRUE(extractOutlines({{0, 0}, {1, 1}, {2, 2}, {3, 3}}, OutlineParams{}).parts.empty()); // on a line
    EXPECT_TRUE(extractOutlines({}, OutlineParams{}).parts.empty());
    EXPECT_EQ(test::errorCodeOf([] { extractOutlines({{0, 0}, {1, 0}, {0, std::nan("")}}, OutlineParams{}); }), ErrorCode::InvalidData);
    EXPECT_EQ(test::errorCodeOf([&] { extractOutlines(points, alpha(-1)); }), ErrorCode::InvalidArgument);
    EXPECT_EQ(parseOutlineMethod("alpha"), OutlineMethod::Alpha);
    EXPECT_EQ(test::errorCodeOf([] { parseOutlineMethod("concave"); }), ErrorCode::InvalidArgument);
}

TEST(Outlines, AHoleTouchingTheOutlineCountsAsAHoleInTheMeasures)
{
    // A square ring that passes twice through (0,0) around a clockwise
    // triangle: the triangle is a hole (area 16 - 1.5) in every measure.
    const Polygon2d keyhole{{{0, 0}, {4, 0}, {4, 4}, {0, 4}, {0, 0}, {1, 2}, {2, 1}}, {}};
    EXPECT_DOUBLE_EQ(polygonArea(keyhole), 14.5);
    EXPECT_DOUBLE_EQ(intersectionArea(keyhole, keyhole), 14.5);
    const AreaMeasures self = compareAreas(keyhole, keyhole);
    EXPECT_DOUBLE_EQ(self.quality, 1.0);
    EXPECT_DOUBLE_EQ(self.detection, 1.0);
    // An empty reference is no match, not a crash.
    const PolygonMatching matching = matchPolygons({keyhole}, {Polygon2d{}, keyhole});
    EXPECT_EQ(matching.referenceOfModel[0], 1);
}

TEST(PolygonMeasures, RingsThatCrossOrFoldBackAreNotSimple)
{
    using R = std::vector<Eigen::Vector2d>;
    const Eigen::Vector2d far(672345.0, 6843210.0); // Lambert-93: the tests hold far from the origin
    auto shifted = [&](R ring) {
        for (auto& q : ring)
            q += far;
        return ring;
    };
    EXPECT_FALSE(crossesItself(shifted({{0, 0}, {1, 0}, {1, 1}, {0, 1}})));
    EXPECT_FALSE(crossesItself(shifted({{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}}))); // concave L
    EXPECT_TRUE(crossesItself(shifted({{0, 0}, {1, 1}, {1, 0}, {0, 1}})));                  // bow-tie
    EXPECT_TRUE(crossesItself(shifted({{0, 0}, {2, 0}, {2, 2}, {1, 0}, {0, 2}})));          // a vertex on another edge
    EXPECT_TRUE(crossesItself(shifted({{0, 0}, {2, 0}, {1, 0}, {1, 1}})));                  // an edge folding back
    EXPECT_TRUE(crossesItself(shifted({{0, 0}, {2, 0}, {1, 0}})));                          // a fold-back alone
    EXPECT_FALSE(crossesItself(R{{0, 0}, {1, 0}}));
}

TEST(Outlines, ThePlaneFrameIsOrthonormalAndExactFarFromTheOrigin)
{
    const test::WallFrame frame;
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < 50; ++i)
        for (int j = 0; j < 30; ++j)
            points.push_back(frame.world({0.1 * i, 0.1 * j}, (i + j) % 2 ? 0.004 : -0.004));
    const PlaneFrame plane = fitPlaneFrame(points);
    EXPECT_NEAR(plane.u.dot(plane.v), 0.0, 1e-12);
    EXPECT_NEAR(plane.u.norm(), 1.0, 1e-12);
    EXPECT_NEAR(plane.normal.cross(frame.along().cross(Eigen::Vector3d::UnitZ())).norm(), 0.0, 1e-9);
    EXPECT_NEAR(plane.u.z(), 0.0, 1e-12); // horizontal, and v up
    EXPECT_GT(plane.v.z(), 0.999999);
    EXPECT_NEAR(plane.rms, 0.004, 1e-9);
    const Eigen::Vector3d p = points[123];
    const Eigen::Vector3d projected = p - (p - plane.origin).dot(plane.normal) * plane.normal;
    EXPECT_NEAR((plane.toWorld(plane.toPlane(p)) - projected).norm(), 0.0, 1e-9);
    EXPECT_EQ(test::errorCodeOf([] { fitPlaneFrame({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}); }), ErrorCode::InvalidData);
}

TEST(InterMeans, SymmetricModesGiveTheMidpoint)
{
    // Mirror-symmetric about -1150: the fixed point is exactly the middle.
    std::mt19937 rng(1);
    std::normal_distribution<double> mode(250.0, 40.0);
    std::vector<float> values;
    for (int i = 0; i < 20000; ++i) {
        const double d = std::round(mode(rng)); // integers: exact in float either side
        values.push_back(static_cast<float>(-1150 - d));
        values.push_back(static_cast<float>(-1150 + d));
    }
    const InterMeansThreshold t = interMeansThreshold(values);
    EXPECT_NEAR(t.threshold, -1150.0, 1e-9);
    EXPECT_EQ(t.lowCount, 20000u);
    // Equal Gaussians drawn independently: within 1 % of the separation, from any start between the modes.
    std::vector<float> drawn;
    std::normal_distribution<double> dark(-1400, 40), light(-900, 40);
    for (int i = 0; i < 50000; ++i) {
        drawn.push_back(static_cast<float>(dark(rng)));
        drawn.push_back(static_cast<float>(light(rng)));
    }
    for (double start : {-1350.0, -1150.0, -950.0})
        EXPECT_NEAR(interMeansThreshold(drawn, start).threshold, -1150.0, 5.0) << start;
    EXPECT_EQ(test::errorCodeOf([] { interMeansThreshold({3.0f, 3.0f, std::nanf("")}); }), ErrorCode::InvalidData);
}

TEST(Stones, EveryStoneIsOneClosedPolygonWithin3cmOfItsTruth)
{
    for (bool bright : {false, true}) {
        test::StoneWallOptions options;
        options.brightStones = bright;
        const test::StoneWallScene scene = test::makeStoneWall(options);
        StoneParams params;
        params.polarity = bright ? StonePolarity::Bright : StonePolarity::Dark;
        const StoneWallResult wall = extractStones(scene.cloud, params);
        // Point level (thesis 003 P1, P2).
        std::size_t truePositive = 0, detected = 0, real = 0;
        for (std::size_t i = 0; i < scene.isStone.size(); ++i) {
            truePositive += scene.isStone[i] && wall.stoneClass[i];
            detected += wall.stoneClass[i];
            real += scene.isStone[i];
        }
        EXPECT_GT(static_cast<double>(truePositive) / real, 0.99);
        EXPECT_LT(1.0 - static_cast<double>(truePositive) / detected, 0.01);
        EXPECT_NEAR(wall.threshold, -1150.0, 25.0);
        // Contour level: one polygon per stone, IoU >= 0.8, within 3 cm.
        const auto [model, truth, matching] = matchStones(wall, scene);
        EXPECT_EQ(wall.stones.size(), scene.stones.size()) << (bright ? "bright" : "dark");
        EXPECT_EQ(matching.correct, scene.stones.size());
        for (std::size_t m = 0; m < model.size(); ++m) {
            ASSERT_GE(matching.referenceOfModel[m], 0) << m;
            EXPECT_LE(boundaryHausdorff(model[m].outer, truth[static_cast<std::size_t>(matching.referenceOfModel[m])].outer), 0.03) << m;
            EXPECT_GT(signedArea(model[m].outer), 0.0);
            // Planar, in the wall's plane.
            for (const Eigen::Vector3d& p : wall.stones[m].outline)
                EXPECT_NEAR((p - wall.wall.origin).dot(wall.wall.normal), 0.0, 1e-9);
        }
        EXPECT_GT(wall.isolatedRemoved, 0u);
    }
}

TEST(Stones, RegionGrowingOnIntensityFindsTheSameStones)
{
    const test::StoneWallScene scene = test::makeStoneWall(test::StoneWallOptions{});
    StoneParams params;
    params.method = StoneMethod::Grow;
    const StoneMatch found = matchStones(extractStones(scene.cloud, params), scene);
    EXPECT_EQ(found.matching.correct, scene.stones.size());
    EXPECT_EQ(found.matching.falseRate, 0.0);
}

TEST(Stones, BadInputIsAClearError)
{
    test::StoneWallOptions small;
    small.courses = 1;
    small.stonesPerCourse = 2;
    const test::StoneWallScene scene = test::makeStoneWall(small);
    StoneParams params;
    params.field = "reflectance";
    EXPECT_EQ(test::errorCodeOf([&] { extractStones(scene.cloud, params); }), ErrorCode::InvalidArgument);
    PointCloud two;
    two.resize(2);
    two.addField("intensity");
    EXPECT_EQ(test::errorCodeOf([&] { extractStones(two, StoneParams{}); }), ErrorCode::InvalidData);
    EXPECT_EQ(test::errorCodeOf([] { parseStonePolarity("grey"); }), ErrorCode::InvalidArgument);
    // A wall of one intensity: no threshold separates anything.
    PointCloud flat = scene.cloud.clone();
    std::fill(flat.field("intensity")->values().begin(), flat.field("intensity")->values().end(), 7.0f);
    EXPECT_EQ(test::errorCodeOf([&] { extractStones(flat, StoneParams{}); }), ErrorCode::InvalidData);
    StoneParams thesis;
    thesis.localLevels = false;
    EXPECT_EQ(test::errorCodeOf([&] { extractStones(flat, thesis); }), ErrorCode::InvalidData);
    // Every intensity NaN: nothing to classify, a clear error.
    PointCloud blind = scene.cloud.clone();
    std::fill(blind.field("intensity")->values().begin(), blind.field("intensity")->values().end(), std::nanf(""));
    EXPECT_EQ(test::errorCodeOf([&] { extractStones(blind, StoneParams{}); }), ErrorCode::InvalidData);
    // The thesis's classification with a threshold below every value: one
    // class, no stone and no error, the means at the threshold for the empty one.
    thesis.threshold = -1e9;
    thesis.polarity = StonePolarity::Dark;
    const StoneWallResult none = extractStones(scene.cloud, thesis);
    EXPECT_TRUE(none.stones.empty());
    EXPECT_EQ(none.stoneMean, -1e9);
    // A handful of points, duplicates among them: an answer, not a crash.
    PointCloud few = scene.cloud.subset(std::vector<std::size_t>{0, 1, 2, 3, 4, 5, 5, 5, 6, 7});
    EXPECT_NO_THROW(extractStones(few, StoneParams{}));
    // More cleaning neighbours than the twelve nearest hold: counted in a
    // radius of two median spacings, where at most about 13 others lie, so
    // 40 leaves every point isolated, and 13 fewer than all of them.
    StoneParams many;
    many.cleaningNeighbours = 40;
    const StoneWallResult cleaned = extractStones(scene.cloud, many);
    EXPECT_TRUE(cleaned.stones.empty());
    many.cleaningNeighbours = 13;
    const StoneWallResult some = extractStones(scene.cloud, many);
    EXPECT_GT(some.isolatedRemoved, 0u);
    EXPECT_LT(some.isolatedRemoved, scene.cloud.size() / 2);
}

TEST(Contours, TheFacadeOpeningsAreFoundWithTheirCorners)
{
    // Through the tool, as the CLI and the workbench run it.
    const test::FacadeScene scene = test::makeFacade();
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("contours");
    for (const bool vectorise : {false, true}) {
        ToolResult result = tool.execute(ToolInputs().add("input", scene.cloud), tool.resolve({{"vectorise", vectorise ? "true" : "false"}}), nullptr);
        const Drawing& drawing = std::get<Drawing>(result.find("contours")->data);
        std::vector<Ring2d> rings;
        for (const DrawingPolyline& polyline : drawing.polylines) {
            EXPECT_TRUE(polyline.closed);
            EXPECT_EQ(polyline.layer, "OUTLINE"); // the whole cloud: no segment field
            rings.push_back(inWall(polylineVertices(polyline), scene.frame)); // the arch: points along its arc
        }
        // The wall's outline (with the door's notch) and one ring per opening.
        ASSERT_EQ(rings.size(), 1 + scene.openings.size()) << "vectorise " << vectorise;
        for (std::size_t o = 0; o < scene.openings.size(); ++o) {
            const Polygon2d truth{scene.openings[o], {}};
            double best = 0.0;
            std::size_t match = 0;
            for (std::size_t r = 1; r < rings.size(); ++r) {
                const AreaMeasures m = compareAreas({rings[r], {}}, truth);
                if (m.detection > best) {
                    best = m.detection;
                    match = r;
                }
            }
            EXPECT_GE(best, vectorise ? 0.98 : 0.95) << "opening " << o << " vectorise " << vectorise;
            if (vectorise && o < scene.corners.size())
                for (const Eigen::Vector2d& corner : scene.corners[o]) {
                    double nearest = 1e9;
                    for (const Eigen::Vector2d& q : rings[match])
                        nearest = std::min(nearest, (q - corner).norm());
                    EXPECT_LE(nearest, 0.02) << "opening " << o << " corner " << corner.transpose();
                }
        }
        const auto json = nlohmann::json::parse(std::get<TextDocument>(result.find("document")->data).text);
        ASSERT_EQ(json["planes"].size(), 1u);
        EXPECT_EQ(json["planes"][0]["polygons"][0]["holes"].size(), scene.openings.size());
        if (vectorise) {
            std::size_t arcs = 0;
            for (const auto& hole : json["planes"][0]["polygons"][0]["holes"])
                for (const auto& piece : hole["pieces"])
                    if (piece["type"] == "arc") {
                        ++arcs;
                        EXPECT_NEAR(piece["radius"].get<double>(), 0.5, 0.01);
                    }
            EXPECT_EQ(arcs, 1u);
            // The drawing holds the arch's arc as a bulge in the façade's plane.
            std::size_t bulged = 0;
            for (const DrawingPolyline& polyline : drawing.polylines)
                bulged += std::count_if(polyline.bulges.begin(), polyline.bulges.end(), [](double b) { return b != 0.0; });
            EXPECT_EQ(bulged, 1u);
        }
    }
}

TEST(Contours, NeighbouringPlanesMeetAlongTheirCommonLines)
{
    // A corner of a building at UTM coordinates: two walls at right angles
    // (4 x 3 m and 3 x 3 m) standing on a floor (4 x 3 m), sampled every 2 cm
    // with 1 mm of noise, one primitive_id per plane. Each outline stops
    // short of the shared edges; joined, the vertices there lie on both
    // planes (on the three at the corner) and the two outlines share them.
    const Eigen::Vector3d at(652000.0, 6862000.0, 120.0);
    PointCloud cloud;
    cloud.setOrigin(at);
    std::mt19937 random(4);
    std::normal_distribution<float> noise(0.0f, 0.001f);
    std::vector<Eigen::Vector3f> points;
    std::vector<float> ids;
    auto sample = [&](int id, const Eigen::Vector3f& corner, const Eigen::Vector3f& u, const Eigen::Vector3f& v, float lu, float lv) {
        const Eigen::Vector3f n = u.cross(v);
        for (float a = 0.01f; a < lu; a += 0.02f)
            for (float b = 0.01f; b < lv; b += 0.02f) {
                points.push_back(corner + a * u + b * v + noise(random) * n);
                ids.push_back(static_cast<float>(id));
            }
    };
    sample(0, {0, 0, 0}, Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitZ(), 4.0f, 3.0f); // wall y = 0
    sample(1, {0, 0, 0}, Eigen::Vector3f::UnitY(), Eigen::Vector3f::UnitZ(), 3.0f, 3.0f); // wall x = 0
    sample(2, {0, 0, 0}, Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitY(), 4.0f, 3.0f); // floor z = 0
    cloud.resize(points.size());
    cloud.positions() = points;
    cloud.addField("primitive_id").values() = ids;

    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("contours");
    ToolResult result = tool.execute(ToolInputs().add("input", cloud), tool.resolve({{"vectorise", "true"}}), nullptr);
    const Drawing& drawing = std::get<Drawing>(result.find("contours")->data);
    ASSERT_EQ(drawing.polylines.size(), 3u);
    const auto json = nlohmann::json::parse(std::get<TextDocument>(result.find("document")->data).text);
    EXPECT_GT(json["joined_vertices"].get<std::size_t>(), 0u);
    // Each outline's plane, from the JSON (n.x + d = 0).
    std::map<std::string, std::pair<Eigen::Vector3d, double>> planeOf;
    for (const auto& plane : json["planes"])
        planeOf[plane["layer"].get<std::string>()] = {
            Eigen::Vector3d(plane["normal"][0].get<double>(), plane["normal"][1].get<double>(), plane["normal"][2].get<double>()),
            plane["d"].get<double>()};
    ASSERT_EQ(planeOf.size(), 3u);
    auto onPlanes = [&](const Eigen::Vector3d& p) {
        std::size_t count = 0;
        for (const auto& [layer, plane] : planeOf)
            count += std::abs(plane.first.dot(p) + plane.second) < 1e-6;
        return count;
    };
    // The corner of the three planes: one vertex of each outline, the same point.
    std::vector<Eigen::Vector3d> corners;
    std::size_t shared = 0;
    for (const DrawingPolyline& polyline : drawing.polylines) {
        for (const Eigen::Vector3d& p : polyline.points) {
            const Eigen::Vector3d local = p - at;
            const bool nearCorner = local.norm() < 0.1;
            if (nearCorner) {
                EXPECT_EQ(onPlanes(p), 3u) << local.transpose();
                corners.push_back(p);
            }
            // A vertex along a shared edge (x = 0 or y = 0 or z = 0 for two planes) lies on both.
            const int onEdges = (std::abs(local.x()) < 0.1) + (std::abs(local.y()) < 0.1) + (std::abs(local.z()) < 0.1);
            if (onEdges >= 2) {
                EXPECT_GE(onPlanes(p), 2u) << local.transpose();
                ++shared;
            }
        }
    }
    ASSERT_EQ(corners.size(), 3u);
    EXPECT_EQ(corners[0], corners[1]);
    EXPECT_EQ(corners[1], corners[2]);
    EXPECT_LT((corners[0] - at).norm(), 0.01); // the true corner, within the noise and the spacing
    EXPECT_GE(shared, 9u); // each outline's two ends of each of its two shared edges... and the corner
    // The same run without joining leaves the outlines apart.
    ToolResult apart = tool.execute(ToolInputs().add("input", cloud), tool.resolve({{"vectorise", "true"}, {"join-planes", "false"}}), nullptr);
    std::size_t onTwo = 0;
    for (const DrawingPolyline& polyline : std::get<Drawing>(apart.find("contours")->data).polylines)
        for (const Eigen::Vector3d& p : polyline.points)
            onTwo += onPlanes(p) >= 2;
    EXPECT_EQ(onTwo, 0u);
}

TEST(Contours, TheDrawingPassesAnIndependentDxfAudit)
{
    const test::StoneWallScene scene = test::makeStoneWall(test::StoneWallOptions{});
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& tool = *registry.tools.find("stones");
    ToolResult result = tool.execute(ToolInputs().add("input", scene.cloud), tool.defaults(), nullptr);
    const Drawing& drawing = std::get<Drawing>(result.find("drawing")->data);
    EXPECT_EQ(drawing.polylines.size(), scene.stones.size());
    EXPECT_EQ(drawing.texts.size(), scene.stones.size());
    const std::filesystem::path file = std::filesystem::temp_directory_path() / "scandiff-stones-test.dxf";
    io::writeDrawingDxf(drawing, file);
    const test::DxfCheck check = test::checkDxf(file);
    EXPECT_EQ(check.exitStatus, 0);
    EXPECT_EQ(check.count("POLYLINE@STONES"), static_cast<int>(scene.stones.size()));
    std::filesystem::remove(file);
    const PointCloud& labelled = std::get<PointCloud>(result.find("stones")->data);
    ASSERT_NE(labelled.field("stone_id"), nullptr);
    std::set<int> ids;
    for (float v : labelled.field("stone_id")->values())
        ids.insert(static_cast<int>(v));
    EXPECT_EQ(ids.size(), scene.stones.size() + 1); // and -1
}

TEST(Contours, ComparePolygonsGivesTheThesisMeasures)
{
    // The façade's vectorised model against its true openings, drawn as a
    // reference: every opening found, rho_d >= 0.98; and the reference
    // against itself: every measure at its ideal.
    const test::FacadeScene scene = test::makeFacade();
    const PluginRegistry registry = makePluginRegistry();
    const ToolSpec& contours = *registry.tools.find("contours");
    ToolResult model = contours.execute(ToolInputs().add("input", scene.cloud), contours.resolve({{"vectorise", "true"}}), nullptr);
    const Drawing& modelDrawing = std::get<Drawing>(model.find("contours")->data);
    Drawing reference;
    for (const test::Outline& opening : scene.openings) {
        DrawingPolyline polyline{"OPENINGS", {}, true};
        for (const Eigen::Vector2d& q : opening)
            polyline.points.push_back(scene.frame.world(q));
        reference.polylines.push_back(polyline);
    }
    const ToolSpec& compare = *registry.tools.find("compare-polygons");
    const ToolResult result = compare.execute(ToolInputs().add("input", modelDrawing).add("input", reference), compare.defaults(), nullptr);
    const Table& table = result.table("measures");
    ASSERT_EQ(table.rows.size(), scene.openings.size());
    auto column = [&](const std::string& name) {
        return static_cast<std::size_t>(std::find(table.columns.begin(), table.columns.end(), name) - table.columns.begin());
    };
    for (const auto& row : table.rows) {
        EXPECT_GE(std::get<double>(row[column("detection")]), 0.98);
        EXPECT_GE(std::get<double>(row[column("quality")]), 0.95);
        EXPECT_LT(std::get<double>(row[column("vertex_max")]), 0.05);
    }
    EXPECT_NE(result.summary.find(std::to_string(scene.openings.size()) + " of " + std::to_string(scene.openings.size())), std::string::npos)
        << result.summary;
    const ToolResult self = compare.execute(ToolInputs().add("input", reference).add("input", reference), compare.defaults(), nullptr);
    for (const auto& row : self.table("measures").rows) {
        EXPECT_NEAR(std::get<double>(row[column("detection")]), 1.0, 1e-12);
        EXPECT_NEAR(std::get<double>(row[column("quality")]), 1.0, 1e-12);
        EXPECT_NEAR(std::get<double>(row[column("failure")]), 0.0, 1e-12);
        EXPECT_NEAR(std::get<double>(row[column("vertex_max")]), 0.0, 1e-12);
    }
    EXPECT_EQ(test::errorCodeOf([&] { compare.execute(ToolInputs().add("input", reference), compare.defaults(), nullptr); }),
              ErrorCode::InvalidArgument);
}
