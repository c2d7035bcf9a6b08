// SPDX-License-Identifier: GPL-3.0-or-later
#include "MainWindow.h"
#include "view/CloudView.h"
#include "view/ViewTimings.h"

#include <QApplication>
#include <QCommandLineParser>
#include <QSurfaceFormat>
#include <QTimer>

int main(int argc, char** argv)
{
    // VTK's widget needs its OpenGL format set before the application exists.
    QSurfaceFormat::setDefaultFormat(scandiff::gui::CloudView::defaultSurfaceFormat());
    QApplication app(argc, argv);
    QApplication::setApplicationName("scandiff");
    QApplication::setApplicationVersion("0.1.0");
    QApplication::setOrganizationName("scandiff"); // where QSettings keeps recent files

    QCommandLineParser parser;
    parser.setApplicationDescription("scandiff: a workbench for comparing 3D scans");
    parser.addHelpOption();
    parser.addVersionOption();
    QCommandLineOption screenshot("screenshot", "Load FILEs, save the view to PNG and quit.", "png");
    parser.addOption(screenshot);
    QCommandLineOption measure("measure-view",
                               "Load FILEs, print the view's timings (first picture, everything drawn slice by slice, longest "
                               "event-loop turn, render while moving, threshold update) and quit.");
    parser.addOption(measure);
    QCommandLineOption measureC2c("measure-c2c",
                                  "Load REFERENCE and COMPARED, run C2C from the workbench, print its time, the longest the "
                                  "interface waited and the memory, and quit.");
    parser.addOption(measureC2c);
    parser.addPositionalArgument("FILE", "Clouds or meshes to open", "[FILE...]");
    parser.process(app);

    const scandiff::PluginRegistry registry = scandiff::makePluginRegistry();
    scandiff::gui::MainWindow window(registry);
    window.show();
    const QStringList files = parser.positionalArguments();
    const bool quiet = parser.isSet(screenshot) || parser.isSet(measure) || parser.isSet(measureC2c); // no questions (global shift) in unattended runs
    QTimer::singleShot(0, &window, [&] {
        const int loaded = files.isEmpty() ? 0 : window.openFiles(files, quiet);
        if (parser.isSet(measureC2c)) {
            QApplication::exit(loaded == files.size() ? scandiff::gui::measureCloudToCloud(window) : 1);
            return;
        }
        if (parser.isSet(measure)) {
            QApplication::exit(loaded == files.size() ? scandiff::gui::measureView(window) : 1);
            return;
        }
        if (parser.isSet(screenshot)) {
            const bool saved = window.view()->saveScreenshot(parser.value(screenshot));
            QApplication::exit(saved && loaded == files.size() ? 0 : 1);
        }
    });
    return app.exec();
}
