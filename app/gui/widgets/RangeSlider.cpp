// SPDX-License-Identifier: GPL-3.0-or-later
#include "widgets/RangeSlider.h"

#include <QKeyEvent>
#include <QMouseEvent>
#include <QPainter>
#include <QStyle>
#include <QStyleOptionSlider>

#include <algorithm>
#include <cmath>

namespace scandiff::gui {

RangeSlider::RangeSlider(QWidget* parent) : QWidget(parent)
{
    setFocusPolicy(Qt::StrongFocus);
    setSizePolicy(QSizePolicy::Expanding, QSizePolicy::Fixed);
    setAttribute(Qt::WA_Hover); // the style highlights the handle under the mouse
}

void RangeSlider::setBounds(double min, double max)
{
    if (!std::isfinite(min) || !std::isfinite(max))
        return;
    if (min > max)
        std::swap(min, max);
    min_ = min;
    max_ = max;
    applyRange(low_, high_); // clamps, and emits only if the range moved
    update();
}

void RangeSlider::setRange(double low, double high)
{
    if (std::isnan(low) || std::isnan(high))
        return;
    if (low > high)
        std::swap(low, high);
    applyRange(low, high);
}

void RangeSlider::applyRange(double low, double high)
{
    low = std::clamp(low, min_, max_);
    high = std::clamp(high, min_, max_);
    if (low == low_ && high == high_)
        return;
    low_ = low;
    high_ = high;
    update();
    emit rangeChanged(low_, high_);
}

void RangeSlider::moveHandle(Handle handle, double value)
{
    if (handle == Handle::Low)
        applyRange(std::clamp(value, min_, high_), high_);
    else if (handle == Handle::High)
        applyRange(low_, std::clamp(value, low_, max_));
}

void RangeSlider::initStyleOption(QStyleOptionSlider* option, double value) const
{
    option->initFrom(this);
    option->orientation = Qt::Horizontal;
    option->minimum = 0;
    option->maximum = kSteps;
    const double span = max_ - min_;
    const int step = span > 0 ? static_cast<int>(std::lround((value - min_) / span * kSteps)) : 0;
    option->sliderPosition = option->sliderValue = std::clamp(step, 0, kSteps);
    option->singleStep = kSteps / 100;
    option->pageStep = kSteps / 10;
    option->tickPosition = QSlider::NoTicks;
    option->subControls = QStyle::SC_None;
    option->activeSubControls = QStyle::SC_None;
}

int RangeSlider::handleWidth() const
{
    QStyleOptionSlider option;
    initStyleOption(&option, min_);
    const QRect handle = style()->subControlRect(QStyle::CC_Slider, &option, QStyle::SC_SliderHandle, this);
    return std::max(handle.width(), 1);
}

// The style places the handle's left edge at sliderPositionFromValue over
// (width - handle width); centres therefore run over this groove.
int RangeSlider::grooveStart() const { return handleWidth() / 2; }

int RangeSlider::grooveLength() const { return std::max(width() - handleWidth(), 1); }

int RangeSlider::pixelOf(double value) const
{
    QStyleOptionSlider option;
    initStyleOption(&option, value);
    return grooveStart()
           + QStyle::sliderPositionFromValue(0, kSteps, option.sliderPosition, grooveLength());
}

double RangeSlider::valueAtPixel(int x) const
{
    const int step = QStyle::sliderValueFromPosition(0, kSteps, x - grooveStart(), grooveLength());
    if (step <= 0)
        return min_;
    if (step >= kSteps)
        return max_; // exactly, not min + span * 1.0 rounded
    return min_ + (max_ - min_) * (static_cast<double>(step) / kSteps);
}

QPoint RangeSlider::handleCentre(Handle handle) const
{
    QStyleOptionSlider option;
    initStyleOption(&option, handle == Handle::High ? high_ : low_);
    const QRect rect = style()->subControlRect(QStyle::CC_Slider, &option, QStyle::SC_SliderHandle, this);
    return {pixelOf(handle == Handle::High ? high_ : low_), rect.center().y()};
}

QSize RangeSlider::sizeHint() const
{
    QStyleOptionSlider option;
    initStyleOption(&option, min_);
    const int thickness = style()->pixelMetric(QStyle::PM_SliderThickness, &option, this);
    return style()->sizeFromContents(QStyle::CT_Slider, &option, QSize(200, thickness), this);
}

QSize RangeSlider::minimumSizeHint() const
{
    const QSize hint = sizeHint();
    return {2 * handleWidth() + 20, hint.height()};
}

void RangeSlider::paintEvent(QPaintEvent*)
{
    QPainter painter(this);

    // The groove with its handle at the minimum, so styles that fill the groove
    // up to the handle (Fusion) leave it empty; the span is painted below.
    QStyleOptionSlider option;
    initStyleOption(&option, min_);
    option.subControls = QStyle::SC_SliderGroove;
    style()->drawComplexControl(QStyle::CC_Slider, &option, &painter, this);

    QRect groove = style()->subControlRect(QStyle::CC_Slider, &option, QStyle::SC_SliderGroove, this);
    const int thickness = std::max(4, std::min(groove.height(), 6));
    const QRect span(QPoint(pixelOf(low_), groove.center().y() - thickness / 2),
                     QPoint(pixelOf(high_), groove.center().y() - thickness / 2 + thickness - 1));
    painter.setPen(Qt::NoPen);
    painter.setBrush(palette().color(isEnabled() ? QPalette::Active : QPalette::Disabled, QPalette::Highlight));
    painter.drawRoundedRect(span, 2, 2);

    // The inactive handle first, so the active one is on top when they overlap.
    const Handle order[2] = {active_ == Handle::Low ? Handle::High : Handle::Low, active_};
    for (Handle h : order) {
        QStyleOptionSlider handleOption;
        initStyleOption(&handleOption, h == Handle::Low ? low_ : high_);
        handleOption.subControls = QStyle::SC_SliderHandle;
        if (dragging_ == h) {
            handleOption.activeSubControls = QStyle::SC_SliderHandle;
            handleOption.state |= QStyle::State_Sunken;
        }
        if (h != active_)
            handleOption.state &= ~QStyle::State_HasFocus;
        style()->drawComplexControl(QStyle::CC_Slider, &handleOption, &painter, this);
    }
}

void RangeSlider::mousePressEvent(QMouseEvent* event)
{
    if (event->button() != Qt::LeftButton) {
        event->ignore();
        return;
    }
    const int x = event->pos().x();
    const int lowX = pixelOf(low_);
    const int highX = pixelOf(high_);
    const int grab = handleWidth() / 2 + 1;
    const int lowDistance = std::abs(x - lowX);
    const int highDistance = std::abs(x - highX);
    tiePressX_ = -1;
    if (std::min(lowDistance, highDistance) <= grab) {
        if (lowX == highX) {
            // Stacked handles: the first movement decides which one is dragged.
            dragging_ = Handle::Low;
            tiePressX_ = x;
        } else {
            dragging_ = lowDistance <= highDistance ? Handle::Low : Handle::High;
        }
        dragOffset_ = x - (dragging_ == Handle::Low ? lowX : highX);
    } else {
        // A press on the groove brings the nearer handle under the mouse.
        dragging_ = lowDistance < highDistance || (lowDistance == highDistance && x < lowX) ? Handle::Low
                                                                                            : Handle::High;
        dragOffset_ = 0;
        moveHandle(dragging_, valueAtPixel(x));
    }
    active_ = dragging_;
    update();
    event->accept();
}

void RangeSlider::mouseMoveEvent(QMouseEvent* event)
{
    if (dragging_ == Handle::None) {
        event->ignore();
        return;
    }
    const int x = event->pos().x();
    if (tiePressX_ >= 0) {
        if (x == tiePressX_)
            return;
        dragging_ = active_ = x < tiePressX_ ? Handle::Low : Handle::High;
        tiePressX_ = -1;
    }
    moveHandle(dragging_, valueAtPixel(x - dragOffset_));
    event->accept();
}

void RangeSlider::mouseReleaseEvent(QMouseEvent* event)
{
    if (dragging_ == Handle::None || event->button() != Qt::LeftButton) {
        event->ignore();
        return;
    }
    dragging_ = Handle::None;
    tiePressX_ = -1;
    update();
    emit dragFinished();
    event->accept();
}

void RangeSlider::keyPressEvent(QKeyEvent* event)
{
    const double span = max_ - min_;
    const double current = active_ == Handle::High ? high_ : low_;
    switch (event->key()) {
    case Qt::Key_Left:
    case Qt::Key_Down: moveHandle(active_, current - span / 100); break;
    case Qt::Key_Right:
    case Qt::Key_Up: moveHandle(active_, current + span / 100); break;
    case Qt::Key_PageDown: moveHandle(active_, current - span / 10); break;
    case Qt::Key_PageUp: moveHandle(active_, current + span / 10); break;
    case Qt::Key_Home: moveHandle(active_, min_); break;
    case Qt::Key_End: moveHandle(active_, max_); break;
    default: QWidget::keyPressEvent(event); return;
    }
    event->accept();
}

bool RangeSlider::focusNextPrevChild(bool next)
{
    // Tab visits the low handle, then the high one, then leaves.
    if (hasFocus() && next && active_ == Handle::Low) {
        active_ = Handle::High;
        update();
        return true;
    }
    if (hasFocus() && !next && active_ == Handle::High) {
        active_ = Handle::Low;
        update();
        return true;
    }
    return QWidget::focusNextPrevChild(next);
}

void RangeSlider::focusInEvent(QFocusEvent* event)
{
    if (event->reason() == Qt::TabFocusReason)
        active_ = Handle::Low;
    else if (event->reason() == Qt::BacktabFocusReason)
        active_ = Handle::High;
    QWidget::focusInEvent(event);
}

} // namespace scandiff::gui
