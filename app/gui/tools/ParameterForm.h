// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A form generated from parameter declarations (ParameterSpec): one widget per
//! parameter, initialised with its default, limited to its range, with its help
//! as tooltip. An optional parameter gets a checkbox that switches it on;
//! alternatives are one choice showing only the chosen one's row; a parameter
//! used only with another shows only when that one is given; a 0 that means
//! "automatic" says so. There
//! is no second copy of any default: values() gives text the declarations parse,
//! exactly as the command line's options do.

#include "document/Document.h"

#include <scandiff/core/ToolRegistry.h>

#include <QWidget>

#include <map>
#include <string>
#include <vector>

class QCheckBox;
class QComboBox;
class QFormLayout;
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

    //! The combo box choosing among the alternatives of `group`, null if none.
    QComboBox* groupChoice(const std::string& group) const
    {
        const auto it = groupChoices_.find(group);
        return it == groupChoices_.end() ? nullptr : it->second;
    }
    //! Whether a parameter's row is shown (its alternative chosen, its condition met).
    bool isShown(const std::string& parameterName) const { return rows_.count(parameterName) && !rows_.at(parameterName)->isHidden(); }

private:
    //! Whether `name` is given: an optional one switched on, a switch on, anything else.
    bool isGiven(const std::string& name) const;
    //! Whether `p.usedWith` holds.
    bool conditionHolds(const ParameterSpec& p) const;
    void updateVisibility();

    std::vector<ParameterSpec> parameters_;
    QFormLayout* form_ = nullptr;
    std::map<std::string, QWidget*> editors_;
    std::map<std::string, QCheckBox*> enablers_;
    std::map<std::string, QWidget*> rows_;              //!< the field widget of each parameter's row
    std::map<std::string, QComboBox*> groupChoices_;    //!< by alternative group
};

//! Fills a field parameter's list with the fields of `item` (none if null),
//! its active field selected (what the user is looking at), else the text
//! typed before if it is one of them.
void listFieldsOf(QComboBox* box, const Document::Item* item);

//! Puts `form` in a scroll area and OK/Cancel buttons below it, the bottom of
//! every parameter dialog.
void addFormAndButtons(QDialog& dialog, QVBoxLayout& layout, ParameterForm* form);

} // namespace scandiff::gui
