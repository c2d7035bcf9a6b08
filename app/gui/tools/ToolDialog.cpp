// SPDX-License-Identifier: GPL-3.0-or-later
#include "tools/ToolDialog.h"

#include <QCheckBox>
#include <QComboBox>
#include <QDialogButtonBox>
#include <QDoubleSpinBox>
#include <QFormLayout>
#include <QLabel>
#include <QSpinBox>
#include <QVBoxLayout>

#include <cmath>
#include <limits>

namespace scandiff::gui {

namespace {

QString helpText(const ParameterSpec& p)
{
    QString text = QString::fromStdString(p.description);
    if (!p.unit.empty())
        text += QString(" (%1)").arg(QString::fromStdString(p.unit));
    return text;
}

double clampToWidget(double v, double fallback)
{
    return std::isfinite(v) ? v : fallback;
}

} // namespace

ToolDialog::ToolDialog(const ToolSpec& tool, QWidget* parent) : QDialog(parent), tool_(tool)
{
    setWindowTitle(QString::fromStdString(tool.title));
    auto* layout = new QVBoxLayout(this);
    auto* description = new QLabel(QString::fromStdString(tool.description), this);
    description->setWordWrap(true);
    layout->addWidget(description);
    auto* form = new QFormLayout;
    layout->addLayout(form);
    for (const ParameterSpec& p : tool.parameters) {
        QWidget* editor = nullptr;
        switch (p.type) {
        case ParameterType::Integer: {
            auto* box = new QSpinBox(this);
            const double lo = clampToWidget(p.minimum, std::numeric_limits<int>::min());
            const double hi = clampToWidget(p.maximum, std::numeric_limits<int>::max());
            box->setRange(static_cast<int>(std::max<double>(lo, std::numeric_limits<int>::min())),
                          static_cast<int>(std::min<double>(hi, std::numeric_limits<int>::max())));
            box->setValue(static_cast<int>(std::get<std::int64_t>(p.defaultValue)));
            if (!p.unit.empty())
                box->setSuffix(" " + QString::fromStdString(p.unit));
            editor = box;
            break;
        }
        case ParameterType::Real: {
            auto* box = new QDoubleSpinBox(this);
            box->setDecimals(6);
            box->setRange(clampToWidget(p.minimum, -1e12), clampToWidget(p.maximum, 1e12));
            box->setValue(std::get<double>(p.defaultValue));
            if (!p.unit.empty())
                box->setSuffix(" " + QString::fromStdString(p.unit));
            editor = box;
            break;
        }
        case ParameterType::Boolean: {
            auto* box = new QCheckBox(this);
            box->setChecked(std::get<bool>(p.defaultValue));
            editor = box;
            break;
        }
        case ParameterType::Choice: {
            auto* box = new QComboBox(this);
            for (const auto& c : p.choices)
                box->addItem(QString::fromStdString(c));
            box->setCurrentText(QString::fromStdString(std::get<std::string>(p.defaultValue)));
            editor = box;
            break;
        }
        }
        editor->setObjectName(QString::fromStdString(p.name));
        editor->setToolTip(helpText(p));
        form->addRow(QString::fromStdString(p.label), editor);
        editors_[p.name] = editor;
    }
    auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel, this);
    connect(buttons, &QDialogButtonBox::accepted, this, &QDialog::accept);
    connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
    layout->addWidget(buttons);
}

std::map<std::string, std::string> ToolDialog::values() const
{
    std::map<std::string, std::string> out;
    for (const ParameterSpec& p : tool_.parameters) {
        QWidget* editor = editors_.at(p.name);
        switch (p.type) {
        case ParameterType::Integer:
            out[p.name] = std::to_string(static_cast<QSpinBox*>(editor)->value());
            break;
        case ParameterType::Real:
            out[p.name] = ParameterSpec::format(static_cast<QDoubleSpinBox*>(editor)->value());
            break;
        case ParameterType::Boolean:
            out[p.name] = static_cast<QCheckBox*>(editor)->isChecked() ? "true" : "false";
            break;
        case ParameterType::Choice:
            out[p.name] = static_cast<QComboBox*>(editor)->currentText().toStdString();
            break;
        }
    }
    return out;
}

QWidget* ToolDialog::editor(const std::string& parameterName) const
{
    const auto it = editors_.find(parameterName);
    return it == editors_.end() ? nullptr : it->second;
}

} // namespace scandiff::gui
