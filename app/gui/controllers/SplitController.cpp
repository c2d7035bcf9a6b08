// SPDX-License-Identifier: GPL-3.0-or-later
#include "controllers/SplitController.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/FieldRange.h>
#include <scandiff/core/processing/CloudEditing.h>

#include <algorithm>

namespace scandiff::gui {

SplitController::SplitController(Document& document, QObject* parent) : QObject(parent), document_(document) {}

std::pair<EntityId, EntityId> SplitController::split(EntityId id, const std::string& field, double low, double high)
{
    const Document::Item* item = document_.find(id);
    if (!item || !item->cloud()) {
        emit failed(tr("Split needs a point cloud"));
        return {kNoEntity, kNoEntity};
    }
    try {
        FieldRangeSplit parts = splitByFieldRange(*item->cloud(), field, low, high);
        if (parts.inside.empty()) {
            emit failed(tr("split %1: no point has %2 in [%3, %4]; nothing was split")
                            .arg(item->name, QString::fromStdString(field))
                            .arg(low, 0, 'g', 6)
                            .arg(high, 0, 'g', 6));
            return {kNoEntity, kNoEntity};
        }
        const QString name = item->name;
        const Document::UndoGroup group(document_, tr("split %1").arg(name)); // the parts go, the parent comes back
        const QString range = QString("[%1, %2]").arg(low, 0, 'g', 6).arg(high, 0, 'g', 6);
        const std::size_t insideCount = parts.inside.size(), outsideCount = parts.outside.size();
        // The parts keep the field's display (scale, thresholds) so they look as they did.
        const FieldDisplay display = document_.fieldDisplay(id, field);
        const DisplayState parentDisplay = item->display;
        EntityId inside = kNoEntity, outside = kNoEntity;
        if (insideCount) {
            inside = document_.add(name + " " + range, std::move(parts.inside), id);
            document_.setActiveField(inside, field);
            document_.setOutsideMode(inside, parentDisplay.outside);
            document_.setFieldDisplay(inside, field, display);
        }
        if (outsideCount) {
            outside = document_.add(name + tr(" outside ") + range, std::move(parts.outside), id);
            document_.setActiveField(outside, field);
            FieldDisplay full = display;
            full.low = -std::numeric_limits<double>::infinity();
            full.high = std::numeric_limits<double>::infinity();
            document_.setFieldDisplay(outside, field, full);
            // What the user was looking for is inside: the rest waits, unticked, in the tree.
            document_.setVisible(outside, false);
        }
        // The parts replace their parent on screen.
        document_.setVisible(id, false);
        emit finished(tr("split %1 on %2 %3: %4 points inside, %5 outside")
                          .arg(name, QString::fromStdString(field), range)
                          .arg(insideCount)
                          .arg(outsideCount));
        emit resultReady(inside != kNoEntity ? inside : outside);
        return {inside, outside};
    } catch (const Error& e) {
        emit failed(QString::fromStdString(e.what()));
        return {kNoEntity, kNoEntity};
    }
}

int SplitController::cutWithPolygon(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Matrix4d& globalToPixels,
                                    const std::function<bool(EntityId, std::size_t)>& shown, Keep keep)
{
    return cutVisibleClouds(
        tr("segment by polygon"), tr("inside polygon"), tr("outside polygon"),
        [&](EntityId id, const PointCloud& cloud) {
            std::vector<std::size_t> inside = pointsInScreenPolygon(cloud, globalToPixels, polygon);
            inside.erase(std::remove_if(inside.begin(), inside.end(), [&](std::size_t i) { return !shown(id, i); }), inside.end());
            return inside;
        },
        keep);
}

int SplitController::extractInBox(const CropBox& box)
{
    return cutVisibleClouds(tr("extract in the clipping box"), tr("in box"), tr("outside box"),
                            [&](EntityId, const PointCloud& cloud) { return pointsInBox(cloud, box); }, Keep::Both);
}

int SplitController::cutVisibleClouds(const QString& what, const QString& insideName, const QString& outsideName,
                                      const std::function<std::vector<std::size_t>(EntityId, const PointCloud&)>& select, Keep keep)
{
    int cut = 0;
    EntityId lastInside = kNoEntity;
    const Document::UndoGroup group(document_, what); // one undo for every cloud it cut
    for (EntityId id : document_.ids()) {
        const Document::Item* item = document_.find(id);
        if (!item || !item->cloud() || !item->display.visible)
            continue;
        std::vector<std::size_t> inside;
        try {
            inside = select(id, *item->cloud());
        } catch (const Error& e) {
            emit failed(QString::fromStdString(e.what()));
            return cut;
        }
        const std::vector<std::size_t> outside = complementOf(inside, item->cloud()->size());
        // Nothing to cut off: the part kept would be the whole cloud, or nothing.
        if (inside.empty() || (keep != Keep::Both && outside.empty()))
            continue;
        const QString name = item->name;
        const DisplayState display = item->display;
        PointCloud insidePart = keep != Keep::Outside ? item->cloud()->subset(inside) : PointCloud();
        PointCloud outsidePart = keep != Keep::Inside ? item->cloud()->subset(outside) : PointCloud();
        // The parts look as their cloud did: active field, scales, thresholds.
        auto dress = [this, &display](EntityId part) {
            for (const auto& [field, fieldDisplay] : display.fields)
                document_.setFieldDisplay(part, field, fieldDisplay);
            document_.setActiveField(part, display.activeField);
            document_.setOutsideMode(part, display.outside);
            document_.setNeutral(part, display.neutral);
        };
        if (keep != Keep::Outside) {
            lastInside = document_.add(QString("%1 (%2)").arg(name, insideName), std::move(insidePart), id);
            dress(lastInside);
        }
        if (keep != Keep::Inside && !outside.empty()) {
            const EntityId rest = document_.add(QString("%1 (%2)").arg(name, outsideName), std::move(outsidePart), id);
            dress(rest);
            if (keep == Keep::Both)
                document_.setVisible(rest, false);
            else
                lastInside = rest; // the part kept is what the tree selects
        }
        document_.setVisible(id, false);
        emit finished(tr("%1 %2: %3 points inside, %4 outside").arg(what, name).arg(inside.size()).arg(outside.size()));
        ++cut;
    }
    if (cut == 0)
        emit failed(tr("%1: no shown cloud has a point inside").arg(what));
    else
        emit resultReady(lastInside);
    return cut;
}

} // namespace scandiff::gui
