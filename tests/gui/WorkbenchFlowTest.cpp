// SPDX-License-Identifier: GPL-3.0-or-later
// Qt Test: the workbench's whole flow driven through its window, panels and
// controllers as a user would: open the demo pair, run C2C from the dialog's
// declarations, set a threshold in the scalar-field panel, split, export, save
// and restore the session. Answers are checked against core called directly
// and against brute-force counts.
#include "WorkbenchFixture.h"
#include "MainWindow.h"
#include "PrimitiveScene.h"
#include "WallScenes.h"

#include <scandiff/io/DxfReader.h>
#include <scandiff/io/E57.h>
#include "controllers/CommandLine.h"
#include "controllers/GlobalShiftDialog.h"
#include "panels/ConsolePanel.h"
#include "tools/MeasurePanel.h"
#include "controllers/DistanceController.h"
#include "controllers/FileController.h"
#include "controllers/SegmentationController.h"
#include "controllers/SessionController.h"
#include "controllers/SplitController.h"
#include "controllers/FileController.h"
#include "panels/EntityTree.h"
#include "panels/PropertiesPanel.h"
#include "panels/ScalarFieldPanel.h"
#include "controllers/ToolController.h"
#include "tools/ParameterForm.h"
#include "tools/TableDialog.h"
#include "tools/ToolDialog.h"
#include "view/CloudView.h"
#include "widgets/HistogramWidget.h"
#include "widgets/RangeEditor.h"

#include <scandiff/core/distance/CloudToCloud.h>
#include <scandiff/core/distance/DistanceParameters.h>
#include <scandiff/io/FileIO.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <QAction>
#include <memory>
#include <QCheckBox>
#include <QDockWidget>
#include <QDropEvent>
#include <QMessageBox>
#include <QMimeData>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QPushButton>
#include <QMenu>
#include <QMenuBar>
#include <QSignalSpy>
#include <QStandardPaths>
#include <QProcess>
#include <QRegularExpression>
#include <QTemporaryDir>
#include <QDir>
#include <QFile>
#include <QFileInfo>
#include <QTableWidget>
#include <QTemporaryDir>
#include <QtTest>

#include <algorithm>

#include <Eigen/Geometry>

#include <cmath>

using namespace scandiff;
using gui::EntityId;

namespace {

using test::Workbench;
using test::kReference;
using test::kCompared;

std::size_t bruteForceInside(const ScalarField& f, double low, double high)
{
    std::size_t n = 0;
    for (std::size_t i = 0; i < f.size(); ++i)
        if (!std::isnan(f.values()[i]) && f.value(i) >= low && f.value(i) <= high)
            ++n;
    return n;
}

} // namespace

class WorkbenchFlowTest : public QObject
{
    Q_OBJECT

private slots:
    void initTestCase()
    {
        QStandardPaths::setTestModeEnabled(true); // recent files go to a test location, not the user's
        QCoreApplication::setOrganizationName("scandiff-tests");
        qRegisterMetaType<gui::EntityId>("EntityId");
        qRegisterMetaType<std::size_t>("std::size_t");
    }

    void distanceDialogComesFromTheSharedDeclarations()
    {
        gui::Document document;
        gui::DistanceDialog dialog(gui::DistanceKind::CloudToCloud, document);
        for (const ParameterSpec& p : cloudToCloudParameters())
            QVERIFY2(dialog.form()->editor(p.name), p.name.c_str());
        // Untouched, the dialog gives exactly the command line's defaults.
        const ParameterValues fromDialog = resolveParameters(cloudToCloudParameters(), dialog.values(), "c2c");
        const ParameterValues fromCli = resolveParameters(cloudToCloudParameters(), {}, "c2c");
        QCOMPARE(fromDialog.all().size(), fromCli.all().size());
        for (const auto& [name, value] : fromCli.all())
            QVERIFY2(fromDialog.all().at(name) == value, name.c_str());
        // An optional value is off until its checkbox is ticked.
        QVERIFY(!dialog.values().count("max-dist"));
        // Issue 50, defect 9: an option that does nothing in this state is not
        // offered: clamping without a maximum distance, the model's neighbours
        // without a model, a sensor's step, field of view and range without a sensor.
        QVERIFY(!dialog.form()->isShown("clamp"));
        QVERIFY(!dialog.values().count("clamp"));
        for (const char* name : {"sensor-step", "sensor-fov", "sensor-range"})
            QVERIFY2(!dialog.form()->isShown(name), name);
        dialog.form()->enabler("max-dist")->setChecked(true);
        QCOMPARE(dialog.values().at("max-dist"), std::string("1"));
        QVERIFY(dialog.form()->isShown("clamp"));
        dialog.form()->setValue("model", "none");
        QVERIFY(!dialog.form()->isShown("knn"));
        QVERIFY(!dialog.values().count("knn"));
        dialog.form()->setValue("model", "plane");
        QVERIFY(dialog.form()->isShown("knn"));
    }

    void theLoggedCommandsRunAsIsAndGiveTheSameNumbers()
    {
        // Issue 50, defect 10: the console's "equivalent command line" of C2C
        // lacked the files. Run from a folder whose name needs quoting, the
        // logged lines of C2C and of a tool are run by a shell as they are,
        // with the real scandiff-cli, and give the workbench's numbers.
        QTemporaryDir temporary;
        const QString folder = temporary.filePath("survey 2024 (it's here)");
        QVERIFY(QDir().mkpath(folder));
        const QString reference = folder + "/site-2019.ply", compared = folder + "/site-2024.ply";
        QVERIFY(QFile::copy(kReference, reference));
        QVERIFY(QFile::copy(kCompared, compared));
        Workbench workbench;
        gui::MainWindow& window = workbench.window;
        QCOMPARE(window.openFiles({reference, compared}, true), 2);
        const EntityId referenceId = window.document().ids()[0], comparedId = window.document().ids()[1];
        const auto loggedCommand = [](const QString& message) {
            const QRegularExpressionMatch match = QRegularExpression("\\[(scandiff-cli .*?)\\][: ]").match(message);
            return match.captured(1);
        };
        const auto runInShell = [](const QString& command) {
            QProcess shell;
            QProcessEnvironment environment = QProcessEnvironment::systemEnvironment();
            environment.insert("PATH", QFileInfo(SCANDIFF_CLI).absolutePath() + ":" + environment.value("PATH"));
            shell.setProcessEnvironment(environment);
            shell.start("sh", {"-c", command});
            const bool finished = shell.waitForFinished(120000);
            return finished && shell.exitStatus() == QProcess::NormalExit && shell.exitCode() == 0 ? QString()
                                                                                                   : QString(shell.readAllStandardError());
        };
        QSignalSpy distanceDone(window.distances(), &gui::DistanceController::finished);
        QVERIFY(window.distances()->runCloudToCloud(comparedId, referenceId, {{"split-xyz", "true"}, {"knn", "6"}, {"model", "plane"}}));
        const QString c2c = loggedCommand(distanceDone.at(0).at(0).toString());
        QVERIFY2(c2c.startsWith("scandiff-cli c2c --reference " + gui::shellQuoted(reference) + " --compared " + gui::shellQuoted(compared) +
                                 " -o "),
                 qPrintable(c2c));
        const QString error = runInShell(c2c);
        QVERIFY2(error.isEmpty(), qPrintable(c2c + "\n" + error));
        const PointCloud written = io::readPointCloud(makePluginRegistry().formats, (folder + "/site-2024_c2c.ply").toStdString());
        const PointCloud& shown = window.document().item(comparedId).points();
        for (const char* name : {"c2c_distance", "c2c_dz"}) {
            QVERIFY2(written.field(name), name);
            QCOMPARE(written.field(name)->values(), shown.field(name)->values());
        }

        // A tool of the registry, on a file: its line writes what the workbench made.
        const PluginRegistry registry = makePluginRegistry();
        gui::ToolController subsample(*registry.tools.find("subsample"), window.document(), nullptr);
        QSignalSpy toolDone(&subsample, &gui::ToolController::finished);
        QVERIFY(subsample.run(referenceId, {{"spatial", "0.5"}}));
        const QString tool = loggedCommand(toolDone.at(0).at(0).toString());
        QVERIFY2(tool.contains("-o " + gui::shellQuoted(folder + "/site-2019_subsample.ply")), qPrintable(tool));
        QVERIFY2(!tool.contains("export"), qPrintable(tool));
        const QString toolError = runInShell(tool);
        QVERIFY2(toolError.isEmpty(), qPrintable(tool + "\n" + toolError));
        const PointCloud sparse = io::readPointCloud(registry.formats, (folder + "/site-2019_subsample.ply").toStdString());
        QCOMPARE(sparse.size(), window.document().item(window.document().ids().back()).points().size());

        // After File > Export, the entity's file is the exported one: the
        // distances are in it, not in site-2024.ply it was opened from.
        const QString exported = folder + "/site-2024 with distances.ply";
        QVERIFY(window.files()->exportEntity(comparedId, exported));
        QSignalSpy filterDone(&subsample, &gui::ToolController::finished);
        QVERIFY(subsample.run(comparedId, {{"spatial", "0.5"}}));
        const QString again = loggedCommand(filterDone.at(0).at(0).toString());
        QVERIFY2(again.contains(gui::shellQuoted(exported)) && !again.contains(gui::shellQuoted(compared)), qPrintable(again));
        const QString againError = runInShell(again);
        QVERIFY2(againError.isEmpty(), qPrintable(again + "\n" + againError));
        const PointCloud sparseWithDistances =
            io::readPointCloud(registry.formats, (folder + "/site-2024_with_distances_subsample.ply").toStdString());
        QVERIFY(sparseWithDistances.field("c2c_distance"));
        QCOMPARE(sparseWithDistances.size(), window.document().item(window.document().ids().back()).points().size());
    }

