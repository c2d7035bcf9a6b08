// SPDX-License-Identifier: GPL-3.0-or-later
#include "controllers/GlobalShiftDialog.h"

#include <QCheckBox>
#include <QDialogButtonBox>
#include <QDoubleSpinBox>
#include <QFileInfo>
#include <QFormLayout>
#include <QLabel>
#include <QPushButton>
#include <QSettings>
#include <QVBoxLayout>

namespace scandiff::gui {

namespace {
constexpr const char* kLastOrigin = "io/lastGlobalShift";
}

GlobalShiftDialog::GlobalShiftDialog(const QString& file, const Eigen::Vector3d& suggested, const Eigen::Vector3d& example, QWidget* parent)
    : QDialog(parent)
{
    setWindowTitle(tr("Global shift"));
    setObjectName("globalShift");
    auto* layout = new QVBoxLayout(this);
    auto* text = new QLabel(tr("<b>%1</b> has large coordinates (a point: %2, %3, %4).<br>"
                               "Its points are kept in double precision whatever you choose; the shift is the origin "
                               "their local coordinates are relative to. Give the epochs of one survey the same origin "
                               "to work in one local frame.")
                                .arg(QFileInfo(file).fileName())
                                .arg(example.x(), 0, 'f', 3)
                                .arg(example.y(), 0, 'f', 3)
                                .arg(example.z(), 0, 'f', 3),
                            this);
    text->setWordWrap(true);
    layout->addWidget(text);
    auto* form = new QFormLayout;
    const char* names[3] = {"X", "Y", "Z"};
    for (int a = 0; a < 3; ++a) {
        boxes_[a] = new QDoubleSpinBox(this);
        boxes_[a]->setObjectName(QString("origin%1").arg(names[a]));
        boxes_[a]->setRange(-1e10, 1e10);
        boxes_[a]->setDecimals(3);
        boxes_[a]->setSuffix(" m");
        form->addRow(tr("Origin %1").arg(names[a]), boxes_[a]);
    }
    layout->addLayout(form);
    setOrigin(suggested);
    wholeSession_ = new QCheckBox(tr("Use this origin for every file of this session without asking"), this);
    layout->addWidget(wholeSession_);
    auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel, this);
    QPushButton* sameAsLast = buttons->addButton(tr("Same as last"), QDialogButtonBox::ActionRole);
    sameAsLast->setObjectName("sameAsLast");
    const std::optional<Eigen::Vector3d> last = lastOrigin();
    sameAsLast->setEnabled(last.has_value());
    connect(sameAsLast, &QPushButton::clicked, this, [this, last] {
        if (last)
            setOrigin(*last);
    });
    connect(buttons, &QDialogButtonBox::accepted, this, &QDialog::accept);
    connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
    layout->addWidget(buttons);
}

Eigen::Vector3d GlobalShiftDialog::origin() const { return {boxes_[0]->value(), boxes_[1]->value(), boxes_[2]->value()}; }

void GlobalShiftDialog::setOrigin(const Eigen::Vector3d& origin)
{
    for (int a = 0; a < 3; ++a)
        boxes_[a]->setValue(origin[a]);
}

bool GlobalShiftDialog::forTheWholeSession() const { return wholeSession_->isChecked(); }

std::optional<Eigen::Vector3d> GlobalShiftDialog::lastOrigin()
{
    const QList<QVariant> values = QSettings().value(kLastOrigin).toList();
    if (values.size() != 3)
        return std::nullopt;
    return Eigen::Vector3d(values[0].toDouble(), values[1].toDouble(), values[2].toDouble());
}

void GlobalShiftDialog::rememberOrigin(const Eigen::Vector3d& origin)
{
    QSettings().setValue(kLastOrigin, QList<QVariant>{origin.x(), origin.y(), origin.z()});
}

} // namespace scandiff::gui
