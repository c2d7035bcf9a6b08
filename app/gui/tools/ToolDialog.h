// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A parameter dialog generated from a tool's declarations (ToolSpec): one
//! widget per ParameterSpec, initialised with its default, limited to its range,
//! with its help as tooltip. There is no second copy of any default: the values
//! go back through ToolSpec::resolve, exactly as the CLI's options do.

#include <scandiff/core/ToolRegistry.h>

#include <QDialog>

#include <map>
#include <string>

class QWidget;

namespace scandiff::gui {

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
    const ToolSpec& tool_;
    std::map<std::string, QWidget*> editors_;
};

} // namespace scandiff::gui
