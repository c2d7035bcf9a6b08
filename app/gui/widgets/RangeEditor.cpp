// SPDX-License-Identifier: GPL-3.0-or-later
#include "widgets/RangeEditor.h"

#include "widgets/RangeSlider.h"

#include <QDoubleSpinBox>
#include <QGridLayout>
#include <QSignalBlocker>

#include <algorithm>
#include <cmath>

namespace scandiff::gui {

namespace {

// Enough decimals to show about a ten-thousandth of the span (the slider's
// resolution); for an empty span, of the value's own magnitude.
int decimalsFor(double min, double max)
{
    double scale = max - min;
    if (!(scale > 0))
        scale = std::max(std::abs(min), std::abs(max));
    if (!(scale > 0))
        return 4;
    const int decimals = static_cast<int>(std::ceil(4.0 - std::log10(scale)));
    return std::clamp(decimals, 0, 12);
}

} // namespace

RangeEditor::RangeEditor(QWidget* parent)
    : QWidget(parent), slider_(new RangeSlider(this)), lowBox_(new QDoubleSpinBox(this)),
      highBox_(new QDoubleSpinBox(this))
{
    lowBox_->setObjectName("lowBox");
    highBox_->setObjectName("highBox");
    lowBox_->setToolTip(tr("Lower end of the range"));
    highBox_->setToolTip(tr("Upper end of the range"));
    for (QDoubleSpinBox* box : {lowBox_, highBox_}) {
        // Otherwise every keystroke of "2.5" would be a separate change.
        box->setKeyboardTracking(false);
        box->setAccelerated(true);
        box->setSizePolicy(QSizePolicy::Preferred, QSizePolicy::Fixed);
    }
    auto* layout = new QGridLayout(this);
    layout->setContentsMargins(0, 0, 0, 0);
    layout->addWidget(slider_, 0, 0, 1, 3);
    layout->addWidget(lowBox_, 1, 0);
    layout->setColumnStretch(1, 1);
    layout->addWidget(highBox_, 1, 2);
    setFocusProxy(slider_);

    connect(slider_, &RangeSlider::rangeChanged, this, [this](double low, double high) {
        showRangeInBoxes();
        emit rangeChanged(low, high);
    });
    // A typed bound counts once it is complete (Enter or leaving the box), not at each digit.
    lowBox_->setKeyboardTracking(false);
    highBox_->setKeyboardTracking(false);
    connect(lowBox_, qOverload<double>(&QDoubleSpinBox::valueChanged), this, &RangeEditor::lowBoxEdited);
    connect(highBox_, qOverload<double>(&QDoubleSpinBox::valueChanged), this, &RangeEditor::highBoxEdited);

    setBounds(slider_->minimum(), slider_->maximum());
    showRangeInBoxes();
}

void RangeEditor::setBounds(double min, double max)
{
    if (!std::isfinite(min) || !std::isfinite(max))
        return;
    if (min > max)
        std::swap(min, max);
    const int decimals = decimalsFor(min, max);
    for (QDoubleSpinBox* box : {lowBox_, highBox_}) {
        const QSignalBlocker blocker(box);
        box->setDecimals(decimals);
        // The boxes' limits are rounded to their decimals; widen them by half a
        // unit so the rounded ends of the bounds stay reachable.
        const double half = 0.5 * std::pow(10.0, -decimals);
        box->setRange(min - half, max + half);
        box->setSingleStep(max > min ? (max - min) / 100 : 1.0);
    }
    slider_->setBounds(min, max); // emits (and updates the boxes) if the range was clamped
    showRangeInBoxes();
}

void RangeEditor::setRange(double low, double high) { slider_->setRange(low, high); }

double RangeEditor::minimum() const { return slider_->minimum(); }
double RangeEditor::maximum() const { return slider_->maximum(); }
double RangeEditor::low() const { return slider_->low(); }
double RangeEditor::high() const { return slider_->high(); }

void RangeEditor::showRangeInBoxes()
{
    const QSignalBlocker lowBlocker(lowBox_);
    const QSignalBlocker highBlocker(highBox_);
    lowBox_->setValue(slider_->low());
    highBox_->setValue(slider_->high());
}

// A box moves only its own end, so the other end keeps its exact value. A low
// typed above the high end stops at it (and the other way round).
void RangeEditor::lowBoxEdited(double value)
{
    slider_->setRange(std::min(value, slider_->high()), slider_->high());
    showRangeInBoxes(); // the box may show a value the slider refused
}

void RangeEditor::highBoxEdited(double value)
{
    slider_->setRange(slider_->low(), std::max(value, slider_->low()));
    showRangeInBoxes();
}

} // namespace scandiff::gui
