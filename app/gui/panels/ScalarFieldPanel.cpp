// SPDX-License-Identifier: GPL-3.0-or-later
#include "panels/ScalarFieldPanel.h"

#include "colour/ColourScaleEditor.h"
#include "view/EntityColouring.h"
#include "widgets/HistogramWidget.h"
#include "widgets/RangeEditor.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/FieldRange.h>
#include <scandiff/core/processing/FieldOperations.h>
#include <scandiff/io/ResultFiles.h>

#include <QCheckBox>
#include <QAbstractItemView>
#include <QComboBox>
#include <QFileDialog>
#include <QFormLayout>
#include <QMessageBox>
#include <QHBoxLayout>
#include <QLabel>
#include <QPushButton>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>
#include <limits>

namespace scandiff::gui {

namespace {

constexpr int kHistogramBins = 128;

} // namespace

ScalarFieldPanel::ScalarFieldPanel(Document& document, QWidget* parent) : QWidget(parent), document_(document)
{
    auto* layout = new QVBoxLayout(this);
    title_ = new QLabel(this);
    title_->setWordWrap(true);
    layout->addWidget(title_);
    auto* form = new QFormLayout;
    fieldBox_ = new QComboBox(this);
    fieldBox_->setObjectName("fieldBox");
    fieldBox_->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon); // long field names: see the scale's
    fieldBox_->setMinimumContentsLength(22);
    form->addRow(tr("Active field"), fieldBox_);
    auto* scaleRow = new QHBoxLayout;
    scaleBox_ = new QComboBox(this);
    scaleBox_->setObjectName("scaleBox");
    // As wide as a usual name, not the longest: the panel keeps its width
    // (the list that opens shows every name whole).
    scaleBox_->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
    scaleBox_->setMinimumContentsLength(22);
    editScale_ = new QPushButton(tr("Edit..."), this);
    editScale_->setToolTip(tr("Edit the colour scale's stops and save it as a new scale"));
    scaleRow->addWidget(scaleBox_, 1);
    scaleRow->addWidget(editScale_);
    form->addRow(tr("Colour scale"), scaleRow);
    outsideBox_ = new QComboBox(this);
    outsideBox_->setObjectName("outsideBox");
    outsideBox_->addItem(tr("Hidden"));
    outsideBox_->addItem(tr("Greyed"));
    form->addRow(tr("Outside the range"), outsideBox_);
    blendColours_ = new QCheckBox(tr("Shaded by the cloud's colours"), this);
    blendColours_->setObjectName("blendColours");
    blendColours_->setToolTip(tr("The field's colours darkened where the cloud's own colours (its photo) are dark: "
                                 "the field over the texture"));
    form->addRow(QString(), blendColours_);
    layout->addLayout(form);
    // The colour range: what the scale spans, apart from what is shown.
    colours_ = new RangeEditor(this);
    colours_->setObjectName("colourRange");
    layout->addWidget(new QLabel(tr("Colour range (values beyond it take the end colours):"), this));
    layout->addWidget(colours_);
    auto* colourRow = new QHBoxLayout;
    symmetric_ = new QCheckBox(tr("Symmetric around 0"), this);
    symmetric_->setObjectName("symmetric");
    symmetric_->setToolTip(tr("The colour range becomes -m..m: 0 at the scale's middle, as for signed distances"));
    automaticColours_ = new QPushButton(tr("Automatic"), this);
    automaticColours_->setObjectName("automaticColours");
    automaticColours_->setToolTip(tr("The colour range follows the field's minimum and maximum"));
    colourRow->addWidget(symmetric_);
    colourRow->addStretch(1);
    colourRow->addWidget(automaticColours_);
    layout->addLayout(colourRow);
    range_ = new RangeEditor(this);
    range_->setObjectName("thresholds");
    layout->addWidget(new QLabel(tr("Threshold range (points inside are shown):"), this));
    layout->addWidget(range_);
    histogram_ = new HistogramWidget(this);
    histogram_->setObjectName("histogram");
    layout->addWidget(histogram_, 1);
    auto* countsRow = new QHBoxLayout;
    inside_ = new QLabel(this);
    auto* logScale = new QCheckBox(tr("Log counts"), this);
    logScale->setObjectName("logCounts");
    logScale->setToolTip(tr("Histogram heights on a logarithmic scale: the few changed points next to the many unchanged ones"));
    exportHistogram_ = new QPushButton(tr("CSV..."), this);
    exportHistogram_->setObjectName("exportHistogram");
    exportHistogram_->setToolTip(tr("Save the histogram's bins as a CSV table (bin_min, bin_max, count)"));
    connect(exportHistogram_, &QPushButton::clicked, this, &ScalarFieldPanel::exportHistogramWithDialog);
    countsRow->addWidget(inside_, 1);
    countsRow->addWidget(logScale);
    countsRow->addWidget(exportHistogram_);
    layout->addLayout(countsRow);
    connect(logScale, &QCheckBox::toggled, histogram_, &HistogramWidget::setLogarithmic);
    auto* buttons = new QHBoxLayout;
    resetRange_ = new QPushButton(tr("Full range"), this);
    split_ = new QPushButton(tr("Split at thresholds"), this);
    split_->setObjectName("splitButton");
    split_->setToolTip(tr("Add the points inside and outside the range as two new clouds"));
    buttons->addWidget(resetRange_);
    buttons->addStretch(1);
    buttons->addWidget(split_);
    layout->addLayout(buttons);

