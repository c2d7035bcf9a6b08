// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The active scalar field of the current entity: which field, its colour scale
//! (presets or user-edited) and the range it spans (narrowed by hand, or
//! symmetric around 0), the threshold range (double-ended slider with
//! numeric boxes), what happens to points outside it (hidden or greyed), the
//! histogram with the range marked, and "Split at thresholds". Every change goes
//! to the Document; the view follows the document's signals.

#include "colour/ColourScale.h"
#include "document/Document.h"

#include <QTimer>
#include <QWidget>

#include <functional>
#include <vector>

class QCheckBox;
class QComboBox;
class QLabel;
class QPushButton;

namespace scandiff::gui {

class HistogramWidget;
class RangeEditor;

class ScalarFieldPanel : public QWidget
{
    Q_OBJECT
public:
    ScalarFieldPanel(Document& document, QWidget* parent = nullptr);

    void showEntity(EntityId id);
    EntityId entity() const { return entity_; }
    //! Scales offered besides the presets (user-edited ones; sessions restore them).
    const std::vector<ColourScale>& customScales() const { return customScales_; }
    void addCustomScale(const ColourScale& scale);

    // For tests and controllers.
    QComboBox* fieldBox() const { return fieldBox_; }
    QComboBox* scaleBox() const { return scaleBox_; }
    QComboBox* outsideBox() const { return outsideBox_; }
    RangeEditor* rangeEditor() const { return range_; }
    RangeEditor* colourRangeEditor() const { return colours_; }
    QCheckBox* symmetricBox() const { return symmetric_; }
    QCheckBox* blendColoursBox() const { return blendColours_; }
    QPushButton* automaticColoursButton() const { return automaticColours_; }
    HistogramWidget* histogram() const { return histogram_; }
    QPushButton* splitButton() const { return split_; }
    QString insideText() const;
    //! The histogram as drawn (its bins over the field's range) to a CSV file
    //! bin_min,bin_max,count, the table `scandiff-cli field-histogram` writes.
    //! False, with the reason in `error`, when there is no field or the write fails.
    bool exportHistogram(const QString& path, QString* error = nullptr);
    //! Asks for a file, then exportHistogram.
    void exportHistogramWithDialog();

signals:
    void splitRequested(EntityId id, const std::string& field, double low, double high);

private:
    void refresh();
    //! refresh() once the event loop turns (started by the document's
    //! signals): a tool's results change a cloud's fields and display several
    //! times in one go, and each refresh reads every value (range, histogram,
    //! count inside): one refresh, in a turn of its own.
    QTimer* refreshSoon_ = new QTimer(this);
    void refreshScaleBox();
    void onFieldChosen(int index);
    void onScaleChosen(int index);
    void onRangeEdited(double low, double high);
    void onColourRangeEdited(double low, double high);
    //! Changes the active field's display with `edit` and stores it.
    void editDisplay(const std::function<void(FieldDisplay&)>& edit);
    void editScale();
    void updateInsideCount();
    const ScalarField* activeField() const;

    Document& document_;
    EntityId entity_ = kNoEntity;
    std::vector<ColourScale> customScales_;
    QLabel* title_;
    QComboBox* fieldBox_;
    QComboBox* scaleBox_;
    QPushButton* editScale_;
    QComboBox* outsideBox_;
    RangeEditor* colours_;
    QCheckBox* symmetric_;
    QPushButton* automaticColours_;
    RangeEditor* range_;
    HistogramWidget* histogram_;
    QLabel* inside_;
    QPushButton* resetRange_;
    QPushButton* split_;
    QPushButton* exportHistogram_;
    QCheckBox* blendColours_;
    bool updating_ = false;
};

} // namespace scandiff::gui
