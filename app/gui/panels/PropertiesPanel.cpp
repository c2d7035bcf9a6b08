// SPDX-License-Identifier: GPL-3.0-or-later
#include "panels/PropertiesPanel.h"

#include <scandiff/io/CoordinateSystem.h>

#include <QHeaderView>

#include <cmath>
#include <limits>
#include <map>

namespace scandiff::gui {

namespace {

QString number(double v, int decimals = 3)
{
    return std::isnan(v) ? QStringLiteral("NaN") : QString::number(v, 'f', decimals);
}

QString triple(const Eigen::Vector3d& v, int decimals = 3)
{
    return QString("%1, %2, %3").arg(number(v.x(), decimals), number(v.y(), decimals), number(v.z(), decimals));
}

//! Significant digits for field values, whatever their magnitude.
QString fieldValue(double v) { return std::isnan(v) ? QStringLiteral("NaN (no value)") : QString::number(v, 'g', 8); }

} // namespace

QString describePoint(const Document::Item& item, std::size_t index)
{
    const PointCloud& points = item.points();
    QString text = QString("%1 #%2: %3").arg(item.name).arg(index).arg(triple(points.globalPosition(index)));
    for (const ScalarField& f : points.fields())
        text += QString("; %1 = %2").arg(QString::fromStdString(f.name()), fieldValue(f.value(index)));
    return text;
}

PropertiesPanel::PropertiesPanel(const Document& document, QWidget* parent) : QTreeWidget(parent), document_(document)
{
    setColumnCount(2);
    setHeaderLabels({tr("Property"), tr("Value")});
    // No value is cut: a global shift, a box corner or a path is read whole
    // (the panel scrolls sideways when it is narrower than a value).
    header()->setSectionResizeMode(0, QHeaderView::ResizeToContents);
    header()->setSectionResizeMode(1, QHeaderView::ResizeToContents);
    header()->setStretchLastSection(false);
    setTextElideMode(Qt::ElideNone);
    setHorizontalScrollMode(QAbstractItemView::ScrollPerPixel);
    setRootIsDecorated(true);
    rebuildSoon_->setSingleShot(true);
    rebuildSoon_->setInterval(2); // after the scalar field panel's
    connect(rebuildSoon_, &QTimer::timeout, this, &PropertiesPanel::rebuild);
    connect(&document_, &Document::fieldsChanged, this, [this](EntityId id) {
        if (id == entity_)
            rebuildSoon_->start();
    });
    connect(&document_, &Document::renamed, this, [this](EntityId id) {
        if (id == entity_ || id == pickedEntity_)
            rebuild();
    });
    connect(&document_, &Document::removed, this, [this](EntityId id) {
        if (id == pickedEntity_)
            pickedEntity_ = kNoEntity;
        if (id == entity_)
            entity_ = kNoEntity;
        rebuild();
    });
    connect(&document_, &Document::cleared, this, [this] {
        entity_ = pickedEntity_ = kNoEntity;
        rebuild();
    });
}

void PropertiesPanel::showEntity(EntityId id)
{
    entity_ = id;
    rebuild();
}

void PropertiesPanel::showPickedPoint(EntityId id, std::size_t index)
{
    pickedEntity_ = id;
    pickedIndex_ = index;
    rebuild();
}

void PropertiesPanel::rebuild()
{
    rebuildSoon_->stop();
    clear();
    const auto add = [this](QTreeWidgetItem* parent, const QString& key, const QString& value) {
        auto* row = parent ? new QTreeWidgetItem(parent) : new QTreeWidgetItem(this);
        row->setText(0, key);
        row->setText(1, value);
        row->setToolTip(1, value); // whole, when the column is narrower than a path or coordinates
        return row;
    };
    if (const Document::Item* item = document_.find(entity_); item && item->isDrawing()) {
        add(nullptr, tr("Name"), item->name);
        add(nullptr, tr("Type"), tr("Drawing"));
        if (!item->sourcePath.isEmpty())
            add(nullptr, tr("File"), item->sourcePath);
        const Drawing& drawing = *item->drawing;
        std::size_t closed = 0, vertices = 0;
        std::map<std::string, std::size_t> layers;
        Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), high = -low;
        for (const DrawingPolyline& p : drawing.polylines) {
            closed += p.closed;
            vertices += p.points.size();
            ++layers[p.layer];
            for (const Eigen::Vector3d& v : p.points) {
                low = low.cwiseMin(v);
                high = high.cwiseMax(v);
            }
        }
        add(nullptr, tr("Polylines"), tr("%1 (%2 closed), %3 vertices").arg(drawing.polylines.size()).arg(closed).arg(vertices));
        add(nullptr, tr("Labels"), QString::number(drawing.texts.size()));
        if (vertices > 0) {
            add(nullptr, tr("Bounds min"), triple(low));
            add(nullptr, tr("Bounds max"), triple(high));
        }
        QTreeWidgetItem* layerRows = add(nullptr, tr("Layers"), QString::number(layers.size()));
        for (const auto& [name, count] : layers)
            add(layerRows, QString::fromStdString(name), tr("%1 polylines").arg(count));
        layerRows->setExpanded(layers.size() <= 20);
    } else if (item && item->isGroup()) {
        // The parts of one file (the scans of an E57): what they hold together.
        add(nullptr, tr("Name"), item->name);
        add(nullptr, tr("Type"), tr("Group"));
        if (!item->sourcePath.isEmpty())
            add(nullptr, tr("File"), item->sourcePath);
        std::size_t total = 0;
        QTreeWidgetItem* parts = add(nullptr, tr("Scans"), QString());
        for (EntityId child : document_.children(item->id)) {
            const Document::Item& part = document_.item(child);
            total += part.points().size();
            add(parts, part.name, tr("%1 points, %2").arg(part.points().size())
                                      .arg(part.points().sensors().empty() ? tr("no sensor pose")
                                                                           : tr("scanner at %1").arg(triple(part.points().sensors().front().position))));
        }
        parts->setText(1, QString::number(parts->childCount()));
        parts->setExpanded(parts->childCount() <= 20);
        add(nullptr, tr("Points"), QString::number(total));
    } else if (item) {
        const PointCloud& points = item->points();
        add(nullptr, tr("Name"), item->name);
        add(nullptr, tr("Type"), item->mesh() ? tr("Mesh") : tr("Point cloud"));
        if (!item->sourcePath.isEmpty())
            add(nullptr, tr("File"), item->sourcePath);
        if (!item->properties.empty()) {
            // What the tool that made it said of it: a shape's parameters.
            QTreeWidgetItem* described = add(nullptr, item->properties.front().first, item->properties.front().second);
            for (std::size_t k = 1; k < item->properties.size(); ++k)
                add(described, item->properties[k].first, item->properties[k].second);
            described->setExpanded(true);
        }
        add(nullptr, item->mesh() ? tr("Vertices") : tr("Points"), QString::number(points.size()));
        if (const Mesh* mesh = item->mesh())
            add(nullptr, tr("Triangles"), QString::number(mesh->triangles.size()));
        add(nullptr, tr("Global shift"), triple(points.origin()));
        add(nullptr, tr("Coordinate system"),
            points.crsWkt().empty() ? tr("none") : QString::fromStdString(io::crsName(points.crsWkt())));
        const BoundingBox box = points.bounds();
        if (!box.empty) {
            add(nullptr, tr("Bounds min"), triple(box.min));
            add(nullptr, tr("Bounds max"), triple(box.max));
            add(nullptr, tr("Extent"), triple(box.max - box.min));
        }
        add(nullptr, tr("Colours"), points.hasColors() ? tr("yes") : tr("no"));
        add(nullptr, tr("Normals"), points.hasNormals() ? tr("yes") : tr("no"));
        add(nullptr, tr("Sensor poses"), QString::number(points.sensors().size()));
        QTreeWidgetItem* fields = add(nullptr, tr("Scalar fields"), QString::number(points.fields().size()));
        for (const ScalarField& f : points.fields()) {
            const ValueRange r = f.range();
            const QString range = r.validCount ? QString("[%1, %2], %3 values").arg(fieldValue(r.min), fieldValue(r.max)).arg(r.validCount)
                                               : tr("no value");
            add(fields, QString::fromStdString(f.name()), range);
        }
        fields->setExpanded(true);
        // The transformations applied, oldest first, each with its matrix
        // (the rows as the text files and the console give them).
        const auto& history = points.transformHistory();
        if (!history.empty()) {
            QTreeWidgetItem* steps = add(nullptr, tr("Transformations"), QString::number(history.size()));
            for (std::size_t k = 0; k < history.size(); ++k) {
                QTreeWidgetItem* step = add(steps, QString("%1").arg(k + 1), QString::fromStdString(history[k].description));
                const Eigen::Matrix4d& m = history[k].matrix;
                for (int r = 0; r < 4; ++r)
                    add(step, tr("row %1").arg(r + 1),
                        QString("%1 %2 %3 %4").arg(m(r, 0), 0, 'g', 12).arg(m(r, 1), 0, 'g', 12).arg(m(r, 2), 0, 'g', 12).arg(m(r, 3), 0, 'g', 12));
            }
            steps->setExpanded(true);
        }
    }
    if (const Document::Item* picked = document_.find(pickedEntity_); picked && pickedIndex_ < picked->points().size()) {
        const PointCloud& points = picked->points();
        QTreeWidgetItem* point = add(nullptr, tr("Picked point"), QString("%1 #%2").arg(picked->name).arg(pickedIndex_));
        add(point, tr("X, Y, Z"), triple(points.globalPosition(pickedIndex_)));
        if (points.hasColors()) {
            const Rgb8 c = points.colors()[pickedIndex_];
            add(point, tr("RGB"), QString("%1, %2, %3").arg(c.r).arg(c.g).arg(c.b));
        }
        for (const ScalarField& f : points.fields())
            add(point, QString::fromStdString(f.name()), fieldValue(f.value(pickedIndex_)));
        point->setExpanded(true);
    }
}

QString PropertiesPanel::value(const QString& property) const
{
    const QList<QTreeWidgetItem*> rows = findItems(property, Qt::MatchExactly | Qt::MatchRecursive, 0);
    return rows.isEmpty() ? QString() : rows.first()->text(1);
}

} // namespace scandiff::gui