    connect(fieldBox_, qOverload<int>(&QComboBox::activated), this, &ScalarFieldPanel::onFieldChosen);
    connect(scaleBox_, qOverload<int>(&QComboBox::activated), this, &ScalarFieldPanel::onScaleChosen);
    connect(editScale_, &QPushButton::clicked, this, &ScalarFieldPanel::editScale);
    connect(outsideBox_, qOverload<int>(&QComboBox::activated), this, [this](int index) {
        document_.setOutsideMode(entity_, index == 1 ? FieldColouring::Outside::Grey : FieldColouring::Outside::Hide);
    });
    connect(range_, &RangeEditor::rangeChanged, this, &ScalarFieldPanel::onRangeEdited);
    connect(colours_, &RangeEditor::rangeChanged, this, &ScalarFieldPanel::onColourRangeEdited);
    connect(blendColours_, &QCheckBox::toggled, this, [this](bool on) {
        if (!updating_)
            document_.setBlendColours(entity_, on);
    });
    connect(symmetric_, &QCheckBox::toggled, this, [this](bool on) {
        if (!updating_)
            editDisplay([on](FieldDisplay& d) { d.symmetric = on; });
    });
    connect(automaticColours_, &QPushButton::clicked, this, [this] {
        editDisplay([](FieldDisplay& d) {
            d.colourLow = -std::numeric_limits<double>::infinity();
            d.colourHigh = std::numeric_limits<double>::infinity();
        });
    });
    connect(histogram_, &HistogramWidget::markedRangeEdited, this, [this](double low, double high) { range_->setRange(low, high); });
    connect(resetRange_, &QPushButton::clicked, this, [this] {
        if (const ScalarField* field = activeField()) {
            FieldDisplay display = document_.fieldDisplay(entity_, field->name());
            display.low = -std::numeric_limits<double>::infinity();
            display.high = std::numeric_limits<double>::infinity();
            document_.setFieldDisplay(entity_, field->name(), display);
            refresh();
        }
    });
    connect(split_, &QPushButton::clicked, this, [this] {
        if (const ScalarField* field = activeField())
            emit splitRequested(entity_, field->name(), range_->low(), range_->high());
    });
    refreshSoon_->setSingleShot(true);
    refreshSoon_->setInterval(1);
    connect(refreshSoon_, &QTimer::timeout, this, &ScalarFieldPanel::refresh);
    connect(&document_, &Document::fieldsChanged, this, [this](EntityId id) {
        if (id == entity_)
            refreshSoon_->start();
    });
    connect(&document_, &Document::renamed, this, [this](EntityId id) {
        if (const Document::Item* item = document_.find(id); item && id == entity_)
            title_->setText(tr("<b>%1</b>").arg(item->name.toHtmlEscaped()));
    });
    connect(&document_, &Document::displayChanged, this, [this](EntityId id) {
        if (id == entity_ && !updating_)
            refreshSoon_->start();
    });
    connect(&document_, &Document::removed, this, [this](EntityId id) {
        if (id == entity_)
            showEntity(kNoEntity);
    });
    connect(&document_, &Document::cleared, this, [this] { showEntity(kNoEntity); });
    refreshScaleBox();
    refresh();
}

void ScalarFieldPanel::showEntity(EntityId id)
{
    // A drawing has no scalar field: the panel waits for a cloud.
    entity_ = document_.contains(id) && document_.item(id).hasData() ? id : kNoEntity;
    refresh();
}

void ScalarFieldPanel::addCustomScale(const ColourScale& scale)
{
    const auto same = std::find_if(customScales_.begin(), customScales_.end(), [&](const ColourScale& s) { return s.name() == scale.name(); });
    if (same != customScales_.end())
        *same = scale;
    else
        customScales_.push_back(scale);
    refreshScaleBox();
}

const ScalarField* ScalarFieldPanel::activeField() const
{
    const Document::Item* item = document_.find(entity_);
    return item && !item->display.activeField.empty() ? item->points().field(item->display.activeField) : nullptr;
}

