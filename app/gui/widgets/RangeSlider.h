// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A horizontal slider with two handles choosing a sub-range [low, high] of
//! [minimum, maximum]. Handles are drawn by the current QStyle, the span between
//! them in the palette's highlight colour.
//!
//! Mouse: drag either handle; a press on the groove jumps the nearer handle there
//! and drags it. Keyboard: arrows move the active handle by 1% of the bounds,
//! Page Up/Down by 10%, Home/End to the bounds; Tab switches from the low to the
//! high handle before focus leaves the widget (Shift+Tab the other way).
//! Positions from the mouse and keys are quantised to kSteps steps of the
//! bounds; values given to setRange are kept exactly.

#include <QWidget>

class QStyleOptionSlider;

namespace scandiff::gui {

class RangeSlider : public QWidget
{
    Q_OBJECT
public:
    static constexpr int kSteps = 10000;
    enum class Handle { None, Low, High };

    explicit RangeSlider(QWidget* parent = nullptr);

    //! Swapped if min > max; ignored if either is not finite. The range is
    //! clamped into the new bounds (emitting rangeChanged if that moves it).
    void setBounds(double min, double max);
    //! Clamped to the bounds; swapped if low > high; ignored if either is NaN.
    //! Emits rangeChanged when low or high changes.
    void setRange(double low, double high);

    double minimum() const { return min_; }
    double maximum() const { return max_; }
    double low() const { return low_; }
    double high() const { return high_; }

    //! The handle the keyboard moves (the last one pressed or tabbed to).
    Handle activeHandle() const { return active_; }
    //! Where a handle's centre is drawn, in widget coordinates (tests aim with it).
    QPoint handleCentre(Handle handle) const;

    QSize sizeHint() const override;
    QSize minimumSizeHint() const override;

signals:
    //! Emitted on every change, including each step of a drag.
    void rangeChanged(double low, double high);
    //! A mouse drag ended (e.g. to record one undo step for the whole drag).
    void dragFinished();

protected:
    void paintEvent(QPaintEvent* event) override;
    void mousePressEvent(QMouseEvent* event) override;
    void mouseMoveEvent(QMouseEvent* event) override;
    void mouseReleaseEvent(QMouseEvent* event) override;
    void keyPressEvent(QKeyEvent* event) override;
    bool focusNextPrevChild(bool next) override;
    void focusInEvent(QFocusEvent* event) override;

private:
    void initStyleOption(QStyleOptionSlider* option, double value) const;
    int handleWidth() const;
    int grooveStart() const;
    int grooveLength() const;
    int pixelOf(double value) const;
    double valueAtPixel(int x) const;
    //! Moves one handle, keeping low <= high.
    void moveHandle(Handle handle, double value);
    void applyRange(double low, double high);

    double min_ = 0, max_ = 1;
    double low_ = 0, high_ = 1;
    Handle active_ = Handle::Low;
    Handle dragging_ = Handle::None;
    int dragOffset_ = 0; // press point minus handle centre, so a grabbed handle does not jump
    int tiePressX_ = -1; // >= 0 while a press on stacked handles waits for the first move
};

} // namespace scandiff::gui
