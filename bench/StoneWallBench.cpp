// SPDX-License-Identifier: GPL-3.0-or-later
// The stone-wall benchmark of docs/benchmarks.md (thesis 003 §7.2): a
// synthetic wall of COURSES x STONES stones (one in three with cut corners),
// joints of 1-2 cm, stones darker than joints, 17 isolated mislabelled
// points, scanned on a jittered grid; the stones tool's result scored against
// the truth: point-level rates P1-P4 (thesis 003 §II.1.4), contour-level P5
// (stones found, IoU >= 0.8 with exactly one true stone) and P6 (false
// contours), the worst Hausdorff distance of a found stone, and the time.
//
//   scandiff-stone-wall [--courses 16] [--stones 20] [--spacing 0.0044] [--sigma 40] [--write wall.ply] [--method classify|grow]
//   scandiff-stone-wall --facade SPACING facade.ply       # the test façade and facade.ply.openings.dxf, for `contours`
#include <scandiff/io/DxfWriter.h>
#include <scandiff/io/FileIO.h>
#include <scandiff/plugins/PluginRegistry.h>
#include <scandiff/plugins/contours/PolygonMeasures.h>
#include <scandiff/plugins/contours/StoneWall.h>

#include "WallScenes.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>

using namespace scandiff;
using namespace scandiff::plugins;

int main(int argc, char** argv)
{
    test::StoneWallOptions options;
    options.courses = 16;
    options.stonesPerCourse = 20;
    options.spacing = 0.0044;
    std::string write, method = "classify";
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string key = argv[i], value = argv[i + 1];
        if (key == "--courses")
            options.courses = std::stoi(value);
        else if (key == "--stones")
            options.stonesPerCourse = std::stoi(value);
        else if (key == "--spacing")
            options.spacing = std::stod(value);
        else if (key == "--sigma")
            options.intensitySigma = std::stod(value);
        else if (key == "--write")
            write = value;
        else if (key == "--method")
            method = value;
        else if (key == "--facade") {
            // The test façade (three windows, a door, an arch) at this spacing, for timing `contours`.
            if (i + 2 >= argc) {
                std::fprintf(stderr, "--facade SPACING FILE\n");
                return 2;
            }
            const test::FacadeScene facade = test::makeFacade(std::stod(value));
            const PluginRegistry registry = makePluginRegistry();
            io::writePointCloud(registry.formats, facade.cloud, argv[i + 2]);
            // Its true openings as a reference drawing, for compare-polygons.
            Drawing truth;
            for (const test::Outline& opening : facade.openings) {
                DrawingPolyline polyline{"OPENINGS", {}, true};
                for (const Eigen::Vector2d& q : opening)
                    polyline.points.push_back(facade.frame.world(q));
                truth.polylines.push_back(std::move(polyline));
            }
            const std::string reference = std::string(argv[i + 2]) + ".openings.dxf";
            io::writeDrawingDxf(truth, reference);
            std::printf("wrote a façade of %zu points and its openings, %s\n", facade.cloud.size(), reference.c_str());
            return 0;
        }
        else {
            std::fprintf(stderr, "unknown option %s\n", key.c_str());
            return 2;
        }
    }
    const test::StoneWallScene scene = test::makeStoneWall(options);
    std::printf("wall: %zu stones, %zu points, spacing %.4f m\n", scene.stones.size(), scene.cloud.size(), options.spacing);
    if (!write.empty()) {
        const PluginRegistry registry = makePluginRegistry();
        io::writePointCloud(registry.formats, scene.cloud, write);
        std::printf("wrote %s\n", write.c_str());
        return 0;
    }
    StoneParams params;
    params.method = parseStoneMethod(method);
    const auto start = std::chrono::steady_clock::now();
    const StoneWallResult wall = extractStones(scene.cloud, params);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    std::size_t tp = 0, fp = 0, fn = 0, tn = 0;
    for (std::size_t i = 0; i < scene.isStone.size(); ++i) {
        const bool found = wall.stoneOfPoint[i] >= 0;
        tp += scene.isStone[i] && found;
        fp += !scene.isStone[i] && found;
        fn += scene.isStone[i] && !found;
        tn += !scene.isStone[i] && !found;
    }
    std::vector<Polygon2d> model, truth;
    for (const Stone& stone : wall.stones)
        model.push_back({stone.outline2d, {}});
    for (const test::Outline& outline : scene.stones) {
        Ring2d ring;
        for (const Eigen::Vector2d& q : outline)
            ring.push_back(wall.wall.toPlane(scene.frame.world(q)));
        truth.push_back({ring, {}});
    }
    const PolygonMatching matching = matchPolygons(model, truth);
    double worst = 0.0;
    for (std::size_t m = 0; m < model.size(); ++m)
        if (matching.referenceOfModel[m] >= 0)
            worst = std::max(worst, boundaryHausdorff(model[m].outer, truth[static_cast<std::size_t>(matching.referenceOfModel[m])].outer));
    std::printf("method %s, threshold %.2f (%d iterations), alpha %.4f m, %zu isolated removed\n", method.c_str(), wall.threshold,
                wall.thresholdIterations, wall.alpha, wall.isolatedRemoved);
    std::printf("points (stone points kept in a stone): P1 %.2f %%, P2 %.2f %%, P3 %.2f %%, P4 %.2f %%\n", 100.0 * tp / (tp + fn),
                100.0 * fp / (tp + fp), 100.0 * tn / (tn + fp), 100.0 * fn / (tn + fn));
    std::printf("contours: %zu detected, %zu correct of %zu: P5 %.2f %%, P6 %.2f %%; worst Hausdorff of a correct one %.4f m\n",
                model.size(), matching.correct, truth.size(), 100.0 * matching.detectionRate, 100.0 * matching.falseRate, worst);
    std::printf("time in extractStones: %.3f s\n", seconds);
    return 0;
}
