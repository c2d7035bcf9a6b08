// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The global-shift question CloudCompare asks when a file's coordinates are
//! large. scandiff keeps every coordinate in double (an origin plus float
//! offsets) and draws each cloud in double, so no shift is needed for
//! precision; the shift chosen here is the origin the cloud's floats are
//! relative to (what Properties shows as its global shift), which lets the
//! epochs of a survey share one local frame exactly. Suggested: the reader's
//! choice; editable; "Same as last" (remembered between sessions); "for every
//! file of this session" stops the question.

#include <Eigen/Core>

#include <QDialog>

#include <optional>

class QCheckBox;
class QDoubleSpinBox;

namespace scandiff::gui {

class GlobalShiftDialog : public QDialog
{
    Q_OBJECT
public:
    //! `suggested`: the origin the reader chose; `example`: one of the file's points (global).
    GlobalShiftDialog(const QString& file, const Eigen::Vector3d& suggested, const Eigen::Vector3d& example, QWidget* parent = nullptr);

    Eigen::Vector3d origin() const;
    void setOrigin(const Eigen::Vector3d& origin);
    bool forTheWholeSession() const;
    //! The origin used last (QSettings), if any.
    static std::optional<Eigen::Vector3d> lastOrigin();
    static void rememberOrigin(const Eigen::Vector3d& origin);

private:
    QDoubleSpinBox* boxes_[3];
    QCheckBox* wholeSession_;
};

} // namespace scandiff::gui
