// SPDX-License-Identifier: GPL-3.0-or-later
#include "colour/ColourScaleEditor.h"

#include <QCheckBox>
#include <QColorDialog>
#include <QComboBox>
#include <QDialogButtonBox>
#include <QDoubleSpinBox>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QLineEdit>
#include <QPainter>
#include <QPushButton>
#include <QSignalBlocker>
#include <QTableWidget>
#include <QVBoxLayout>

#include <algorithm>
#include <stdexcept>

namespace scandiff::gui {

namespace {

//! The gradient of the scale being edited, or a hatched bar while it is invalid.
class GradientPreview : public QWidget
{
public:
    explicit GradientPreview(QWidget* parent) : QWidget(parent)
    {
        setMinimumHeight(24);
        setSizePolicy(QSizePolicy::Expanding, QSizePolicy::Fixed);
    }
    void showScale(const std::optional<ColourScale>& scale)
    {
        scale_ = scale;
        update();
    }
    QSize sizeHint() const override { return {300, 28}; }

protected:
    void paintEvent(QPaintEvent*) override
    {
        QPainter painter(this);
        const QRect r = rect().adjusted(0, 0, -1, -1);
        if (!scale_) {
            painter.fillRect(r, QBrush(palette().color(QPalette::Mid), Qt::BDiagPattern));
        } else {
            const int w = std::max(r.width(), 1);
            for (int x = 0; x <= r.width(); ++x) {
                const auto c = scale_->colourAt(static_cast<double>(x) / w);
                painter.setPen(QColor(c[0], c[1], c[2]));
                painter.drawLine(r.left() + x, r.top(), r.left() + x, r.bottom());
            }
        }
        painter.setPen(palette().color(QPalette::Dark));
        painter.drawRect(r);
    }

private:
    std::optional<ColourScale> scale_;
};

QColor toQColor(const ColourStop& s) { return QColor(s.r, s.g, s.b); }

void paintSwatch(QPushButton* button, const QColor& colour)
{
    QPixmap swatch(32, 14);
    swatch.fill(colour);
    button->setIcon(QIcon(swatch));
    button->setIconSize(swatch.size());
    button->setText(colour.name());
}

} // namespace

ColourScaleEditor::ColourScaleEditor(const ColourScale& initial, QWidget* parent)
    : QDialog(parent), nameEdit_(new QLineEdit(this)), symmetricBox_(new QCheckBox(tr("Centred on zero"), this)),
      presetBox_(new QComboBox(this)), table_(new QTableWidget(0, 2, this)),
      addButton_(new QPushButton(tr("Add stop"), this)), removeButton_(new QPushButton(tr("Remove stop"), this)),
      preview_(new GradientPreview(this)), message_(new QLabel(this)),
      buttons_(new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel, this)), lastValid_(initial)
{
    setWindowTitle(tr("Edit colour scale"));
    nameEdit_->setObjectName("nameEdit");
    symmetricBox_->setObjectName("symmetricBox");
    symmetricBox_->setToolTip(tr("A symmetric scale is shown over a colour range centred on 0"));
    presetBox_->setObjectName("presetBox");
    table_->setObjectName("stopsTable");
    addButton_->setObjectName("addStopButton");
    removeButton_->setObjectName("removeStopButton");
    preview_->setObjectName("preview");
    message_->setObjectName("messageLabel");
    buttons_->setObjectName("buttonBox");

    presetBox_->addItem(tr("Start from a preset..."));
    for (const ColourScale& s : ColourScale::presets())
        presetBox_->addItem(QString::fromStdString(s.name()));

    table_->setHorizontalHeaderLabels({tr("Position"), tr("Colour")});
    table_->horizontalHeader()->setSectionResizeMode(QHeaderView::Stretch);
    table_->verticalHeader()->setVisible(false);
    table_->setSelectionBehavior(QAbstractItemView::SelectRows);
    table_->setSelectionMode(QAbstractItemView::SingleSelection);

    message_->setWordWrap(true);
    QPalette warning = message_->palette();
    warning.setColor(QPalette::WindowText, QColor(190, 30, 30));
    message_->setPalette(warning);

    auto* form = new QFormLayout;
    form->addRow(tr("Name:"), nameEdit_);
    form->addRow(QString(), symmetricBox_);
    form->addRow(QString(), presetBox_);
    auto* rowButtons = new QHBoxLayout;
    rowButtons->addWidget(addButton_);
    rowButtons->addWidget(removeButton_);
    rowButtons->addStretch();
    auto* layout = new QVBoxLayout(this);
    layout->addLayout(form);
    layout->addWidget(table_, 1);
    layout->addLayout(rowButtons);
    layout->addWidget(preview_);
    layout->addWidget(message_);
    layout->addWidget(buttons_);

    connect(nameEdit_, &QLineEdit::textChanged, this, &ColourScaleEditor::revalidate);
    connect(symmetricBox_, &QCheckBox::toggled, this, &ColourScaleEditor::revalidate);
    connect(presetBox_, qOverload<int>(&QComboBox::activated), this, [this](int index) {
        if (index <= 0)
            return;
        if (auto preset = ColourScale::preset(presetBox_->itemText(index).toStdString()))
            setScale(*preset);
        presetBox_->setCurrentIndex(0); // a prompt, not a state
    });
    connect(addButton_, &QPushButton::clicked, this, [this] { addStop(); });
    connect(removeButton_, &QPushButton::clicked, this, &ColourScaleEditor::removeStop);
    connect(buttons_, &QDialogButtonBox::accepted, this, &QDialog::accept);
    connect(buttons_, &QDialogButtonBox::rejected, this, &QDialog::reject);

    setScale(initial);
    resize(380, 460);
}

