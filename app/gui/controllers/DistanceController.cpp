// SPDX-License-Identifier: GPL-3.0-or-later
#include "controllers/DistanceController.h"
#include "controllers/CommandLine.h"

#include "TaskRunner.h"
#include "tools/ParameterForm.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/DistanceParameters.h>

#include <QComboBox>
#include <QElapsedTimer>
#include <QFormLayout>
#include <QLabel>
#include <QMessageBox>
#include <QSettings>
#include <QVBoxLayout>

#include <optional>

namespace scandiff::gui {

namespace {

QString statisticsText(const DistanceStatistics& s)
{
    return QString("%1 values, mean %2, std %3, min %4, max %5, RMS %6")
        .arg(s.count)
        .arg(s.mean, 0, 'g', 6)
        .arg(s.standardDeviation, 0, 'g', 6)
        .arg(s.min, 0, 'g', 6)
        .arg(s.max, 0, 'g', 6)
        .arg(s.rms, 0, 'g', 6);
}

void fillEntities(QComboBox* box, const Document& document, bool meshes, bool clouds)
{
    for (EntityId id : document.ids()) {
        const Document::Item& item = document.item(id);
        if ((meshes && item.mesh()) || (clouds && item.cloud()))
            box->addItem(item.name, id);
    }
}

} // namespace

DistanceDialog::DistanceDialog(DistanceKind kind, const Document& document, QWidget* parent) : QDialog(parent)
{
    const bool c2c = kind == DistanceKind::CloudToCloud;
    setWindowTitle(c2c ? tr("Cloud-to-cloud distance") : tr("Cloud-to-mesh distance"));
    auto* layout = new QVBoxLayout(this);
    auto* help = new QLabel(c2c ? tr("For every point of the compared cloud, its distance to the reference cloud "
                                     "(nearest neighbour, or a local model of the reference).")
                                : tr("For every point of the compared cloud, its exact distance to the reference mesh."),
                            this);
    help->setWordWrap(true);
    layout->addWidget(help);
    auto* entities = new QFormLayout;
    reference_ = new QComboBox(this);
    reference_->setObjectName("reference");
    compared_ = new QComboBox(this);
    compared_->setObjectName("compared");
    fillEntities(reference_, document, !c2c, c2c);
    fillEntities(compared_, document, false, true);
    entities->addRow(tr("Reference"), reference_);
    entities->addRow(tr("Compared"), compared_);
    layout->addLayout(entities);
    form_ = new ParameterForm(c2c ? cloudToCloudParameters() : cloudToMeshParameters(), this);
    addFormAndButtons(*this, *layout, form_);
    resize(520, c2c ? 640 : 360);
}

EntityId DistanceDialog::reference() const { return reference_->currentData().isValid() ? reference_->currentData().toInt() : kNoEntity; }
EntityId DistanceDialog::compared() const { return compared_->currentData().isValid() ? compared_->currentData().toInt() : kNoEntity; }

void DistanceDialog::setReference(EntityId id)
{
    if (const int i = reference_->findData(id); i >= 0)
        reference_->setCurrentIndex(i);
}

void DistanceDialog::setCompared(EntityId id)
{
    if (const int i = compared_->findData(id); i >= 0)
        compared_->setCurrentIndex(i);
}

std::map<std::string, std::string> DistanceDialog::values() const { return form_->values(); }

DistanceController::DistanceController(Document& document, QWidget* parentWindow)
    : QObject(parentWindow), document_(document), parentWindow_(parentWindow)
{
}

void DistanceController::runInteractively(DistanceKind kind, EntityId current)
{
    DistanceDialog dialog(kind, document_, parentWindow_);
    const bool c2c = kind == DistanceKind::CloudToCloud;
    if (dialog.reference() == kNoEntity || dialog.compared() == kNoEntity) {
        QMessageBox::information(parentWindow_, dialog.windowTitle(),
                                 c2c ? tr("Open two point clouds first.") : tr("Open a mesh and a point cloud first."));
        return;
    }
    // CloudCompare's habit: the older epoch (opened first) is the reference;
    // the current selection, else the last cloud, is compared.
    const Document::Item* currentItem = document_.find(current);
    dialog.setCompared(currentItem && currentItem->cloud() ? current : document_.lastCloudId());
    if (c2c && dialog.reference() == dialog.compared())
        for (EntityId id : document_.ids())
            if (id != dialog.compared() && document_.item(id).cloud()) {
                dialog.setReference(id);
                break;
            }
    if (dialog.exec() != QDialog::Accepted)
        return;
    if (c2c)
        runCloudToCloud(dialog.compared(), dialog.reference(), dialog.values());
    else
        runCloudToMesh(dialog.compared(), dialog.reference(), dialog.values());
}

namespace {

//! The console's command of a distance run ("c2c", "c2m"): both files, the
//! output beside the compared one, the options as the dialog gave them.
QString distanceCommand(const Document& document, const QString& tool, const Document::Item& reference,
                        const Document::Item& compared, const std::map<std::string, std::string>& parameters,
                        const std::vector<ParameterSpec>& specs)
{
    return CommandLine(document, "scandiff-cli " + tool)
        .word("--reference")
        .file(reference)
        .word("--compared")
        .file(compared)
        .outputBeside("-o", compared, "_" + tool)
        .options(parameters, specs)
        .text();
}

} // namespace

bool DistanceController::runCloudToCloud(EntityId comparedId, EntityId referenceId,
                                         const std::map<std::string, std::string>& parameters)
{
    const Document::Item* compared = document_.find(comparedId);
    const Document::Item* reference = document_.find(referenceId);
    if (!compared || !reference || !compared->cloud() || !reference->cloud()) {
        emit failed(tr("C2C needs two point clouds"));
        return false;
    }
    // Before the run: the files as they are now (the run adds fields).
    const QString command = distanceCommand(document_, "c2c", *reference, *compared, parameters, cloudToCloudParameters());
    std::optional<CloudToCloudRun> run;
    QElapsedTimer clock;
    clock.start();
    const TaskResult outcome = runTask(parentWindow_, tr("Cloud-to-cloud distance"), [&](ProgressObserver& progress) {
        const ParameterValues values = resolveParameters(cloudToCloudParameters(), parameters, "c2c");
        run = scandiff::runCloudToCloud(*compared->cloud(), *reference->cloud(), values, &progress);
    });
    if (outcome.outcome != TaskOutcome::Done) {
        if (outcome.outcome == TaskOutcome::Cancelled)
            emit cancelled(tr("C2C was cancelled"));
        else
            emit failed(outcome.error);
        return false;
    }
    const double seconds = clock.elapsed() / 1000.0;
    const Document::UndoGroup group(document_, tr("C2C"));
    CloudToCloudResult& forward = run->forward;
    for (auto* extra : {&forward.dx, &forward.dy, &forward.dz, &forward.visibility})
        if (*extra)
            document_.addField(comparedId, std::move(**extra));
    const DistanceStatistics statistics = forward.statistics;
    document_.addField(comparedId, std::move(forward.distance)); // last: the active field
    const bool revealed = document_.revealResult(comparedId);
    const bool reverse = run->reverse.has_value();
    if (reverse)
        document_.addField(referenceId, std::move(run->reverse->distance));
    showReference(referenceId, reverse);
    if (forward.closest) {
        PointCloud closest = std::move(*forward.closest);
        document_.add(compared->name + tr(" closest points"), std::move(closest), comparedId);
    }
    emit finished(tr("C2C %1 -> %2 [%3] %4; octree level %5; %6 s%7")
                      .arg(compared->name, reference->name, command, statisticsText(statistics))
                      .arg(forward.level)
                      .arg(seconds, 0, 'f', 3)
                      .arg(revealed ? tr("; %1 was hidden: shown with its distances").arg(compared->name) : QString()));
    emit resultReady(comparedId);
    return true;
}

bool DistanceController::runCloudToMesh(EntityId comparedId, EntityId referenceId,
                                        const std::map<std::string, std::string>& parameters)
{
    const Document::Item* compared = document_.find(comparedId);
    const Document::Item* reference = document_.find(referenceId);
    if (!compared || !reference || !compared->cloud() || !reference->mesh()) {
        emit failed(tr("C2M needs a point cloud and a mesh"));
        return false;
    }
    const QString command = distanceCommand(document_, "c2m", *reference, *compared, parameters, cloudToMeshParameters());
    std::optional<CloudToMeshResult> result;
    QElapsedTimer clock;
    clock.start();
    const TaskResult outcome = runTask(parentWindow_, tr("Cloud-to-mesh distance"), [&](ProgressObserver& progress) {
        const CloudToMeshParams params = cloudToMeshSettings(resolveParameters(cloudToMeshParameters(), parameters, "c2m"));
        result = cloudToMesh(*compared->cloud(), *reference->mesh(), params, &progress);
    });
    if (outcome.outcome != TaskOutcome::Done) {
        if (outcome.outcome == TaskOutcome::Cancelled)
            emit cancelled(tr("C2M was cancelled"));
        else
            emit failed(outcome.error);
        return false;
    }
    const double seconds = clock.elapsed() / 1000.0;
    const DistanceStatistics statistics = result->statistics;
    const Document::UndoGroup group(document_, tr("C2M"));
    document_.addField(comparedId, std::move(result->distance));
    const bool revealed = document_.revealResult(comparedId);
    showReference(referenceId, false);
    emit finished(tr("C2M %1 -> %2 [%3] %4; %5 degenerate triangles; %6 s%7")
                      .arg(compared->name, reference->name, command, statisticsText(statistics))
                      .arg(result->degenerateTriangles)
                      .arg(seconds, 0, 'f', 3)
                      .arg(revealed ? tr("; %1 was hidden: shown with its distances").arg(compared->name) : QString()));
    emit resultReady(comparedId);
    return true;
}

namespace {
constexpr const char* kReferenceSetting = "display/referenceAfterComparison";
}

ReferenceAfterComparison DistanceController::referenceAfterComparison()
{
    const QString choice = QSettings().value(kReferenceSetting, "grey").toString();
    return choice == "hide" ? ReferenceAfterComparison::Hide : choice == "keep" ? ReferenceAfterComparison::Keep : ReferenceAfterComparison::Grey;
}

void DistanceController::setReferenceAfterComparison(ReferenceAfterComparison choice)
{
    QSettings().setValue(kReferenceSetting, choice == ReferenceAfterComparison::Hide   ? "hide"
                                            : choice == ReferenceAfterComparison::Keep ? "keep"
                                                                                       : "grey");
}

void DistanceController::showReference(EntityId referenceId, bool gotDistances)
{
    if (gotDistances)
        return; // both ways: it shows its own distances, on the same scale
    switch (referenceAfterComparison()) {
    case ReferenceAfterComparison::Grey:
        document_.setActiveField(referenceId, std::string());
        document_.setNeutral(referenceId, true);
        break;
    case ReferenceAfterComparison::Hide: document_.setVisible(referenceId, false); break;
    case ReferenceAfterComparison::Keep: break;
    }
}

} // namespace scandiff::gui
