// SPDX-License-Identifier: GPL-3.0-or-later
// Registers the tools "contours" (outlines and openings of planar segments,
// thesis 001 ch. 4) and "stones" (stone-by-stone wall drawing, thesis 003).
#include "ContourTools.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/segmentation/RegionReport.h>
#include <scandiff/plugins/PluginRegistry.h>
#include <scandiff/plugins/contours/PlaneJoining.h>
#include <scandiff/plugins/contours/PlanarContours.h>
#include <scandiff/plugins/contours/StoneWall.h>
#include <scandiff/plugins/contours/Vectorisation.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

namespace scandiff::plugins {

namespace {

nlohmann::json pointJson(const Eigen::Vector3d& p) { return nlohmann::json::array({p.x(), p.y(), p.z()}); }

//! The JSON's points that the plane joining moved, moved too (the same bits: the same computation gave them).
void replaceMovedPoints(nlohmann::json& node, const std::map<std::array<double, 3>, Eigen::Vector3d>& moves)
{
    if (moves.empty())
        return;
    if (node.is_array() && node.size() == 3 && node[0].is_number() && node[1].is_number() && node[2].is_number()) {
        const auto it = moves.find({node[0].get<double>(), node[1].get<double>(), node[2].get<double>()});
        if (it != moves.end())
            node = pointJson(it->second);
        return;
    }
    if (node.is_array() || node.is_object())
        for (auto& child : node)
            replaceMovedPoints(child, moves);
}

nlohmann::json ringJson(const std::vector<Eigen::Vector3d>& ring)
{
    nlohmann::json out = nlohmann::json::array();
    for (const Eigen::Vector3d& p : ring)
        out.push_back(pointJson(p));
    return out;
}

std::vector<Eigen::Vector3d> lift(const PlaneFrame& frame, const Ring2d& ring)
{
    std::vector<Eigen::Vector3d> out;
    out.reserve(ring.size());
    for (const Eigen::Vector2d& q : ring)
        out.push_back(frame.toWorld(q));
    return out;
}

std::string layerName(const char* prefix, long id)
{
    char name[40];
    std::snprintf(name, sizeof name, "%s_%04ld", prefix, id);
    return name;
}

//! "auto" or a positive length.
double thresholdFrom(const std::string& text)
{
    if (text == "auto" || text.empty())
        return 0.0;
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0' || !(value > 0) || !std::isfinite(value))
        throw Error(ErrorCode::InvalidArgument, "contours: --edge-threshold is 'auto' or a length > 0, not '" + text + "'");
    return value;
}

struct Segment
{
    long id = -1;
    std::vector<std::size_t> points;
};

//! The segments to outline: one per value >= 0 of the id field, or the whole
//! cloud when it has no such field.
std::vector<Segment> segmentsOf(const PointCloud& cloud, const std::string& fieldName, std::string& note)
{
    std::vector<Segment> segments;
    const ScalarField* field = fieldName.empty() ? nullptr : cloud.field(fieldName);
    if (!field) {
        Segment all;
        all.points.resize(cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i)
            all.points[i] = i;
        segments.push_back(std::move(all));
        note = "no field '" + fieldName + "': the cloud is one segment";
        return segments;
    }
    std::map<long, std::vector<std::size_t>> byId;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const double v = field->value(i);
        if (std::isfinite(v) && v >= 0)
            byId[std::lround(v)].push_back(i);
    }
    for (auto& [id, points] : byId)
        segments.push_back({id, std::move(points)});
    return segments;
}

//! What the contours tool gives, built plane by plane: the drawing (a layer
//! per plane), the table of rings, the JSON document, and each plane's
//! outline polylines for the joining of neighbouring planes.
class ContoursOutput
{
public:
    ContoursOutput(const ParameterValues& values) : values_(values)
    {
        table_.columns = {"plane", "part", "ring", "vertices", "area", "perimeter", "threshold", "plane_rms"};
    }

