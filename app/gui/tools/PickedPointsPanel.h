// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The part of a tool's dialog that fills a parameter by picking points in
//! the view (ParameterSpec::pickedOn): in turn on the entity chosen for each
//! role (moving, then reference: a pair), listed as they come, the last one
//! undoable, with the tool's preview (each pair's residual) refreshed after
//! every pick. The parameter's text follows the list; nothing is computed here.

#include "document/Document.h"

#include <scandiff/core/Table.h>
#include <scandiff/core/ToolRegistry.h>

#include <Eigen/Core>

#include <QGroupBox>

#include <functional>
#include <string>
#include <vector>

class QLabel;
class QPushButton;
class QTableWidget;

namespace scandiff::gui {

class PickedPointsPanel : public QGroupBox
{
    Q_OBJECT
public:
    //! Each role of `parameter.pickedOn` is named by its input's label.
    PickedPointsPanel(const ParameterSpec& parameter, const std::vector<InputSpec>& inputs, QWidget* parent = nullptr);

    //! The entity the next pick must lie on, given the entity chosen for each role.
    const std::string& expectedRole() const;
    //! A point picked on `entity` (global coordinates): kept when `entity` is
    //! the one chosen for the expected role (`entityOfRole`), else refused
    //! with a message saying which one to pick on. Returns whether it was kept.
    bool addPoint(EntityId entity, const Eigen::Vector3d& global, const std::function<EntityId(const std::string&)>& entityOfRole);
    void undoLast();
    void clear();
    std::size_t pointCount() const { return points_.size(); }
    //! The parameter's value: each complete group's numbers, groups joined by ';'.
    QString text() const;
    //! Shows what the tool's preview gave, or why it could not give one.
    void showPreview(const Table& table);
    void showPreviewError(const QString& reason);

    QPushButton* pickButton() const { return pick_; }
    QTableWidget* pointsView() const { return pointsView_; }
    QTableWidget* previewView() const { return previewView_; }

signals:
    //! The list changed: the dialog sets the parameter and refreshes the preview.
    void changed();
    //! The view's pick mode should follow the Pick button.
    void pickModeRequested(bool on);

private:
    void refresh();

    std::vector<std::string> roles_;
    std::vector<QString> roleLabels_;
    std::vector<Eigen::Vector3d> points_; //!< in picking order: role 0, role 1, role 0...
    QLabel* status_;
    QPushButton* pick_;
    QTableWidget* pointsView_;
    QTableWidget* previewView_;
    QLabel* previewStatus_;
};

} // namespace scandiff::gui
