// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Move / rotate interactively (CloudCompare's Translate/Rotate): while the
//! dialog is open the view's box moves and turns the selected entities with the
//! mouse, and the typed values (offset in metres, heading, pitch and roll in
//! degrees about the selection's centre) move them as well; both stay in step.
//! Apply hands the motion on (the main window runs the transform tool with
//! it: exact, undoable, logged); Cancel or closing puts everything back.

#include "document/Document.h"

#include <scandiff/core/processing/CloudEditing.h>

#include <QDialog>

#include <Eigen/Core>

#include <array>
#include <optional>
#include <vector>

class QDoubleSpinBox;
class QLabel;

namespace scandiff::gui {

class CloudView;

class MoveDialog : public QDialog
{
    Q_OBJECT
public:
    //! Starts moving `ids` in the view; check view.movingEntities() (none of
    //! them shown: nothing to move). Closing the dialog, however, stops it.
    MoveDialog(CloudView& view, const std::vector<EntityId>& ids, QWidget* parent = nullptr);

    RigidMotion motion() const;
    //! As if typed: the boxes, the view's box and drawing follow.
    void setMotion(const RigidMotion& motion);
    //! The motion as a matrix on global coordinates: the last drag's exactly,
    //! else the typed values' about the selection's centre.
    Eigen::Matrix4d matrix() const;

signals:
    void applyRequested(const Eigen::Matrix4d& global);

private:
    void typed();
    void dragged(const Eigen::Matrix4d& global);
    void done(int result) override;

    CloudView& view_;
    //! Offset X, Y, Z, then heading, pitch, roll.
    std::array<QDoubleSpinBox*, 6> boxes_{};
    bool updating_ = false;
    //! The box's motion after a drag, until something is typed.
    std::optional<Eigen::Matrix4d> dragged_;
};

} // namespace scandiff::gui
