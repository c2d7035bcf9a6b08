// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Draws a scalar field's histogram: one bar per bin, coloured as colourise
//! would colour the bin's centre, the colour range's ends dashed, a marked
//! range (e.g. the visible threshold) with the outside shaded, the value
//! axis labelled at min, middle and max and the count axis at 0, its middle
//! and the tallest bar's count. The markers can be dragged with the
//! mouse; hovering a bar shows its count.

#include "colour/ColourScale.h"

#include <QColor>
#include <QWidget>

#include <functional>
#include <utility>
#include <vector>

namespace scandiff::gui {

class HistogramWidget : public QWidget
{
    Q_OBJECT
public:
    explicit HistogramWidget(QWidget* parent = nullptr);

    void setHistogram(Histogram histogram);
    void setColouring(const ColourScale& scale, double colourMin, double colourMax);
    //! Categories (labels, yes/no flags): each bar in the colour of the
    //! integer value at its centre, as the points of that value are drawn;
    //! the colour range is then not marked. An empty function: the scale.
    void setCategoryColour(std::function<QColor(long)> colour);
    bool categorical() const { return static_cast<bool>(categoryColour_); }
    //! The colour a bar centred on `value` is drawn in.
    QColor colourOfValue(double value) const;
    //! Swapped if low > high. Markers outside the histogram's span are not drawn,
    //! but the shading still covers the part of the span outside [low, high].
    void setMarkedRange(double low, double high);
    //! Bar heights on a log(1 + count) scale, so sparse tails stay visible.
    void setLogarithmic(bool logarithmic);
    //! Values a tool found (a threshold, the modes it separated), drawn as
    //! labelled dotted lines; they cannot be dragged. Empty: none.
    void setReferenceLines(std::vector<std::pair<double, QString>> lines);
    const std::vector<std::pair<double, QString>>& referenceLines() const { return references_; }

    const Histogram& histogram() const { return histogram_; }
    double markedLow() const { return markedLow_; }
    double markedHigh() const { return markedHigh_; }
    bool logarithmic() const { return logarithmic_; }

    //! The value axis as drawn: the histogram's span, widened when it is empty.
    double axisMin() const;
    double axisMax() const;
    //! The plot area (bars) in widget coordinates, and the x of a value in it.
    //! Its left margin holds the count axis's labels.
    QRect plotRect() const;
    //! The count axis as drawn: (count, y of its tick) from 0 at the plot's
    //! bottom to the tallest bar's count at its top; the middle tick is the
    //! count of a bar half as tall (on the log scale, e^(log(1 + top) / 2) - 1).
    //! Empty when there are no values.
    std::vector<std::pair<std::size_t, int>> countTicks() const;
    int xOfValue(double value) const;

    QSize sizeHint() const override;
    QSize minimumSizeHint() const override;

signals:
    //! While a marker is dragged; the widget has already moved it.
    void markedRangeEdited(double low, double high);

protected:
    void paintEvent(QPaintEvent* event) override;
    void mousePressEvent(QMouseEvent* event) override;
    void mouseMoveEvent(QMouseEvent* event) override;
    void mouseReleaseEvent(QMouseEvent* event) override;
    bool event(QEvent* event) override;

private:
    enum class Marker { None, Low, High };
    Marker markerNear(int x) const;
    double valueAtX(int x) const;
    QString formatValue(double value) const;

    Histogram histogram_;
    ColourScale scale_;
    double colourMin_ = 0, colourMax_ = 1;
    double markedLow_ = -std::numeric_limits<double>::infinity();
    double markedHigh_ = std::numeric_limits<double>::infinity();
    bool logarithmic_ = false;
    std::vector<std::pair<double, QString>> references_;
    std::function<QColor(long)> categoryColour_;
    Marker dragging_ = Marker::None;
};

} // namespace scandiff::gui