    //! One segment: its plane, its outline parts (and holes) above the
    //! smallest area, each ring as it is drawn (vectorised on request).
    //! False when the segment has no plane (fewer than 3 points, or a line).
    bool addSegment(const PointCloud& cloud, const Segment& segment, const OutlineParams& outline)
    {
        std::vector<Eigen::Vector3d> global;
        global.reserve(segment.points.size());
        for (std::size_t i : segment.points)
            global.push_back(cloud.globalPosition(i));
        PlaneFrame frame;
        try {
            frame = fitPlaneFrame(global);
        } catch (const Error&) {
            return false;
        }
        std::vector<Eigen::Vector2d> uv;
        uv.reserve(global.size());
        for (const Eigen::Vector3d& p : global)
            uv.push_back(frame.toPlane(p));
        const OutlineResult parts = extractOutlines(uv, outline);
        const double spacing = parts.spacing;
        largestSpacing_ = std::max(largestSpacing_, spacing);
        outlined_.push_back(OutlinedPlane{frame, {}, {}});
        const double minArea = values_.real("min-area") > 0 ? values_.real("min-area") : 50.0 * spacing * spacing;
        VectoriseParams vector;
        vector.tolerance = values_.real("tolerance") > 0 ? values_.real("tolerance") : std::max(1.5 * spacing, 1e-6);
        vector.edgeOffset = values_.boolean("offset-edges") ? 0.5 * spacing : 0.0;

        nlohmann::json polygons = nlohmann::json::array();
        const std::string layer = segment.id < 0 ? std::string("OUTLINE") : layerName("PLANE", segment.id);
        long partNumber = 0;
        for (const OutlinePart& part : parts.parts) {
            if (part.area < minArea)
                continue;
            std::vector<Ring2d> ringList{part.outer};
            for (const Ring2d& hole : part.holes)
                if (std::abs(signedArea(hole)) >= minArea)
                    ringList.push_back(hole);
            nlohmann::json polygon = {{"holes", nlohmann::json::array()}};
            for (std::size_t r = 0; r < ringList.size(); ++r) {
                nlohmann::json ringDoc = addRing(ringList[r], r == 0, frame, vector, layer);
                table_.rows.push_back({static_cast<double>(segment.id), static_cast<double>(partNumber), std::string(r == 0 ? "outer" : "hole"),
                                       ringDoc["vertex_count"].get<double>(), ringDoc["area"].get<double>(), ringDoc["perimeter"].get<double>(),
                                       parts.threshold, frame.rms});
                ringDoc.erase("vertex_count");
                if (r == 0)
                    polygon["outer"] = ringDoc;
                else
                    polygon["holes"].push_back(ringDoc);
            }
            polygons.push_back(polygon);
            ++partNumber;
        }
        planes_.push_back({{"id", segment.id},
                           {"layer", layer},
                           {"normal", pointJson(frame.normal)},
                           {"d", -frame.normal.dot(frame.origin)},
                           {"points", segment.points.size()},
                           {"plane_rms", frame.rms},
                           {"method", values_.text("method")},
                           {"threshold", parts.threshold},
                           {"polygons", polygons}});
        return true;
    }

    //! Vertices near the lines where neighbouring planes meet moved onto them
    //! (thesis 001 §4.4), in the drawing and the document.
    PlaneJoinResult joinPlanes()
    {
        PlaneJoinResult joined;
        if (!values_.boolean("join-planes") || outlined_.size() < 2)
            return joined;
        PlaneJoinParams join;
        join.tolerance = values_.real("join-tolerance") > 0 ? values_.real("join-tolerance") : std::max(3.0 * largestSpacing_, 1e-6);
        joined = joinNeighbouringPlanes(drawing_, outlined_, join);
        replaceMovedPoints(planes_, joined.moves);
        return joined;
    }

