// SPDX-License-Identifier: GPL-3.0-or-later
// Qt Test, offscreen platform: the generated tool dialog and the tool controller,
// driven through their widgets as a user would.
#include "document/Document.h"
#include "controllers/SegmentationController.h"
#include "controllers/ToolController.h"
#include "tools/ParameterForm.h"
#include "tools/ToolDialog.h"

#include <scandiff/core/segmentation/SegmentationParameters.h>
#include <scandiff/plugins/PluginRegistry.h>

#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QListWidget>
#include <QProgressDialog>
#include <QPushButton>
#include <QThread>
#include <QTimer>
#include <QSignalSpy>
#include <QSpinBox>
#include <QtTest>

#include <limits>

#include <random>

using namespace scandiff;

class ToolDialogTest : public QObject
{
    Q_OBJECT

private slots:
    void initTestCase()
    {
        qRegisterMetaType<gui::EntityId>("EntityId");
        qRegisterMetaType<gui::NamedTables>("scandiff::gui::NamedTables");
    }

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
        QVERIFY(!document.item(inputId).display.visible); // and no longer drawn under the result
        QVERIFY(output.display.visible);
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
        QSignalSpy cancelled(&controller, &gui::ToolController::cancelled);
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
        QCOMPARE(failed.count(), 0); // stopping is no error
        QCOMPARE(cancelled.count(), 1);
        QVERIFY(cancelled.at(0).at(0).toString().contains("cancelled"));
        QCOMPARE(document.size(), std::size_t(1));
    }

    void inputsAreProposedFromTheSelectionByRole()
    {
        const PluginRegistry registry = makePluginRegistry();
        gui::Document document;
        PointCloud a, b, c;
        a.resize(4);
        b.resize(4);
        c.resize(4);
        const gui::EntityId idA = document.add("a", std::move(a));
        const gui::EntityId idB = document.add("b", std::move(b));
        document.add("c", std::move(c));
        Mesh mesh;
        mesh.vertices.resize(3);
        mesh.triangles = {{0, 1, 2}};
        const gui::EntityId idMesh = document.add("mesh", std::move(mesh));
        // Merge takes every selected cloud; a mesh's vertices count as a cloud.
        const gui::ToolInputChoice merge = gui::proposeInputs(document, *registry.tools.find("merge"), {idB, idA});
        QCOMPARE(merge.at("input"), (std::vector<gui::EntityId>{idB, idA}));
        // A single input takes the first selected; without a selection, the last added.
        QCOMPARE(gui::proposeInputs(document, *registry.tools.find("normals"), {idA}).at("input"), (std::vector<gui::EntityId>{idA}));
        QCOMPARE(gui::proposeInputs(document, *registry.tools.find("normals"), {}).at("input"), (std::vector<gui::EntityId>{idMesh}));
        // A mesh input only accepts meshes, whatever is selected.
        QCOMPARE(gui::proposeInputs(document, *registry.tools.find("sample-mesh"), {idA}).at("input"),
                 (std::vector<gui::EntityId>{idMesh}));
        // Two epochs: the selected one is compared (or moved), the reference
        // the first opened of the others, as in the C2C dialog, whatever the
        // order of the roles.
        const gui::ToolInputChoice m3c2 = gui::proposeInputs(document, *registry.tools.find("m3c2"), {idB});
        QCOMPARE(m3c2.at("compared"), (std::vector<gui::EntityId>{idB}));
        QCOMPARE(m3c2.at("reference"), (std::vector<gui::EntityId>{idA}));
        QVERIFY(m3c2.at("core-points").empty());
        const gui::ToolInputChoice dod = gui::proposeInputs(document, *registry.tools.find("dod"), {idA});
        QCOMPARE(dod.at("compared"), (std::vector<gui::EntityId>{idA}));
        QCOMPARE(dod.at("reference"), (std::vector<gui::EntityId>{idB}));
        const gui::ToolInputChoice icp = gui::proposeInputs(document, *registry.tools.find("register"), {idB});
        QCOMPARE(icp.at("moving"), (std::vector<gui::EntityId>{idB}));
        QCOMPARE(icp.at("reference"), (std::vector<gui::EntityId>{idA}));

        // The dialog lists them: a checkable list for merge, a combo box for a single input.
        gui::ToolDialog mergeDialog(*registry.tools.find("merge"), document, merge);
        auto* list = mergeDialog.findChild<QListWidget*>("input-input");
        QVERIFY(list);
        QCOMPARE(list->count(), 4);
        QCOMPARE(mergeDialog.inputs().at("input").size(), std::size_t(2));
        list->item(2)->setCheckState(Qt::Checked);
        QCOMPARE(mergeDialog.inputs().at("input").size(), std::size_t(3));
        gui::ToolDialog sampleDialog(*registry.tools.find("sample-mesh"), document, {{"input", {idMesh}}});
        auto* combo = sampleDialog.findChild<QComboBox*>("input-input");
        QVERIFY(combo);
        QCOMPARE(combo->count(), 1); // the clouds are not offered
    }

    void segmentationDialogOffersChoicesFromTheData()
    {
        gui::Document document;
        PointCloud cloud;
        cloud.resize(3);
        ScalarField& d = cloud.addField("c2m_distance");
        d.values() = {0.0f, 1.0f, 2.0f};
        cloud.addField("intensity").values() = {5.0f, 6.0f, 7.0f};
        const gui::EntityId id = document.add("epoch", std::move(cloud));
        document.setActiveField(id, "c2m_distance");
        // The panel's threshold, as the user left it: low end at 0.5.
        gui::FieldDisplay display = document.fieldDisplay(id, "c2m_distance");
        display.low = 0.5;
        document.setFieldDisplay(id, "c2m_distance", display);

        gui::SegmentationDialog dialog(document, id);
        gui::ParameterForm* form = dialog.findChild<gui::ParameterForm*>();
        QVERIFY(form);
        // The field is a choice of the cloud's fields, the shown one selected.
        auto* field = qobject_cast<QComboBox*>(form->editor("field"));
        QVERIFY(field);
        QCOMPARE(field->count(), 2);
        QCOMPARE(field->currentText(), QString("c2m_distance"));
        // The exclusive methods are one choice; the threshold is the panel's.
        QComboBox* method = form->groupChoice("method");
        QVERIFY(method);
        QCOMPARE(method->currentData().toString(), QString("above"));
        QCOMPARE(dialog.values().at("above"), std::string("0.5"));
        QVERIFY(form->isShown("above") && !form->isShown("range") && !form->isShown("kmeans"));
        // The statistical test's own parameters show only with it.
        QVERIFY(!form->isShown("neighbours") && !form->isShown("confidence"));
        method->setCurrentIndex(method->findData("stat-test"));
        QVERIFY(form->isShown("neighbours") && form->isShown("stat-test") && !form->isShown("above"));
        QVERIFY(dialog.values().count("stat-test") && !dialog.values().count("above"));
        // Components' own parameters show with it; propagation replaces the methods.
        QVERIFY(!form->isShown("connectivity"));
        qobject_cast<QCheckBox*>(form->editor("components"))->setChecked(true);
        QVERIFY(form->isShown("connectivity") && form->isShown("min-points"));
        qobject_cast<QCheckBox*>(form->editor("components"))->setChecked(false);
        QVERIFY(form->isShown("min-points")); // the single region and the propagation use it too
        qobject_cast<QCheckBox*>(form->editor("components"))->setChecked(true);
        QVERIFY(!form->isShown("alpha"));
        qobject_cast<QCheckBox*>(form->editor("propagate"))->setChecked(true);
        QVERIFY(form->isShown("alpha") && !method->isVisibleTo(&dialog) && !form->isShown("stat-test"));
        QVERIFY(!dialog.values().count("stat-test")); // what the CLI would refuse together is not given
        QVERIFY(resolveParameters(segmentationParameters(), dialog.values(), "segment").boolean("propagate"));
        // 0 says what it means.
        QCOMPARE(qobject_cast<QSpinBox*>(form->editor("level"))->specialValueText(), QString("automatic"));

        // Both thresholds set: the range is proposed.
        display.high = 1.5;
        document.setFieldDisplay(id, "c2m_distance", display);
        gui::SegmentationDialog ranged(document, id);
        QCOMPARE(ranged.values().at("range"), std::string("0.5 1.5"));
    }

    void aDrawingOutputJoinsTheTreeUnderItsCloud()
    {
        const PluginRegistry registry = makePluginRegistry();
        gui::Document document;
        PointCloud block;
        for (int i = 0; i <= 20; ++i)
            for (int j = 0; j <= 10; ++j)
                block.positions().emplace_back(0.1f * i, 0.1f * j, 0.0f);
        const gui::EntityId id = document.add("block", std::move(block));
        gui::ToolController controller(*registry.tools.find("sections"), document, nullptr);
        QSignalSpy tables(&controller, &gui::ToolController::tablesReady);
        QVERIFY(controller.run(id, {{"axis", "x"}, {"thickness", "0.12"}, {"step", "0.5"}, {"first", "0.25"}}));
        // The slabs and the drawing go into the tree, the drawing under the block.
        QCOMPARE(document.size(), std::size_t(1 + 4 + 1));
        const gui::Document::Item* drawing = nullptr;
        for (gui::EntityId e : document.ids())
            if (document.item(e).isDrawing())
                drawing = &document.item(e);
        QVERIFY(drawing);
        QCOMPARE(drawing->parent, id);
        QCOMPARE(drawing->drawing->polylines.size(), std::size_t(4)); // sections at 0.25, 0.75, 1.25, 1.75 m, two columns each
        QVERIFY(drawing->cloud() == nullptr); // no tool takes it as a cloud
        QCOMPARE(tables.count(), 1);
        // The tools' dialogs do not offer it as an input.
        for (gui::EntityId e : gui::acceptedEntities(document, InputSpec{}))
            QVERIFY(!document.item(e).isDrawing());
    }

    void aThresholdStartsWhereTheHistogramsSliderWasDragged()
    {
        // The stones' threshold on "intensity": the upper bound the user
        // dragged on the field's histogram (the low values shown), else the
        // lower one; nothing dragged, nothing proposed (the tool's automatic one).
        const PluginRegistry registry = makePluginRegistry();
        gui::Document document;
        PointCloud wall;
        wall.resize(100);
        ScalarField& intensity = wall.addField("intensity");
        for (std::size_t i = 0; i < 100; ++i)
            intensity.setValue(i, static_cast<double>(i));
        const gui::EntityId id = document.add("wall", std::move(wall));
        const ToolSpec& stones = *registry.tools.find("stones");
        {
            gui::ToolDialog dialog(stones, document, {{"input", {id}}});
            QVERIFY(!dialog.values().count("threshold"));
        }
        gui::FieldDisplay display = document.fieldDisplay(id, "intensity");
        display.high = 40.5;
        document.setFieldDisplay(id, "intensity", display);
        {
            gui::ToolDialog dialog(stones, document, {{"input", {id}}});
            QCOMPARE(QString::fromStdString(dialog.values().at("threshold")).toDouble(), 40.5);
        }
        display.high = std::numeric_limits<double>::infinity();
        display.low = 60.25;
        document.setFieldDisplay(id, "intensity", display);
        gui::ToolDialog dialog(stones, document, {{"input", {id}}});
        QCOMPARE(QString::fromStdString(dialog.values().at("threshold")).toDouble(), 60.25);
    }

    void alternativesAndRequiredParametersInTheForm()
    {
        const PluginRegistry registry = makePluginRegistry();
        gui::Document document;
        gui::ToolDialog dialog(*registry.tools.find("normals"), document, {});
        QCheckBox* knn = dialog.form()->enabler("knn");
        QCheckBox* radius = dialog.form()->enabler("radius");
        QVERIFY(knn && radius);
        QVERIFY(knn->isChecked()); // the group's first is proposed
        QVERIFY(!radius->isChecked());
        radius->setChecked(true);
        QVERIFY(!knn->isChecked()); // switching one on switches the other off
        QVERIFY(dialog.values().count("radius") && !dialog.values().count("knn"));
        QVERIFY(registry.tools.find("normals")->resolve(dialog.values()).has("radius"));
        // A field parameter lists the fields of the picked entity, its active one first.
        PointCloud withFields;
        withFields.resize(3);
        withFields.addField("alpha");
        withFields.addField("beta");
        const gui::EntityId id = document.add("fields", std::move(withFields));
        document.setActiveField(id, "beta");
        gui::ToolDialog histogram(*registry.tools.find("field-histogram"), document, {{"input", {id}}});
        auto* field = qobject_cast<QComboBox*>(histogram.editor("field"));
        QVERIFY(field);
        QCOMPARE(field->count(), 2);
        QCOMPARE(field->currentText(), QString("beta"));
        QCOMPARE(histogram.values().at("field"), std::string("beta"));
        // An orientation is offered from a list and may be typed.
        auto* orient = qobject_cast<QComboBox*>(dialog.editor("orient"));
        QVERIFY(orient && orient->isEditable() && orient->findText("mst") >= 0);
        orient->setCurrentText("0,1,1");
        QCOMPARE(dialog.values().at("orient"), std::string("0,1,1"));
        // A required parameter is sent with the proposed value.
        gui::ToolDialog features(*registry.tools.find("features"), document, {});
        QVERIFY(features.values().count("radius"));
        QVERIFY(registry.tools.find("features")->resolve(features.values()).has("radius"));
    }

    void outputsGoWhereTheirDeclarationSays()
    {
        const PluginRegistry registry = makePluginRegistry();
        gui::Document document;
        PointCloud plane;
        plane.name = "plane";
        plane.resize(400);
        for (int i = 0; i < 20; ++i)
            for (int j = 0; j < 20; ++j)
                plane.positions()[static_cast<std::size_t>(i * 20 + j)] = Eigen::Vector3f(0.1f * i, 0.1f * j, 0.01f * ((i * j) % 3));
        const gui::EntityId id = document.add("plane", std::move(plane));
        QSignalSpy replaced(&document, &gui::Document::dataReplaced);

        // Normals update the entity in place: same id, normals, the new field active.
        gui::ToolController normals(*registry.tools.find("normals"), document, nullptr);
        QVERIFY(normals.run(id, {{"knn", "8"}}));
        QCOMPARE(document.size(), std::size_t(1));
        QCOMPARE(replaced.count(), 1);
        QVERIFY(document.item(id).cloud()->hasNormals());
        QCOMPARE(document.item(id).display.activeField, std::string("surface_variation"));

        // A mesh goes under its input; a table goes to its window.
        gui::ToolController mesh(*registry.tools.find("mesh"), document, nullptr);
        QVERIFY(mesh.run(id, {}));
        QCOMPARE(document.size(), std::size_t(2));
        const gui::EntityId meshId = document.ids().back();
        QVERIFY(document.item(meshId).mesh());
        QCOMPARE(document.item(meshId).parent, id);
        gui::ToolController histogram(*registry.tools.find("field-histogram"), document, nullptr);
        QSignalSpy tables(&histogram, &gui::ToolController::tablesReady);
        QVERIFY(histogram.run(id, {{"field", "surface_variation"}, {"bins", "7"}}));
        QCOMPARE(tables.count(), 1);
        QCOMPARE(tables.at(0).at(1).value<gui::NamedTables>().front().second.rows.size(), std::size_t(7));
        QCOMPARE(document.size(), std::size_t(2));

        // A tool that updates a mesh's vertices keeps its triangles.
        const std::size_t triangles = document.item(meshId).mesh()->triangles.size();
        QVERIFY(normals.run(meshId, {{"knn", "8"}}));
        QVERIFY(document.item(meshId).mesh());
        QCOMPARE(document.item(meshId).mesh()->triangles.size(), triangles);
        QVERIFY(document.item(meshId).mesh()->vertices.hasNormals());

        // Two roles at once: merge the plane and the mesh's vertices.
        gui::ToolController merge(*registry.tools.find("merge"), document, nullptr);
        QSignalSpy finished(&merge, &gui::ToolController::finished);
        QVERIFY(merge.run(gui::ToolInputChoice{{"input", {id, meshId}}}, {}));
        QCOMPARE(document.item(document.ids().back()).points().size(), std::size_t(800));
        // Entities in no file: named as the files to export them to, and said so.
        const QString logged = finished.at(0).at(0).toString();
        QVERIFY2(logged.contains("scandiff-cli merge plane.ply plane_mesh.ply -o plane_merge.ply"), qPrintable(logged));
        QVERIFY2(logged.contains("export plane.ply, plane_mesh.ply first"), qPrintable(logged));
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
