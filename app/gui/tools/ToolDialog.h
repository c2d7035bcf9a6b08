// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A plugin tool's parameter dialog: its description above a ParameterForm
//! generated from the tool's declarations (ToolSpec).

#include <scandiff/core/ToolRegistry.h>

#include <QDialog>

#include <map>
#include <string>

class QWidget;

namespace scandiff::gui {

class ParameterForm;

class ToolDialog : public QDialog
{
    Q_OBJECT
public:
    explicit ToolDialog(const ToolSpec& tool, QWidget* parent = nullptr);

    //! The widgets' values as text, keyed by parameter name (the CLI's form).
    std::map<std::string, std::string> values() const;
    //! The widget editing `parameterName` (tests drive it), null if unknown.
    QWidget* editor(const std::string& parameterName) const;

private:
    ParameterForm* form_;
};

} // namespace scandiff::gui
