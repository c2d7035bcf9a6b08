// SPDX-License-Identifier: GPL-3.0-or-later
// Qt Test under Xvfb: the everyday conveniences a CloudCompare user reaches
// for, driven through the workbench's own menus and keys: the Help menu, the
// shortcuts (none shared by two actions), the standard views' keys, Close and
// Close all, the tree's context menu (show/hide, colour, clone, rename...).
#include "WorkbenchFixture.h"
#include "HelpDialogs.h"
#include "MainWindow.h"
#include "controllers/SessionController.h"
#include "panels/EntityTree.h"
#include "tools/MeasurePanel.h"
#include "tools/MoveDialog.h"
#include "view/CloudView.h"

#include <scandiff/core/processing/CloudEditing.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <QAction>
#include <QFileInfo>
#include <QListWidget>
#include <QTemporaryDir>
#include <QTreeWidgetItem>
#include <QMenu>
#include <QMenuBar>
#include <QMessageBox>
#include <QPushButton>
#include <QStandardPaths>
#include <QtTest>

#include <map>

using namespace scandiff;
using gui::EntityId;

namespace {

using test::Workbench;
using test::kReference;
using test::kCompared;

QAction* treeAction(gui::MainWindow& window, const char* name)
{
    for (QAction* action : window.tree()->actions())
        if (action->objectName() == name)
            return action;
    return nullptr;
}

} // namespace

class WorkbenchMenusTest : public QObject
{
    Q_OBJECT

private slots:
    void initTestCase()
    {
        QStandardPaths::setTestModeEnabled(true);
        QCoreApplication::setOrganizationName("scandiff-tests");
        qRegisterMetaType<gui::EntityId>("EntityId");
    }

    // Help > the guide's pages (files that exist), the shortcuts, About; the
    // shortcut list read from the menus; no key given to two actions (Qt then
    // runs neither: an "ambiguous shortcut").
    void theHelpMenuAndTheShortcutsAreCompleteAndUnambiguous()
    {
        Workbench w;
        QVERIFY(w.shown());
        QMenu* help = nullptr;
        for (QAction* a : w.window.menuBar()->actions())
            if (a->text().remove('&') == "Help")
                help = a->menu();
        QVERIFY(help);
        QStringList texts;
        for (QAction* a : help->actions())
            texts << a->text().remove('&');
        QVERIFY2(texts.contains("User guide (the workbench step by step)"), qPrintable(texts.join('|')));
        QVERIFY(texts.contains("Keyboard shortcuts") && texts.contains("About scandiff"));
        const QString docs = gui::documentationFolder();
        QVERIFY(QFileInfo::exists(docs + "/workbench.md"));
        for (QAction* a : help->actions())
            if (!a->statusTip().isEmpty())
                QVERIFY2(QFileInfo::exists(a->statusTip()), qPrintable(a->statusTip()));

        std::map<QString, QString> byAction;
        for (const auto& [action, keys] : gui::shortcutList(*w.window.menuBar()))
            byAction[action] = keys;
        QCOMPARE(byAction["View > Standard views > Top"], QString("8"));
        QCOMPARE(byAction["View > Standard views > Front"], QString("5"));
        QCOMPARE(byAction["File > Close all"], QString("Ctrl+Shift+W"));
        QCOMPARE(byAction["File > Close selected"], QKeySequence(QKeySequence::Close).toString(QKeySequence::NativeText));
        QVERIFY(byAction.count("Edit > Redo") == 1 && byAction.count("Help > User guide (the workbench step by step)") == 1);

        std::map<QString, QStringList> actionsOfKey;
        std::function<void(QMenu*)> walk = [&](QMenu* menu) {
            for (QAction* a : menu->actions()) {
                if (a->menu())
                    walk(a->menu());
                for (const QKeySequence& key : a->shortcuts())
                    actionsOfKey[key.toString()] << a->text();
            }
        };
        for (QAction* a : w.window.menuBar()->actions())
            if (a->menu())
                walk(a->menu());
        for (const auto& [key, actions] : actionsOfKey)
            QVERIFY2(actions.size() == 1, qPrintable(key + ": " + actions.join(", ")));

        QVERIFY(QMetaObject::invokeMethod(help->actions().last(), "trigger", Qt::QueuedConnection)); // About: a modal box
        QTimer::singleShot(300, [] {
            if (QWidget* box = QApplication::activeModalWidget())
                box->close();
        });
        QTest::qWait(600);
    }

