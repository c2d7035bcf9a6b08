// SPDX-License-Identifier: GPL-3.0-or-later
#include "tools/ParameterForm.h"

#include <QCheckBox>
#include <QDialog>
#include <QDialogButtonBox>
#include <QScrollArea>
#include <QVBoxLayout>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLineEdit>
#include <QSignalBlocker>
#include <QSpinBox>

#include <algorithm>
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

double finiteOr(double v, double fallback) { return std::isfinite(v) ? v : fallback; }

QWidget* makeEditor(const ParameterSpec& p, QWidget* parent)
{
    switch (p.type) {
    case ParameterType::Integer: {
        auto* box = new QSpinBox(parent);
        box->setRange(static_cast<int>(std::max<double>(finiteOr(p.minimum, INT_MIN), INT_MIN)),
                      static_cast<int>(std::min<double>(finiteOr(p.maximum, INT_MAX), INT_MAX)));
        box->setValue(static_cast<int>(std::get<std::int64_t>(p.defaultValue)));
        if (!p.unit.empty())
            box->setSuffix(" " + QString::fromStdString(p.unit));
        if (!p.zeroMeans.empty() && p.minimum == 0) // the minimum shows as its meaning
            box->setSpecialValueText(QString::fromStdString(p.zeroMeans));
        return box;
    }
    case ParameterType::Real: {
        auto* box = new QDoubleSpinBox(parent);
        box->setDecimals(6);
        box->setRange(finiteOr(p.minimum, -1e12), finiteOr(p.maximum, 1e12));
        box->setValue(std::get<double>(p.defaultValue));
        if (!p.unit.empty())
            box->setSuffix(" " + QString::fromStdString(p.unit));
        if (!p.zeroMeans.empty() && p.minimum == 0)
            box->setSpecialValueText(QString::fromStdString(p.zeroMeans));
        return box;
    }
    case ParameterType::Boolean: {
        auto* box = new QCheckBox(parent);
        box->setChecked(std::get<bool>(p.defaultValue));
        return box;
    }
    case ParameterType::Choice: {
        auto* box = new QComboBox(parent);
        for (const auto& c : p.choices)
            box->addItem(QString::fromStdString(c));
        box->setCurrentText(QString::fromStdString(std::get<std::string>(p.defaultValue)));
        return box;
    }
    case ParameterType::Text: {
        if (!p.suggestions.empty() || !p.fieldOfInput.empty()) {
            // An editable list: the usual values at hand, any other typed.
            auto* box = new QComboBox(parent);
            box->setEditable(true);
            for (const auto& value : p.suggestions)
                box->addItem(QString::fromStdString(value));
            box->setCurrentText(QString::fromStdString(std::get<std::string>(p.defaultValue)));
            return box;
        }
        auto* line = new QLineEdit(QString::fromStdString(std::get<std::string>(p.defaultValue)), parent);
        line->setPlaceholderText(QString::fromStdString(p.description));
        return line;
    }
    }
    return nullptr;
}

std::string editorText(const ParameterSpec& p, QWidget* editor)
{
    switch (p.type) {
    case ParameterType::Integer:
        return std::to_string(static_cast<QSpinBox*>(editor)->value());
    case ParameterType::Real:
        return ParameterSpec::format(static_cast<QDoubleSpinBox*>(editor)->value());
    case ParameterType::Boolean:
        return static_cast<QCheckBox*>(editor)->isChecked() ? "true" : "false";
    case ParameterType::Choice:
        return static_cast<QComboBox*>(editor)->currentText().toStdString();
    case ParameterType::Text:
        if (auto* box = qobject_cast<QComboBox*>(editor))
            return box->currentText().toStdString();
        return static_cast<QLineEdit*>(editor)->text().toStdString();
    }
    return {};
}

} // namespace

