// SPDX-License-Identifier: GPL-3.0-or-later
#include "widgets/HistogramWidget.h"

#include <QHelpEvent>
#include <QMouseEvent>
#include <QPainter>
#include <QToolTip>

#include <algorithm>
#include <cmath>

namespace scandiff::gui {

namespace {

constexpr int kMarkerGrab = 4; // pixels either side of a marker line that grab it

} // namespace

HistogramWidget::HistogramWidget(QWidget* parent)
    : QWidget(parent), scale_(ColourScale::defaultScale())
{
    setMouseTracking(true); // for the cursor over the markers
    setSizePolicy(QSizePolicy::Expanding, QSizePolicy::Preferred);
}

void HistogramWidget::setHistogram(Histogram histogram)
{
    histogram_ = std::move(histogram);
    update();
}

void HistogramWidget::setColouring(const ColourScale& scale, double colourMin, double colourMax)
{
    scale_ = scale;
    colourMin_ = colourMin;
    colourMax_ = colourMax;
    update();
}

void HistogramWidget::setCategoryColour(std::function<QColor(long)> colour)
{
    categoryColour_ = std::move(colour);
    update();
}

QColor HistogramWidget::colourOfValue(double value) const
{
    if (categoryColour_)
        return categoryColour_(std::lround(value));
    double t;
    if (!(colourMax_ > colourMin_))
        t = value < colourMin_ ? 0.0 : value > colourMax_ ? 1.0 : 0.5;
    else
        t = (value - colourMin_) / (colourMax_ - colourMin_);
    const auto c = scale_.colourAt(t);
    return QColor(c[0], c[1], c[2]);
}

void HistogramWidget::setMarkedRange(double low, double high)
{
    if (std::isnan(low) || std::isnan(high))
        return;
    if (low > high)
        std::swap(low, high);
    markedLow_ = low;
    markedHigh_ = high;
    update();
}

void HistogramWidget::setReferenceLines(std::vector<std::pair<double, QString>> lines)
{
    references_ = std::move(lines);
    update();
}

void HistogramWidget::setLogarithmic(bool logarithmic)
{
    logarithmic_ = logarithmic;
    update();
}

double HistogramWidget::axisMin() const
{
    if (histogram_.finiteCount == 0)
        return 0.0;
    if (histogram_.max > histogram_.min)
        return histogram_.min;
    const double v = histogram_.min;
    return v - (v != 0 ? std::abs(v) * 0.05 : 0.5);
}

double HistogramWidget::axisMax() const
{
    if (histogram_.finiteCount == 0)
        return 1.0;
    if (histogram_.max > histogram_.min)
        return histogram_.max;
    const double v = histogram_.max;
    return v + (v != 0 ? std::abs(v) * 0.05 : 0.5);
}

QRect HistogramWidget::plotRect() const
{
    const int labelHeight = fontMetrics().height() + 4;
    // Room for the widest count label (the tallest bar's), and half a line
    // above the plot so the top label is not cut.
    std::size_t most = 0;
    for (std::size_t c : histogram_.counts)
        most = std::max(most, c);
    const int countWidth = fontMetrics().horizontalAdvance(QString::number(static_cast<qulonglong>(most)));
    return rect().adjusted(countWidth + 10, fontMetrics().height() / 2 + 2, -6, -labelHeight - 3);
}

std::vector<std::pair<std::size_t, int>> HistogramWidget::countTicks() const
{
    if (histogram_.finiteCount == 0 || histogram_.counts.empty())
        return {};
    const std::size_t most = *std::max_element(histogram_.counts.begin(), histogram_.counts.end());
    const QRect plot = plotRect();
    // The top of a bar of that fraction of the tallest (as paintEvent draws it).
    const auto yOf = [&](double fraction) { return plot.bottom() + 1 - std::max(1, static_cast<int>(std::lround(fraction * plot.height()))); };
    const double middle = logarithmic_ ? std::expm1(std::log1p(static_cast<double>(most)) / 2) : most / 2.0;
    std::vector<std::pair<std::size_t, int>> ticks{{0, plot.bottom()}};
    const auto middleCount = static_cast<std::size_t>(std::llround(middle));
    if (middleCount > 0 && middleCount < most) { // a tick of its own, at the height a bar of that count has
        const double top = logarithmic_ ? std::log1p(static_cast<double>(most)) : static_cast<double>(most);
        const double c = static_cast<double>(middleCount);
        ticks.push_back({middleCount, yOf((logarithmic_ ? std::log1p(c) : c) / top)});
    }
    if (most > 0)
        ticks.push_back({most, yOf(1.0)});
    return ticks;
}

int HistogramWidget::xOfValue(double value) const
{
    const QRect plot = plotRect();
    const double amin = axisMin();
    const double amax = axisMax();
    const double f = (value - amin) / (amax - amin);
    // Clamped just outside the plot so infinite ends stay drawable integers.
    const double x = plot.left() + std::clamp(f, -0.01, 1.01) * plot.width();
    return static_cast<int>(std::lround(x));
}

double HistogramWidget::valueAtX(int x) const
{
    const QRect plot = plotRect();
    const double f = std::clamp(static_cast<double>(x - plot.left()) / std::max(plot.width(), 1), 0.0, 1.0);
    return axisMin() + f * (axisMax() - axisMin());
}

QString HistogramWidget::formatValue(double value) const
{
    // Enough significant digits that the labels of a narrow span far from zero
    // (e.g. 1000.01 .. 1000.02) still differ.
    const double span = axisMax() - axisMin();
    const double magnitude = std::max(std::abs(axisMin()), std::abs(axisMax()));
    int digits = 4;
    if (span > 0 && magnitude > 0)
        digits = std::clamp(static_cast<int>(std::ceil(std::log10(magnitude / span))) + 3, 3, 12);
    return QString::number(value, 'g', digits);
}

QSize HistogramWidget::sizeHint() const { return {320, 150}; }

QSize HistogramWidget::minimumSizeHint() const { return {250, 120}; }

void HistogramWidget::paintEvent(QPaintEvent*)
{
    QPainter painter(this);
    const QRect plot = plotRect();
    painter.fillRect(plot, palette().color(QPalette::Base));

    const auto& counts = histogram_.counts;
    if (histogram_.finiteCount == 0 || counts.empty()) {
        painter.setPen(palette().color(QPalette::Disabled, QPalette::Text));
        painter.drawText(plot, Qt::AlignCenter, tr("No values"));
    } else {
        const std::size_t most = *std::max_element(counts.begin(), counts.end());
        const double top = logarithmic_ ? std::log1p(static_cast<double>(most)) : static_cast<double>(most);
        auto colourOf = [&](double value) { return colourOfValue(value); };
        const double binWidth = (histogram_.max - histogram_.min) / static_cast<double>(counts.size());
        for (std::size_t i = 0; i < counts.size(); ++i) {
            if (counts[i] == 0)
                continue;
            const double c = static_cast<double>(counts[i]);
            const double fraction = logarithmic_ ? std::log1p(c) / top : c / top;
            // A bin with anything in it is at least one pixel high.
            const int height = std::max(1, static_cast<int>(std::lround(fraction * plot.height())));
            int left, right;
            double centre;
            if (binWidth > 0) {
                const double a = histogram_.min + binWidth * static_cast<double>(i);
                left = xOfValue(a);
                right = std::max(left + 1, xOfValue(a + binWidth));
                centre = a + binWidth / 2;
            } else {
                // All values equal: one bar at that value.
                centre = histogram_.min;
                const int half = std::max(2, plot.width() / 60);
                left = xOfValue(centre) - half;
                right = xOfValue(centre) + half;
            }
            painter.fillRect(QRect(QPoint(left, plot.bottom() - height + 1), QPoint(right - 1, plot.bottom())),
                             colourOf(centre));
        }
    }

    // The part of the axis outside the marked range is washed out towards the background.
    QColor wash = palette().color(QPalette::Window);
    wash.setAlpha(170);
    const int lowX = std::clamp(xOfValue(markedLow_), plot.left(), plot.right() + 1);
    const int highX = std::clamp(xOfValue(markedHigh_), plot.left(), plot.right() + 1);
    if (lowX > plot.left())
        painter.fillRect(QRect(plot.left(), plot.top(), lowX - plot.left(), plot.height()), wash);
    if (highX <= plot.right())
        painter.fillRect(QRect(highX, plot.top(), plot.right() + 1 - highX, plot.height()), wash);

    painter.setPen(palette().color(QPalette::Mid));
    painter.setBrush(Qt::NoBrush);
    painter.drawRect(plot.adjusted(0, 0, -1, -1));

    // The colour range's ends, dashed: beyond them the bars keep the end colours.
    for (double value : {colourMin_, colourMax_}) {
        if (categorical())
            break; // categories have no range
        if (!(value > axisMin() && value < axisMax()))
            continue;
        const int x = xOfValue(value);
        painter.setPen(QPen(palette().color(QPalette::Dark), 1, Qt::DashLine));
        painter.drawLine(x, plot.top(), x, plot.bottom());
    }

    // A tool's values: dotted, labelled at the top, staggered so neighbours stay legible.
    int row = 0;
    for (const auto& [value, label] : references_) {
        if (!(value >= axisMin() && value <= axisMax()))
            continue;
        const int x = xOfValue(value);
        painter.setPen(QPen(QColor(200, 40, 160), 1.5, Qt::DotLine));
        painter.drawLine(x, plot.top(), x, plot.bottom());
        painter.setPen(QColor(200, 40, 160));
        const int y = plot.top() + 8 + fontMetrics().height() * (row++ % 3);
        const int width = fontMetrics().horizontalAdvance(label);
        const int left = x + 3 + width <= plot.right() ? x + 3 : x - 3 - width;
        painter.drawText(QPoint(left, y + fontMetrics().ascent() - fontMetrics().height() / 2), label);
    }

    // Markers: a line with a small tab at the top to grab. Ends outside the axis
    // (e.g. an unbounded threshold) have no line.
    const QColor markerColour = palette().color(QPalette::WindowText);
    for (double value : {markedLow_, markedHigh_}) {
        if (!(value >= axisMin() && value <= axisMax()))
            continue;
        const int x = xOfValue(value);
        painter.setPen(QPen(markerColour, 2));
        painter.drawLine(x, plot.top(), x, plot.bottom());
        painter.setPen(Qt::NoPen);
        painter.setBrush(markerColour);
        const QPoint tab[3] = {{x - 5, plot.top()}, {x + 5, plot.top()}, {x, plot.top() + 6}};
        painter.drawPolygon(tab, 3);
        painter.setBrush(Qt::NoBrush);
    }

    // The count axis on the left: ticks and their counts, right-aligned.
    painter.setPen(palette().color(QPalette::WindowText));
    for (const auto& [count, y] : countTicks()) {
        painter.drawLine(plot.left() - 4, y, plot.left() - 1, y);
        const QRect label(0, y - fontMetrics().height() / 2, plot.left() - 6, fontMetrics().height());
        painter.drawText(label, Qt::AlignRight | Qt::AlignVCenter, QString::number(static_cast<qulonglong>(count)));
    }

    // Axis labels at min, middle and max, under the plot.
    const QRect labels(plot.left(), plot.bottom() + 3, plot.width(), fontMetrics().height() + 2);
    const double amin = axisMin();
    const double amax = axisMax();
    painter.drawText(labels, Qt::AlignLeft | Qt::AlignTop, formatValue(amin));
    painter.drawText(labels, Qt::AlignRight | Qt::AlignTop, formatValue(amax));
    const QString mid = formatValue((amin + amax) / 2);
    // The middle label only where it does not run into the outer ones.
    const int midWidth = fontMetrics().horizontalAdvance(mid);
    const int outerWidth = std::max(fontMetrics().horizontalAdvance(formatValue(amin)),
                                    fontMetrics().horizontalAdvance(formatValue(amax)));
    if (midWidth + 2 * outerWidth + 16 < labels.width())
        painter.drawText(labels, Qt::AlignHCenter | Qt::AlignTop, mid);
}

HistogramWidget::Marker HistogramWidget::markerNear(int x) const
{
    const QRect plot = plotRect();
    const int lowX = std::clamp(xOfValue(markedLow_), plot.left(), plot.right());
    const int highX = std::clamp(xOfValue(markedHigh_), plot.left(), plot.right());
    const int lowDistance = std::abs(x - lowX);
    const int highDistance = std::abs(x - highX);
    if (std::min(lowDistance, highDistance) > kMarkerGrab)
        return Marker::None;
    if (lowDistance == highDistance) // stacked: the side of the press decides
        return x <= lowX ? Marker::Low : Marker::High;
    return lowDistance < highDistance ? Marker::Low : Marker::High;
}

void HistogramWidget::mousePressEvent(QMouseEvent* event)
{
    if (event->button() != Qt::LeftButton || !plotRect().adjusted(-kMarkerGrab, 0, kMarkerGrab, 0).contains(event->pos())) {
        event->ignore();
        return;
    }
    dragging_ = markerNear(event->pos().x());
    if (dragging_ == Marker::None) {
        event->ignore();
        return;
    }
    event->accept();
}

void HistogramWidget::mouseMoveEvent(QMouseEvent* event)
{
    if (dragging_ == Marker::None) {
        const bool over = plotRect().adjusted(-kMarkerGrab, 0, kMarkerGrab, 0).contains(event->pos())
                          && markerNear(event->pos().x()) != Marker::None;
        if (over)
            setCursor(Qt::SizeHorCursor);
        else
            unsetCursor();
        return;
    }
    const double value = valueAtX(event->pos().x());
    double low = markedLow_;
    double high = markedHigh_;
    if (dragging_ == Marker::Low)
        low = std::min(value, high);
    else
        high = std::max(value, low);
    if (low == markedLow_ && high == markedHigh_)
        return;
    markedLow_ = low;
    markedHigh_ = high;
    update();
    emit markedRangeEdited(low, high);
}

void HistogramWidget::mouseReleaseEvent(QMouseEvent* event)
{
    if (dragging_ == Marker::None || event->button() != Qt::LeftButton) {
        event->ignore();
        return;
    }
    dragging_ = Marker::None;
    event->accept();
}

bool HistogramWidget::event(QEvent* event)
{
    if (event->type() == QEvent::ToolTip) {
        const auto* help = static_cast<QHelpEvent*>(event);
        const QRect plot = plotRect();
        const auto& counts = histogram_.counts;
        if (histogram_.finiteCount > 0 && !counts.empty() && plot.contains(help->pos())) {
            QString text;
            if (histogram_.max > histogram_.min) {
                const double f = static_cast<double>(help->pos().x() - plot.left()) / plot.width();
                const auto bin = std::min(counts.size() - 1, static_cast<std::size_t>(f * counts.size()));
                const double w = (histogram_.max - histogram_.min) / static_cast<double>(counts.size());
                const double a = histogram_.min + w * static_cast<double>(bin);
                text = tr("%1 to %2: %3 points")
                           .arg(formatValue(a), formatValue(a + w))
                           .arg(static_cast<qulonglong>(counts[bin]));
            } else {
                text = tr("%1: %2 points").arg(formatValue(histogram_.min)).arg(static_cast<qulonglong>(counts[0]));
            }
            QToolTip::showText(help->globalPos(), text, this);
        } else {
            QToolTip::hideText();
            event->ignore();
        }
        return true;
    }
    return QWidget::event(event);
}

} // namespace scandiff::gui
