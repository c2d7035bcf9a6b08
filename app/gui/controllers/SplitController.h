// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! "Split at thresholds": the points of a cloud inside and outside a range of
//! a field become two new clouds under it in the tree (core's splitByFieldRange).

#include "document/Document.h"

#include <scandiff/core/processing/CloudEditing.h>

#include <Eigen/Core>

#include <functional>
#include <vector>

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

    //! What a cut keeps as clouds of their own: both parts (the inside shown,
    //! the outside unticked), or only one of them, shown (CloudCompare's
    //! "segment in" / "segment out" then confirm). The cloud cut is hidden
    //! either way, never removed: nothing is lost, and Undo takes the cut back.
    enum class Keep { Both, Inside, Outside };

    //! The scissors: every visible cloud's points shown inside `polygon` (screen
    //! pixels; `globalToPixels` the projection it was drawn with, see core's
    //! pointsInScreenPolygon) become a cloud under it, the rest another,
    //! as `keep` says. Points hidden by thresholds are not inside (they stay in
    //! the rest). Returns how many clouds were cut.
    int cutWithPolygon(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Matrix4d& globalToPixels,
                       const std::function<bool(EntityId, std::size_t)>& shown, Keep keep = Keep::Both);

    //! The clipping box's "Extract inside": every visible cloud's points in
    //! `box` (global coordinates) become a cloud under it, the rest another,
    //! unticked; the cloud is hidden. Returns how many clouds were cut.
    int extractInBox(const CropBox& box);

signals:
    void finished(const QString& summary);
    void failed(const QString& message);
    //! The user stopped a run: no error, nothing changed.
    void cancelled(const QString& message);
    void resultReady(EntityId id);

private:
    //! What both cuts share: `select` picks each visible cloud's inside points.
    int cutVisibleClouds(const QString& what, const QString& insideName, const QString& outsideName,
                         const std::function<std::vector<std::size_t>(EntityId, const PointCloud&)>& select, Keep keep);

    Document& document_;
};

} // namespace scandiff::gui
