// SPDX-License-Identifier: GPL-3.0-or-later
// Qt Test, offscreen platform: the generated tool dialog and the tool controller,
// driven through their widgets as a user would.
#include "document/Document.h"
#include "controllers/ToolController.h"
#include "tools/ToolDialog.h"

#include <scandiff/plugins/PluginRegistry.h>

#include <QDoubleSpinBox>
#include <QProgressDialog>
#include <QPushButton>
#include <QThread>
#include <QTimer>
#include <QSignalSpy>
#include <QSpinBox>
#include <QtTest>

#include <random>

using namespace scandiff;

class ToolDialogTest : public QObject
{
    Q_OBJECT

private slots:
    void widgetsStartAtTheDeclaredDefaults()
    {
        const PluginRegistry registry = makePluginRegistry();
        const ToolSpec* tool = registry.tools.find("sor-filter");
        QVERIFY(tool);
        gui::Document document;
        gui::ToolDialog dialog(*tool, document, {});
        auto* k = qobject_cast<QSpinBox*>(dialog.editor("k"));
        auto* sigma = qobject_cast<QDoubleSpinBox*>(dialog.editor("n-sigma"));
        QVERIFY(k && sigma);
        QCOMPARE(k->value(), static_cast<int>(std::get<std::int64_t>(tool->parameter("k")->defaultValue)));
        QCOMPARE(k->minimum(), 1);
        QCOMPARE(k->maximum(), 1000);
        QCOMPARE(sigma->value(), std::get<double>(tool->parameter("n-sigma")->defaultValue));
        // The dialog's values resolve exactly like the CLI's defaults.
        const ParameterValues values = tool->resolve(dialog.values());
        QCOMPARE(values.integer("k"), tool->defaults().integer("k"));
        QCOMPARE(values.real("n-sigma"), tool->defaults().real("n-sigma"));
    }

    void editedValuesReachTheTool()
    {
        const PluginRegistry registry = makePluginRegistry();
        const ToolSpec* tool = registry.tools.find("sor-filter");
        gui::Document document;
        gui::ToolDialog dialog(*tool, document, {});
        auto* k = qobject_cast<QSpinBox*>(dialog.editor("k"));
        k->selectAll();
        QTest::keyClicks(k, "12");
        auto* sigma = qobject_cast<QDoubleSpinBox*>(dialog.editor("n-sigma"));
        sigma->setValue(2.5);
        const ParameterValues values = tool->resolve(dialog.values());
        QCOMPARE(values.integer("k"), std::int64_t(12));
        QCOMPARE(values.real("n-sigma"), 2.5);
        // The spin box refuses what the declaration refuses.
        k->setValue(5000);
        QCOMPARE(k->value(), 1000);
    }

    void controllerAddsTheResultToTheDocument()
    {
        const PluginRegistry registry = makePluginRegistry();
        const ToolSpec* tool = registry.tools.find("sor-filter");
        gui::Document document;
        PointCloud input;
        input.resize(1001);
        std::mt19937 rng(3);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        for (std::size_t i = 0; i < 1000; ++i)
            input.positions()[i] = {u(rng), u(rng), 0.0f};
        input.positions()[1000] = {9.0f, 9.0f, 9.0f};
        input.name = "plane";
        const gui::EntityId inputId = document.add("plane", std::move(input));
        gui::ToolController controller(*tool, document, nullptr);
        QSignalSpy finished(&controller, &gui::ToolController::finished);
        QVERIFY(controller.run(inputId, {{"k", "8"}, {"n-sigma", "2"}}));
        QCOMPARE(finished.count(), 1);
        QCOMPARE(document.size(), std::size_t(2));
        const gui::Document::Item& output = document.item(document.ids().back());
        QVERIFY(output.points().size() < 1001);
        QCOMPARE(output.parent, inputId); // shown under its input in the tree
        QCOMPARE(document.item(inputId).points().size(), std::size_t(1001)); // the input is untouched
        QVERIFY(finished.at(0).at(0).toString().contains("kept"));
    }

    void cancelStopsTheWorkAndKeepsTheDocument()
    {
        // A tool that works until it is told to stop.
        ToolSpec slow;
        slow.name = "slow";
        slow.title = "Slow tool";
        slow.run = [](const ToolInputs&, const ParameterValues&, ProgressObserver* progress) -> ToolResult {
            ProgressTicker ticker(progress, "waiting", 1000000);
            for (;;) {
                ticker.checkCancel();
                QThread::msleep(5);
            }
        };
        gui::Document document;
        PointCloud input;
        input.resize(10);
        const gui::EntityId inputId = document.add("ten", std::move(input));
        QWidget window;
        gui::ToolController controller(slow, document, &window);
        QSignalSpy failed(&controller, &gui::ToolController::failed);
        // Once the progress dialog shows, press its Cancel button as a user would.
        bool clicked = false;
        QTimer poll;
        connect(&poll, &QTimer::timeout, [&] {
            for (QWidget* w : QApplication::topLevelWidgets())
                if (auto* dialog = qobject_cast<QProgressDialog*>(w); dialog && dialog->isVisible() && !clicked) {
                    QPushButton* cancel = dialog->findChild<QPushButton*>();
                    QVERIFY(cancel);
                    QTest::mouseClick(cancel, Qt::LeftButton);
                    clicked = true;
                }
        });
        poll.start(50);
        QVERIFY(!controller.run(inputId, {}));
        QVERIFY(clicked);
        QCOMPARE(failed.count(), 1);
        QVERIFY(failed.at(0).at(0).toString().contains("cancelled"));
        QCOMPARE(document.size(), std::size_t(1));
    }

    void controllerReportsInvalidParameters()
    {
        const PluginRegistry registry = makePluginRegistry();
        const ToolSpec* tool = registry.tools.find("sor-filter");
        gui::Document document;
        PointCloud input;
        input.resize(3);
        const gui::EntityId inputId = document.add("three", std::move(input));
        gui::ToolController controller(*tool, document, nullptr);
        QSignalSpy failed(&controller, &gui::ToolController::failed);
        QVERIFY(!controller.run(inputId, {{"k", "0"}}));
        QCOMPARE(failed.count(), 1);
        QVERIFY(failed.at(0).at(0).toString().contains("k"));
        QCOMPARE(document.size(), std::size_t(1));
    }
};

QTEST_MAIN(ToolDialogTest)
#include "ToolDialogTest.moc"
