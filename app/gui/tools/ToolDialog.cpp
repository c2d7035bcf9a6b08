// SPDX-License-Identifier: GPL-3.0-or-later
#include "tools/ToolDialog.h"

#include "tools/ParameterForm.h"
#include "tools/PickedPointsPanel.h"

#include <scandiff/core/Error.h>

#include <QComboBox>
#include <QFormLayout>
#include <QGroupBox>
#include <QLabel>
#include <QListWidget>
#include <QVBoxLayout>

#include <algorithm>

namespace scandiff::gui {

std::vector<EntityId> acceptedEntities(const Document& document, const InputSpec& input)
{
    std::vector<EntityId> out;
    for (EntityId id : document.ids())
        if (document.item(id).hasData() && (input.kind != DataKind::Mesh || document.item(id).mesh()))
            out.push_back(id);
    return out;
}

ToolInputChoice proposeInputs(const Document& document, const ToolSpec& tool, const std::vector<EntityId>& selection)
{
    ToolInputChoice choice;
    std::vector<EntityId> used;
    const auto isUsed = [&](EntityId id) { return std::find(used.begin(), used.end(), id) != used.end(); };
    // As in CloudCompare and the C2C dialog: the selected cloud is the one
    // compared or moved, the reference the first opened of the others (the
    // older epoch). So the "reference" role chooses last.
    std::vector<const InputSpec*> order;
    for (const InputSpec& input : tool.inputs)
        if (input.role != "reference")
            order.push_back(&input);
    for (const InputSpec& input : tool.inputs)
        if (input.role == "reference")
            order.push_back(&input);
    for (const InputSpec* inputPointer : order) {
        const InputSpec& input = *inputPointer;
        const std::vector<EntityId> accepted = acceptedEntities(document, input);
        const auto accepts = [&](EntityId id) { return std::find(accepted.begin(), accepted.end(), id) != accepted.end(); };
        std::vector<EntityId>& picked = choice[input.role];
        for (EntityId id : selection)
            if (accepts(id) && !isUsed(id)) {
                picked.push_back(id);
                used.push_back(id);
                if (!input.repeated)
                    break;
            }
        // A repeated role (merge, stations) with fewer than two chosen: every
        // accepted entity left, in the document's order.
        if (input.repeated && picked.size() < 2) {
            for (EntityId id : accepted)
                if (!isUsed(id) && std::find(picked.begin(), picked.end(), id) == picked.end()) {
                    picked.push_back(id);
                    used.push_back(id);
                }
        }
        if (picked.empty() && input.role == "reference") {
            for (EntityId id : accepted)
                if (!isUsed(id)) {
                    picked.push_back(id);
                    used.push_back(id);
                    break;
                }
        } else if (picked.empty() && !input.optional) {
            for (auto it = accepted.rbegin(); it != accepted.rend(); ++it)
                if (!isUsed(*it)) {
                    picked.push_back(*it);
                    used.push_back(*it);
                    break;
                }
        }
    }
    return choice;
}

ToolDialog::ToolDialog(const ToolSpec& tool, const Document& document, const ToolInputChoice& proposed, QWidget* parent)
    : QDialog(parent), tool_(tool), document_(document)
{
    setWindowTitle(QString::fromStdString(tool.title));
    auto* layout = new QVBoxLayout(this);
    auto* description = new QLabel(QString::fromStdString(tool.description), this);
    description->setWordWrap(true);
    layout->addWidget(description);

    auto* inputsBox = new QGroupBox(tr("Inputs"), this);
    auto* inputsForm = new QFormLayout(inputsBox);
    for (const InputSpec& input : tool.inputs) {
        Picker picker;
        picker.role = input.role;
        const auto it = proposed.find(input.role);
        const std::vector<EntityId> chosen = it == proposed.end() ? std::vector<EntityId>{} : it->second;
        const QString tip = QString::fromStdString(input.description);
        if (input.repeated) {
            picker.several = new QListWidget(inputsBox);
            for (EntityId id : acceptedEntities(document, input)) {
                auto* row = new QListWidgetItem(document.item(id).name, picker.several);
                row->setData(Qt::UserRole, id);
                row->setFlags(row->flags() | Qt::ItemIsUserCheckable);
                const bool on = std::find(chosen.begin(), chosen.end(), id) != chosen.end();
                row->setCheckState(on ? Qt::Checked : Qt::Unchecked);
            }
            picker.several->setMaximumHeight(120);
            picker.several->setObjectName(QString::fromStdString("input-" + input.role));
            picker.several->setToolTip(tip);
            inputsForm->addRow(QString::fromStdString(input.label), picker.several);
        } else {
            picker.single = new QComboBox(inputsBox);
            if (input.optional)
                picker.single->addItem(tr("(none)"), kNoEntity);
            for (EntityId id : acceptedEntities(document, input))
                picker.single->addItem(document.item(id).name + (document.item(id).mesh() ? tr(" (mesh)") : QString()), id);
            if (!chosen.empty())
                picker.single->setCurrentIndex(std::max(0, picker.single->findData(chosen.front())));
            picker.single->setObjectName(QString::fromStdString("input-" + input.role));
            picker.single->setToolTip(tip);
            inputsForm->addRow(QString::fromStdString(input.label), picker.single);
        }
        pickers_.push_back(picker);
    }
    layout->addWidget(inputsBox);

    form_ = new ParameterForm(tool.parameters, this);
    // A parameter picked in the view: the panel between the form and the buttons.
    for (const ParameterSpec& p : tool.parameters)
        if (!p.pickedOn.empty() && !picked_) {
            picked_ = new PickedPointsPanel(p, tool.inputs, this);
            pickedParameter_ = p.name;
        }
    addFormAndButtons(*this, *layout, form_);
    if (picked_) {
        layout->insertWidget(layout->count() - 1, picked_);
        connect(picked_, &PickedPointsPanel::pickModeRequested, this, &ToolDialog::pickModeRequested);
        connect(picked_, &PickedPointsPanel::changed, this, [this] {
            form_->setValue(pickedParameter_, picked_->text());
            refreshPreview();
        });
        // Another degree-of-freedom setting changes the fit: the preview follows.
        for (const ParameterSpec& p : tool.parameters)
            if (QWidget* editor = form_->editor(p.name); editor && p.name != pickedParameter_) {
                if (auto* box = qobject_cast<QComboBox*>(editor))
                    connect(box, &QComboBox::currentTextChanged, this, &ToolDialog::refreshPreview);
            }
        connect(this, &QDialog::finished, this, [this] { emit pickModeRequested(false); });
        refreshPreview();
        // Tall enough for the form and the picks, at the right of the window,
        // so that the view stays in sight while picking.
        resize(std::max(width(), 560), 800);
        if (parent)
            move(parent->geometry().right() - width() - 8, parent->geometry().top() + 40);
    }

    // A parameter naming a field lists the fields of the entity picked for its
    // role, and follows the picker.
    for (const ParameterSpec& p : tool.parameters) {
        if (p.fieldOfInput.empty())
            continue;
        auto* box = qobject_cast<QComboBox*>(form_->editor(p.name));
        const auto picker = std::find_if(pickers_.begin(), pickers_.end(), [&](const Picker& k) { return k.role == p.fieldOfInput; });
        if (!box || picker == pickers_.end() || !picker->single)
            continue;
        QComboBox* entities = picker->single;
        const auto fill = [box, entities, &document] { listFieldsOf(box, document.find(entities->currentData().toInt())); };
        fill();
        connect(entities, QOverload<int>::of(&QComboBox::currentIndexChanged), box, fill);
    }
    proposeThresholds();
}

void ToolDialog::proposeThresholds()
{
    // A threshold on a field starts at the bound the user dragged on that
    // field's histogram: the upper one when only it moved (the low values
    // shown), else the lower one.
    for (const ParameterSpec& p : tool_.parameters) {
        if (p.thresholdOfField.empty())
            continue;
        const ParameterSpec* field = tool_.parameter(p.thresholdOfField);
        auto* fieldBox = field ? qobject_cast<QComboBox*>(form_->editor(field->name)) : nullptr;
        if (!fieldBox)
            continue;
        const EntityId id = chosenEntity(field->fieldOfInput);
        const Document::Item* item = document_.find(id);
        const std::string name = fieldBox->currentText().toStdString();
        const ScalarField* values = item ? item->points().field(name) : nullptr;
        if (!values)
            continue;
        const ValueRange range = values->range();
        const FieldDisplay display = document_.fieldDisplay(id, name);
        if (display.high < range.max)
            form_->setValue(p.name, QString::number(display.high, 'g', 10));
        else if (display.low > range.min)
            form_->setValue(p.name, QString::number(display.low, 'g', 10));
    }
}

std::map<std::string, std::string> ToolDialog::values() const { return form_->values(); }

EntityId ToolDialog::chosenEntity(const std::string& role) const
{
    const ToolInputChoice choice = inputs();
    const auto it = choice.find(role);
    return it == choice.end() || it->second.empty() ? kNoEntity : it->second.front();
}

void ToolDialog::pointPicked(EntityId id, std::size_t index)
{
    const Document::Item* item = document_.find(id);
    if (!picked_ || !item || index >= item->points().size())
        return;
    picked_->addPoint(id, item->points().globalPosition(index), [this](const std::string& role) { return chosenEntity(role); });
}

void ToolDialog::refreshPreview()
{
    if (!picked_ || !tool_.preview)
        return;
    try {
        ToolInputs inputs;
        for (const auto& [role, ids] : this->inputs())
            for (EntityId id : ids)
                if (const Document::Item* item = document_.find(id))
                    inputs.add(role, item->entity);
        picked_->showPreview(tool_.preview(inputs, tool_.resolve(values())));
    } catch (const std::exception& e) {
        picked_->showPreviewError(QString::fromStdString(e.what()));
    }
}

ToolInputChoice ToolDialog::inputs() const
{
    ToolInputChoice choice;
    for (const Picker& picker : pickers_) {
        std::vector<EntityId>& ids = choice[picker.role];
        if (picker.single) {
            const EntityId id = picker.single->currentData().toInt();
            if (id != kNoEntity && picker.single->currentIndex() >= 0)
                ids.push_back(id);
        } else {
            for (int r = 0; r < picker.several->count(); ++r)
                if (picker.several->item(r)->checkState() == Qt::Checked)
                    ids.push_back(picker.several->item(r)->data(Qt::UserRole).toInt());
        }
    }
    return choice;
}

QWidget* ToolDialog::editor(const std::string& parameterName) const { return form_->editor(parameterName); }

} // namespace scandiff::gui
