// SPDX-License-Identifier: GPL-3.0-or-later
// The tool "compare-polygons": a vector model against a reference drawing
// with the measures of thesis 001 §5.6 (Tab. 5.5 areas, Tab. 5.8 vertices).
#include "ContourTools.h"

#include <scandiff/core/Error.h>
#include <scandiff/plugins/contours/PolygonMeasures.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace scandiff::plugins {

namespace {

struct Polygon3d
{
    const DrawingPolyline* source = nullptr;
    std::vector<Eigen::Vector3d> points; //!< without a repeated closing vertex
};

//! The closed polylines of a drawing (the last vertex dropped when it repeats the first).
std::vector<Polygon3d> closedPolygons(const Drawing& drawing)
{
    std::vector<Polygon3d> out;
    for (const DrawingPolyline& polyline : drawing.polylines) {
        std::vector<Eigen::Vector3d> points = polylineVertices(polyline); // arcs as points along them
        const bool closesItself = points.size() > 3 && (points.front() - points.back()).norm() < 1e-9;
        if (!polyline.closed && !closesItself)
            continue;
        if (closesItself)
            points.pop_back();
        if (points.size() >= 3)
            out.push_back({&polyline, std::move(points)});
    }
    return out;
}

} // namespace

ToolSpec comparePolygonsTool()
{
    ToolSpec tool;
    tool.name = "compare-polygons";
    tool.title = "Compare polygons";
    tool.category = "Contours";
    tool.description =
        "Compares a vector model (DXF) with a reference drawing (DXF), closed polyline by closed polyline: each reference polygon "
        "is matched with the model polygon on its plane that overlaps it best, and gets the area measures of thesis 001 Tab. 5.5 "
        "(detection rate |R∩A|/|R|, quality |R∩A|/|R∪A|, branching, miss and failure factors as the thesis computes them, the "
        "excess and deficit areas) and the deviation of each reference vertex from the nearest model vertex (Tab. 5.8). A "
        "reference is found when its IoU reaches --min-iou; a model polygon matching no reference is a false contour.";
    tool.inputs = {InputSpec{"input", "Model then reference", "Two DXF drawings: the model, then the reference", DataKind::Drawing, true}};
    tool.outputs = {OutputSpec{"measures", "Polygon measures", DataKind::Table}};
    tool.parameters = {
        ParameterSpec::real("plane-tolerance", "Plane tolerance",
                            "A model polygon is compared with a reference one when all its vertices lie this close to the "
                            "reference's plane",
                            0.1, 0.0, 1e9, "m"),
        ParameterSpec::real("min-iou", "Smallest IoU", "A reference overlapped at least this much (intersection over union) is found",
                            0.8, 0.0, 1.0),
    };
    tool.run = [](const ToolInputs& inputs, const ParameterValues& values, ProgressObserver* progress) {
        if (inputs.count("input") != 2)
            throw Error(ErrorCode::InvalidArgument, "compare-polygons takes two drawings: the model, then the reference");
        const std::vector<Polygon3d> model = closedPolygons(inputs.drawing("input", 0));
        const std::vector<Polygon3d> reference = closedPolygons(inputs.drawing("input", 1));
        if (reference.empty())
            throw Error(ErrorCode::InvalidData, "compare-polygons: the reference drawing has no closed polyline");
        const double tolerance = values.real("plane-tolerance"), minIou = values.real("min-iou");
        ProgressTicker ticker(progress, "Comparing polygons", reference.size());

        Table table;
        table.columns = {"reference", "layer", "model", "reference_area", "model_area", "detection", "quality", "branching", "miss",
                         "failure", "excess", "deficit", "vertex_mean", "vertex_max", "dx_max", "dy_max", "dz_max"};
        const double nan = std::numeric_limits<double>::quiet_NaN();
        std::vector<bool> modelMatched(model.size(), false);
        std::size_t found = 0;
        for (std::size_t r = 0; r < reference.size(); ++r) {
            ticker.checkCancel();
            ticker.step();
            PlaneFrame plane;
            try {
                plane = fitPlaneFrame(reference[r].points);
            } catch (const Error&) {
                continue; // a reference polygon on a line has no area to compare
            }
            Ring2d referenceRing;
            for (const Eigen::Vector3d& p : reference[r].points)
                referenceRing.push_back(plane.toPlane(p));
            const Polygon2d referencePolygon{referenceRing, {}};
            int best = -1;
            AreaMeasures bestMeasures;
            for (std::size_t m = 0; m < model.size(); ++m) {
                bool onPlane = true;
                Ring2d ring;
                for (const Eigen::Vector3d& p : model[m].points) {
                    onPlane = onPlane && std::abs((p - plane.origin).dot(plane.normal)) <= tolerance;
                    ring.push_back(plane.toPlane(p));
                }
                if (!onPlane)
                    continue;
                const AreaMeasures measures = compareAreas({ring, {}}, referencePolygon);
                if (measures.intersection > 0 && (best < 0 || measures.quality > bestMeasures.quality)) {
                    best = static_cast<int>(m);
                    bestMeasures = measures;
                }
            }
            std::vector<TableCell> row{static_cast<double>(r), reference[r].source->layer};
            if (best < 0) {
                row.push_back(-1.0);
                row.push_back(std::abs(signedArea(referenceRing)));
                for (std::size_t c = row.size(); c < table.columns.size(); ++c)
                    row.push_back(nan);
                table.rows.push_back(std::move(row));
                continue;
            }
            if (bestMeasures.quality >= minIou) {
                ++found;
                modelMatched[static_cast<std::size_t>(best)] = true;
            }
            // Tab. 5.8: each reference vertex against its nearest model vertex.
            double sum = 0.0, worst = 0.0;
            Eigen::Vector3d worstDelta = Eigen::Vector3d::Zero();
            for (const Eigen::Vector3d& p : reference[r].points) {
                Eigen::Vector3d nearest = model[static_cast<std::size_t>(best)].points.front();
                for (const Eigen::Vector3d& q : model[static_cast<std::size_t>(best)].points)
                    if ((q - p).squaredNorm() < (nearest - p).squaredNorm())
                        nearest = q;
                const double d = (nearest - p).norm();
                sum += d;
                if (d >= worst) {
                    worst = d;
                    worstDelta = nearest - p;
                }
            }
            const AreaMeasures& m = bestMeasures;
            for (double v : {static_cast<double>(best), m.reference, m.model, m.detection, m.quality, m.branching, m.miss, m.failure, m.excess,
                             m.deficit, sum / static_cast<double>(reference[r].points.size()), worst, worstDelta.x(), worstDelta.y(),
                             worstDelta.z()})
                row.push_back(v);
            table.rows.push_back(std::move(row));
        }
        const std::size_t falseContours = static_cast<std::size_t>(std::count(modelMatched.begin(), modelMatched.end(), false));
        ToolResult result;
        result.add("measures", std::move(table));
        std::ostringstream summary;
        summary << found << " of " << reference.size() << " reference polygons found (IoU >= " << minIou << "): "
                << 100.0 * static_cast<double>(found) / static_cast<double>(reference.size()) << " %; " << falseContours << " of "
                << model.size() << " model polygons match no reference";
        result.summary = summary.str();
        return result;
    };
    return tool;
}

} // namespace scandiff::plugins