void ColourScaleEditor::setScale(const ColourScale& scale)
{
    {
        const QSignalBlocker nameBlocker(nameEdit_);
        const QSignalBlocker symmetricBlocker(symmetricBox_);
        nameEdit_->setText(QString::fromStdString(scale.name()));
        symmetricBox_->setChecked(scale.symmetric());
        table_->setRowCount(0);
        positions_.clear();
        colours_.clear();
        for (const ColourStop& s : scale.stops())
            insertRow(table_->rowCount(), s.position, toQColor(s));
    }
    revalidate();
}

void ColourScaleEditor::insertRow(int row, double position, const QColor& colour)
{
    table_->insertRow(row);
    positions_.insert(row, position);
    colours_.insert(row, colour);
    auto* box = new QDoubleSpinBox(table_);
    box->setRange(0.0, 1.0);
    box->setDecimals(4);
    box->setSingleStep(0.01);
    box->setValue(position);
    box->setFrame(false);
    connect(box, qOverload<double>(&QDoubleSpinBox::valueChanged), this,
            [this, box](double value) { positionEdited(box, value); });
    table_->setCellWidget(row, 0, box);
    auto* button = new QPushButton(table_);
    button->setFlat(true);
    paintSwatch(button, colour);
    connect(button, &QPushButton::clicked, this, [this, button] { chooseColour(button); });
    table_->setCellWidget(row, 1, button);
}

void ColourScaleEditor::chooseColour(QPushButton* button)
{
    // Rows move when others are added or removed, so the button is looked up now.
    for (int row = 0; row < table_->rowCount(); ++row) {
        if (table_->cellWidget(row, 1) != button)
            continue;
        const QColor chosen = QColorDialog::getColor(colours_[row], this, tr("Stop colour"));
        if (chosen.isValid())
            setStopColour(row, chosen);
        return;
    }
}

void ColourScaleEditor::positionEdited(QDoubleSpinBox* box, double value)
{
    for (int row = 0; row < table_->rowCount(); ++row) {
        if (table_->cellWidget(row, 0) == box) {
            positions_[row] = value;
            break;
        }
    }
    revalidate();
}

int ColourScaleEditor::stopCount() const { return table_->rowCount(); }

QDoubleSpinBox* ColourScaleEditor::positionBox(int row) const
{
    return qobject_cast<QDoubleSpinBox*>(table_->cellWidget(row, 0));
}

QPushButton* ColourScaleEditor::colourButton(int row) const
{
    return qobject_cast<QPushButton*>(table_->cellWidget(row, 1));
}

QColor ColourScaleEditor::stopColour(int row) const
{
    return row >= 0 && row < colours_.size() ? colours_[row] : QColor();
}

void ColourScaleEditor::setStopColour(int row, const QColor& colour)
{
    if (row < 0 || row >= colours_.size() || !colour.isValid())
        return;
    colours_[row] = colour.toRgb();
    paintSwatch(colourButton(row), colours_[row]);
    revalidate();
}

int ColourScaleEditor::addStop()
{
    std::vector<double> positions;
    for (double p : positions_)
        positions.push_back(p);
    std::sort(positions.begin(), positions.end());
    double position;
    if (positions.empty() || positions.front() > 0.0) {
        position = 0.0; // the ends come first: without them no scale is valid
    } else if (positions.back() < 1.0) {
        position = 1.0;
    } else {
        std::size_t widest = 0;
        for (std::size_t i = 1; i + 1 < positions.size(); ++i) {
            if (positions[i + 1] - positions[i] > positions[widest + 1] - positions[widest])
                widest = i;
        }
        position = (positions[widest] + positions[widest + 1]) / 2;
    }
    // The new row goes where its position sorts, so the table stays readable.
    int row = 0;
    while (row < stopCount() && positions_[row] <= position)
        ++row;
    const auto c = scale().colourAt(position);
    insertRow(row, position, QColor(c[0], c[1], c[2]));
    table_->selectRow(row);
    revalidate();
    return row;
}

void ColourScaleEditor::removeStop()
{
    if (stopCount() == 0)
        return;
    int row = table_->currentRow();
    if (row < 0 || row >= stopCount())
        row = stopCount() - 1;
    table_->removeRow(row);
    positions_.remove(row);
    colours_.remove(row);
    revalidate();
}

ColourScale ColourScaleEditor::scale() const { return edited_ ? *edited_ : lastValid_; }

QString ColourScaleEditor::problem() const { return problem_; }

void ColourScaleEditor::revalidate()
{
    std::vector<ColourStop> stops;
    for (int row = 0; row < stopCount(); ++row) {
        const QColor& c = colours_[row];
        stops.push_back({positions_[row], static_cast<std::uint8_t>(c.red()),
                         static_cast<std::uint8_t>(c.green()), static_cast<std::uint8_t>(c.blue())});
    }
    edited_.reset();
    problem_.clear();
    const QString name = nameEdit_->text().trimmed();
    if (name.isEmpty()) {
        problem_ = tr("The scale needs a name.");
    } else if (stops.size() < 2) {
        problem_ = tr("A scale needs at least two stops.");
    } else {
        try {
            edited_ = ColourScale(name.toStdString(), std::move(stops), symmetricBox_->isChecked());
            lastValid_ = *edited_;
        } catch (const std::invalid_argument&) {
            problem_ = tr("The stops must start at position 0 and end at position 1.");
        }
    }
    message_->setText(problem_);
    message_->setVisible(!problem_.isEmpty());
    buttons_->button(QDialogButtonBox::Ok)->setEnabled(edited_.has_value());
    removeButton_->setEnabled(stopCount() > 0);
    static_cast<GradientPreview*>(preview_)->showScale(edited_);
    emit scaleEdited();
}

} // namespace scandiff::gui
