// SPDX-License-Identifier: GPL-3.0-or-later
#include "controllers/SegmentationController.h"
#include "controllers/CommandLine.h"

#include "TaskRunner.h"
#include "tools/ParameterForm.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/segmentation/SegmentationParameters.h>
#include <scandiff/io/RegionExport.h>

#include <QCheckBox>
#include <QComboBox>
#include <QElapsedTimer>
#include <QFileDialog>
#include <QFormLayout>
#include <QLabel>
#include <QMessageBox>
#include <QPushButton>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

namespace scandiff::gui {

SegmentationDialog::SegmentationDialog(const Document& document, EntityId input, QWidget* parent) : QDialog(parent)
{
    setWindowTitle(tr("Segment the changes"));
    auto* layout = new QVBoxLayout(this);
    auto* help = new QLabel(tr("Classify a field (thresholds, K-means or the local chi-square test), group the changed points "
                               "into regions (connected components on the octree grid) or grow them by fast marching, and "
                               "measure each region."),
                            this);
    help->setWordWrap(true);
    layout->addWidget(help);
    auto* entities = new QFormLayout;
    input_ = new QComboBox(this);
    input_->setObjectName("input");
    reference_ = new QComboBox(this);
    reference_->setObjectName("reference");
    for (EntityId id : document.ids()) {
        const Document::Item& item = document.item(id);
        if (item.cloud() && !item.points().fields().empty())
            input_->addItem(item.name, id);
    }
    if (const int i = input_->findData(input); i >= 0)
        input_->setCurrentIndex(i);
    // The other epoch: any cloud but the one segmented (kept when still offered).
    const auto listOtherEpochs = [this, &document] {
        const EntityId chosen = reference();
        reference_->clear();
        reference_->addItem(tr("(none: no volume)"), kNoEntity);
        for (EntityId id : document.ids())
            if (id != this->input() && document.item(id).cloud())
                reference_->addItem(document.item(id).name, id);
        if (const int i = reference_->findData(chosen); i >= 0)
            reference_->setCurrentIndex(i);
    };
    listOtherEpochs();
    connect(input_, qOverload<int>(&QComboBox::currentIndexChanged), this, listOtherEpochs);
    entities->addRow(tr("Cloud"), input_);
    entities->addRow(tr("Other epoch (volume)"), reference_);
    layout->addLayout(entities);
    form_ = new ParameterForm(segmentationParameters(), this);
    // The field: a choice of the cloud's fields, the one the user is looking at
    // first; the method: the panel's thresholds when the user set some (a range
    // when both ends are set, "above" when only the low one is).
    const auto followInput = [this, &document] {
        const Document::Item* item = document.find(this->input());
        auto* fields = qobject_cast<QComboBox*>(form_->editor("field"));
        if (!fields)
            return;
        listFieldsOf(fields, item);
        if (!item || item->display.activeField.empty())
            return;
        const std::string& active = item->display.activeField;
        const ScalarField* field = item->points().field(active);
        const auto it = item->display.fields.find(active);
        if (!field || it == item->display.fields.end())
            return;
        const ValueRange range = field->range();
        const bool lowSet = std::isfinite(it->second.low) && it->second.low > range.min;
        const bool highSet = std::isfinite(it->second.high) && it->second.high < range.max;
        if (lowSet && highSet)
            form_->setValue("range", QString("%1 %2").arg(it->second.low, 0, 'g', 10).arg(it->second.high, 0, 'g', 10));
        else if (lowSet)
            form_->setValue("above", QString::number(it->second.low, 'g', 10));
    };
    followInput();
    connect(input_, qOverload<int>(&QComboBox::currentIndexChanged), this, followInput);
    addFormAndButtons(*this, *layout, form_);
    resize(560, 700);
}

EntityId SegmentationDialog::input() const { return input_->currentData().isValid() ? input_->currentData().toInt() : kNoEntity; }
EntityId SegmentationDialog::reference() const
{
    return reference_->currentData().isValid() ? reference_->currentData().toInt() : kNoEntity;
}
std::map<std::string, std::string> SegmentationDialog::values() const { return form_->values(); }

SegmentationController::SegmentationController(const PluginRegistry& registry, Document& document, QWidget* parentWindow)
    : QObject(parentWindow), registry_(registry), document_(document), parentWindow_(parentWindow)
{
    connect(&document_, &Document::removed, this, [this](EntityId id) {
        reports_.erase(id);
        distanceFields_.erase(id);
        regionEntities_.erase(id);
        for (auto& [parent, children] : regionEntities_)
            children.erase(std::remove(children.begin(), children.end(), id), children.end());
    });
    connect(&document_, &Document::cleared, this, [this] {
        reports_.clear();
        distanceFields_.clear();
        regionEntities_.clear();
    });
}

void SegmentationController::runInteractively(EntityId current)
{
    SegmentationDialog dialog(document_, current, parentWindow_);
    if (dialog.input() == kNoEntity) {
        QMessageBox::information(parentWindow_, dialog.windowTitle(), tr("Compute distances first: segmentation works on a scalar field."));
        return;
    }
    if (dialog.exec() == QDialog::Accepted)
        run(dialog.input(), dialog.reference(), dialog.values());
}

bool SegmentationController::run(EntityId inputId, EntityId referenceId, const std::map<std::string, std::string>& parameters)
{
    const Document::Item* input = document_.find(inputId);
    const Document::Item* reference = document_.find(referenceId);
    if (!input || !input->cloud()) {
        emit failed(tr("Segmentation needs a point cloud"));
        return false;
    }
    if (referenceId == inputId) {
        emit failed(tr("The other epoch must be another cloud: a cloud has no volume of change against itself"));
        return false;
    }
    CommandLine command(document_, "scandiff-cli segment");
    command.file(*input);
    if (reference)
        command.word("--reference").file(*reference);
    command.outputBeside("--out-dir", *input, "_regions", QString()).options(parameters, segmentationParameters());
    const QString commandText = command.text();
    QElapsedTimer clock;
    clock.start();
    std::optional<SegmentationRun> run;
    std::optional<ParameterValues> values;
    TaskResult outcome = runTask(parentWindow_, tr("Segmenting"), [&](ProgressObserver& progress) {
        values = resolveParameters(segmentationParameters(), parameters, "segment");
        run = runSegmentation(*input->cloud(), *values, &progress);
    });
    if (outcome.outcome != TaskOutcome::Done) {
        if (outcome.outcome == TaskOutcome::Cancelled)
            emit cancelled(tr("Segmentation was cancelled"));
        else
            emit failed(outcome.error);
        return false;
    }
    // A new run replaces the regions of the previous one (a copy: removing
    // them updates regionEntities_ through the document's signal).
    for (EntityId old : std::exchange(regionEntities_[inputId], {}))
        document_.remove(old);
    const std::string summary = run->summary;
    std::vector<ScalarField> fields = std::move(run->fields);
    // region_id last: it becomes the active field, coloured by region.
    std::stable_partition(fields.begin(), fields.end(), [](const ScalarField& f) { return f.name() != "region_id"; });
    for (ScalarField& field : fields)
        document_.addField(inputId, std::move(field));

    // The report and the regions as clouds, from the cloud that now holds region_id.
    const PointCloud& cloud = *input->cloud();
    std::vector<RegionStatistics> report;
    std::vector<PointCloud> regionClouds;
    outcome = runTask(parentWindow_, tr("Measuring the regions"), [&](ProgressObserver& progress) {
        report = regionReport(cloud, regionReportSettings(*values, reference ? reference->cloud() : nullptr), &progress);
        const std::map<int, std::vector<std::size_t>> members = pointsByRegion(*cloud.field("region_id"));
        for (std::size_t r = 0; r < report.size() && r < kMaxRegionEntities; ++r) {
            const auto m = members.find(report[r].id);
            regionClouds.push_back(cloud.subset(m == members.end() ? std::vector<std::size_t>{} : m->second));
        }
    });
    if (outcome.outcome != TaskOutcome::Done) {
        if (outcome.outcome == TaskOutcome::Cancelled)
            emit cancelled(tr("Measuring the regions was cancelled"));
        else
            emit failed(outcome.error);
        return false;
    }
    const std::string distanceField = values->text("field");
    for (std::size_t r = 0; r < regionClouds.size(); ++r) {
        const RegionStatistics& s = report[r];
        const EntityId child = document_.add(tr("region %1 (%2 points, %3 m2)").arg(s.id).arg(s.pointCount).arg(s.footprintArea, 0, 'f', 1),
                                             std::move(regionClouds[r]), inputId);
        document_.setActiveField(child, distanceField);
        // The cloud shows every region in its own colour; a region's own cloud
        // (its distances) is shown by ticking it, not drawn over them.
        document_.setVisible(child, false);
        regionEntities_[inputId].push_back(child);
    }
    if (report.size() > regionClouds.size())
        emit finished(tr("%1 regions: the %2 largest are listed in the tree, all are exported").arg(report.size()).arg(regionClouds.size()));
    reports_[inputId] = std::move(report);
    distanceFields_[inputId] = distanceField;
    document_.setActiveField(inputId, "region_id");
    const bool revealed = document_.revealResult(inputId);
    // The regions, report and export state live here; bringing back the
    // previous fields alone would leave them describing this run.
    document_.forgetUndo();
    emit finished(tr("segment %1 [%2]: %3; %4 s%5")
                      .arg(input->name, commandText, QString::fromStdString(summary))
                      .arg(clock.elapsed() / 1000.0, 0, 'f', 3)
                      .arg(revealed ? tr("; %1 was hidden: shown with its regions").arg(input->name) : QString()));
    emit resultReady(inputId);
    return true;
}

const std::vector<RegionStatistics>& SegmentationController::report(EntityId id) const
{
    static const std::vector<RegionStatistics> none;
    const auto it = reports_.find(id);
    return it == reports_.end() ? none : it->second;
}

bool SegmentationController::exportRegions(EntityId id, const QString& folder, bool dxfPoints)
{
    const Document::Item* item = document_.find(id);
    if (!item || !item->cloud() || !item->points().field("region_id")) {
        emit failed(tr("Export regions: the cloud has no region_id field (run Segment the changes first)"));
        return false;
    }
    const PointCloud& cloud = *item->cloud();
    std::vector<RegionStatistics> report = this->report(id);
    // Everything the worker needs is read here, on the GUI thread.
    RegionReportParams params;
    const auto known = distanceFields_.find(id);
    params.distanceField = known != distanceFields_.end() ? known->second : item->display.activeField;
    if (params.distanceField == "region_id" || !cloud.field(params.distanceField))
        params.distanceField.clear();
    io::RegionExportFiles files;
    const TaskResult outcome = runTask(parentWindow_, tr("Exporting regions"), [&](ProgressObserver& progress) {
        if (report.empty()) // a cloud read with its region_id: measure it now
            report = regionReport(cloud, params, &progress);
        io::RegionExportOptions options;
        options.write.progress = &progress;
        options.dxf.includePoints = dxfPoints;
        files = io::exportRegions(registry_.formats, cloud, report, folder.toStdString(), options);
    });
    if (outcome.outcome != TaskOutcome::Done) {
        if (outcome.outcome == TaskOutcome::Cancelled)
            emit cancelled(tr("Export was cancelled"));
        else
            emit failed(outcome.error);
        return false;
    }
    emit finished(tr("exported %1 regions of %2 to %3: regions.ply, %4 region files, regions.dxf%5, regions.csv")
                      .arg(report.size())
                      .arg(item->name, folder)
                      .arg(files.regionClouds.size())
                      .arg(dxfPoints ? tr(" (outlines, labels and points)") : QString()));
    return true;
}

bool SegmentationController::hasRegions(EntityId id) const
{
    for (const auto& [parent, children] : regionEntities_)
        if (std::find(children.begin(), children.end(), id) != children.end())
            id = parent;
    const Document::Item* item = document_.find(id);
    return item && item->cloud() && item->points().field("region_id");
}

void SegmentationController::exportRegionsWithDialog(EntityId id)
{
    // A region's own entity exports its parent's regions.
    for (const auto& [parent, children] : regionEntities_)
        if (std::find(children.begin(), children.end(), id) != children.end())
            id = parent;
    const QString folder = QFileDialog::getExistingDirectory(parentWindow_, tr("Export the regions (PLY, DXF, CSV) into"));
    if (folder.isEmpty())
        return;
    // The DXF holds each region's outlines and label; its points are an option
    // (the CLI's --dxf-points), since they can make a CAD file heavy.
    QMessageBox confirm(QMessageBox::Question, tr("Export regions"),
                        tr("Write regions.ply, one PLY per region, regions.dxf and regions.csv into\n%1?").arg(folder),
                        QMessageBox::Ok | QMessageBox::Cancel, parentWindow_);
    confirm.button(QMessageBox::Ok)->setText(tr("Export"));
    auto* points = new QCheckBox(tr("Also draw each region's points in the DXF"));
    points->setChecked(dxfPointsChoice_);
    confirm.setCheckBox(points);
    if (confirm.exec() != QMessageBox::Ok)
        return;
    dxfPointsChoice_ = points->isChecked();
    exportRegions(id, folder, dxfPointsChoice_);
}

} // namespace scandiff::gui
