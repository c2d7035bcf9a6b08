// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A tool's dialog: its description, one picker per declared input (a list of
//! the open entities of the right kind, several ticked for a repeated input),
//! a ParameterForm generated from the tool's declarations (ToolSpec), and for
//! a parameter picked in the view a PickedPointsPanel with the tool's preview.

#include "document/Document.h"

#include <scandiff/core/ToolRegistry.h>

#include <QDialog>

#include <map>
#include <string>
#include <vector>

class QComboBox;
class QListWidget;
class QWidget;

namespace scandiff::gui {

class ParameterForm;
class PickedPointsPanel;

//! The entities chosen for each input role of a tool.
using ToolInputChoice = std::map<std::string, std::vector<EntityId>>;

//! Entities of `document` a tool's input accepts (meshes only for a Mesh input,
//! clouds and meshes for a Cloud input), in the document's order.
std::vector<EntityId> acceptedEntities(const Document& document, const InputSpec& input);

//! The inputs a tool proposes when started with `selection` (the tree's
//! selected entities, current first): each role takes the first accepted
//! selected entity not used by an earlier role, else the last accepted one
//! added; a repeated role takes every accepted selected entity left, or,
//! with fewer than two selected, every accepted entity left.
ToolInputChoice proposeInputs(const Document& document, const ToolSpec& tool, const std::vector<EntityId>& selection);

class ToolDialog : public QDialog
{
    Q_OBJECT
public:
    ToolDialog(const ToolSpec& tool, const Document& document, const ToolInputChoice& proposed, QWidget* parent = nullptr);

    //! The widgets' values as text, keyed by parameter name (the CLI's form).
    std::map<std::string, std::string> values() const;
    //! The entities picked for each role.
    ToolInputChoice inputs() const;
    //! The widget editing `parameterName` (tests drive it), null if unknown.
    QWidget* editor(const std::string& parameterName) const;
    ParameterForm* form() const { return form_; }
    //! The panel of the parameter picked in the view, null if the tool has none.
    PickedPointsPanel* pickedPoints() const { return picked_; }
    //! A point picked in the view (point `index` of entity `id`), for the panel.
    void pointPicked(EntityId id, std::size_t index);

signals:
    //! The view's pick mode should follow the panel's Pick button.
    void pickModeRequested(bool on);

private:
    //! Thresholds on a field proposed from the field's display (see ParameterSpec::thresholdOfField).
    void proposeThresholds();
    //! Runs the tool's preview on the current inputs and values, into the panel.
    void refreshPreview();
    EntityId chosenEntity(const std::string& role) const;

    struct Picker
    {
        std::string role;
        QComboBox* single = nullptr;
        QListWidget* several = nullptr;
    };
    const ToolSpec& tool_;
    const Document& document_;
    std::vector<Picker> pickers_;
    ParameterForm* form_;
    PickedPointsPanel* picked_ = nullptr;
    std::string pickedParameter_;
};

} // namespace scandiff::gui
