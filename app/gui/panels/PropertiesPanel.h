// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Properties of the current entity (counts, bounds, global shift, fields with
//! their ranges) and of the last picked point (coordinates and every field value).

#include "document/Document.h"

#include <QTimer>
#include <QTreeWidget>

namespace scandiff::gui {

class PropertiesPanel : public QTreeWidget
{
    Q_OBJECT
public:
    PropertiesPanel(const Document& document, QWidget* parent = nullptr);

    void showEntity(EntityId id);
    void showPickedPoint(EntityId id, std::size_t index);
    EntityId entity() const { return entity_; }
    //! The value shown for a property, e.g. value("Points"); empty if absent (tests).
    QString value(const QString& property) const;

private:
    void rebuild();
    //! rebuild() once the event loop turns (started by the document's
    //! signals): a tool's results change a cloud's fields several times in
    //! one go, and each rebuild reads every point (its bounds, its fields'
    //! ranges): one rebuild, in a turn of its own.
    QTimer* rebuildSoon_ = new QTimer(this);
    const Document& document_;
    EntityId entity_ = kNoEntity;
    EntityId pickedEntity_ = kNoEntity;
    std::size_t pickedIndex_ = 0;
};

//! One line describing a picked point: "name #index: X Y Z; field=value ...".
QString describePoint(const Document::Item& item, std::size_t index);

} // namespace scandiff::gui
