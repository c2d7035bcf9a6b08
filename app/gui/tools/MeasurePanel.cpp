// SPDX-License-Identifier: GPL-3.0-or-later
#include "tools/MeasurePanel.h"

#include <QHBoxLayout>
#include <QLabel>
#include <QListWidget>
#include <QPushButton>
#include <QVBoxLayout>

namespace scandiff::gui {

namespace {

QString metres(double v) { return QString::number(v, 'f', 3) + " m"; }
QString degrees(double v) { return QString::number(v, 'f', 3) + QString::fromUtf8("°"); }

} // namespace

MeasurePanel::MeasurePanel(const Document& document, QWidget* parent) : QWidget(parent), document_(document)
{
    auto* layout = new QVBoxLayout(this);
    measure_ = new QPushButton(tr("Measure (click points)"), this);
    measure_->setObjectName("measure");
    measure_->setCheckable(true);
    measure_->setToolTip(tr("Each click on a cloud adds a point: 2 points a distance, 3 an angle, 3 or more an area"));
    layout->addWidget(measure_);
    result_ = new QLabel(this);
    result_->setObjectName("result");
    result_->setTextInteractionFlags(Qt::TextSelectableByMouse);
    result_->setWordWrap(true);
    layout->addWidget(result_);
    auto* buttons = new QHBoxLayout;
    auto* next = new QPushButton(tr("New"), this);
    next->setToolTip(tr("Keep this measurement and start another"));
    auto* undo = new QPushButton(tr("Undo point"), this);
    auto* clear = new QPushButton(tr("Delete all"), this);
    buttons->addWidget(next);
    buttons->addWidget(undo);
    buttons->addWidget(clear);
    layout->addLayout(buttons);
    layout->addWidget(new QLabel(tr("Kept measurements:"), this));
    kept_ = new QListWidget(this);
    kept_->setObjectName("kept");
    layout->addWidget(kept_, 1);
    connect(measure_, &QPushButton::toggled, this, &MeasurePanel::setMeasuring);
    connect(next, &QPushButton::clicked, this, &MeasurePanel::startNew);
    connect(undo, &QPushButton::clicked, this, &MeasurePanel::undoLastPoint);
    connect(clear, &QPushButton::clicked, this, &MeasurePanel::deleteAll);
    connect(&document_, &Document::cleared, this, &MeasurePanel::deleteAll);
    refresh();
}

void MeasurePanel::setMeasuring(bool on)
{
    if (on == measuring_)
        return;
    measuring_ = on;
    measure_->setChecked(on);
    emit measuringChanged(on);
}

void MeasurePanel::addPick(EntityId id, std::size_t index)
{
    const Document::Item* item = document_.find(id);
    if (!measuring_ || !item || index >= item->points().size())
        return;
    // A point label says what the point holds of the field shown.
    if (measurements_.back().empty()) {
        const ScalarField* field = item->display.activeField.empty() ? nullptr : item->points().field(item->display.activeField);
        notes_.back() = field ? tr("%1: %2 = %3")
                                    .arg(item->name, QString::fromStdString(field->name()), QString::number(field->value(index), 'g', 6))
                              : QString();
    }
    addPoint(item->points().globalPosition(index));
}

void MeasurePanel::addPoint(const Eigen::Vector3d& global)
{
    measurements_.back().push_back(global);
    refresh();
}

void MeasurePanel::startNew()
{
    if (!measurements_.back().empty()) {
        measurements_.emplace_back();
        notes_.emplace_back();
    }
    refresh();
}

void MeasurePanel::undoLastPoint()
{
    if (!measurements_.back().empty()) {
        measurements_.back().pop_back();
        if (measurements_.back().empty())
            notes_.back().clear();
    } else if (measurements_.size() > 1) { // back into the previous measurement
        measurements_.pop_back();
        notes_.pop_back();
    }
    refresh();
}

void MeasurePanel::deleteAll()
{
    measurements_.assign(1, {});
    notes_.assign(1, QString());
    refresh();
}

void MeasurePanel::setMeasurements(std::vector<std::vector<Eigen::Vector3d>> measurements, std::vector<QString> notes)
{
    measurements_ = std::move(measurements);
    notes_ = std::move(notes);
    if (measurements_.empty() || !measurements_.back().empty())
        measurements_.emplace_back();
    notes_.resize(measurements_.size());
    refresh();
}

QString MeasurePanel::summary(const PointMeasurement& m, const std::vector<Eigen::Vector3d>& points, const QString& note)
{
    if (m.pointCount == 1) {
        const Eigen::Vector3d& p = points.front();
        const QString where = tr("X %1, Y %2, Z %3").arg(p.x(), 0, 'f', 3).arg(p.y(), 0, 'f', 3).arg(p.z(), 0, 'f', 3);
        return note.isEmpty() ? where : where + "; " + note;
    }
    if (m.pointCount < 2)
        return QString();
    if (m.pointCount == 2)
        return metres(m.pathLength);
    if (m.pointCount == 3)
        return degrees(*m.angleDegrees) + ", " + QString::number(*m.area, 'f', 3) + QString::fromUtf8(" m²");
    return QString::number(*m.area, 'f', 3) + QString::fromUtf8(" m²");
}

QString MeasurePanel::resultText() const
{
    const PointMeasurement m = measurePoints(measurements_.back());
    QStringList lines;
    lines << tr("%n point(s)", nullptr, static_cast<int>(m.pointCount));
    if (m.pointCount >= 2) {
        lines << (m.pointCount == 2 ? tr("Distance: %1") : tr("Path length: %1")).arg(metres(m.pathLength));
        lines << tr("ΔX %1, ΔY %2, ΔZ %3 (last - first)").arg(metres(m.delta.x()), metres(m.delta.y()), metres(m.delta.z()));
        lines << tr("Horizontal: %1, slope %2").arg(metres(m.horizontalDistance), degrees(m.slopeDegrees));
    }
    if (m.angleDegrees)
        lines << tr("Angle at point 2: %1").arg(degrees(*m.angleDegrees));
    if (m.area)
        lines << tr("Polygon: area %1, perimeter %2").arg(QString::number(*m.area, 'f', 3) + QString::fromUtf8(" m²"), metres(*m.perimeter));
    return lines.join('\n');
}

void MeasurePanel::refresh()
{
    result_->setText(resultText());
    kept_->clear();
    std::vector<CloudView::Annotation> annotations;
    for (std::size_t k = 0; k < measurements_.size(); ++k) {
        const auto& points = measurements_[k];
        if (points.empty())
            continue;
        const PointMeasurement m = measurePoints(points);
        const QString label = summary(m, points, notes_[k]);
        if (k + 1 < measurements_.size())
            kept_->addItem(tr("M%1: %2").arg(k + 1).arg(label));
        annotations.push_back({points, points.size() > 3, QString("M%1: %2").arg(k + 1).arg(label).toStdString()});
    }
    emit annotationsChanged(annotations);
}

} // namespace scandiff::gui
