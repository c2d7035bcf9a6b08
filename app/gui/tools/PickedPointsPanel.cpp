// SPDX-License-Identifier: GPL-3.0-or-later
#include "tools/PickedPointsPanel.h"

#include "tools/TableDialog.h"

#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QPushButton>
#include <QTableWidget>
#include <QVBoxLayout>

namespace scandiff::gui {

PickedPointsPanel::PickedPointsPanel(const ParameterSpec& parameter, const std::vector<InputSpec>& inputs, QWidget* parent)
    : QGroupBox(QString::fromStdString(parameter.label) + tr(" (pick in the view)"), parent), roles_(parameter.pickedOn)
{
    setObjectName(QString::fromStdString("picked-" + parameter.name));
    for (const std::string& role : roles_) {
        QString label = QString::fromStdString(role);
        for (const InputSpec& input : inputs)
            if (input.role == role)
                label = QString::fromStdString(input.label);
        roleLabels_.push_back(label);
    }
    auto* layout = new QVBoxLayout(this);
    status_ = new QLabel(this);
    status_->setWordWrap(true);
    layout->addWidget(status_);
    auto* buttons = new QHBoxLayout;
    pick_ = new QPushButton(tr("Pick points"), this);
    pick_->setCheckable(true);
    pick_->setToolTip(tr("Click points in the view, in turn on each entity"));
    auto* undo = new QPushButton(tr("Undo last point"), this);
    auto* clearAll = new QPushButton(tr("Clear"), this);
    buttons->addWidget(pick_);
    buttons->addWidget(undo);
    buttons->addWidget(clearAll);
    buttons->addStretch();
    layout->addLayout(buttons);
    pointsView_ = new QTableWidget(this);
    pointsView_->setMinimumHeight(90);
    pointsView_->setMaximumHeight(170);
    layout->addWidget(pointsView_);
    previewStatus_ = new QLabel(this);
    previewStatus_->setWordWrap(true);
    layout->addWidget(previewStatus_);
    previewView_ = new QTableWidget(this);
    previewView_->setMinimumHeight(80);
    previewView_->setMaximumHeight(150);
    layout->addWidget(previewView_);
    connect(pick_, &QPushButton::toggled, this, &PickedPointsPanel::pickModeRequested);
    connect(undo, &QPushButton::clicked, this, &PickedPointsPanel::undoLast);
    connect(clearAll, &QPushButton::clicked, this, &PickedPointsPanel::clear);
    refresh();
}

const std::string& PickedPointsPanel::expectedRole() const
{
    return roles_.at(points_.size() % roles_.size());
}

bool PickedPointsPanel::addPoint(EntityId entity, const Eigen::Vector3d& global,
                                 const std::function<EntityId(const std::string&)>& entityOfRole)
{
    if (entityOfRole(expectedRole()) != entity) {
        status_->setText(tr("That point is not on the %1 entity: pick on it (untick the other in the Entities tree to "
                            "pick through it, or change the choice above).")
                             .arg(roleLabels_.at(points_.size() % roles_.size()).toLower()));
        return false;
    }
    points_.push_back(global);
    refresh();
    emit changed();
    return true;
}

void PickedPointsPanel::undoLast()
{
    if (points_.empty())
        return;
    points_.pop_back();
    refresh();
    emit changed();
}

void PickedPointsPanel::clear()
{
    points_.clear();
    refresh();
    emit changed();
}

QString PickedPointsPanel::text() const
{
    QStringList groups;
    const std::size_t size = roles_.size();
    for (std::size_t g = 0; g + size <= points_.size(); g += size) {
        QStringList numbers;
        for (std::size_t k = 0; k < size; ++k)
            for (int a = 0; a < 3; ++a)
                numbers << QString::number(points_[g + k][a], 'g', 17);
        groups << numbers.join(',');
    }
    return groups.join(';');
}

void PickedPointsPanel::showPreview(const Table& table)
{
    previewStatus_->clear();
    fillTableWidget(*previewView_, table);
}

void PickedPointsPanel::showPreviewError(const QString& reason)
{
    previewStatus_->setText(reason);
    previewView_->clear();
    previewView_->setRowCount(0);
    previewView_->setColumnCount(0);
}

void PickedPointsPanel::refresh()
{
    // One row per group; a half-picked group shows what it has.
    const std::size_t size = roles_.size();
    const int rows = static_cast<int>((points_.size() + size - 1) / size);
    pointsView_->clear();
    pointsView_->setRowCount(rows);
    pointsView_->setColumnCount(static_cast<int>(3 * size));
    QStringList headers;
    for (const QString& label : roleLabels_)
        headers << label + " X" << label + " Y" << label + " Z";
    pointsView_->setHorizontalHeaderLabels(headers);
    for (std::size_t i = 0; i < points_.size(); ++i)
        for (int a = 0; a < 3; ++a) {
            auto* item = new QTableWidgetItem(QString::number(points_[i][a], 'f', 3));
            item->setFlags(item->flags() & ~Qt::ItemIsEditable);
            pointsView_->setItem(static_cast<int>(i / size), static_cast<int>(3 * (i % size)) + a, item);
        }
    pointsView_->horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
    status_->setText(tr("Next: a point on the %1 entity (group %2).")
                         .arg(roleLabels_.at(points_.size() % size).toLower())
                         .arg(points_.size() / size + 1));
}

} // namespace scandiff::gui
