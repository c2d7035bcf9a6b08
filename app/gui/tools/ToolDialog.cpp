// SPDX-License-Identifier: GPL-3.0-or-later
#include "tools/ToolDialog.h"

#include "tools/ParameterForm.h"

#include <QLabel>
#include <QVBoxLayout>

namespace scandiff::gui {

ToolDialog::ToolDialog(const ToolSpec& tool, QWidget* parent) : QDialog(parent)
{
    setWindowTitle(QString::fromStdString(tool.title));
    auto* layout = new QVBoxLayout(this);
    auto* description = new QLabel(QString::fromStdString(tool.description), this);
    description->setWordWrap(true);
    layout->addWidget(description);
    form_ = new ParameterForm(tool.parameters, this);
    addFormAndButtons(*this, *layout, form_);
}

std::map<std::string, std::string> ToolDialog::values() const { return form_->values(); }

QWidget* ToolDialog::editor(const std::string& parameterName) const { return form_->editor(parameterName); }

} // namespace scandiff::gui
