// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! "Split at thresholds": the points of a cloud inside and outside a range of
//! a field become two new clouds under it in the tree (core's splitByFieldRange).

#include "document/Document.h"

#include <QObject>

namespace scandiff::gui {

class SplitController : public QObject
{
    Q_OBJECT
public:
    explicit SplitController(Document& document, QObject* parent = nullptr);

    //! Adds "<name> [low, high]" and "<name> outside" (an empty outside part is
    //! not added); returns their ids (kNoEntity for a part not added). With no
    //! point inside, nothing changes and failed() explains why.
    std::pair<EntityId, EntityId> split(EntityId id, const std::string& field, double low, double high);

signals:
    void finished(const QString& summary);
    void failed(const QString& message);
    void resultReady(EntityId id);

private:
    Document& document_;
};

} // namespace scandiff::gui