    void theColourBarDescribesACloudInTheFrame()
    {
        // Issue 50, defect 1: two LAZ clouds side by side, one zoomed to, a
        // group selected: the bar showed the other cloud's 2..68 over colours
        // of 2816..37888.
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        gui::Document& document = window.document();
        const auto cloudWith = [](double x0, double low, double high) {
            PointCloud cloud;
            cloud.setOrigin({512000 + x0, 5423000, 100});
            cloud.resize(400);
            ScalarField& intensity = cloud.addField("intensity");
            for (std::size_t i = 0; i < cloud.size(); ++i) {
                cloud.positions()[i] = Eigen::Vector3f(static_cast<float>(i % 20), static_cast<float>(i / 20), 0.0f);
                intensity.setValue(i, low + (high - low) * static_cast<double>(i) / 399.0);
            }
            return cloud;
        };
        const EntityId group = document.addGroup("scans.e57");
        const EntityId bright = document.add("scan 1", cloudWith(0, 2816, 37888), group);
        const EntityId dim = document.add("other.laz", cloudWith(5000, 2, 68)); // 5 km away, added last
        window.view()->zoomToEntity(bright);
        QTest::qWait(300); // the bar follows the camera once it rests
        window.tree()->selectEntity(group);
        QCOMPARE(window.view()->legend().min, 2816.0);
        QCOMPARE(window.view()->legend().max, 37888.0);
        // Nothing selected that has a field: the cloud in the frame gives the bar, whichever was added last.
        window.view()->zoomToEntity(dim);
        QTest::qWait(300);
        QCOMPARE(window.view()->legend().min, 2.0); // the group's scan is out of the frame now
        window.view()->zoomToEntity(bright);
        QTest::qWait(300);
        QCOMPARE(window.view()->legend().min, 2816.0); // the camera moved: the bar followed, the selection did not change
        // A selected cloud keeps its own bar wherever the camera is.
        window.tree()->selectEntity(dim);
        QCOMPARE(window.view()->legend().min, 2.0);
    }

    void resultsOnAHiddenCloudAreShownAndTheDialogsOfferWhatMeansSomething()
    {
        // Issue 50, defects 4, 9, 12 and 11.
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        gui::Document& document = window.document();

        // 12: an RGB LAZ (point format 3, with intensity) opens in its colours.
        QCOMPARE(window.openFiles({SCANDIFF_SAMPLE_DATA_DIR "/laz/simple.laz"}, true), 1);
        const EntityId laz = document.ids().back();
        QVERIFY(document.item(laz).points().hasColors());
        QVERIFY(document.item(laz).points().field("intensity"));
        QVERIFY(document.item(laz).display.activeField.empty());

        // 4: split, the parent hidden; segmenting the parent shows it with its regions.
        QCOMPARE(window.openFiles({kReference, kCompared}, true), 2);
        const EntityId reference = document.ids()[document.ids().size() - 2], compared = document.ids().back();
        QVERIFY(window.distances()->runCloudToCloud(compared, reference, {}));
        QVERIFY(window.splits()->split(compared, "c2c_distance", 0.2, 100.0).first != gui::kNoEntity);
        QVERIFY(!document.item(compared).display.visible);
        QSignalSpy segmented(window.segmentation(), &gui::SegmentationController::finished);
        QVERIFY(window.segmentation()->run(compared, reference,
                                            {{"field", "c2c_distance"}, {"above", "0.2"}, {"components", "true"}, {"min-points", "50"}}));
        QVERIFY(document.item(compared).display.visible);
        QVERIFY(window.view()->isShownHere(compared));
        for (EntityId child : document.children(compared)) // the split's parts no longer draw over the regions
            QVERIFY(!document.item(child).display.visible);
        QVERIFY2(segmented.last().at(0).toString().contains("was hidden"), qPrintable(segmented.last().at(0).toString()));
        // The same for a tool that updates its hidden input, and for C2C on a hidden cloud.
        document.setVisible(compared, false);
        QVERIFY(window.toolController("normals")->run(compared, {{"radius", "2"}}));
        QVERIFY(document.item(compared).display.visible);
        document.setVisible(compared, false);
        QVERIFY(window.distances()->runCloudToCloud(compared, reference, {}));
        QVERIFY(document.item(compared).display.visible);

        // 9: the other epoch is never the segmented cloud itself; refused if asked for.
        gui::SegmentationDialog dialog(document, compared);
        auto* others = dialog.findChild<QComboBox*>("reference");
        QVERIFY(others);
        QCOMPARE(others->findData(compared), -1);
        QVERIFY(others->findData(reference) >= 0);
        QSignalSpy refused(window.segmentation(), &gui::SegmentationController::failed);
        QVERIFY(!window.segmentation()->run(compared, compared, {{"field", "c2c_distance"}, {"above", "0.2"}}));
        QCOMPARE(refused.count(), 1);

        // 5: no value of the Properties panel is cut (a global shift, a box corner, a path).
        window.tree()->selectEntity(reference);
        QApplication::processEvents();
        gui::PropertiesPanel* properties = window.properties();
        QCOMPARE(properties->textElideMode(), Qt::ElideNone);
        QVERIFY(!properties->value("Global shift").isEmpty());
        for (int r = 0; r < properties->topLevelItemCount(); ++r) {
            const QTreeWidgetItem* row = properties->topLevelItem(r);
            const int needed = properties->fontMetrics().horizontalAdvance(row->text(1));
            QVERIFY2(properties->columnWidth(1) >= needed, qPrintable(row->text(0) + ": " + row->text(1)));
        }

        // 11: opening the Measure panel does not grow the window.
        window.resize(1200, 700);
        QApplication::processEvents();
        const QSize before = window.size();
        window.findChild<QAction*>("measureAction")->setChecked(true);
        QTest::qWait(100);
        QCOMPARE(window.size(), before);
        QVERIFY(window.findChild<QDockWidget*>("Measure")->isVisible());
        window.findChild<QAction*>("measureAction")->setChecked(false);
    }

