// SPDX-License-Identifier: GPL-3.0-or-later
#include "controllers/SplitController.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/FieldRange.h>

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

} // namespace scandiff::gui
