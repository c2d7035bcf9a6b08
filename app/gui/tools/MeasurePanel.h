// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Measuring in the view, as a CloudCompare user expects of its point-picking
//! tool: with *Measure* on, each click on a cloud adds a point to the current
//! measurement; two points give the distance with ΔX, ΔY, ΔZ, the horizontal
//! distance and the slope, three the angle at the middle one, three or more the
//! area and perimeter of the polygon; a measurement of one point is a point
//! label (its coordinates, and the value of the field shown where it was
//! picked). Each measurement is drawn in the view
//! with its label and kept (in the list and in the session) until deleted. The
//! numbers come from core's measurePoints().

#include "document/Document.h"
#include "view/CloudView.h"

#include <scandiff/core/geometry/Measurement.h>

#include <QWidget>

#include <vector>

class QLabel;
class QListWidget;
class QPushButton;

namespace scandiff::gui {

class MeasurePanel : public QWidget
{
    Q_OBJECT
public:
    MeasurePanel(const Document& document, QWidget* parent = nullptr);

    //! Measure mode: clicks in the view add points.
    void setMeasuring(bool on);
    bool measuring() const { return measuring_; }
    //! A point picked in the view (ignored unless measuring).
    void addPick(EntityId id, std::size_t index);
    //! Adds a point in global coordinates to the current measurement.
    void addPoint(const Eigen::Vector3d& global);
    //! Keeps the current measurement and starts another.
    void startNew();
    void undoLastPoint();
    void deleteAll();

    //! Every measurement, the current one last (possibly empty); for sessions and tests.
    const std::vector<std::vector<Eigen::Vector3d>>& measurements() const { return measurements_; }
    //! Beside each measurement, what its first point was picked on ("site-2024:
    //! c2c_distance = 0.0123"), empty when it was not picked on a field.
    const std::vector<QString>& notes() const { return notes_; }
    //! `notes` aligned with `measurements` (missing ones empty).
    void setMeasurements(std::vector<std::vector<Eigen::Vector3d>> measurements, std::vector<QString> notes = {});
    //! The result text of the current measurement, one line per quantity.
    QString resultText() const;

    //! The label a measurement gets in the view and the list; a point's is
    //! its coordinates (millimetres), then `note`.
    static QString summary(const PointMeasurement& m, const std::vector<Eigen::Vector3d>& points, const QString& note = {});

signals:
    void measuringChanged(bool on);
    void annotationsChanged(const std::vector<CloudView::Annotation>& annotations);

private:
    void refresh();

    const Document& document_;
    bool measuring_ = false;
    std::vector<std::vector<Eigen::Vector3d>> measurements_{{}};
    std::vector<QString> notes_{QString()}; //!< one per measurement
    QPushButton* measure_;
    QLabel* result_;
    QListWidget* kept_;
};

} // namespace scandiff::gui