    // A measurement of one point is a label: its coordinates to the
    // millimetre and the value of the field shown where it was picked; kept
    // in the list, the view and the session.
    void aPointLabelStaysWithItsCoordinatesAndValue()
    {
        Workbench w;
        QVERIFY(w.shown());
        QCOMPARE(w.window.openFiles({kCompared}, true), 1);
        gui::Document& document = w.window.document();
        const EntityId id = document.ids().front();
        ScalarField d("d", document.item(id).points().size());
        for (std::size_t i = 0; i < d.size(); ++i)
            d.setValue(i, 0.001 * double(i));
        document.addField(id, std::move(d));
        QCOMPARE(document.item(id).display.activeField, std::string("d"));
        w.window.measure()->setMeasuring(true);
        w.window.measure()->addPick(id, 1234);
        w.window.measure()->startNew();
        w.window.measure()->setMeasuring(false);
        const Eigen::Vector3d p = document.item(id).points().globalPosition(1234);
        const QString expected = QString("X %1, Y %2, Z %3; site-2024: d = 1.234")
                                     .arg(p.x(), 0, 'f', 3)
                                     .arg(p.y(), 0, 'f', 3)
                                     .arg(p.z(), 0, 'f', 3);
        auto* kept = w.window.measure()->findChild<QListWidget*>("kept");
        QVERIFY(kept);
        QCOMPARE(kept->count(), 1);
        QCOMPARE(kept->item(0)->text(), "M1: " + expected);
        QCOMPARE(w.window.view()->annotationCount(), std::size_t(1));
        QTemporaryDir folder;
        const QString session = folder.filePath("label.scandiff");
        QVERIFY(w.window.sessions()->save(session));
        document.clear();
        QVERIFY(w.window.sessions()->restore(session));
        QCOMPARE(kept->count(), 1);
        QCOMPARE(kept->item(0)->text(), "M1: " + expected);
        QCOMPARE(w.window.view()->annotationCount(), std::size_t(1));
    }