void ScalarFieldPanel::refreshScaleBox()
{
    scaleBox_->clear();
    for (const ColourScale& s : ColourScale::presets())
        scaleBox_->addItem(QString::fromStdString(s.name()));
    for (const ColourScale& s : customScales_)
        scaleBox_->addItem(QString::fromStdString(s.name()));
    scaleBox_->view()->setMinimumWidth(scaleBox_->view()->sizeHintForColumn(0) + 24);
}

void ScalarFieldPanel::refresh()
{
    refreshSoon_->stop();
    updating_ = true;
    const Document::Item* item = document_.find(entity_);
    fieldBox_->clear();
    const ScalarField* field = activeField();
    if (item) {
        title_->setText(tr("<b>%1</b>").arg(item->name.toHtmlEscaped()));
        fieldBox_->addItem(item->points().hasColors() ? tr("(colours)") : tr("(height)"));
        fieldBox_->addItem(tr("(neutral grey)"));
        for (const ScalarField& f : item->points().fields())
            fieldBox_->addItem(QString::fromStdString(f.name()));
        fieldBox_->setCurrentIndex(field ? fieldBox_->findText(QString::fromStdString(field->name())) : item->display.neutral ? 1 : 0);
        outsideBox_->setCurrentIndex(item->display.outside == FieldColouring::Outside::Grey ? 1 : 0);
    } else {
        title_->setText(tr("Select a cloud in the tree."));
    }
    const bool enabled = field != nullptr;
    for (QWidget* w : std::initializer_list<QWidget*>{scaleBox_, editScale_, outsideBox_, colours_, symmetric_, automaticColours_, range_,
                                                      histogram_, exportHistogram_, resetRange_, split_})
        w->setEnabled(enabled);
    fieldBox_->setEnabled(item != nullptr);
    // Only where it does something: a field shown on a cloud with colours.
    blendColours_->setEnabled(enabled && item->points().hasColors());
    blendColours_->setChecked(item && item->display.blendColours);
    if (field) {
        const FieldDisplay display = document_.fieldDisplay(entity_, field->name());
        scaleBox_->setCurrentText(QString::fromStdString(display.scale.name()));
        const ValueRange r = field->range();
        const double lo = r.validCount ? r.min : 0.0, hi = r.validCount ? r.max : 0.0;
        range_->setBounds(lo, hi);
        range_->setRange(std::max(lo, display.low), std::min(hi, display.high));
        histogram_->setHistogram(computeHistogram(field->values().data(), field->size(), field->offset(), kHistogramBins));
        const auto [cmin, cmax] = colourRange(*field, display);
        // The colour editor spans the field and the colour range (-m..m when
        // symmetric; a split part's values may all lie outside the range its
        // parent coloured with, and the editor must still show that range).
        colours_->setBounds(std::min(lo, cmin), std::max(hi, cmax));
        colours_->setRange(cmin, cmax);
        symmetric_->setChecked(display.symmetric);
        histogram_->setColouring(display.scale, cmin, cmax);
        // Labels and flags: each bar in the colour its points are drawn in.
        if (isCategoricalField(*field)) {
            const bool label = isLabelField(*field);
            histogram_->setCategoryColour([label](long value) {
                const auto c = categoryColour(label, value);
                return QColor(c[0], c[1], c[2]);
            });
        } else {
            histogram_->setCategoryColour({});
        }
        histogram_->setMarkedRange(range_->low(), range_->high());
        std::vector<std::pair<double, QString>> references;
        for (const auto& [value, label] : display.marks)
            references.emplace_back(value, QString::fromStdString(label) + " " + QString::number(value, 'g', 6));
        histogram_->setReferenceLines(std::move(references));
    } else {
        // Nothing of the previous entity's field stays on show; the height is
        // drawn in the default scale.
        scaleBox_->setCurrentText(QString::fromStdString(ColourScale::defaultScale().name()));
        for (RangeEditor* editor : {range_, colours_}) {
            editor->setBounds(0.0, 1.0);
            editor->setRange(0.0, 1.0);
        }
        symmetric_->setChecked(false);
        histogram_->setHistogram({});
        histogram_->setMarkedRange(-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity());
        histogram_->setReferenceLines({});
    }
    updating_ = false;
    updateInsideCount();
}

void ScalarFieldPanel::onFieldChosen(int index)
{
    const Document::Item* item = document_.find(entity_);
    if (!item)
        return;
    // 0: colours or height, 1: neutral grey, then the fields.
    document_.setNeutral(entity_, index == 1);
    document_.setActiveField(entity_, index <= 1 ? std::string() : fieldBox_->itemText(index).toStdString());
}

void ScalarFieldPanel::onScaleChosen(int index)
{
    const ScalarField* field = activeField();
    if (!field || index < 0)
        return;
    const auto& presets = ColourScale::presets();
    const std::size_t i = static_cast<std::size_t>(index);
    FieldDisplay display = document_.fieldDisplay(entity_, field->name());
    display.scale = i < presets.size() ? presets[i] : customScales_.at(i - presets.size());
    document_.setFieldDisplay(entity_, field->name(), display);
}