    std::size_t rings() const { return rings_; }
    std::size_t holes() const { return holes_; }
    Drawing takeDrawing() { return std::move(drawing_); }
    Table takeTable() { return std::move(table_); }
    const nlohmann::json& planes() const { return planes_; }

private:
    //! One ring drawn (its corners and arcs as bulges when vectorised, CAD
    //! draws true arcs) and described: its document entry, with its vertex
    //! count beside it for the table.
    nlohmann::json addRing(Ring2d ring, bool outer, const PlaneFrame& frame, const VectoriseParams& vector, const std::string& layer)
    {
        nlohmann::json pieces = nlohmann::json::array();
        DrawingPolyline polyline{layer, {}, true};
        const bool vectorise = values_.boolean("vectorise");
        if (vectorise) {
            const VectorRing vectorised = vectoriseRing(ring, vector);
            ring = vectorised.vertices;
            bool arcs = false;
            for (const VectorPiece& piece : vectorised.pieces) {
                polyline.points.push_back(frame.toWorld(piece.start));
                polyline.bulges.push_back(piece.bulge);
                arcs = arcs || piece.bulge != 0.0;
            }
            if (arcs)
                polyline.normal = frame.normal;
            else
                polyline.bulges.clear();
            for (const VectorPiece& piece : vectorised.pieces) {
                nlohmann::json p = {{"type", pieceKindName(piece.kind)},
                                    {"start", pointJson(frame.toWorld(piece.start))},
                                    {"end", pointJson(frame.toWorld(piece.end))}};
                if (piece.kind == PieceKind::Arc) {
                    p["centre"] = pointJson(frame.toWorld(piece.centre));
                    p["radius"] = piece.radius;
                    p["sagitta"] = piece.sagitta;
                    p["bulge"] = piece.bulge;
                }
                pieces.push_back(p);
            }
        }
        const std::vector<Eigen::Vector3d> lifted = lift(frame, ring);
        if (polyline.points.size() < 3) { // not vectorised, or a ring too small to split
            polyline.points = lifted;
            polyline.bulges.clear();
        }
        (outer ? outlined_.back().outer : outlined_.back().holes).push_back(drawing_.polylines.size());
        drawing_.polylines.push_back(std::move(polyline));
        const double area = std::abs(signedArea(ring)), perimeter = ringPerimeter(ring);
        nlohmann::json ringDoc = {{"vertices", ringJson(lifted)}, {"area", area}, {"perimeter", perimeter}};
        if (vectorise)
            ringDoc["pieces"] = pieces;
        ringDoc["vertex_count"] = static_cast<double>(ring.size());
        ++rings_;
        holes_ += outer ? 0 : 1;
        return ringDoc;
    }