ParameterForm::ParameterForm(const std::vector<ParameterSpec>& parameters, QWidget* parent)
    : QWidget(parent), parameters_(parameters)
{
    form_ = new QFormLayout(this);
    form_->setContentsMargins(0, 0, 0, 0);
    for (const ParameterSpec& p : parameters_) {
        QWidget* editor = makeEditor(p, this);
        editor->setObjectName(QString::fromStdString(p.name));
        editor->setToolTip(helpText(p));
        editors_[p.name] = editor;
        // A switch others depend on shows or hides them.
        if (auto* check = qobject_cast<QCheckBox*>(editor))
            connect(check, &QCheckBox::toggled, this, &ParameterForm::updateVisibility);
        if (p.type == ParameterType::Choice) // and so does a choice ("method=alpha")
            if (auto* combo = qobject_cast<QComboBox*>(editor))
                connect(combo, QOverload<int>::of(&QComboBox::currentIndexChanged), this, &ParameterForm::updateVisibility);
        if (!p.optional) {
            form_->addRow(QString::fromStdString(p.label), editor);
            rows_[p.name] = editor;
            continue;
        }
        // Alternatives ("--radius R | --knn K"): one choice, the group's first
        // proposed; only the chosen one's row shows.
        if (!p.alternativeGroup.empty() && !groupChoices_.count(p.alternativeGroup)) {
            auto* choice = new QComboBox(this);
            choice->setObjectName(QString::fromStdString(p.alternativeGroup + "-choice"));
            for (const ParameterSpec& member : parameters_)
                if (member.alternativeGroup == p.alternativeGroup) {
                    choice->addItem(QString::fromStdString(member.label), QString::fromStdString(member.name));
                    choice->setItemData(choice->count() - 1, helpText(member), Qt::ToolTipRole);
                }
            QString title = QString::fromStdString(p.alternativeGroup);
            title[0] = title[0].toUpper();
            form_->addRow(title, choice);
            groupChoices_[p.alternativeGroup] = choice;
            connect(choice, QOverload<int>::of(&QComboBox::currentIndexChanged), this, [this, group = p.alternativeGroup](int) {
                QComboBox* box = groupChoices_.at(group);
                const std::string chosen = box->currentData().toString().toStdString();
                enablers_.at(chosen)->setChecked(true);
            });
        }
        // An optional value: the checkbox says whether it is given at all (hidden
        // for an alternative: the group's choice sets it).
        auto* row = new QWidget(this);
        auto* layout = new QHBoxLayout(row);
        layout->setContentsMargins(0, 0, 0, 0);
        auto* enabler = new QCheckBox(row);
        enabler->setObjectName(QString::fromStdString(p.name + "-enabled"));
        enabler->setToolTip(tr("Use this parameter"));
        layout->addWidget(enabler);
        layout->addWidget(editor, 1);
        editor->setEnabled(false);
        enabler->setVisible(p.alternativeGroup.empty());
        connect(enabler, &QCheckBox::toggled, editor, &QWidget::setEnabled);
        connect(enabler, &QCheckBox::toggled, this, &ParameterForm::updateVisibility);
        enablers_[p.name] = enabler;
        rows_[p.name] = row;
        form_->addRow(QString::fromStdString(p.label), row);
    }
    // Switching one alternative on switches the others of its group off and
    // moves the group's choice to it.
    std::map<std::string, std::vector<QCheckBox*>> groups;
    for (const ParameterSpec& p : parameters_)
        if (p.optional && !p.alternativeGroup.empty())
            groups[p.alternativeGroup].push_back(enablers_.at(p.name));
    for (const auto& [group, members] : groups) {
        QComboBox* choice = groupChoices_.at(group);
        for (std::size_t i = 0; i < members.size(); ++i) {
            QCheckBox* member = members[i];
            connect(member, &QCheckBox::toggled, this, [member, members, choice, i](bool on) {
                if (!on)
                    return;
                for (QCheckBox* other : members)
                    if (other != member)
                        other->setChecked(false);
                const QSignalBlocker quiet(choice);
                choice->setCurrentIndex(static_cast<int>(i));
            });
        }
        members.front()->setChecked(true);
    }
    updateVisibility();
}

bool ParameterForm::isGiven(const std::string& name) const
{
    const auto spec = std::find_if(parameters_.begin(), parameters_.end(), [&](const ParameterSpec& p) { return p.name == name; });
    if (spec == parameters_.end())
        return true;
    if (spec->optional && !enablers_.at(name)->isChecked())
        return false;
    if (!spec->usedWith.empty() && !conditionHolds(*spec))
        return false; // chosen, but inside a part that does not apply
    if (spec->type == ParameterType::Boolean)
        return static_cast<QCheckBox*>(editors_.at(name))->isChecked();
    return true;
}

