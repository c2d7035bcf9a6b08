// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A dialog editing a ColourScale: its name, whether it is symmetric, and its
//! stops (position and colour), with a live preview of the gradient. Rows are
//! left in the order the user made them; scale() sorts them. While the edits do
//! not make a valid scale, OK is disabled and a message says why.

#include "colour/ColourScale.h"

#include <QDialog>
#include <QVector>

#include <optional>

class QCheckBox;
class QComboBox;
class QDialogButtonBox;
class QDoubleSpinBox;
class QLabel;
class QLineEdit;
class QPushButton;
class QTableWidget;

namespace scandiff::gui {

class ColourScaleEditor : public QDialog
{
    Q_OBJECT
public:
    explicit ColourScaleEditor(const ColourScale& initial, QWidget* parent = nullptr);

    //! The edited scale, or the last valid one while the edits are invalid.
    ColourScale scale() const;
    bool isValid() const { return edited_.has_value(); }
    //! Why the edits are not a valid scale; empty when they are.
    QString problem() const;

    //! Replaces every row with the scale's stops, its name and symmetry.
    void setScale(const ColourScale& scale);

    int stopCount() const;
    QDoubleSpinBox* positionBox(int row) const;
    QPushButton* colourButton(int row) const;
    QColor stopColour(int row) const;
    //! What choosing a colour in the row's colour dialog does.
    void setStopColour(int row, const QColor& colour);
    //! Adds a stop in the middle of the widest gap between stops, coloured as
    //! the scale is there. Returns its row.
    int addStop();
    //! Removes the selected row, or the last one if none is selected.
    void removeStop();

signals:
    //! After every edit, valid or not.
    void scaleEdited();

private:
    void insertRow(int row, double position, const QColor& colour);
    void chooseColour(QPushButton* button);
    void positionEdited(QDoubleSpinBox* box, double value);
    void revalidate();

    QLineEdit* nameEdit_;
    QCheckBox* symmetricBox_;
    QComboBox* presetBox_;
    QTableWidget* table_;
    QPushButton* addButton_;
    QPushButton* removeButton_;
    QWidget* preview_;
    QLabel* message_;
    QDialogButtonBox* buttons_;
    // One per table row. Positions are kept here exactly: the boxes show them
    // rounded, and an untouched stop (e.g. a preset's 1/3) must not move.
    QVector<double> positions_;
    QVector<QColor> colours_;
    std::optional<ColourScale> edited_;
    ColourScale lastValid_;
    QString problem_;
};

} // namespace scandiff::gui
