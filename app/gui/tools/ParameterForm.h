// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A form generated from parameter declarations (ParameterSpec): one widget per
//! parameter, initialised with its default, limited to its range, with its help
//! as tooltip. An optional parameter gets a checkbox that switches it on. There
//! is no second copy of any default: values() gives text the declarations parse,
//! exactly as the command line's options do.

#include <scandiff/core/ToolRegistry.h>

#include <QWidget>

#include <map>
#include <string>
#include <vector>

class QCheckBox;
class QDialog;
class QVBoxLayout;

namespace scandiff::gui {

class ParameterForm : public QWidget
{
    Q_OBJECT
public:
    ParameterForm(const std::vector<ParameterSpec>& parameters, QWidget* parent = nullptr);

    //! The values as text keyed by parameter name; optional parameters that are
    //! switched off are absent (as an option not given on the command line).
    std::map<std::string, std::string> values() const;
    //! Sets a parameter from text (switching an optional one on); false if unknown.
    bool setValue(const std::string& parameterName, const QString& text);
    //! The widget editing `parameterName` (tests drive it), null if unknown.
    QWidget* editor(const std::string& parameterName) const;
    //! The checkbox of an optional parameter, null otherwise.
    QCheckBox* enabler(const std::string& parameterName) const;

private:
    std::vector<ParameterSpec> parameters_;
    std::map<std::string, QWidget*> editors_;
    std::map<std::string, QCheckBox*> enablers_;
};

//! Parameter text as `scandiff-cli` options ("--knn 12 --signed"): flags only
//! when on, so the console's line can be pasted into a batch script.
QString commandLineText(const std::map<std::string, std::string>& parameters);

//! Puts `form` in a scroll area and OK/Cancel buttons below it, the bottom of
//! every parameter dialog.
void addFormAndButtons(QDialog& dialog, QVBoxLayout& layout, ParameterForm* form);

} // namespace scandiff::gui