    // Move / rotate: a drag on the box moves the entities' drawing and the
    // typed boxes follow; typed values move the drawing; Cancel leaves the
    // data as it was; Apply moves every point by the matrix (brute force),
    // as one undo step.
    void moveAndRotateByMouseAndByValuesThenApplyOrCancel()
    {
        Workbench w;
        QVERIFY(w.shown());
        QCOMPARE(w.window.openFiles({kCompared}, true), 1);
        gui::Document& document = w.window.document();
        const EntityId id = document.ids().front();
        w.window.tree()->selectEntity(id);
        w.window.view()->setStandardView(gui::StandardView::Top);
        QApplication::processEvents();
        std::vector<Eigen::Vector3d> before;
        for (std::size_t i = 0; i < document.item(id).points().size(); i += 97)
            before.push_back(document.item(id).points().globalPosition(i));

        // A field's row selected stands for its cloud (as in the trial, a
        // click on a field in the tree is the usual selection).
        document.addField(id, ScalarField("d", document.item(id).points().size()));
        w.window.tree()->clearSelection();
        QTreeWidgetItem* fieldRow = w.window.tree()->fieldRow(id, "d");
        QVERIFY(fieldRow);
        fieldRow->setSelected(true);
        gui::MoveDialog* byField = w.window.moveSelectedInteractively();
        QVERIFY(byField && w.window.view()->movingEntities());
        byField->reject();
        QApplication::processEvents();
        w.window.tree()->selectEntity(id);

        // Cancelled: nothing moves.
        gui::MoveDialog* dialog = w.window.moveSelectedInteractively();
        QVERIFY(dialog && w.window.view()->movingEntities());
        RigidMotion typed;
        typed.offset = Eigen::Vector3d(1.5, -2.0, 0.25);
        typed.heading = 30;
        dialog->setMotion(typed);
        const Eigen::Vector3d centre = w.window.view()->movingCentre();
        QVERIFY((w.window.view()->movedBy() - rigidMotionMatrix(typed, centre)).norm() < 1e-12);
        dialog->reject();
        QApplication::processEvents();
        QVERIFY(!w.window.view()->movingEntities());
        QVERIFY(w.window.view()->movedBy().isIdentity(0.0));
        QCOMPARE(document.item(id).points().globalPosition(0), before.front());

        // A middle-button drag inside the box, seen from above: a move in the
        // ground plane, no turn, and the boxes show it.
        dialog = w.window.moveSelectedInteractively();
        QVERIFY(dialog);
        dialog->move(w.window.geometry().right() - 10, 0); // out of the view's way
        const Eigen::Vector4d c = w.window.view()->globalToWidgetPixels() * w.window.view()->movingCentre().homogeneous();
        const QPoint from(int(c.x() / c.w()), int(c.y() / c.w()));
        QWidget* surface = w.window.view()->childAt(from);
        QVERIFY(surface);
        const QPoint at = surface->mapFrom(w.window.view(), from);
        QTest::mousePress(surface, Qt::MiddleButton, {}, at);
        for (int step = 1; step <= 8; ++step) {
            QMouseEvent drag(QEvent::MouseMove, at + QPoint(5 * step, 0), Qt::NoButton, Qt::MiddleButton, Qt::NoModifier);
            QApplication::sendEvent(surface, &drag);
        }
        QTest::mouseRelease(surface, Qt::MiddleButton, {}, at + QPoint(40, 0));
        const Eigen::Matrix4d dragged = w.window.view()->movedBy();
        const Eigen::Vector3d draggedBy = dragged.topRightCorner<3, 1>();
        QVERIFY2(draggedBy.norm() > 0.1, "the drag moved the box");
        const Eigen::Matrix3d draggedTurn = dragged.topLeftCorner<3, 3>();
        QVERIFY((draggedTurn - Eigen::Matrix3d::Identity()).norm() < 1e-9);
        QVERIFY(std::abs(dragged(2, 3)) < 1e-6); // seen from above: no height change
        const RigidMotion shown = dialog->motion();
        QVERIFY(std::abs(shown.offset.x() - dragged(0, 3)) < 1e-4 && std::abs(shown.offset.y() - dragged(1, 3)) < 1e-4);
        QVERIFY(dialog->matrix() == dragged); // Apply would apply the drag itself, not its rounded values
        QCOMPARE(w.window.moveSelectedInteractively(), dialog); // one dialog at a time

        // Typed, then applied.
        dialog->setMotion(typed);
        const Eigen::Matrix4d m = rigidMotionMatrix(typed, w.window.view()->movingCentre());
        dialog->findChild<QPushButton*>("apply")->click();
        QApplication::processEvents();
        QVERIFY(!w.window.view()->movingEntities());
        const PointCloud& moved = document.item(id).points();
        for (std::size_t k = 0; k < before.size(); ++k) {
            const Eigen::Vector3d expected = (m * before[k].homogeneous()).head<3>();
            QVERIFY2((moved.globalPosition(97 * k) - expected).norm() < 1e-3, qPrintable(QString::number(k)));
        }
        QVERIFY(document.undoText().contains("move"));
        document.undo();
        QCOMPARE(document.item(id).points().globalPosition(0), before.front());
    }