    const ParameterValues& values_;
    Drawing drawing_;
    Table table_;
    nlohmann::json planes_ = nlohmann::json::array();
    std::vector<OutlinedPlane> outlined_;
    double largestSpacing_ = 0;
    std::size_t rings_ = 0, holes_ = 0;
};

ToolResult runContours(const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress)
{
    const PointCloud& cloud = inputs.cloud();
    OutlineParams outline;
    outline.method = parseOutlineMethod(values.text("method"));
    outline.threshold = outline.method == OutlineMethod::LongEdges ? thresholdFrom(values.text("edge-threshold")) : values.real("alpha");
    std::string note;
    const std::vector<Segment> segments = segmentsOf(cloud, values.text("segment-field"), note);
    ProgressTicker ticker(progress, "Contours", segments.size());
    ContoursOutput output(values);
    std::size_t skipped = 0;
    for (const Segment& segment : segments) {
        ticker.checkCancel();
        ticker.step();
        if (!output.addSegment(cloud, segment, outline))
            ++skipped; // fewer than 3 points, or a line
    }
    const PlaneJoinResult joined = output.joinPlanes();
    ToolResult result;
    const std::string document =
        nlohmann::json({{"planes", output.planes()}, {"joined_vertices", joined.movedVertices}}).dump(1) + "\n";
    result.add("contours", output.takeDrawing());
    result.add("rings", output.takeTable());
    result.add("document", TextDocument{".json", document});
    std::ostringstream summary;
    summary << segments.size() - skipped << " planes outlined: " << output.rings() - output.holes() << " outer rings, " << output.holes()
            << " holes";
    if (joined.joints > 0)
        summary << "; " << joined.joints << " pairs of planes joined (" << joined.movedVertices << " vertices moved onto their common lines)";
    if (skipped)
        summary << "; " << skipped << " segments skipped (fewer than 3 points or on a line)";
    if (!note.empty())
        summary << "; " << note;
    result.summary = summary.str();
    return result;
}

ToolSpec contoursTool()
{
    ToolSpec tool;
    tool.name = "contours";
    tool.title = "Contours";
    tool.category = "Contours";
    tool.description =
        "Outlines every planar segment (the primitive_id field of the primitives tool, or the whole cloud) with its openings: "
        "the points in their best-fit plane are triangulated (Delaunay) and the triangles spanning gaps removed, by the long-edge "
        "criterion of thesis 001 (threshold at the knee of the sorted edge lengths) or by alpha shapes; each part gives a closed "
        "outer ring and one ring per hole. --vectorise turns the rings into straight pieces (horizontal, vertical, inclined) and "
        "arcs with corners at the intersections of neighbouring pieces (thesis 001 §4.3). Gives the rings as a drawing (a layer per "
        "plane), a table and a JSON document.";
    tool.parameters = {
        ParameterSpec::choice("method", "Method",
                              "long-edges: drop triangles with an edge longer than the threshold (thesis 001); alpha: drop "
                              "triangles whose circumradius exceeds alpha (alpha shapes)",
                              {"long-edges", "alpha"}, "long-edges"),
        ParameterSpec::text("edge-threshold", "Edge threshold",
                            "long-edges: 'auto' (the knee of the sorted edge lengths) or the longest edge of the surface, m", "auto")
            .withSuggestions({"auto"})
            .onlyWith("method=long-edges"),
        ParameterSpec::real("alpha", "Alpha", "alpha: the largest circumradius of the surface's triangles", 0.0, 0.0, 1e9, "m")
            .withZeroMeaning("automatic (knee of the sorted circumradii)")
            .onlyWith("method=alpha"),
        // Free text rather than a list of the cloud's fields: a cloud without
        // this field is one segment, never segmented by whatever field is shown.
        ParameterSpec::text("segment-field", "Segment field",
                            "The field holding each point's segment id (-1: none); a cloud without it is one segment",
                            "primitive_id")
            .withSuggestions({"primitive_id", "region_id", "stone_id"}),
        ParameterSpec::real("min-area", "Smallest area",
                            "Parts and holes smaller than this are dropped (missed points, occlusion specks)", 0.0, 0.0, 1e12, "m²")
            .withZeroMeaning("automatic (50 x the squared point spacing)"),
        ParameterSpec::boolean("vectorise", "Vectorise", "Straight pieces and arcs, corners by intersection", false),
        ParameterSpec::real("tolerance", "Line tolerance", "Vectorise: largest distance of a contour point to its piece", 0.0, 0.0,
                            1e9, "m")
            .withZeroMeaning("automatic (1.5 x the point spacing)")
            .onlyWith("vectorise"),
        ParameterSpec::boolean("offset-edges", "Edges at half a spacing",
                               "Vectorise: move the straight pieces half a point spacing away from the surface, where the true "
                               "edge lies on average",
                               true)
            .onlyWith("vectorise"),
        ParameterSpec::boolean("join-planes", "Join neighbouring planes",
                               "Several planes: vertices near the line where two planes meet (inside the other's outline) are "
                               "moved onto it, onto the point of three planes at a corner of three, and made one with the "
                               "other outline's, so the 3D model's planes meet (thesis 001 §4.4)",
                               true),
        ParameterSpec::real("join-tolerance", "Join tolerance",
                            "Join: largest distance of a vertex from the line where the planes meet", 0.0, 0.0, 1e9, "m")
            .withZeroMeaning("automatic (3 x the largest point spacing of the planes)")
            .onlyWith("join-planes"),
    };
    tool.outputs = {OutputSpec{"contours", "Contours", DataKind::Drawing},
                    OutputSpec{"rings", "Contour rings", DataKind::Table, false, false, "contours"},
                    OutputSpec{"document", "Contours (JSON)", DataKind::Document, false, false, "contours"}};
    tool.run = runContours;
    return tool;
}

ToolSpec stonesTool()
{
    const StoneParams defaults;
    ToolSpec tool;
    tool.name = "stones";
    tool.title = "Stones";
    tool.category = "Contours";
    tool.description =
        "Draws a masonry wall stone by stone from its scan (thesis 003): the points are classified into stone and joint by "
        "their intensity, starting from a threshold (the iterative inter-means threshold of the thesis when none is given) "
        "with the stones darker or brighter, then by the two classes' levels around each point and the point's offset from "
        "the stone faces around it (the joints' recess); isolated stone points are removed, stone points bridging a joint are "
        "given to the nearest stone, and each group of stone points separated by joints becomes one closed polygon in the "
        "wall's best-fit plane; small and nested contours are dropped. Gives the points with "
        "stone_id and stone_class, the polygons as a drawing (a polyline and an id label per stone) and a table (area, perimeter, "
        "centroid, plane residual).";
    tool.parameters = {
        ParameterSpec::text("field", "Intensity field", "The field classified into stone and joint", "intensity").asFieldOf("input"),
        ParameterSpec::choice("polarity", "Stones are",
                              "dark: stones below the threshold; bright: above; auto: the side with more points (stones cover "
                              "most of a wall, joints are narrow)",
                              {"auto", "dark", "bright"}, "auto"),
        ParameterSpec::real("threshold", "Threshold",
                            "The intensity separating stone from joint (the workbench proposes the bound dragged on the "
                            "field's histogram); absent: the thesis's iterative inter-means threshold",
                            0.0, -1e30, 1e30)
            .asOptional()
            .asThresholdOf("field"),
        ParameterSpec::boolean("local-levels", "Local levels",
                               "The stone and joint intensity levels and the faces' surface taken over a window around each "
                               "point, the points classified again until the classes settle (intensity falls across a wall seen "
                               "obliquely); off: the threshold alone on the whole wall, as thesis 003",
                               defaults.localLevels),
        ParameterSpec::boolean("relief", "Relief",
                               "Each point's offset from the stone faces around it votes with its intensity (joints are usually "
                               "recessed); used when the joints stand apart from the faces by half the faces' noise",
                               defaults.relief)
            .onlyWith("local-levels"),
        ParameterSpec::real("window", "Window", "Side of the square around each point for the local levels", 0.0, 0.0, 1e9, "m")
            .withZeroMeaning("automatic (30 point spacings, at least 0.15 m)")
            .onlyWith("local-levels"),
        ParameterSpec::choice("method", "Method",
                              "classify: every point classified (threshold, local levels, relief), isolated points removed, "
                              "stones parted along their joints; grow: regions grown on intensity from stone seeds (thesis 003 "
                              "§II.2), one per stone",
                              {"classify", "grow"}, "classify"),
        ParameterSpec::real("alpha", "Alpha", "Largest circumradius of a stone's triangles (alpha-shape radius)", 0.0, 0.0, 1e9, "m")
            .withZeroMeaning("automatic (longest edges at their knee, in the spacing where each triangle lies)"),
        ParameterSpec::real("min-area", "Smallest stone", "Contours smaller than this are dropped", 0.0, 0.0, 1e12, "m²")
            .withZeroMeaning("automatic (25 x the squared point spacing, or a twentieth of the median stone if larger)"),
        ParameterSpec::real("cleaning-radius", "Cleaning radius", "classify: radius of the isolated-point test", 0.0, 0.0, 1e9, "m")
            .withZeroMeaning("automatic (2 x the point spacing)")
            .onlyWith("method=classify"),
        ParameterSpec::integer("cleaning-neighbours", "Cleaning neighbours",
                               "classify: a stone point with fewer stone neighbours in the radius is isolated",
                               defaults.cleaningNeighbours, 0, 1000)
            .onlyWith("method=classify"),
        ParameterSpec::real("grow-radius", "Growth radius R", "grow: neighbourhood radius", 0.0, 0.0, 1e9, "m")
            .withZeroMeaning("automatic (2 x the point spacing, as the thesis)")
            .onlyWith("method=grow"),
        ParameterSpec::real("grow-variance", "Variance tolerance", "grow: largest intensity variance of a region", 0.0, 0.0, 1e30)
            .withZeroMeaning("automatic (the variance of the stone class)")
            .onlyWith("method=grow"),
        ParameterSpec::boolean("vectorise", "Vectorise outlines",
                               "Each stone's outline as straight pieces and arcs with corners at their intersections (as "
                               "contours --vectorise), its edges half a spacing out; off: the ring of the stone's triangles",
                               true),
    };
    tool.outputs = {OutputSpec{"stones", "Cloud with stone_id", DataKind::Cloud, true},
                    OutputSpec{"drawing", "Stone contours", DataKind::Drawing, false, false, "stones"},
                    OutputSpec{"table", "Stones", DataKind::Table, false, false, "stones"}};
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        const PointCloud& cloud = inputs.cloud();
        StoneParams params;
        params.field = values.text("field");
        params.polarity = parseStonePolarity(values.text("polarity"));
        params.vectorise = values.boolean("vectorise");
        if (values.has("threshold"))
            params.threshold = values.real("threshold");
        params.method = parseStoneMethod(values.text("method"));
        params.localLevels = values.boolean("local-levels");
        params.relief = values.boolean("relief");
        params.window = values.real("window");
        params.alpha = values.real("alpha");
        params.minStoneArea = values.real("min-area");
        params.cleaningRadius = values.real("cleaning-radius");
        params.cleaningNeighbours = static_cast<int>(values.integer("cleaning-neighbours"));
        params.growRadius = values.real("grow-radius");
        params.growVariance = values.real("grow-variance");
        const StoneWallResult wall = extractStones(cloud, params, progress);

        PointCloud labelled = cloud.clone();
        for (const char* name : {"stone_id", "stone_class", "stone_joint"})
            labelled.addField(name);
        std::vector<float>& id = labelled.field("stone_id")->values();
        std::vector<float>& cls = labelled.field("stone_class")->values();
        std::vector<float>& joint = labelled.field("stone_joint")->values();
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            id[i] = static_cast<float>(wall.stoneOfPoint[i]);
            cls[i] = wall.stoneClass[i];
            joint[i] = wall.jointLine[i] ? 2.0f : wall.partingPoint[i] ? 1.0f : 0.0f;
        }
        Drawing drawing;
        Table table;
        table.columns = {"id", "area", "perimeter", "centroid_x", "centroid_y", "centroid_z", "plane_rms", "points", "vertices"};
        const double textHeight = std::max(0.01, 0.2 * std::sqrt(wall.stones.empty() ? 0.01 : wall.stones.front().area));
        for (std::size_t s = 0; s < wall.stones.size(); ++s) {
            const Stone& stone = wall.stones[s];
            drawing.polylines.push_back({"STONES", stone.outline, true});
            drawing.texts.push_back({"STONE_IDS", stone.centroid, textHeight, std::to_string(s)});
            table.rows.push_back({static_cast<double>(s), stone.area, stone.perimeter, stone.centroid.x(), stone.centroid.y(),
                                  stone.centroid.z(), stone.planeRms, static_cast<double>(stone.points),
                                  static_cast<double>(stone.outline.size())});
        }
        ToolResult result;
        result.add("stones", std::move(labelled));
        result.add("drawing", std::move(drawing));
        result.add("table", std::move(table));
        std::ostringstream summary;
        summary << wall.stones.size() << " stones; threshold " << wall.threshold
                << (wall.thresholdIterations ? " (inter-means, " + std::to_string(wall.thresholdIterations) + " iterations)" : "")
                << ", point spacing " << wall.spacing << " m, outline threshold " << wall.alpha << " m; ";
        if (wall.classificationRounds)
            summary << "classification rounds " << wall.classificationRounds << ", joints " << wall.jointOffset * 1e3
                    << " mm off the faces (noise " << wall.reliefNoise * 1e3 << " mm, relief " << (wall.reliefUsed ? "used" : "not used") << "); ";
        summary << wall.isolatedRemoved << " isolated points removed, " << wall.pointsNearJoints
                << " stone points near joints given to the nearest stone's core, " << wall.smallDropped << " small and " << wall.nestedDropped
                << " nested contours dropped; wall plane RMS " << wall.wall.rms << " m; mean intensity of the stones "
                << wall.stoneMean << ", of the joints " << wall.jointMean;
        result.summary = summary.str();
        // The threshold between the histogram's two modes, for the workbench to draw on the field's histogram.
        result.marks = {FieldMark{"input", params.field, wall.threshold, "threshold"},
                        FieldMark{"input", params.field, wall.stoneMean, "stones"},
                        FieldMark{"input", params.field, wall.jointMean, "joints"}};
        return result;
    };
    return tool;
}

} // namespace

} // namespace scandiff::plugins

void scandiff_register_plugin_contours(scandiff::PluginRegistry& registry)
{
    using namespace scandiff::plugins;
    registry.plugins.push_back({"contours", "Outlines and openings of planar segments; stone-by-stone wall drawings", "CGAL"});
    registry.tools.add(contoursTool());
    registry.tools.add(stonesTool());
    registry.tools.add(comparePolygonsTool());
}