void ScalarFieldPanel::onRangeEdited(double low, double high)
{
    const ScalarField* field = activeField();
    if (!field || updating_)
        return;
    FieldDisplay display = document_.fieldDisplay(entity_, field->name());
    display.low = low;
    display.high = high;
    updating_ = true; // the panel already shows this range: no rebuild while dragging
    document_.setFieldDisplay(entity_, field->name(), display);
    updating_ = false;
    histogram_->setMarkedRange(low, high);
    updateInsideCount();
}

void ScalarFieldPanel::onColourRangeEdited(double low, double high)
{
    if (!activeField() || updating_)
        return;
    FieldDisplay display = document_.fieldDisplay(entity_, activeField()->name());
    if (display.symmetric || display.scale.symmetric()) {
        // Symmetric around 0: the bound the user just typed or dragged sets
        // both (typing 0.02 as the maximum makes the minimum -0.02).
        const auto [previousLow, previousHigh] = colourRange(*activeField(), display);
        const bool lowMoved = low != previousLow, highMoved = high != previousHigh;
        const double m = highMoved && !lowMoved ? std::abs(high)
                         : lowMoved && !highMoved ? std::abs(low)
                                                  : std::max(std::abs(low), std::abs(high));
        low = -m;
        high = m;
    }
    display.colourLow = low;
    display.colourHigh = high;
    updating_ = true; // as for the thresholds: no rebuild while dragging
    document_.setFieldDisplay(entity_, activeField()->name(), display);
    if (colours_->low() != low || colours_->high() != high) {
        colours_->setBounds(std::min(colours_->minimum(), low), std::max(colours_->maximum(), high));
        colours_->setRange(low, high);
    }
    updating_ = false;
    const auto [cmin, cmax] = colourRange(*activeField(), display);
    histogram_->setColouring(display.scale, cmin, cmax);
}

void ScalarFieldPanel::editDisplay(const std::function<void(FieldDisplay&)>& edit)
{
    const ScalarField* field = activeField();
    if (!field)
        return;
    FieldDisplay display = document_.fieldDisplay(entity_, field->name());
    edit(display);
    document_.setFieldDisplay(entity_, field->name(), display);
    refresh();
}

void ScalarFieldPanel::editScale()
{
    const ScalarField* field = activeField();
    if (!field)
        return;
    FieldDisplay display = document_.fieldDisplay(entity_, field->name());
    ColourScaleEditor editor(display.scale, this);
    if (editor.exec() != QDialog::Accepted)
        return;
    display.scale = editor.scale();
    const auto& presets = ColourScale::presets();
    const bool isPreset = std::any_of(presets.begin(), presets.end(), [&](const ColourScale& s) { return s.name() == display.scale.name(); });
    if (isPreset) // an edited preset becomes a custom scale of its own
        display.scale = ColourScale(display.scale.name() + " (custom)", display.scale.stops(), display.scale.symmetric());
    addCustomScale(display.scale);
    document_.setFieldDisplay(entity_, field->name(), display);
}

void ScalarFieldPanel::updateInsideCount()
{
    const ScalarField* field = activeField();
    if (!field) {
        inside_->clear();
        return;
    }
    const std::size_t inside = countInRange(*field, range_->low(), range_->high());
    const double percent = field->size() ? 100.0 * double(inside) / double(field->size()) : 0.0;
    inside_->setText(tr("Inside the range: %1 of %2 points (%3 %)").arg(inside).arg(field->size()).arg(percent, 0, 'f', 1));
}

QString ScalarFieldPanel::insideText() const { return inside_->text(); }

bool ScalarFieldPanel::exportHistogram(const QString& path, QString* error)
{
    const ScalarField* field = activeField();
    try {
        if (!field)
            throw Error(ErrorCode::InvalidArgument, "the selected entity shows no scalar field");
        io::writeTable(fieldHistogram(*field, kHistogramBins), path.toStdString());
        return true;
    } catch (const std::exception& e) {
        if (error)
            *error = QString::fromStdString(e.what());
        return false;
    }
}

void ScalarFieldPanel::exportHistogramWithDialog()
{
    const ScalarField* field = activeField();
    if (!field)
        return;
    const QString path = QFileDialog::getSaveFileName(this, tr("Export the histogram"),
                                                      QString::fromStdString(field->name()) + "-histogram.csv",
                                                      tr("CSV tables (*.csv)"));
    if (path.isEmpty())
        return;
    QString error;
    if (!exportHistogram(path, &error))
        QMessageBox::warning(this, tr("Export the histogram"), error);
}

} // namespace scandiff::gui
