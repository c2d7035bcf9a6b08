// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The tree of loaded entities: clouds and meshes with a visibility checkbox,
//! their scalar fields underneath (the active one in bold; clicking a field
//! makes it active) and derived entities (split parts, closest points) under
//! the entity they came from. It mirrors the Document; it owns nothing.

#include "document/Document.h"

#include <QTreeWidget>

#include <map>

namespace scandiff::gui {

class EntityTree : public QTreeWidget
{
    Q_OBJECT
public:
    EntityTree(Document& document, QWidget* parent = nullptr);

    //! The entity of the current row (a field row gives its entity).
    EntityId currentEntity() const;
    //! The selected entities, in tree order; with `fieldRowsCount` a selected
    //! field row stands for its entity (export), else only entity rows do (delete).
    std::vector<EntityId> selectedEntities(bool fieldRowsCount = true) const;
    void selectEntity(EntityId id);
    //! The row of an entity, null if unknown (tests click it).
    QTreeWidgetItem* entityRow(EntityId id) const;
    //! The row of a field of an entity, null if unknown.
    QTreeWidgetItem* fieldRow(EntityId id, const std::string& fieldName) const;

signals:
    void currentEntityChanged(EntityId id);

private:
    void addRow(EntityId id);
    void fillFields(EntityId id);
    void refreshRow(EntityId id);
    void onItemChanged(QTreeWidgetItem* row, int column);
    void onItemClicked(QTreeWidgetItem* row, int column);

    Document& document_;
    std::map<EntityId, QTreeWidgetItem*> rows_;
    bool updating_ = false;
};

} // namespace scandiff::gui
