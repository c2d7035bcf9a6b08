// SPDX-License-Identifier: GPL-3.0-or-later
#include "panels/EntityTree.h"

#include <QHeaderView>

namespace scandiff::gui {

namespace {

constexpr int kEntityRole = Qt::UserRole;
constexpr int kFieldRole = Qt::UserRole + 1; //!< field name on field rows, empty on entity rows

QString describe(const Document::Item& item)
{
    if (item.isDrawing())
        return QObject::tr("drawing, %1 polylines").arg(item.drawing->polylines.size());
    if (item.isGroup())
        return QObject::tr("group");
    if (const Mesh* mesh = item.mesh())
        return QObject::tr("mesh, %1 triangles").arg(mesh->triangles.size());
    return QObject::tr("%1 points").arg(item.points().size());
}

} // namespace

EntityTree::EntityTree(Document& document, QWidget* parent) : QTreeWidget(parent), document_(document)
{
    setColumnCount(2);
    setHeaderLabels({tr("Entity"), tr("Size")});
    header()->setSectionResizeMode(0, QHeaderView::Stretch);
    header()->setSectionResizeMode(1, QHeaderView::ResizeToContents);
    header()->setStretchLastSection(false);
    setSelectionMode(QAbstractItemView::ExtendedSelection);
    connect(&document_, &Document::added, this, &EntityTree::addRow);
    connect(&document_, &Document::removed, this, [this](EntityId id) {
        const auto it = rows_.find(id);
        if (it == rows_.end())
            return;
        delete it->second; // also deletes the rows underneath; their ids were removed first
        rows_.erase(it);
    });
    connect(&document_, &Document::cleared, this, [this] {
        rows_.clear();
        clear();
    });
    connect(&document_, &Document::fieldsChanged, this, &EntityTree::fillFields);
    connect(&document_, &Document::displayChanged, this, &EntityTree::refreshRow);
    connect(&document_, &Document::renamed, this, &EntityTree::refreshRow);
    connect(this, &QTreeWidget::itemChanged, this, &EntityTree::onItemChanged);
    connect(this, &QTreeWidget::itemClicked, this, &EntityTree::onItemClicked);
    connect(this, &QTreeWidget::currentItemChanged, this, [this] { emit currentEntityChanged(currentEntity()); });
}

void EntityTree::addRow(EntityId id)
{
    const Document::Item& item = document_.item(id);
    const auto parentRow = rows_.find(item.parent);
    // Filled before it enters the tree: itemChanged must not see a half-made row.
    auto* row = new QTreeWidgetItem;
    row->setData(0, kEntityRole, id);
    row->setData(0, kFieldRole, QString());
    row->setIcon(0, style()->standardIcon(item.isGroup()     ? QStyle::SP_DirIcon
                                          : item.isDrawing() ? QStyle::SP_FileDialogContentsView
                                          : item.mesh()    ? QStyle::SP_FileDialogDetailedView
                                                           : QStyle::SP_FileIcon));
    row->setFlags(row->flags() | Qt::ItemIsUserCheckable);
    row->setCheckState(0, item.display.visible ? Qt::Checked : Qt::Unchecked);
    updating_ = true;
    if (parentRow != rows_.end())
        parentRow->second->addChild(row);
    else
        addTopLevelItem(row);
    updating_ = false;
    rows_[id] = row;
    fillFields(id);
    if (parentRow != rows_.end())
        parentRow->second->setExpanded(true);
    setCurrentItem(row);
}

void EntityTree::fillFields(EntityId id)
{
    const auto it = rows_.find(id);
    if (it == rows_.end())
        return;
    QTreeWidgetItem* row = it->second;
    updating_ = true;
    for (int i = row->childCount() - 1; i >= 0; --i)
        if (!row->child(i)->data(0, kFieldRole).toString().isEmpty())
            delete row->takeChild(i);
    const PointCloud& points = document_.item(id).points();
    int at = 0;
    for (const ScalarField& field : points.fields()) {
        auto* fieldRow = new QTreeWidgetItem;
        row->insertChild(at++, fieldRow);
        fieldRow->setText(0, QString::fromStdString(field.name()));
        fieldRow->setData(0, kEntityRole, id);
        fieldRow->setData(0, kFieldRole, QString::fromStdString(field.name()));
        fieldRow->setToolTip(0, tr("Click to colour by this field"));
    }
    updating_ = false;
    refreshRow(id);
    row->setExpanded(true);
}

void EntityTree::refreshRow(EntityId id)
{
    const auto it = rows_.find(id);
    if (it == rows_.end())
        return;
    const Document::Item& item = document_.item(id);
    QTreeWidgetItem* row = it->second;
    updating_ = true;
    row->setText(0, item.name);
    row->setText(1, describe(item));
    row->setFlags(row->flags() | Qt::ItemIsUserCheckable);
    row->setCheckState(0, item.display.visible ? Qt::Checked : Qt::Unchecked);
    for (int i = 0; i < row->childCount(); ++i) {
        QTreeWidgetItem* child = row->child(i);
        const QString field = child->data(0, kFieldRole).toString();
        if (field.isEmpty())
            continue;
        QFont font = child->font(0);
        font.setBold(field.toStdString() == item.display.activeField);
        child->setFont(0, font);
    }
    updating_ = false;
}

void EntityTree::onItemChanged(QTreeWidgetItem* row, int column)
{
    if (updating_ || column != 0 || !row->data(0, kFieldRole).toString().isEmpty())
        return;
    document_.setVisible(row->data(0, kEntityRole).toInt(), row->checkState(0) == Qt::Checked);
}

void EntityTree::onItemClicked(QTreeWidgetItem* row, int)
{
    const QString field = row->data(0, kFieldRole).toString();
    if (!field.isEmpty())
        document_.setActiveField(row->data(0, kEntityRole).toInt(), field.toStdString());
}

EntityId EntityTree::currentEntity() const
{
    const QTreeWidgetItem* row = currentItem();
    return row ? row->data(0, kEntityRole).toInt() : kNoEntity;
}

std::vector<EntityId> EntityTree::selectedEntities(bool fieldRowsCount) const
{
    std::vector<EntityId> ids;
    for (const auto& [id, row] : rows_) {
        bool selected = row->isSelected();
        for (int i = 0; fieldRowsCount && i < row->childCount() && !selected; ++i)
            selected = row->child(i)->isSelected() && !row->child(i)->data(0, kFieldRole).toString().isEmpty();
        if (selected)
            ids.push_back(id);
    }
    return ids;
}

void EntityTree::selectEntity(EntityId id)
{
    if (QTreeWidgetItem* row = entityRow(id)) {
        clearSelection();
        setCurrentItem(row);
        row->setSelected(true);
    }
}

QTreeWidgetItem* EntityTree::entityRow(EntityId id) const
{
    const auto it = rows_.find(id);
    return it == rows_.end() ? nullptr : it->second;
}

QTreeWidgetItem* EntityTree::fieldRow(EntityId id, const std::string& fieldName) const
{
    QTreeWidgetItem* row = entityRow(id);
    for (int i = 0; row && i < row->childCount(); ++i)
        if (row->child(i)->data(0, kFieldRole).toString().toStdString() == fieldName)
            return row->child(i);
    return nullptr;
}

} // namespace scandiff::gui