    // The keys of the standard views turn the camera as the menu does.
    void theStandardViewsAnswerTheirKeys()
    {
        Workbench w;
        QVERIFY(w.shown());
        QCOMPARE(w.window.openFiles({kReference}, true), 1);
        w.window.view()->setStandardView(gui::StandardView::Iso);
        w.window.activateWindow();
        QVERIFY(QTest::qWaitForWindowActive(&w.window));
        w.window.view()->setFocus();
        QTest::keyClick(w.window.view(), Qt::Key_8);
        QTest::qWait(50);
        gui::CameraState top = w.window.view()->camera();
        Eigen::Vector3d direction = Eigen::Vector3d(top.focalPoint.data()) - Eigen::Vector3d(top.position.data());
        QVERIFY2(direction.normalized().z() < -0.999, "8 looks down");
        QTest::keyClick(w.window.view(), Qt::Key_5);
        QTest::qWait(50);
        const gui::CameraState front = w.window.view()->camera();
        direction = Eigen::Vector3d(front.focalPoint.data()) - Eigen::Vector3d(front.position.data());
        QVERIFY2(std::abs(direction.normalized().z()) < 1e-6 && direction.normalized().y() > 0.999999,
                 qPrintable(QString("5 looks level, along +y: %1 %2 %3").arg(direction.x()).arg(direction.y()).arg(direction.z())));
    }

    // The tree's menu: every entry there; show/hide, one colour (undone by
    // Ctrl+Z), a clone, Close selected (undone) and Close all.
    void theTreeMenuActsOnTheSelection()
    {
        Workbench w;
        QVERIFY(w.shown());
        QCOMPARE(w.window.openFiles({kReference, kCompared}, true), 2);
        gui::Document& document = w.window.document();
        const std::vector<EntityId> ids = document.ids();
        QCOMPARE(ids.size(), std::size_t(2));
        for (const char* name : {"treeShowHide", "treeColour", "treeProperties", "treeClone", "treeMerge", "treeExport",
                                 "treeExportRegions", "treePointSize", "treeDelete"})
            QVERIFY2(treeAction(w.window, name), name);
        QStringList texts;
        for (QAction* a : w.window.tree()->actions())
            texts << a->text().remove('&');
        QVERIFY(texts.contains("Rename...") && texts.contains("Zoom to selection"));

        const EntityId first = ids.front();
        w.window.tree()->selectEntity(first);
        treeAction(w.window, "treeShowHide")->trigger();
        QVERIFY(!document.item(first).display.visible);
        QVERIFY(document.item(ids.back()).display.visible);
        treeAction(w.window, "treeShowHide")->trigger();
        QVERIFY(document.item(first).display.visible);

        const std::vector<Rgb8> before = document.item(first).points().colors();
        QCOMPARE(w.window.colourSelected(QColor(10, 200, 30)), 1);
        const PointCloud& coloured = document.item(first).points();
        QVERIFY(coloured.hasColors());
        for (const Rgb8& c : coloured.colors())
            QVERIFY(c == (Rgb8{10, 200, 30}));
        QVERIFY(document.item(first).display.activeField.empty());
        document.undo();
        QVERIFY(document.item(first).points().colors() == before);

        QCOMPARE(w.window.cloneSelected(), 1);
        QCOMPARE(document.size(), std::size_t(3));
        const EntityId copy = document.ids().back();
        QCOMPARE(document.item(copy).points().size(), document.item(first).points().size());
        QVERIFY(document.item(copy).points().positions() == document.item(first).points().positions());

        w.window.tree()->selectEntity(copy);
        w.window.closeSelected();
        QCOMPARE(document.size(), std::size_t(2));
        QVERIFY(document.undoText().contains("close"));
        document.undo();
        QCOMPARE(document.size(), std::size_t(3));

        // Close all: the clone holds unsaved work, so the question comes: Discard.
        QTimer::singleShot(300, [] {
            if (auto* box = qobject_cast<QMessageBox*>(QApplication::activeModalWidget()))
                box->button(QMessageBox::Discard)->click();
        });
        QVERIFY(w.window.closeEverything());
        QCOMPARE(document.size(), std::size_t(0));
        QVERIFY(!w.window.closeEverything()); // nothing left to close
    }
};

QTEST_MAIN(WorkbenchMenusTest)
#include "WorkbenchMenusTest.moc"
