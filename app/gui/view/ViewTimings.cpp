// SPDX-License-Identifier: GPL-3.0-or-later
#include "view/ViewTimings.h"

#include "MainWindow.h"
#include "controllers/DistanceController.h"
#include "panels/EntityTree.h"
#include "panels/ScalarFieldPanel.h"
#include "view/CloudView.h"
#include "widgets/RangeEditor.h"

#include <QApplication>
#include <QElapsedTimer>
#include <QTimer>

#include <algorithm>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <iomanip>
#include <iostream>

namespace scandiff::gui {

namespace {

constexpr int kRepeats = 5;

template <class F> double averageMilliseconds(F&& f)
{
    f(); // the first call uploads buffers and compiles shaders: not what a user waits for at each frame
    QElapsedTimer clock;
    clock.start();
    for (int i = 0; i < kRepeats; ++i)
        f();
    return clock.nsecsElapsed() / 1e6 / kRepeats;
}

//! Resident memory now and at its peak (MB), from /proc (Linux).
std::pair<double, double> residentMegabytes()
{
    std::ifstream status("/proc/self/status");
    double now = 0, peak = 0;
    std::string key;
    while (status >> key) {
        double kilobytes = 0;
        if (key == "VmRSS:" && status >> kilobytes)
            now = kilobytes / 1024;
        else if (key == "VmHWM:" && status >> kilobytes)
            peak = kilobytes / 1024;
    }
    return {now, peak};
}

} // namespace

int measureView(MainWindow& window)
{
    Document& document = window.document();
    CloudView& view = *window.view();
    std::size_t points = 0;
    EntityId cloud = kNoEntity;
    for (EntityId id : document.ids())
        if (document.item(id).cloud()) {
            points += document.item(id).points().size();
            cloud = id;
        }
    if (cloud == kNoEntity) {
        std::cerr << "measure-view: no point cloud loaded\n";
        return 1;
    }
    view.setStandardView(StandardView::Iso);
    QApplication::processEvents();
    view.setMoving(false);
    // At rest: the first picture, then every slice until everything is drawn;
    // the longest turn of the event loop is the longest the interface waits.
    const auto refine = [&](double& first, double& longest, double& everything) {
        QElapsedTimer clock, turn;
        clock.start();
        view.render();
        first = clock.nsecsElapsed() / 1e6;
        longest = first;
        while (view.refinement().refining) {
            turn.start();
            QApplication::processEvents();
            longest = std::max(longest, turn.nsecsElapsed() / 1e6);
        }
        everything = clock.nsecsElapsed() / 1e6;
    };
    double first = 0, longest = 0, everything = 0;
    refine(first, longest, everything); // uploads buffers and compiles shaders, and measures the machine
    refine(first, longest, everything);
    const std::size_t slices = view.refinement().starts > 0 ? view.refinement().slicesDrawn : 1;
    view.setMoving(true);
    const double moving = averageMilliseconds([&] { view.render(); });
    view.setMoving(false);

    // A threshold drag: the active field's range narrowed step by step (height
    // when the cloud has no field: its colours then depend on no threshold).
    const PointCloud& target = document.item(cloud).points();
    double threshold = 0;
    std::string fieldName;
    if (!target.fields().empty()) {
        fieldName = target.fields().front().name();
        document.setActiveField(cloud, fieldName);
        const ValueRange r = target.fields().front().range();
        // The path of a slider drag: the panel's range editor, then the document, then the view.
        window.tree()->selectEntity(cloud);
        RangeEditor* range = window.scalarPanel()->rangeEditor();
        int step = 0;
        threshold = averageMilliseconds([&] {
            range->setRange(r.min + (r.max - r.min) * 0.05 * (++step % 10), r.max);
            while (view.frameScheduled()) // the frame the change asked for, drawn when the event loop turns
                QApplication::processEvents();
        });
    }
    const auto [resident, peak] = residentMegabytes();
    std::cout << std::fixed << std::setprecision(1) << "points " << points << "\n"
              << "resident MB " << resident << " (" << resident * 1048576 / static_cast<double>(points) << " bytes a point), peak "
              << peak << "\n"
              << "first picture ms " << first << " (slice 0 of " << slices << ")\n"
              << "everything drawn ms " << everything << "\n"
              << "longest event-loop turn ms " << longest << "\n"
              << "moving render ms " << moving << " (stride " << view.interactiveStride() << ")\n";
    if (!fieldName.empty())
        std::cout << "threshold update ms " << threshold << " (field " << fieldName << ", as a slider drag: recolour, count, decimated render)\n";
    return 0;
}

int measureCloudToCloud(MainWindow& window)
{
    Document& document = window.document();
    std::vector<EntityId> clouds;
    for (EntityId id : document.ids())
        if (document.item(id).cloud())
            clouds.push_back(id);
    if (clouds.size() < 2) {
        std::cerr << "measure-c2c: two point clouds are needed (reference, compared)\n";
        return 1;
    }
    CloudView& view = *window.view();
    view.setStandardView(StandardView::Iso);
    QApplication::processEvents();
    view.setMoving(false); // at rest: the slices start
    while (view.refinement().refining) // the opened clouds drawn first: the run alone is measured
        QApplication::processEvents();
    QElapsedTimer sinceBeat, clock;
    double longest = 0;
    QTimer beat;
    beat.setInterval(10);
    QObject::connect(&beat, &QTimer::timeout, [&] {
        longest = std::max(longest, sinceBeat.nsecsElapsed() / 1e6);
        sinceBeat.restart();
    });
    sinceBeat.start();
    beat.start();
    clock.start();
    const bool done = window.distances()->runCloudToCloud(clouds[1], clouds[0], {});
    const double runSeconds = clock.nsecsElapsed() / 1e9;
    // The result drawn: the recoloured clouds refined slice by slice.
    QElapsedTimer drawing;
    drawing.start();
    do
        QApplication::processEvents(QEventLoop::AllEvents, 50);
    while ((view.refinement().refining || drawing.elapsed() < 500) && drawing.elapsed() < 600000);
    const double drawnSeconds = clock.nsecsElapsed() / 1e9;
    beat.stop();
    const auto [resident, peak] = residentMegabytes();
    std::size_t points = 0;
    for (EntityId id : clouds)
        points += document.item(id).points().size();
    std::cout << std::fixed << std::setprecision(2) << "points " << points << "\n"
              << "c2c " << (done ? "done" : "failed") << " in s " << runSeconds << ", result drawn at s " << drawnSeconds << "\n"
              << "longest event-loop wait ms " << longest << " (10 ms heartbeat included)\n"
              << std::setprecision(1) << "resident MB " << resident << ", peak " << peak << "\n";
    return done ? 0 : 1;
}

} // namespace scandiff::gui
