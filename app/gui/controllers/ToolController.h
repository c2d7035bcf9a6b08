// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Runs a tool from the GUI, whatever its shape: the generated dialog (input
//! pickers and parameters), then the tool's own run function on a worker
//! thread with progress and Cancel; each output goes where its declaration
//! says: a cloud or mesh under the first input (or in its place when it
//! updates it), a table to a table window, a transformation to the console.
//! No algorithm code lives here.

#include "document/Document.h"
#include "tools/TableDialog.h"
#include "tools/ToolDialog.h"

#include <scandiff/core/ToolRegistry.h>

#include <QObject>
#include <QPointer>

class QWidget;

namespace scandiff::gui {

class ToolController : public QObject
{
    Q_OBJECT
public:
    ToolController(const ToolSpec& tool, Document& document, QWidget* parentWindow);
    ~ToolController() override;

    const ToolSpec& tool() const { return tool_; }
    //! Asks for the inputs (proposed from `selection`, the tree's selected
    //! entities, current first) and the parameters, then runs.
    void runInteractively(const std::vector<EntityId>& selection);
    //! Runs with the given parameter text (the dialog's or a test's) on `input`
    //! as the tool's first input. Returns false and emits failed() on error or cancellation.
    bool run(EntityId input, const std::map<std::string, std::string>& parameters);
    //! The same with entities for every role.
    bool run(const ToolInputChoice& inputs, const std::map<std::string, std::string>& parameters);
    //! The dialog open for picking in the view (a tool with a picked
    //! parameter opens it without blocking the view), or null.
    ToolDialog* openDialog() const { return openDialog_; }

public slots:
    //! A point picked in the view: for the open dialog, if it picks.
    void pointPicked(EntityId id, std::size_t index);

signals:
    //! The view's pick mode should be on (a dialog picks points) or off.
    void pickModeRequested(bool on);
    void finished(const QString& summary);
    void failed(const QString& message);
    //! The user stopped a run: no error, nothing changed.
    void cancelled(const QString& message);
    //! The entity the run created or changed last (the tree selects it).
    void resultReady(EntityId id);
    //! The run's table outputs, for the window that shows them (and saves them as CSV).
    void tablesReady(const QString& title, const scandiff::gui::NamedTables& tables);

private:
    //! "scandiff-cli TOOL IN --role FILE ... --param value": what the console shows.
    QString commandLine(const ToolInputChoice& inputs, const std::map<std::string, std::string>& parameters) const;

    const ToolSpec& tool_;
    Document& document_;
    QWidget* parentWindow_;
    QPointer<ToolDialog> openDialog_;
};

} // namespace scandiff::gui

// Tables travel in signals (the table window, tests' signal spies).
Q_DECLARE_METATYPE(scandiff::gui::NamedTables)

Q_DECLARE_METATYPE(scandiff::Drawing)