bool ParameterForm::conditionHolds(const ParameterSpec& p) const
{
    if (p.usedWith.empty())
        return true;
    const bool negated = p.usedWith.front() == '!';
    const std::string condition = negated ? p.usedWith.substr(1) : p.usedWith;
    const std::size_t equals = condition.find('=');
    bool given = false;
    if (equals == std::string::npos) {
        given = isGiven(condition);
    } else {
        // "method=alpha": the choice is given and holds that value.
        const std::string name = condition.substr(0, equals);
        const auto spec = std::find_if(parameters_.begin(), parameters_.end(), [&](const ParameterSpec& s) { return s.name == name; });
        given = spec != parameters_.end() && isGiven(name) && editorText(*spec, editors_.at(name)) == condition.substr(equals + 1);
    }
    return negated ? !given : given;
}

void ParameterForm::updateVisibility()
{
    for (const ParameterSpec& p : parameters_) {
        const bool chosen = p.alternativeGroup.empty() || enablers_.at(p.name)->isChecked();
        const bool shown = chosen && conditionHolds(p);
        QWidget* row = rows_.at(p.name);
        row->setVisible(shown);
        if (QWidget* label = form_->labelForField(row))
            label->setVisible(shown);
    }
    // A group's choice shows when its members apply at all.
    for (const auto& [group, choice] : groupChoices_) {
        bool applies = false;
        for (const ParameterSpec& p : parameters_)
            applies = applies || (p.alternativeGroup == group && conditionHolds(p));
        choice->setVisible(applies);
        if (QWidget* label = form_->labelForField(choice))
            label->setVisible(applies);
    }
}

std::map<std::string, std::string> ParameterForm::values() const
{
    std::map<std::string, std::string> out;
    for (const ParameterSpec& p : parameters_) {
        if (p.optional && !enablers_.at(p.name)->isChecked())
            continue;
        if (!conditionHolds(p))
            continue; // in a part that does not apply: its default, not a hidden value
        out[p.name] = editorText(p, editors_.at(p.name));
    }
    return out;
}

bool ParameterForm::setValue(const std::string& parameterName, const QString& text)
{
    const auto it = editors_.find(parameterName);
    if (it == editors_.end())
        return false;
    QWidget* editor = it->second;
    if (auto* box = qobject_cast<QSpinBox*>(editor))
        box->setValue(text.toInt());
    else if (auto* real = qobject_cast<QDoubleSpinBox*>(editor))
        real->setValue(text.toDouble());
    else if (auto* check = qobject_cast<QCheckBox*>(editor))
        check->setChecked(text == "true" || text == "1");
    else if (auto* combo = qobject_cast<QComboBox*>(editor))
        combo->setCurrentText(text); // a choice's item, or an editable list's text
    else if (auto* line = qobject_cast<QLineEdit*>(editor))
        line->setText(text);
    if (QCheckBox* enabler = this->enabler(parameterName))
        enabler->setChecked(true);
    return true;
}

QWidget* ParameterForm::editor(const std::string& parameterName) const
{
    const auto it = editors_.find(parameterName);
    return it == editors_.end() ? nullptr : it->second;
}

QCheckBox* ParameterForm::enabler(const std::string& parameterName) const
{
    const auto it = enablers_.find(parameterName);
    return it == enablers_.end() ? nullptr : it->second;
}

void listFieldsOf(QComboBox* box, const Document::Item* item)
{
    const QString typed = box->currentText();
    box->clear();
    if (!item)
        return;
    for (const auto& f : item->points().fields())
        box->addItem(QString::fromStdString(f.name()));
    if (!item->display.activeField.empty())
        box->setCurrentText(QString::fromStdString(item->display.activeField));
    else if (!typed.isEmpty() && box->findText(typed) >= 0)
        box->setCurrentText(typed);
}

void addFormAndButtons(QDialog& dialog, QVBoxLayout& layout, ParameterForm* form)
{
    auto* scroll = new QScrollArea(&dialog);
    scroll->setWidget(form);
    scroll->setWidgetResizable(true);
    scroll->setFrameShape(QFrame::NoFrame);
    layout.addWidget(scroll, 1);
    auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel, &dialog);
    QObject::connect(buttons, &QDialogButtonBox::accepted, &dialog, &QDialog::accept);
    QObject::connect(buttons, &QDialogButtonBox::rejected, &dialog, &QDialog::reject);
    layout.addWidget(buttons);
}

} // namespace scandiff::gui
