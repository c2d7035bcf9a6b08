// SPDX-License-Identifier: GPL-3.0-or-later
// Qt Test, offscreen platform: the registration tools in the workbench, driven
// as a user would: point pairs picked in the view with their residuals
// previewed, the moved cloud replacing its input, the undo, the stations.
#include "SyntheticSite.h"

#include "controllers/ToolController.h"
#include "document/Document.h"
#include "tools/ParameterForm.h"
#include "tools/PickedPointsPanel.h"
#include "tools/ToolDialog.h"

#include <scandiff/core/processing/CloudEditing.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <QLineEdit>
#include <QPushButton>
#include <QSignalSpy>
#include <QTableWidget>
#include <QtTest>

using namespace scandiff;

namespace {

const Eigen::Vector3d kUtm(512000, 5423000, 100);

PointCloud site(std::size_t points, unsigned seed)
{
    test::SiteOptions o;
    o.points = points;
    o.seed = seed;
    o.origin = kUtm;
    return test::syntheticSite(o);
}

} // namespace

class RegistrationGuiTest : public QObject
{
    Q_OBJECT

private slots:
    void initTestCase()
    {
        qRegisterMetaType<gui::EntityId>("EntityId");
        qRegisterMetaType<gui::NamedTables>("scandiff::gui::NamedTables");
    }

    void pointPairsArePickedInTheViewThenUndone()
    {
        const PluginRegistry registry = makePluginRegistry();
        gui::Document document;
        // The moving scan is the reference moved away: point i of one is point i of the other.
        const Eigen::Matrix4d truth = test::rigidMotionAbout(33, 0, 0, Eigen::Vector3d(4, -3, 0.5), kUtm);
        PointCloud reference = site(3000, 4);
        PointCloud moving = transformCloud(reference, truth.inverse(), "survey");
        moving.transformHistory().clear();
        const gui::EntityId referenceId = document.add("reference", std::move(reference));
        const gui::EntityId movingId = document.add("moving", std::move(moving));
        const PointCloud original = document.item(movingId).points().clone();

        gui::ToolController controller(*registry.tools.find("register-pairs"), document, nullptr);
        QSignalSpy pickMode(&controller, &gui::ToolController::pickModeRequested);
        controller.runInteractively({movingId, referenceId});
        gui::ToolDialog* dialog = controller.openDialog();
        QVERIFY(dialog);
        QVERIFY(!dialog->isModal()); // the view stays usable for picking
        gui::PickedPointsPanel* panel = dialog->pickedPoints();
        QVERIFY(panel);
        panel->pickButton()->click();
        QCOMPARE(pickMode.count(), 1);
        QCOMPARE(pickMode.at(0).at(0).toBool(), true);

        // A pick on the wrong entity is refused; then three pairs.
        controller.pointPicked(referenceId, 10);
        QCOMPARE(panel->pointCount(), std::size_t(0));
        for (std::size_t i : {10u, 1500u, 2900u}) {
            controller.pointPicked(movingId, i);
            controller.pointPicked(referenceId, i);
        }
        QCOMPARE(panel->pointCount(), std::size_t(6));
        // The preview: a residual per pair and the RMS, about zero.
        QTableWidget* preview = panel->previewView();
        QVERIFY(preview->rowCount() >= 4);
        for (int r = 0; r < 4; ++r)
            QVERIFY(std::abs(preview->item(r, 1)->text().toDouble()) < 1e-3);
        // The parameter's text holds the three pairs.
        auto* pairs = qobject_cast<QLineEdit*>(dialog->editor("pairs"));
        QVERIFY(pairs);
        QCOMPARE(pairs->text().count(';'), 2);
        // Undo the last point: two pairs and a half.
        panel->undoLast();
        QCOMPARE(panel->pointCount(), std::size_t(5));
        QCOMPARE(pairs->text().count(';'), 1);
        controller.pointPicked(referenceId, 2900);

        // OK: the moving cloud is moved in place, its history holds the step.
        QSignalSpy finished(&controller, &gui::ToolController::finished);
        dialog->accept();
        QTRY_COMPARE(finished.count(), 1);
        QCOMPARE(pickMode.last().at(0).toBool(), false); // picking stops with the dialog
        QCOMPARE(document.size(), std::size_t(2));
        const PointCloud& moved = document.item(movingId).points();
        QCOMPARE(moved.transformHistory().size(), std::size_t(1));
        const PointCloud& ref = document.item(referenceId).points();
        for (std::size_t i = 0; i < moved.size(); i += 97)
            QVERIFY((moved.globalPosition(i) - ref.globalPosition(i)).norm() < 2e-4);

        // Edit > Undo the last transformation: back where it was.
        gui::ToolController undo(*registry.tools.find("undo-transform"), document, nullptr);
        QVERIFY(undo.run(movingId, {}));
        const PointCloud& back = document.item(movingId).points();
        QVERIFY(back.transformHistory().empty());
        for (std::size_t i = 0; i < back.size(); i += 97)
            QVERIFY((back.globalPosition(i) - original.globalPosition(i)).norm() < 2.5e-4);
    }

    void icpAndStationsMoveTheirInputsInPlace()
    {
        const PluginRegistry registry = makePluginRegistry();
        gui::Document document;
        const Eigen::Matrix4d truth = test::rigidMotionAbout(6, 1, 0, Eigen::Vector3d(0.4, -0.3, 0.1), kUtm);
        const gui::EntityId referenceId = document.add("reference", site(20000, 1));
        PointCloud moving = transformCloud(site(20000, 2), truth.inverse(), "survey");
        moving.transformHistory().clear();
        const gui::EntityId movingId = document.add("moving", std::move(moving));
        const Eigen::Vector3d before = document.item(movingId).points().globalPosition(0);

        // Fine registration: the moving cloud replaced, the report and trace in tables.
        gui::ToolController icp(*registry.tools.find("register"), document, nullptr);
        QSignalSpy tables(&icp, &gui::ToolController::tablesReady);
        QVERIFY(icp.run(gui::ToolInputChoice{{"moving", {movingId}}, {"reference", {referenceId}}}, {}));
        QCOMPARE(document.size(), std::size_t(2));
        QCOMPARE(tables.count(), 1);
        const gui::NamedTables named = tables.at(0).at(1).value<gui::NamedTables>();
        QCOMPARE(named.size(), std::size_t(2)); // report, trace
        const Eigen::Vector3d after = document.item(movingId).points().globalPosition(0);
        QVERIFY((after - (truth * before.homogeneous()).head<3>()).norm() < 0.005);
        QVERIFY(document.item(movingId).points().field("registration_residual"));

        // Stations: every input replaced by its moved self, in the order given.
        gui::ToolController stations(*registry.tools.find("register-stations"), document, nullptr);
        QSignalSpy stationTables(&stations, &gui::ToolController::tablesReady);
        QVERIFY(stations.run(gui::ToolInputChoice{{"input", {referenceId, movingId}}}, {}));
        QCOMPARE(document.size(), std::size_t(2));
        QCOMPARE(stationTables.count(), 1);
        QCOMPARE(stationTables.at(0).at(1).value<gui::NamedTables>().size(), std::size_t(5)); // poses, report, pairs, loops, trace
        QCOMPARE(document.item(referenceId).points().transformHistory().size(), std::size_t(1)); // the identity, recorded
        QCOMPARE(document.item(movingId).points().transformHistory().size(), std::size_t(2));
    }
};

QTEST_MAIN(RegistrationGuiTest)
#include "RegistrationGuiTest.moc"