    void aMeasurementStaysBetweenTheNearAndFarPlanes()
    {
        // Issue 50, defect 7: a measurement on a cloud hidden since (a parent
        // after a split) was outside the view after reopening a session, until
        // Zoom to all: the near and far planes were fitted to the shown clouds only.
        QTemporaryDir dir;
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        gui::Document& document = window.document();
        const auto plane = [](double z) {
            PointCloud cloud;
            cloud.setOrigin({512000, 5423000, 0});
            for (int i = 0; i < 40; ++i)
                for (int j = 0; j < 40; ++j)
                    cloud.positions().emplace_back(static_cast<float>(i * 0.5), static_cast<float>(j * 0.5), static_cast<float>(z));
            return cloud;
        };
        document.add("ground", plane(0.0));
        const EntityId deep = document.add("deep", plane(-100.0));
        window.measure()->setMeasuring(true);
        window.measure()->addPick(deep, 0);
        window.measure()->addPick(deep, 1599);
        window.measure()->setMeasuring(false);
        const std::vector<Eigen::Vector3d> measured = window.measure()->measurements().front();
        QCOMPARE(measured.size(), std::size_t(2));
        document.setVisible(deep, false);
        const auto betweenThePlanes = [&](const Eigen::Vector3d& p) {
            const Eigen::Vector4d v = window.view()->globalToWidgetPixels() * Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0);
            return v.w() > 0 && v.z() / v.w() >= -1.0 && v.z() / v.w() <= 1.0;
        };
        window.view()->setStandardView(gui::StandardView::Iso); // the camera fitted to the ground alone
        QApplication::processEvents();
        for (const Eigen::Vector3d& p : measured)
            QVERIFY2(betweenThePlanes(p), "after a standard view");
        const QString session = dir.filePath("measured.scandiff");
        QVERIFY(window.sessions()->save(session));
        document.clear();
        QVERIFY(window.sessions()->restore(session));
        QApplication::processEvents();
        QCOMPARE(window.measure()->measurements().front().size(), std::size_t(2));
        for (const Eigen::Vector3d& p : window.measure()->measurements().front())
            QVERIFY2(betweenThePlanes(p), "after the session is reopened");
    }

    void everyMenuIsThereOnceWithItsTools()
    {
        // A tool category named like a built-in submenu (Distances: C2C, C2M)
        // joins it: one Tools > Distances holding C2C, C2M, M3C2, its scales'
        // guess, the DEM of difference and the 2.5D volume.
        Workbench workbench;
        QMenu* tools = nullptr;
        for (QAction* a : workbench.window.menuBar()->actions())
            if (a->text().remove('&') == "Tools")
                tools = a->menu();
        QVERIFY(tools);
        QStringList submenus;
        QMenu* distances = nullptr;
        for (QAction* a : tools->actions())
            if (a->menu()) {
                submenus << a->text().remove('&');
                if (submenus.back() == "Distances")
                    distances = a->menu();
            }
        QCOMPARE(submenus.count("Distances"), 1);
        QCOMPARE(submenus.removeDuplicates(), 0);
        QVERIFY(distances);
        QStringList entries;
        for (QAction* a : distances->actions())
            entries << a->text().remove('&');
        QVERIFY2(entries.size() == 6 && entries.count("M3C2...") == 1 && entries.count("M3C2 scales (guess)...") == 1 &&
                     entries.count("DEM of difference...") == 1,
                 qPrintable(entries.join(", ")));
    }

    void openComputeThresholdSplitExportRestore()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;

        // Open the demo pair.
        QCOMPARE(window.openFiles({kReference, kCompared}, true), 2);
        const std::vector<EntityId> ids = window.document().ids();
        QCOMPARE(ids.size(), std::size_t(2));
        const EntityId reference = ids[0], compared = ids[1];
        QVERIFY(window.tree()->entityRow(reference));
        QCOMPARE(window.tree()->entityRow(reference)->checkState(0), Qt::Checked);
        QCOMPARE(window.tree()->currentEntity(), compared);
        QCOMPARE(window.properties()->value("Points"), QString::number(window.document().item(compared).points().size()));

        // C2C with the same text the dialog would give (split components on).
        QSignalSpy finished(window.distances(), &gui::DistanceController::finished);
        QVERIFY(window.distances()->runCloudToCloud(compared, reference, {{"split-xyz", "true"}}));
        QCOMPARE(finished.count(), 1);
        QVERIFY(finished.at(0).at(0).toString().contains("C2C"));
        const PointCloud& comparedCloud = window.document().item(compared).points();
        const ScalarField* distance = comparedCloud.field("c2c_distance");
        QVERIFY(distance);
        QVERIFY(comparedCloud.field("c2c_dz"));
        QCOMPARE(window.document().item(compared).display.activeField, std::string("c2c_distance"));
        // The reference no longer competes with the distances' colours: one neutral grey.
        QVERIFY(window.document().item(reference).display.neutral);
        QVERIFY(window.document().item(reference).display.activeField.empty());
        // The panels and the colour bar follow once the event loop turns (one
        // refresh for the several changes a run makes).
        QTRY_COMPARE(window.view()->legend().title, std::string("c2c_distance"));
        // The colour bar follows what is shown: with the compared cloud hidden
        // and selected, there is no bar (the reference has no field on screen).
        window.document().setVisible(compared, false);
        QTRY_VERIFY(!window.view()->legend().shown);
        window.document().setVisible(compared, true);
        QTRY_COMPARE(window.view()->legend().title, std::string("c2c_distance"));
        QVERIFY(window.tree()->fieldRow(compared, "c2c_distance"));
        // The same numbers as core called directly.
        const CloudToCloudResult direct =
            cloudToCloud(comparedCloud, window.document().item(reference).points(), CloudToCloudParams{});
        QCOMPARE(direct.distance.values(), distance->values());

        // The scalar-field panel shows the new field; type a threshold as a user does.
        gui::ScalarFieldPanel* panel = window.scalarPanel();
        QCOMPARE(panel->entity(), compared);
        QCOMPARE(panel->fieldBox()->currentText(), QString("c2c_distance"));
        QVERIFY(panel->splitButton()->isEnabled());
        const double low = 0.5;
        QDoubleSpinBox* lowBox = panel->rangeEditor()->lowBox();
        lowBox->setFocus();
        lowBox->selectAll();
        QTest::keyClicks(lowBox, "0.5");
        QTest::keyClick(lowBox, Qt::Key_Return);
        QCOMPARE(panel->rangeEditor()->low(), low);
        const double high = panel->rangeEditor()->high();
        QCOMPARE(window.document().fieldDisplay(compared, "c2c_distance").low, low);
        const std::size_t inside = bruteForceInside(*distance, low, high);
        QVERIFY(inside > 0 && inside < distance->size());
        QVERIFY2(panel->insideText().contains(QString::number(inside)), qPrintable(panel->insideText()));

        // Split at thresholds: two new clouds under the compared one.
        QTest::mouseClick(panel->splitButton(), Qt::LeftButton);
        const std::vector<EntityId> afterSplit = window.document().ids();
        QCOMPARE(afterSplit.size(), std::size_t(4));
        const gui::Document::Item& insidePart = window.document().item(afterSplit[2]);
        const gui::Document::Item& outsidePart = window.document().item(afterSplit[3]);
        QCOMPARE(insidePart.parent, compared);
        QCOMPARE(outsidePart.parent, compared);
        QCOMPARE(insidePart.points().size(), inside);
        QCOMPARE(outsidePart.points().size(), distance->size() - inside);
        for (std::size_t i = 0; i < insidePart.points().size(); ++i) {
            const double v = insidePart.points().field("c2c_distance")->value(i);
            QVERIFY(v >= low && v <= high);
        }
        QVERIFY(!window.document().item(compared).display.visible); // the parts replace it on screen
        QCOMPARE(window.tree()->entityRow(compared)->checkState(0), Qt::Unchecked);

        // Export the inside part: PLY with every field, read back identical.
        QTemporaryDir dir;
        const QString exported = dir.filePath("changes.ply");
        QVERIFY(window.files()->exportEntity(insidePart.id, exported));
        const PointCloud readBack = io::readPointCloud(workbench.registry.formats, exported.toStdString());
        QCOMPARE(readBack.size(), inside);
        QVERIFY(readBack.field("c2c_dx"));
        QCOMPARE(readBack.field("c2c_distance")->values(), insidePart.points().field("c2c_distance")->values());

        // Save and restore the session: entities, tree, active field, thresholds, camera.
        window.view()->setStandardView(gui::StandardView::Top);
        const gui::CameraState camera = window.view()->camera();
        const QString session = dir.filePath("work.scandiff");
        gui::FieldDisplay narrowed = window.document().fieldDisplay(compared, "c2c_distance");
        narrowed.colourLow = 0.125;
        narrowed.colourHigh = 0.75;
        narrowed.symmetric = true;
        window.document().setFieldDisplay(compared, "c2c_distance", narrowed);
        QVERIFY(window.sessions()->save(session));
        window.document().clear();
        QCOMPARE(window.document().size(), std::size_t(0));
        window.view()->setStandardView(gui::StandardView::Front);
        QSignalSpy sessionFailed(window.sessions(), &gui::SessionController::failed);
        const bool restoredOk = window.sessions()->restore(session);
        QVERIFY2(restoredOk, sessionFailed.isEmpty() ? "" : qPrintable(sessionFailed.at(0).at(0).toString()));
        const std::vector<EntityId> restored = window.document().ids();
        QCOMPARE(restored.size(), std::size_t(4));
        const gui::Document::Item& restoredCompared = window.document().item(restored[1]);
        QCOMPARE(restoredCompared.name, QString("site-2024"));
        QCOMPARE(restoredCompared.display.activeField, std::string("c2c_distance"));
        QVERIFY(!restoredCompared.display.visible);
        QCOMPARE(window.document().fieldDisplay(restored[1], "c2c_distance").low, low);
        QCOMPARE(window.document().fieldDisplay(restored[1], "c2c_distance").colourLow, 0.125);
        QCOMPARE(window.document().fieldDisplay(restored[1], "c2c_distance").colourHigh, 0.75);
        QVERIFY(window.document().fieldDisplay(restored[1], "c2c_distance").symmetric);
        QCOMPARE(window.document().item(restored[2]).parent, restored[1]);
        QCOMPARE(window.document().item(restored[2]).points().size(), inside);
        const gui::CameraState back = window.view()->camera();
        for (int k = 0; k < 3; ++k) {
            QCOMPARE(back.position[k], camera.position[k]);
            QCOMPARE(back.viewUp[k], camera.viewUp[k]);
        }
    }

    void stonesDrawnOverTheWallListedExportedAndKeptInTheSession()
    {
        // Tools > Contours > Stones on a synthetic wall of 20 stones: the
        // points get stone_id, the contours join the tree under the wall and
        // are drawn over it; File > Export writes them as DXF; a saved session
        // brings them back.
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        test::StoneWallScene scene = test::makeStoneWall(test::StoneWallOptions{});
        const EntityId wall = window.document().add("wall", std::move(scene.cloud));
        QVERIFY(window.toolController("stones")->run(wall, {}));
        QVERIFY(window.document().item(wall).points().field("stone_id"));
        const gui::Document::Item* contours = nullptr;
        for (EntityId id : window.document().ids())
            if (window.document().item(id).isDrawing())
                contours = &window.document().item(id);
        QVERIFY(contours);
        QCOMPARE(contours->parent, wall);
        QCOMPARE(contours->drawing->polylines.size(), scene.stones.size());
        QVERIFY(window.document().item(wall).display.visible); // the wall stays shown under its contours
        // The inter-means threshold and the two modes it separated are on the intensity histogram.
        window.document().setActiveField(wall, "intensity");
        window.scalarPanel()->showEntity(wall);
        const auto& references = window.scalarPanel()->histogram()->referenceLines();
        QCOMPARE(references.size(), std::size_t(3));
        QVERIFY(references[0].second.startsWith("threshold"));
        QVERIFY(references[1].first < references[0].first && references[0].first < references[2].first); // dark stones
        // Each stone's id is a label in the view, hidden with its drawing.
        QCOMPARE(window.view()->labelCount(contours->id), scene.stones.size());
        QVERIFY(window.view()->labelsVisible(contours->id));
        window.document().setVisible(contours->id, false);
        QVERIFY(!window.view()->labelsVisible(contours->id));
        window.document().setVisible(contours->id, true);
        window.view()->zoomToEntity(contours->id);
        window.view()->render();
        QTemporaryDir dir;
        const QString dxf = dir.filePath("stones.dxf");
        QVERIFY(window.files()->exportEntity(contours->id, dxf));
        QCOMPARE(io::readDrawingDxf(dxf.toStdString()).polylines.size(), scene.stones.size());
        const QString session = dir.filePath("stones.scandiff");
        QVERIFY(window.sessions()->save(session));
        window.document().clear();
        QVERIFY(window.sessions()->restore(session));
        std::size_t drawings = 0;
        for (EntityId id : window.document().ids())
            if (window.document().item(id).isDrawing()) {
                ++drawings;
                QCOMPARE(window.document().item(id).drawing->polylines.size(), scene.stones.size());
                QVERIFY(window.document().item(window.document().item(id).parent).points().field("stone_id"));
            }
        QCOMPARE(drawings, std::size_t(1));
    }

    void primitivesListedUnderTheCloudWithTheirSurfacesAndParameters()
    {
        // Tools > Primitives on an analytic scene: the cloud gets primitive_id;
        // each shape's points join the tree under it, its surface (a mesh) under
        // them, both coloured by the shape's id; selecting either shows the
        // shape's parameters; a saved session keeps them.
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        test::PrimitiveScene scene = test::makePrimitiveScene(test::testSceneShapes(), 40000, 0.005, 0.02, 3, true);
        const EntityId cloud = window.document().add("scene", std::move(scene.cloud));
        QVERIFY(window.toolController("primitives")->run(cloud, {{"seed", "5"}}));
        QVERIFY(window.document().item(cloud).points().field("primitive_id"));
        std::size_t surfaces = 0, shapes = 0;
        EntityId firstSurface = gui::kNoEntity;
        for (EntityId id : window.document().ids()) {
            const gui::Document::Item& item = window.document().item(id);
            if (item.parent == cloud && !item.isDrawing()) {
                ++shapes;
                QVERIFY(!item.properties.empty());
                QCOMPARE(item.properties.front().first, QString("Shape"));
                QCOMPARE(item.display.activeField, std::string("primitive_id")); // one colour per shape
            }
            if (!item.mesh())
                continue;
            ++surfaces;
            // Under its points, which are under the cloud, with the same parameters.
            const gui::Document::Item& points = window.document().item(item.parent);
            QCOMPARE(points.parent, cloud);
            QVERIFY(item.properties == points.properties);
            QVERIFY(item.name.endsWith("_surface"));
            QVERIFY(item.properties.front().second.startsWith(points.name + " "));
            QCOMPARE(item.display.activeField, std::string("primitive_id"));
            if (firstSurface == gui::kNoEntity)
                firstSurface = id;
        }
        QVERIFY(surfaces >= 10);
        QCOMPARE(surfaces, shapes);
        window.properties()->showEntity(firstSurface);
        const gui::Document::Item& first = window.document().item(firstSurface);
        QCOMPARE(window.properties()->value("Shape"), first.properties.front().second);
        QVERIFY(!window.properties()->value("RMS (m)").isEmpty());
        QCOMPARE(window.properties()->value("Triangles"), QString::number(first.mesh()->triangles.size()));
        window.view()->zoomToEntity(cloud);
        window.view()->render();

        QTemporaryDir dir;
        const QString session = dir.filePath("primitives.scandiff");
        QVERIFY(window.sessions()->save(session));
        const auto before = first.properties;
        window.document().clear();
        QVERIFY(window.sessions()->restore(session));
        std::size_t restored = 0;
        for (EntityId id : window.document().ids())
            if (window.document().item(id).mesh()) {
                ++restored;
                QVERIFY(!window.document().item(id).properties.empty());
                if (restored == 1)
                    QVERIFY(window.document().item(id).properties == before);
            }
        QCOMPARE(restored, surfaces);
    }

    void multiScanE57OpensAsAGroupOfScansAndExportsBack()
    {
        // An E57 of two stations opens as one entity per scan under a group
        // named after the file; tools see the scans, not the group; exporting
        // the group writes both scans to one E57; a session keeps the tree.
        QTemporaryDir dir;
        const std::string e57 = dir.filePath("survey.e57").toStdString();
        {
            PointCloud north, south;
            north.name = "north";
            south.name = "south";
            for (PointCloud* scan : {&north, &south}) {
                scan->setOrigin(Eigen::Vector3d(652000.0, 6862000.0, 0.0));
                scan->resize(500);
                for (std::size_t i = 0; i < 500; ++i)
                    scan->positions()[i] = Eigen::Vector3f(float(i % 25), float(i / 25), scan == &north ? 10.0f : 12.5f);
            }
            SensorPose station;
            station.position = Eigen::Vector3d(652010.0, 6862010.0, 1.5);
            north.sensors().push_back(station);
            io::writeE57({&north, &south}, e57);
        }
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        QCOMPARE(window.openFiles({QString::fromStdString(e57)}, true), 2);
        gui::Document& document = window.document();
        QCOMPARE(document.size(), std::size_t(3));
        const EntityId group = document.ids()[0];
        QVERIFY(document.item(group).isGroup());
        QCOMPARE(document.item(group).name, QString("survey"));
        const std::vector<EntityId> scans = document.children(group);
        QCOMPARE(scans.size(), std::size_t(2));
        QCOMPARE(document.item(scans[0]).name, QString("north"));
        QCOMPARE(document.item(scans[0]).points().size(), std::size_t(500));
        QCOMPARE(document.item(scans[0]).points().sensors().size(), std::size_t(1));
        // Both scans keep the site's origin: their points are where they were.
        QCOMPARE(document.item(scans[1]).points().globalPosition(26), Eigen::Vector3d(652001.0, 6862001.0, 12.5));
        const std::vector<EntityId> inputs = gui::acceptedEntities(document, InputSpec{});
        QVERIFY(std::find(inputs.begin(), inputs.end(), group) == inputs.end());
        QCOMPARE(inputs.size(), std::size_t(2));

        // The group's checkbox hides and shows its scans.
        document.setVisible(group, false);
        QVERIFY(!document.item(scans[0]).display.visible && !document.item(scans[1]).display.visible);
        document.setVisible(group, true);
        QVERIFY(document.item(scans[0]).display.visible && document.item(scans[1]).display.visible);

        const QString exported = dir.filePath("again.e57");
        QVERIFY(window.files()->exportEntity(group, exported));
        const std::vector<PointCloud> back = io::readE57Scans(exported.toStdString());
        QCOMPARE(back.size(), std::size_t(2));
        QCOMPARE(back[1].name, std::string("south"));
        QCOMPARE(back[1].size(), std::size_t(500));

        const QString session = dir.filePath("survey.scandiff");
        QVERIFY(window.sessions()->save(session));
        document.clear();
        QVERIFY(window.sessions()->restore(session));
        QCOMPARE(document.size(), std::size_t(3));
        QVERIFY(document.item(document.ids()[0]).isGroup());
        QCOMPARE(document.children(document.ids()[0]).size(), std::size_t(2));
    }

    void processingToolsFromTheMenusDeclarations()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        QCOMPARE(window.openFiles({kReference, kCompared}, true), 2);
        const EntityId reference = window.document().ids()[0], compared = window.document().ids()[1];
        const std::size_t points = window.document().item(reference).points().size();

        // Every tool has its menu entry, under its category, but those that
        // compare drawing files (the command line's).
        for (const ToolSpec& tool : workbench.registry.tools.tools()) {
            const bool needsDrawing = std::any_of(tool.inputs.begin(), tool.inputs.end(),
                                                  [](const InputSpec& in) { return in.kind == DataKind::Drawing; });
            QVERIFY2(bool(window.toolController(tool.name)) != needsDrawing, tool.name.c_str());
        }

        // Normals: the entity in the view is replaced by the same points with normals.
        QVERIFY(window.toolController("normals")->run(reference, {{"radius", "3"}, {"orient", "+z"}}));
        QVERIFY(window.document().item(reference).points().hasNormals());
        QCOMPARE(window.document().item(reference).points().size(), points);
        window.tree()->selectEntity(reference);
        QCOMPARE(window.properties()->value("Normals"), QString("yes"));
        window.view()->render();

        // A translation is kept in the history, shown in the properties, and survives the session.
        QVERIFY(window.toolController("transform")->run(reference, {{"translate", "1,2,3"}}));
        window.tree()->selectEntity(reference);
        QTRY_COMPARE(window.properties()->value("Transformations"), QString("1"));
        QTemporaryDir dir;
        const QString session = dir.filePath("tools.scandiff");
        QVERIFY(window.sessions()->save(session));
        window.document().clear();
        QVERIFY(window.sessions()->restore(session));
        const EntityId restored = window.document().ids()[0];
        const PointCloud& back = window.document().item(restored).points();
        QCOMPARE(back.transformHistory().size(), std::size_t(1));
        QCOMPARE(back.transformHistory()[0].matrix(1, 3), 2.0);
        QVERIFY(back.hasNormals());

        // The 2.5D mesh of the reference is a reference C2M can use.
        QVERIFY(window.toolController("mesh")->run(restored, {{"max-edge", "10"}}));
        const EntityId mesh = window.document().ids().back();
        QVERIFY(window.document().item(mesh).mesh());
        QVERIFY(window.distances()->runCloudToMesh(window.document().ids()[1], mesh, {}));
        QVERIFY(window.document().item(window.document().ids()[1]).points().field("c2m_distance"));

        // A table output opens a window that saves the CSV.
        QVERIFY(window.toolController("field-histogram")->run(window.document().ids()[1], {{"field", "c2m_distance"}, {"bins", "16"}}));
        gui::TableDialog* table = nullptr;
        for (QWidget* w : QApplication::topLevelWidgets())
            if (auto* t = qobject_cast<gui::TableDialog*>(w))
                table = t;
        QVERIFY(table);
        QCOMPARE(table->view(0)->rowCount(), 16);
        QVERIFY(table->saveAs(dir.filePath("histogram.csv")));
        QVERIFY(QFileInfo(dir.filePath("histogram.csv")).size() > 0);
        table->close();
        (void)compared;
    }

    void pickingShowsEveryFieldOfThePoint()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        QCOMPARE(window.openFiles({kReference}, true), 1);
        const EntityId id = window.document().ids().front();
        window.view()->setStandardView(gui::StandardView::Top);
        QSignalSpy picked(window.view(), &gui::CloudView::pointPicked);
        // The middle of a top view of a dense airborne scan is always on a point.
        QVERIFY(window.view()->pickAt(window.view()->width() / 2, window.view()->height() / 2));
        QCOMPARE(picked.count(), 1);
        QCOMPARE(picked.at(0).at(0).toInt(), id);
        const std::size_t index = picked.at(0).at(1).value<std::size_t>();
        QVERIFY(index < window.document().item(id).points().size());
        QVERIFY(!window.properties()->value("Picked point").isEmpty());
        const QString xyz = window.properties()->value("X, Y, Z");
        QVERIFY(xyz.startsWith(QString::number(window.document().item(id).points().globalPosition(index).x(), 'f', 3)));
    }

    void aGridIsDrawnAsItsCellsAndAClickPicksACell()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        QCOMPARE(window.openFiles({kReference, kCompared}, true), 2);
        const EntityId reference = window.document().ids()[0], compared = window.document().ids()[1];
        QVERIFY(window.toolController("dod")->run(gui::ToolInputChoice{{"reference", {reference}}, {"compared", {compared}}},
                                                  {{"cell", "2"}}));
        const EntityId grid = window.document().ids().back();
        const PointCloud& cells = window.document().item(grid).points();
        QVERIFY(cells.field("raster_col") && cells.size() > 10);
        // Drawn as quads: the mean of the first cell's four corners is its centre.
        Eigen::Vector3d offset;
        Eigen::Vector3f first;
        QVERIFY(window.view()->shownFrame(grid, offset, first));
        QVERIFY((first - cells.positions().front()).norm() < 1e-4f);
        // With the epochs hidden, a click on the middle of a top view is on a
        // cell, and picks that cell (not one of its corners).
        window.document().setVisible(reference, false);
        window.document().setVisible(compared, false);
        window.view()->zoomToEntity(grid);
        window.view()->setStandardView(gui::StandardView::Top);
        QSignalSpy picked(window.view(), &gui::CloudView::pointPicked);
        QVERIFY(window.view()->pickAt(window.view()->width() / 2, window.view()->height() / 2));
        QCOMPARE(picked.count(), 1);
        QCOMPARE(picked.at(0).at(0).toInt(), grid);
        const std::size_t cell = picked.at(0).at(1).value<std::size_t>();
        QVERIFY(cell < cells.size());
        // The picked cell is the one under the middle of the view (or its neighbour: the picker has a tolerance).
        const gui::CameraState camera = window.view()->camera();
        const Eigen::Vector3d centre = cells.globalPosition(cell);
        QVERIFY(std::hypot(centre.x() - camera.focalPoint[0], centre.y() - camera.focalPoint[1]) < 2 * 2 * std::sqrt(2.0));
        for (QWidget* w : QApplication::topLevelWidgets())
            if (auto* t = qobject_cast<gui::TableDialog*>(w))
                t->close();
    }

    void segmentTheChangesAndExportTheRegions()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        QCOMPARE(window.openFiles({kReference, kCompared}, true), 2);
        const EntityId reference = window.document().ids()[0], compared = window.document().ids()[1];
        QVERIFY(window.distances()->runCloudToCloud(compared, reference, {}));

        // The dialog proposes the field on screen.
        gui::SegmentationDialog dialog(window.document(), compared);
        QCOMPARE(dialog.input(), compared);
        QCOMPARE(dialog.values().at("field"), std::string("c2c_distance"));

        // The demo's compared epoch holds two changes seen from it: the raised
        // block (+2 m) and the appeared box (the removed area has no points there).
        // Export regions is not offered for a cloud without regions.
        QList<QAction*> regionExports;
        for (QAction* action : window.findChildren<QAction*>())
            if (action->text().remove('&').startsWith("Export regions"))
                regionExports << action;
        QCOMPARE(regionExports.size(), 2); // File menu and the tree's menu
        window.tree()->selectEntity(compared);
        for (QAction* action : regionExports)
            QVERIFY(!action->isEnabled());
        QVERIFY(window.segmentation()->run(compared, reference,
                                           {{"field", "c2c_distance"}, {"above", "0.5"}, {"components", "true"}, {"min-points", "20"}}));
        window.tree()->selectEntity(compared);
        for (QAction* action : regionExports)
            QVERIFY(action->isEnabled());
        const gui::Document::Item& item = window.document().item(compared);
        QCOMPARE(item.display.activeField, std::string("region_id"));
        // Region ids are labels: one swatch per region in the colour bar, not a ramp.
        QCOMPARE(window.view()->legend().categories.size(), std::size_t(2));
        const auto& report = window.segmentation()->report(compared);
        QCOMPARE(report.size(), std::size_t(2));
        // Each region is listed under its cloud with exactly its points.
        std::size_t children = 0;
        for (EntityId id : window.document().ids())
            if (window.document().item(id).parent == compared) {
                const gui::Document::Item& region = window.document().item(id);
                QCOMPARE(region.points().size(), report[children].pointCount);
                QVERIFY(!region.display.visible); // not drawn over the regions' colours
                ++children;
            }
        QCOMPARE(children, report.size());
        // Running again replaces the regions instead of adding a second set.
        const std::size_t entitiesBefore = window.document().size();
        QVERIFY(window.segmentation()->run(compared, reference,
                                           {{"field", "c2c_distance"}, {"above", "0.5"}, {"components", "true"}, {"min-points", "20"}}));
        QCOMPARE(window.document().size(), entitiesBefore);
        // The raised block: no point of it is farther than its 2 m lift (plus the 2 cm noise) from the old surface.
        QVERIFY(std::abs(report[0].maxDistance - 2.0) < 0.1 || std::abs(report[1].maxDistance - 2.0) < 0.1);

        QTemporaryDir dir;
        QVERIFY(window.segmentation()->exportRegions(compared, dir.path()));
        for (const char* name : {"regions.ply", "regions.dxf", "regions.csv", "region_0001.ply", "region_0002.ply"})
            QVERIFY2(QFile::exists(dir.filePath(name)), name);
        QFile csv(dir.filePath("regions.csv"));
        QVERIFY(csv.open(QIODevice::ReadOnly));
        QCOMPARE(QString(csv.readAll()).trimmed().split('\n').size(), 3); // header + two regions
        const PointCloud all = io::readPointCloud(workbench.registry.formats, dir.filePath("regions.ply").toStdString());
        QCOMPARE(all.size(), report[0].pointCount + report[1].pointCount);
        QVERIFY(all.field("region_id"));
        // The DXF holds outlines and labels; with the points option, one POINT
        // entity per region point too.
        auto dxfPoints = [](const QString& path) {
            QFile dxf(path);
            if (!dxf.open(QIODevice::ReadOnly))
                return std::size_t(-1);
            const QStringList lines = QString(dxf.readAll()).split('\n');
            std::size_t count = 0;
            for (int i = 0; i + 1 < lines.size(); ++i)
                count += lines[i].trimmed() == "0" && lines[i + 1].trimmed() == "POINT";
            return count;
        };
        QCOMPARE(dxfPoints(dir.filePath("regions.dxf")), std::size_t(0));
        QTemporaryDir withPoints;
        QVERIFY(window.segmentation()->exportRegions(compared, withPoints.path(), true));
        QCOMPARE(dxfPoints(withPoints.filePath("regions.dxf")), report[0].pointCount + report[1].pointCount);
    }

    void dropRecentAndDecimation()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        // A file dropped on the window opens, and joins the recent files.
        auto* mime = new QMimeData;
        mime->setUrls({QUrl::fromLocalFile(kReference)});
        QDragEnterEvent enter(QPoint(200, 200), Qt::CopyAction, mime, Qt::LeftButton, Qt::NoModifier);
        QApplication::sendEvent(&window, &enter);
        QVERIFY(enter.isAccepted());
        QDropEvent drop(QPointF(200, 200), Qt::CopyAction, mime, Qt::LeftButton, Qt::NoModifier);
        // A dropped UTM file asks the global-shift question: take the suggested origin.
        QTimer answer;
        connect(&answer, &QTimer::timeout, [] {
            if (auto* dialog = qobject_cast<gui::GlobalShiftDialog*>(QApplication::activeModalWidget()))
                dialog->accept();
        });
        answer.start(50);
        QApplication::sendEvent(&window, &drop);
        answer.stop();
        delete mime;
        QCOMPARE(window.document().size(), std::size_t(1));
        QCOMPARE(window.files()->recentFiles().value(0), QFileInfo(kReference).absoluteFilePath());
        // Above the interactive budget, a moving camera draws every k-th point.
        window.view()->setInteractiveBudget(10000);
        const std::size_t points = window.document().item(window.document().ids().front()).points().size();
        QCOMPARE(window.view()->interactiveStride(), (points + 9999) / 10000);
        window.view()->setMoving(true);
        window.view()->render();
        window.view()->setMoving(false);
    }

    void aLargeCloudAtRestIsDrawnInSlicesOfTheBudgetAndAMoveStartsAgain()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        gui::CloudView& view = *window.view();
        // Five million points: a full frame froze the workbench on Mesa's
        // software renderer for seconds (33 s at 2 x 20 M).
        constexpr std::size_t kSide = 2237;
        PointCloud terrain;
        terrain.resize(kSide * kSide);
        for (std::size_t i = 0; i < kSide; ++i)
            for (std::size_t j = 0; j < kSide; ++j)
                terrain.positions()[i * kSide + j] = {0.02f * i, 0.02f * j, static_cast<float>(3 * std::sin(0.01 * i) * std::cos(0.013 * j))};
        // A roof 7 m above the terrain's crests, 1 x 4 m at 5 mm: the slices
        // drawn later must not paint the terrain over it.
        PointCloud roof;
        roof.resize(200 * 800);
        for (std::size_t i = 0; i < 200; ++i)
            for (std::size_t j = 0; j < 800; ++j)
                roof.positions()[i * 800 + j] = {21.0f + 0.005f * i, 20.0f + 0.005f * j, 10.0f};
        const std::size_t points = terrain.size() + roof.size();
        // Each chunk rounds its share of a slice up.
        const std::size_t chunks = ((terrain.size() + (1u << 18) - 1) >> 18) + ((roof.size() + (1u << 18) - 1) >> 18);
        window.document().add("terrain", std::move(terrain));
        window.document().add("roof", std::move(roof));
        constexpr std::size_t kBudget = 400'000;
        view.setInteractiveBudget(kBudget);
        const std::size_t slices = (points + kBudget - 1) / kBudget;
        QTRY_COMPARE(view.interactiveStride(), slices); // the view shows what the document holds
        const gui::CloudView::Refinement& r = view.refinement();

        // A cloud added is drawn decimated at once, at rest a moment later.
        QTRY_VERIFY_WITH_TIMEOUT(view.refinement().starts >= 1, 5000);
        QTRY_VERIFY_WITH_TIMEOUT(!view.refinement().refining, 300000);
        // At rest: the decimated picture at once, the rest slice by slice.
        view.render();
        QCOMPARE(r.slices, slices);
        QCOMPARE(r.slicesDrawn, std::size_t(1));
        QVERIFY(r.refining);
        QVERIFY(r.pointsDrawn <= kBudget + chunks);
        // Left alone, it draws every point once, never more than the budget a frame.
        QTRY_VERIFY_WITH_TIMEOUT(!view.refinement().refining, 300000);
        QCOMPARE(r.slicesDrawn, slices);
        QCOMPARE(r.pointsDrawn, points);
        QVERIFY2(r.largestSlice <= kBudget + chunks, std::to_string(r.largestSlice).c_str());
        // OpenGL was given the decimated frame's points and the last slice's,
        // never a whole chunk (a software renderer keeps a copy of what it is
        // given: 16 bytes a point for the session); the view holds the RGBA
        // colours and those two copies (positions 12 bytes, colours 4, a
        // vertex 8, and VTK's spare capacity: at most 32 a point copied).
        const std::size_t perSlice = points / slices + chunks;
        QVERIFY2(view.pointsGivenToOpenGl() <= 2 * perSlice, std::to_string(view.pointsGivenToOpenGl()).c_str());
        QVERIFY2(view.pointsGivenToOpenGl() >= perSlice, std::to_string(view.pointsGivenToOpenGl()).c_str());
        QVERIFY2(view.heldBytes() <= 4 * points + 2 * 32 * perSlice, std::to_string(view.heldBytes()).c_str());
        // The slices add up to the full picture: on every pixel a point
        // covers, the same colour, but where points tie in depth (the order of
        // drawing differs: a neighbour of a nearly equal colour may win).
        // Seen from close enough that the points stand apart on the screen
        // (about 3 pixels between them), a slice missing shows; the roof in
        // the middle of the view shows a slice drawn through what hides it.
        gui::CameraState close;
        close.focalPoint = {22, 22, 0};
        close.position = {22, 22, 100};
        close.parallel = true;
        close.parallelScale = 2.25;
        view.setCamera(close);
        QCOMPARE(r.slicesDrawn, std::size_t(1));
        const QImage coarse = view.shownPicture();
        QTRY_VERIFY_WITH_TIMEOUT(!view.refinement().refining, 300000);
        QCOMPARE(r.slicesDrawn, slices);
        const QImage refined = view.shownPicture();
        // A click at rest picks among every point, as with every point drawn,
        // though only a stride-th of them went to OpenGL (the decimated copy).
        QSignalSpy picked(&view, &gui::CloudView::pointPicked);
        const int pickX = view.width() / 2 - 37, pickY = view.height() / 2 - 23;
        QVERIFY(view.pickAt(pickX, pickY));
        view.setInteractiveBudget(points);
        view.render();
        QVERIFY(!view.refinement().refining);
        const QImage full = view.shownPicture();
        QVERIFY(view.pickAt(pickX, pickY));
        QCOMPARE(picked.count(), 2);
        QCOMPARE(picked.at(0).at(0).toInt(), picked.at(1).at(0).toInt());
        {
            // The same point, or one as good: the roof is flat at 5 mm, so two
            // of its points can share the cursor's pixel (7.5 mm here) at one
            // depth, and which one the slices met first depends on the budget
            // the machine's speed set (a loaded machine picked one 1 cm away).
            const std::size_t atRest = picked.at(0).at(1).value<std::size_t>(), onFullFrame = picked.at(1).at(1).value<std::size_t>();
            const auto& shown = window.document().item(static_cast<gui::EntityId>(picked.at(0).at(0).toInt())).points().positions();
            QVERIFY(atRest < shown.size() && onFullFrame < shown.size());
            QVERIFY2(atRest == onFullFrame || (shown[atRest].z() == shown[onFullFrame].z() &&
                                               (shown[atRest] - shown[onFullFrame]).head<2>().norm() <= 2 * 0.0075f),
                     qPrintable(QString("picked %1 at rest, %2 on the full frame").arg(atRest).arg(onFullFrame)));
        }
        QCOMPARE(refined.size(), full.size());
        const auto apart = [](QRgb f, QRgb g) {
            return std::max({std::abs(qRed(f) - qRed(g)), std::abs(qGreen(f) - qGreen(g)), std::abs(qBlue(f) - qBlue(g))}) > 24;
        };
        std::size_t differ = 0, covered = 0, coarseDiffer = 0;
        for (int y = 0; y < full.height(); ++y)
            for (int x = 0; x < full.width(); ++x) {
                const QRgb f = full.pixel(x, y);
                if (f == full.pixel(1, y)) // the background's gradient, row by row
                    continue;
                ++covered;
                differ += apart(f, refined.pixel(x, y));
                coarseDiffer += apart(f, coarse.pixel(x, y));
            }
        QVERIFY2(covered > std::size_t(full.width() * full.height() / 5), std::to_string(covered).c_str());
        QVERIFY2(coarseDiffer > covered / 2, (std::to_string(coarseDiffer) + " of " + std::to_string(covered)).c_str());
        QVERIFY2(differ <= covered / 1000, (std::to_string(differ) + " of " + std::to_string(covered)).c_str());

        // A camera move stops the slices; the next rest starts from the decimated picture.
        view.setInteractiveBudget(kBudget);
        view.render();
        QTRY_VERIFY_WITH_TIMEOUT(view.refinement().slicesDrawn >= 3, 60000);
        const std::size_t starts = r.starts;
        view.setMoving(true);
        QVERIFY(!r.refining);
        const std::size_t drawnBefore = r.slicesDrawn;
        QTest::qWait(100);
        QCOMPARE(r.slicesDrawn, drawnBefore);
        view.setMoving(false);
        QCOMPARE(r.starts, starts + 1);
        QCOMPARE(r.slicesDrawn, std::size_t(1));
        QVERIFY(r.refining);
        // A colour change stops them too, and starts them again once the changes stop.
        QTRY_VERIFY_WITH_TIMEOUT(view.refinement().slicesDrawn >= 2, 60000);
        window.document().setNeutral(window.document().ids().front(), true);
        QVERIFY(!r.refining);
        QTRY_VERIFY_WITH_TIMEOUT(view.refinement().starts == starts + 2, 5000);
        QTRY_VERIFY_WITH_TIMEOUT(!view.refinement().refining, 300000);
        QCOMPARE(r.pointsDrawn, points);
    }

    // A threshold drag on a cloud refined in slices colours the points the
    // moving frame draws, not the whole cloud (at 60 M points a step took
    // 324 ms, the whole cloud recoloured each time); the slices colour theirs
    // as they gather them, and what reads every point (the scissors, a
    // pick) gets every point's colour first.
    void aThresholdChangeOnALargeCloudColoursWhatIsDrawn()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        gui::CloudView& view = *window.view();
        constexpr std::size_t kSide = 2237; // five million points
        PointCloud terrain;
        terrain.resize(kSide * kSide);
        ScalarField& distance = terrain.addField("c2c_distance");
        for (std::size_t i = 0; i < kSide; ++i)
            for (std::size_t j = 0; j < kSide; ++j) {
                terrain.positions()[i * kSide + j] = {0.02f * i, 0.02f * j, static_cast<float>(std::sin(0.01 * i))};
                // Smooth, so that points tying in depth have nearly one colour
                // (which of them a frame draws last differs between frames).
                distance.setValue(i * kSide + j, 0.0003 * static_cast<double>(i) + 0.0002 * static_cast<double>(j));
            }
        const std::size_t points = terrain.size();
        const EntityId id = window.document().add("terrain", std::move(terrain));
        window.document().setActiveField(id, "c2c_distance");
        constexpr std::size_t kBudget = 400'000;
        view.setInteractiveBudget(kBudget);
        QTRY_VERIFY_WITH_TIMEOUT(view.refinement().starts >= 1, 5000);
        QTRY_VERIFY_WITH_TIMEOUT(!view.refinement().refining, 300000);
        QCOMPARE(view.pointsAwaitingColour(), std::size_t(0)); // the slices coloured every point

        const auto setThresholds = [&](double low, double high) {
            gui::FieldDisplay display = window.document().fieldDisplay(id, "c2c_distance");
            display.low = low;
            display.high = high;
            window.document().setFieldDisplay(id, "c2c_distance", display);
        };
        gui::CameraState close; // points 3 pixels apart, the value 0.55 across the middle
        close.focalPoint = {22, 22, 0};
        close.position = {22, 22, 100};
        close.parallel = true;
        close.parallelScale = 2.25;
        view.setCamera(close);
        QTRY_VERIFY_WITH_TIMEOUT(!view.refinement().refining, 300000);
        // The slices colour the rest, and the picture is the very one the
        // slices draw when every point was coloured at once.
        const auto refinedAfter = [&](double low, double high, bool colourEverythingFirst, QImage& picture) {
            const std::size_t starts = view.refinement().starts;
            setThresholds(0, 1);
            setThresholds(low, high);
            if (!colourEverythingFirst && view.pointsAwaitingColour() != points)
                return false; // only the decimated frame's were to be coloured
            if (colourEverythingFirst)
                view.isPointShown(id, 0);
            if (!QTest::qWaitFor([&] { return view.refinement().starts > starts && !view.refinement().refining; }, 300000))
                return false;
            picture = view.shownPicture();
            return view.pointsAwaitingColour() == 0;
        };
        QImage lazily, atOnce, everything;
        QVERIFY(refinedAfter(0.2, 0.55, false, lazily));
        QVERIFY(refinedAfter(0.2, 0.55, true, atOnce));
        QVERIFY(refinedAfter(0, 1, false, everything));
        QCOMPARE(lazily.size(), atOnce.size());
        std::size_t differ = 0, hiddenByTheBand = 0;
        for (int y = 0; y < atOnce.height(); ++y)
            for (int x = 0; x < atOnce.width(); ++x) {
                differ += lazily.pixel(x, y) != atOnce.pixel(x, y);
                hiddenByTheBand += everything.pixel(x, y) != atOnce.pixel(x, y);
            }
        QCOMPARE(differ, std::size_t(0));
        // And the band shows: about half the view is above 0.55 and hidden (a
        // slice left in the colours of the thresholds before would show it).
        const auto pixels = static_cast<std::size_t>(atOnce.width() * atOnce.height());
        QVERIFY2(hiddenByTheBand > pixels / 4, (std::to_string(hiddenByTheBand) + " of " + std::to_string(pixels)).c_str());

        // Another change, read at once by what needs every point: each point
        // shown exactly where its value lies within the thresholds.
        setThresholds(0.1, 0.3);
        QCOMPARE(view.pointsAwaitingColour(), points);
        const ScalarField& values = *window.document().item(id).points().field("c2c_distance");
        std::size_t wrong = 0;
        for (std::size_t i = 0; i < points; ++i) {
            const double v = values.value(i);
            wrong += view.isPointShown(id, i) != (v >= 0.1 && v <= 0.3);
        }
        QCOMPARE(wrong, std::size_t(0));
        QCOMPARE(view.pointsAwaitingColour(), std::size_t(0));
    }

    void quittingAsksAboutUnsavedWork()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        // Answers the question with `button` when it comes, and notes what it said.
        QString asked;
        auto answerWith = [&](QMessageBox::StandardButton button) {
            asked.clear();
            QTimer::singleShot(50, [&asked, button] {
                auto* box = qobject_cast<QMessageBox*>(QApplication::activeModalWidget());
                if (!box || box->objectName() != "unsaved-work")
                    return;
                asked = box->text() + "\n" + box->informativeText();
                box->button(button)->click();
            });
        };
        QCOMPARE(window.openFiles({kReference, kCompared}, true), 2);
        const EntityId reference = window.document().ids()[0], compared = window.document().ids()[1];
        QVERIFY(window.document().unsavedIds().empty()); // what was opened is in its files

        QVERIFY(window.distances()->runCloudToCloud(compared, reference, {}));
        QCOMPARE(window.document().unsavedIds(), std::vector<EntityId>{compared});
        answerWith(QMessageBox::Cancel);
        QVERIFY(!window.close()); // Cancel: the window stays, the work too
        QVERIFY(asked.contains(window.document().item(compared).name));
        QVERIFY(window.isVisible());
        QVERIFY(window.document().item(compared).points().field("c2c_distance"));

        // Once exported, the results are in a file: quitting asks nothing.
        QTemporaryDir dir;
        QVERIFY(window.files()->exportEntity(compared, dir.filePath("compared.ply")));
        QVERIFY(window.document().unsavedIds().empty());
        // A derived cloud (the closest points) is unsaved until a session holds it.
        QVERIFY(window.distances()->runCloudToCloud(compared, reference, {{"closest-points", "true"}}));
        QCOMPARE(window.document().unsavedIds().size(), std::size_t(2));
        QVERIFY(window.sessions()->save(dir.filePath("work.scandiff")));
        QVERIFY(window.document().unsavedIds().empty());
        // Discard lets it close.
        QVERIFY(window.distances()->runCloudToCloud(reference, compared, {}));
        answerWith(QMessageBox::Discard);
        QVERIFY(window.close());
        QVERIFY(asked.contains(window.document().item(reference).name));
    }

    void measuringDistancesAnglesAndAreas()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        QCOMPARE(window.openFiles({kReference}, true), 1);
        const EntityId id = window.document().ids().front();
        const PointCloud& cloud = window.document().item(id).points();
        window.view()->setStandardView(gui::StandardView::Top);
        // View > Measure (M): the panel shows and clicks in the view add points.
        auto* action = window.findChild<QAction*>("measureAction");
        QVERIFY(action);
        action->setChecked(true);
        QVERIFY(window.measure()->measuring() && window.view()->pickMode());
        QVERIFY(window.findChild<QDockWidget*>("Measure")->isVisible());
        QVERIFY(window.view()->pickAt(window.view()->width() / 2, window.view()->height() / 2));
        QCOMPARE(window.measure()->measurements().back().size(), std::size_t(1));
        window.measure()->undoLastPoint();
        // Two known points: their distance and components, as core computes them.
        window.measure()->addPick(id, 0);
        window.measure()->addPick(id, 100);
        const Eigen::Vector3d a = cloud.globalPosition(0), b = cloud.globalPosition(100);
        QVERIFY(window.measure()->resultText().contains(QString("Distance: %1 m").arg((b - a).norm(), 0, 'f', 3)));
        QVERIFY(window.measure()->resultText().contains(QString::number(b.z() - a.z(), 'f', 3)));
        QCOMPARE(window.view()->annotationCount(), std::size_t(1)); // drawn with its label
        // A third point: the angle; "New" keeps the measurement and starts another.
        window.measure()->addPick(id, 200);
        QVERIFY(window.measure()->resultText().contains("Angle at point 2"));
        window.measure()->startNew();
        window.measure()->addPoint({0, 0, 0});
        window.measure()->addPoint({4, 0, 0});
        window.measure()->addPoint({4, 3, 0});
        window.measure()->addPoint({0, 3, 0});
        QVERIFY(window.measure()->resultText().contains(QString::fromUtf8("area 12.000 m²")));
        QCOMPARE(window.view()->annotationCount(), std::size_t(2));
        QCOMPARE(window.measure()->measurements().size(), std::size_t(2));
        // Kept in the session.
        QTemporaryDir dir;
        QVERIFY(window.sessions()->save(dir.filePath("m.scandiff")));
        window.measure()->deleteAll();
        QVERIFY(window.sessions()->restore(dir.filePath("m.scandiff")));
        QCOMPARE(window.measure()->measurements().size(), std::size_t(3)); // two kept, a new one begun
        QCOMPARE(window.measure()->measurements()[0][1], b);
        QCOMPARE(window.view()->annotationCount(), std::size_t(2));
        // Turning picking off ends measuring.
        window.view()->setPickMode(false);
        QVERIFY(!window.measure()->measuring() && !action->isChecked());
        window.measure()->deleteAll();
        QCOMPARE(window.view()->annotationCount(), std::size_t(0));
    }

    void scissorsCutWhatIsShownInsideThePolygon()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        QCOMPARE(window.openFiles({kCompared}, true), 1);
        const EntityId id = window.document().ids().front();
        window.view()->setStandardView(gui::StandardView::Iso);
        // Hide the highest points by a threshold on a field: they must not be cut.
        ScalarField height("height", window.document().item(id).points().size());
        const PointCloud& cloud = window.document().item(id).points();
        for (std::size_t i = 0; i < cloud.size(); ++i)
            height.values()[i] = static_cast<float>(cloud.globalPosition(i).z());
        window.document().addField(id, std::move(height));
        gui::FieldDisplay display = window.document().fieldDisplay(id, "height");
        display.high = 360.0;
        window.document().setFieldDisplay(id, "height", display);
        // A triangle drawn in the middle of the view.
        auto* action = window.findChild<QAction*>("scissorsAction");
        QVERIFY(action);
        const double w = window.view()->width(), h = window.view()->height();
        const std::vector<Eigen::Vector2d> triangle{{0.3 * w, 0.3 * h}, {0.8 * w, 0.4 * h}, {0.4 * w, 0.8 * h}};
        // The confirm step asks what to keep: answered by `button` once it shows.
        // Returns a flag set once it has answered, so the test knows the question came.
        const auto answerTheQuestion = [](const char* button) {
            auto answered = std::make_shared<bool>(false);
            auto* poll = new QTimer;
            poll->setInterval(20);
            QObject::connect(poll, &QTimer::timeout, poll, [poll, button, answered] {
                auto* box = qobject_cast<QMessageBox*>(QApplication::activeModalWidget());
                if (!box || box->objectName() != "scissors-question")
                    return;
                QAbstractButton* answer = box->findChild<QAbstractButton*>(button);
                if (!answer) // the standard Cancel has no name of ours
                    answer = box->button(QMessageBox::Cancel);
                answer->click();
                *answered = true;
                poll->deleteLater();
            });
            poll->start();
            return answered;
        };
        const auto drawTriangle = [&] {
            action->setChecked(true);
            for (const Eigen::Vector2d& v : triangle)
                window.view()->addScissorsVertex(v.x(), v.y());
            const Eigen::Matrix4d drawnWith = window.view()->globalToWidgetPixels();
            window.view()->finishScissors();
            return drawnWith;
        };
        // Cancelled: nothing cut.
        const auto cancelled = answerTheQuestion("cancel");
        drawTriangle();
        QTRY_VERIFY(*cancelled);
        QTest::qWait(100);
        QCOMPARE(window.document().ids().size(), std::size_t(1));
        QVERIFY(window.document().item(id).display.visible);
        // Both parts kept.
        const auto bothKept = answerTheQuestion("keepBoth");
        const Eigen::Matrix4d projection = drawTriangle();
        QTRY_VERIFY(*bothKept);
        QVERIFY(!window.view()->scissorsMode() && !action->isChecked());
        // Brute force: project each point, keep those shown and inside the triangle.
        auto insideTriangle = [&](const Eigen::Vector2d& p) {
            int sign = 0;
            for (int k = 0; k < 3; ++k) {
                const Eigen::Vector2d a = triangle[k], b = triangle[(k + 1) % 3];
                const double cross = (b - a).x() * (p - a).y() - (b - a).y() * (p - a).x();
                const int s = cross > 0 ? 1 : -1;
                if (sign == 0)
                    sign = s;
                else if (s != sign)
                    return false;
            }
            return true;
        };
        std::size_t expected = 0;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            const Eigen::Vector4d q = projection * cloud.globalPosition(i).homogeneous();
            if (q.w() > 0 && cloud.globalPosition(i).z() <= 360.0 && insideTriangle(q.head<2>() / q.w()))
                ++expected;
        }
        QVERIFY(expected > 0);
        QTRY_COMPARE(window.document().ids().size(), std::size_t(3)); // the cut runs once the click is over
        const std::vector<EntityId> ids = window.document().ids();
        QCOMPARE(window.document().item(ids[1]).points().size(), expected);
        QCOMPARE(window.document().item(ids[1]).points().size() + window.document().item(ids[2]).points().size(), cloud.size());
        QVERIFY(!window.document().item(id).display.visible);
        QVERIFY(window.document().item(ids[1]).display.visible && !window.document().item(ids[2]).display.visible);
        QCOMPARE(window.document().item(ids[1]).display.activeField, std::string("height"));
    }

    void pointSizesShadingAndBackground()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        QCOMPARE(window.openFiles({kReference, kCompared}, true), 2);
        const EntityId a = window.document().ids()[0], b = window.document().ids()[1];
        // An entity with its own point size keeps it when the view's changes.
        window.document().setPointSize(a, 6.0f);
        window.view()->setPointSize(3.0f);
        QCOMPARE(window.view()->entityPointSize(a), 6.0f);
        QCOMPARE(window.view()->entityPointSize(b), 3.0f);
        window.document().setPointSize(a, 0.0f); // back to the view's
        QCOMPARE(window.view()->entityPointSize(a), 3.0f);
        // A cloud with normals is drawn lit by them; one without is not.
        QVERIFY(!window.view()->isShaded(a));
        PointCloud withNormals;
        withNormals.positions() = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        withNormals.enableNormals().assign(3, Eigen::Vector3f::UnitZ());
        const EntityId lit = window.document().add("with normals", std::move(withNormals));
        QVERIFY(window.view()->isShaded(lit));
        // The scale bar: a round length, about a fifth of the view, and as many
        // pixels on screen as the camera really gives that length at the focal point.
        window.view()->setStandardView(gui::StandardView::Top);
        window.view()->setScaleBar(true);
        const double length = window.view()->scaleBarLength();
        const double decade = std::pow(10.0, std::floor(std::log10(length)));
        const double mantissa = length / decade;
        QVERIFY(std::abs(mantissa - 1) < 1e-9 || std::abs(mantissa - 2) < 1e-9 || std::abs(mantissa - 5) < 1e-9);
        const double viewMetres = window.view()->metresPerPixel() * window.view()->width();
        QVERIFY(length <= viewMetres / 5 + 1e-9 && length > viewMetres / 12.5);
        const gui::CameraState camera = window.view()->camera();
        const Eigen::Vector3d focus(camera.focalPoint[0], camera.focalPoint[1], camera.focalPoint[2]);
        const Eigen::Matrix4d toPixels = window.view()->globalToWidgetPixels();
        const Eigen::Vector4d p0 = toPixels * focus.homogeneous(), p1 = toPixels * (focus + Eigen::Vector3d(length, 0, 0)).homogeneous();
        const double onScreen = (p1.head<2>() / p1.w() - p0.head<2>() / p0.w()).norm();
        QVERIFY2(std::abs(onScreen - length / window.view()->metresPerPixel()) < 0.01 * onScreen, qPrintable(QString::number(onScreen)));
        window.view()->setScaleBar(false);
        QCOMPARE(window.view()->scaleBarLength(), length); // the length is still what it would show
        // Eye-Dome Lighting switches on and off.
        window.view()->setEyeDomeLighting(true);
        QVERIFY(window.view()->eyeDomeLighting());
        window.view()->render();
        window.view()->setEyeDomeLighting(false);
        // A plain background, and back to the gradient.
        window.view()->setBackground(QColor(255, 255, 255));
        QCOMPARE(window.view()->background(), QColor(255, 255, 255));
        window.view()->setBackground(QColor());
        QVERIFY(!window.view()->background().isValid());
    }

    void clippingBoxExtractsWhatIsInside()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        QCOMPARE(window.openFiles({kCompared}, true), 1);
        const EntityId id = window.document().ids().front();
        const PointCloud& cloud = window.document().item(id).points();
        auto* action = window.findChild<QAction*>("clippingAction");
        auto* extract = window.findChild<QAction*>("extractInBoxAction");
        QVERIFY(action && extract && !extract->isEnabled());
        action->setChecked(true);
        QVERIFY(window.view()->clippingBoxOn() && extract->isEnabled());
        // A box turned 30 degrees about the vertical, placed by numbers; it reads back the same.
        CropBox box;
        box.centre = cloud.globalPosition(cloud.size() / 2);
        box.size = {40, 25, 300};
        box.rotation = Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        window.view()->setClippingBox(box);
        const CropBox back = window.view()->clippingBox();
        QVERIFY((back.centre - box.centre).norm() < 1e-6);
        QVERIFY((back.size - box.size).norm() < 1e-6);
        QVERIFY((back.rotation - box.rotation).norm() < 1e-9);
        // Extract inside: exactly the points the box holds (brute force in the box's frame).
        std::size_t expected = 0;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            const Eigen::Vector3d local = box.rotation.transpose() * (cloud.globalPosition(i) - box.centre);
            expected += (local.array().abs() <= (box.size / 2).array()).all();
        }
        QVERIFY(expected > 0 && expected < cloud.size());
        extract->trigger();
        const std::vector<EntityId> ids = window.document().ids();
        QCOMPARE(ids.size(), std::size_t(3));
        QCOMPARE(window.document().item(ids[1]).points().size(), expected);
        action->setChecked(false);
        QVERIFY(!extract->isEnabled());
    }

    void twoEpochsSideBySideWithOneCamera()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        QCOMPARE(window.openFiles({kReference, kCompared}, true), 2);
        const EntityId earlier = window.document().ids()[0], later = window.document().ids()[1];
        auto* action = window.findChild<QAction*>("sideBySideAction");
        QVERIFY(action);
        action->setChecked(true);
        gui::CloudView* right = window.secondView();
        QVERIFY(right && right->isVisible());
        QVERIFY(right->width() > window.view()->width() / 2 && window.view()->width() > right->width() / 2); // two halves
        // An epoch on each side.
        QVERIFY(window.view()->isShownHere(earlier) && !window.view()->isShownHere(later));
        QVERIFY(right->isShownHere(later) && !right->isShownHere(earlier));
        // One camera: a standard view in the left one is the right one's too.
        window.view()->setStandardView(gui::StandardView::Top);
        const gui::CameraState leftCamera = window.view()->camera(), rightCamera = right->camera();
        for (int k = 0; k < 3; ++k)
            QCOMPARE(rightCamera.position[k], leftCamera.position[k]);
        // A field computed later shows on its side.
        QVERIFY(window.distances()->runCloudToCloud(later, earlier, {}));
        QVERIFY(right->isShownHere(later));
        // Off: one view with everything the tree ticks.
        action->setChecked(false);
        QVERIFY(!right->isVisible());
        QVERIFY(window.view()->isShownHere(later));
    }

    void largeCoordinatesAskForTheGlobalShift()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        // The question, answered as a user would: an origin of one's own, for the whole session.
        const Eigen::Vector3d chosen(512700, 5403500, 300);
        bool asked = false;
        QTimer::singleShot(100, [&] {
            auto* dialog = qobject_cast<gui::GlobalShiftDialog*>(QApplication::activeModalWidget());
            if (!dialog)
                return;
            asked = true;
            dialog->setOrigin(chosen);
            dialog->findChild<QCheckBox*>()->setChecked(true);
            dialog->accept();
        });
        QCOMPARE(window.files()->open({kReference}).size(), std::size_t(1));
        QVERIFY(asked);
        const PointCloud& first = window.document().item(window.document().ids()[0]).points();
        QCOMPARE(first.origin(), chosen);
        // Every coordinate is still where it was, to float rounding of local values.
        const PointCloud original = io::readPointCloud(workbench.registry.formats, kReference.toStdString());
        for (std::size_t i = 0; i < original.size(); i += 97)
            QVERIFY((first.globalPosition(i) - original.globalPosition(i)).norm() < 1e-3);
        // The next file takes the same origin without a question; "Same as last" remembers it.
        QCOMPARE(window.files()->open({kCompared}).size(), std::size_t(1));
        QCOMPARE(window.document().item(window.document().ids()[1]).points().origin(), chosen);
        QCOMPARE(*gui::GlobalShiftDialog::lastOrigin(), chosen);
    }

    void thePanelLayoutIsRemembered()
    {
        const PluginRegistry registry = makePluginRegistry();
        {
            gui::MainWindow window(registry);
            window.show();
            QVERIFY(QTest::qWaitForWindowExposed(&window));
            auto* console = window.findChild<QDockWidget*>("Console");
            QVERIFY(console && console->isVisible());
            console->hide();
            QVERIFY(window.close()); // nothing unsaved: no question
        }
        gui::MainWindow again(registry);
        again.show();
        QVERIFY(QTest::qWaitForWindowExposed(&again));
        QVERIFY(!again.findChild<QDockWidget*>("Console")->isVisible());
        again.findChild<QDockWidget*>("Console")->show();
        QVERIFY(again.close());
    }

    void aLocalCloudBesideGeoreferencedOnesKeepsItsPrecision()
    {
        Workbench workbench;
        QVERIFY(workbench.shown());
        gui::MainWindow& window = workbench.window;
        // The trial's mix: a UTM scan first, then a local one 5.4e6 m away, whose
        // 1 mm steps float32 cannot hold at that distance (0.5 m apart there).
        PointCloud utm;
        utm.setOrigin({512000, 5403000, 300});
        utm.positions() = {{0, 0, 0}, {10, 10, 1}};
        window.document().add("utm", std::move(utm));
        PointCloud local;
        local.positions() = {{0.001f, 0.002f, 0.003f}, {1, 1, 1}};
        const EntityId localId = window.document().add("local", std::move(local));
        Eigen::Vector3d offset;
        Eigen::Vector3f first;
        QVERIFY(window.view()->shownFrame(localId, offset, first));
        // Drawn from its own floats, placed by a double offset: nothing rounded.
        QCOMPARE(first, Eigen::Vector3f(0.001f, 0.002f, 0.003f));
        QCOMPARE(offset, Eigen::Vector3d(-512000, -5403000, -300));
        // The camera still speaks global coordinates.
        window.view()->zoomToEntity(localId);
        const gui::CameraState camera = window.view()->camera();
        QVERIFY(std::abs(camera.focalPoint[0] - 0.5) < 0.01 && std::abs(camera.focalPoint[1] - 0.5) < 0.01);
    }

    void badFilesAreReportedNotFatal()
    {
        const PluginRegistry registry = makePluginRegistry();
        gui::MainWindow window(registry);
        QTemporaryDir dir;
        QFile broken(dir.filePath("broken.ply"));
        QVERIFY(broken.open(QIODevice::WriteOnly));
        broken.write("ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\nend_header\n");
        broken.close();
        QSignalSpy failed(window.files(), &gui::FileController::failed);
        QCOMPARE(window.openFiles({dir.filePath("broken.ply"), dir.filePath("missing.las"), kReference}, true), 1);
        QCOMPARE(failed.count(), 2);
        QCOMPARE(window.document().size(), std::size_t(1));
        // A session file that is not one changes nothing.
        QFile notSession(dir.filePath("x.scandiff"));
        QVERIFY(notSession.open(QIODevice::WriteOnly));
        notSession.write("{ not json");
        notSession.close();
        QVERIFY(!window.sessions()->restore(dir.filePath("x.scandiff")));
        // A session whose entries are wrong changes nothing either: the open cloud stays.
        QFile wrongEntries(dir.filePath("y.scandiff"));
        QVERIFY(wrongEntries.open(QIODevice::WriteOnly));
        wrongEntries.write(R"({"scandiffSession": 1, "entities": [{"id": 1, "name": 3}]})");
        wrongEntries.close();
        QVERIFY(!window.sessions()->restore(dir.filePath("y.scandiff")));
        QCOMPARE(window.document().size(), std::size_t(1));
        // A run the user cancelled is logged as such, not as an error.
        emit window.files()->cancelled("Opening big.ply was cancelled");
        const QString log = window.console()->toPlainText();
        QVERIFY(log.trimmed().endsWith("Opening big.ply was cancelled"));
        QVERIFY(!log.trimmed().split('\n').last().contains("error:"));
    }
};

Q_DECLARE_METATYPE(std::size_t)

QTEST_MAIN(WorkbenchFlowTest)
#include "WorkbenchFlowTest.moc"
