// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A RangeSlider with a spin box for each end, kept in step both ways. The
//! boxes show rounded values (their decimals follow the bounds' span); low()
//! and high() are the slider's exact values.

#include <QWidget>

class QDoubleSpinBox;

namespace scandiff::gui {

class RangeSlider;

class RangeEditor : public QWidget
{
    Q_OBJECT
public:
    explicit RangeEditor(QWidget* parent = nullptr);

    //! As RangeSlider::setBounds; also sets the boxes' limits, decimals and step.
    void setBounds(double min, double max);
    //! As RangeSlider::setRange.
    void setRange(double low, double high);

    double minimum() const;
    double maximum() const;
    double low() const;
    double high() const;

    RangeSlider* slider() const { return slider_; }
    QDoubleSpinBox* lowBox() const { return lowBox_; }
    QDoubleSpinBox* highBox() const { return highBox_; }

signals:
    //! Once per change, whether it came from the slider, a box or setRange.
    void rangeChanged(double low, double high);

private:
    void showRangeInBoxes();
    void lowBoxEdited(double value);
    void highBoxEdited(double value);

    RangeSlider* slider_;
    QDoubleSpinBox* lowBox_;
    QDoubleSpinBox* highBox_;
};

} // namespace scandiff::gui
