// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Runs a plugin tool from the GUI: its generated dialog, then the tool's own
//! run function on a worker thread with progress and Cancel; the result is
//! added to the document under its input. No algorithm code lives here.

#include "document/Document.h"

#include <scandiff/core/ToolRegistry.h>

#include <QObject>

class QWidget;

namespace scandiff::gui {

class ToolController : public QObject
{
    Q_OBJECT
public:
    ToolController(const ToolSpec& tool, Document& document, QWidget* parentWindow);

    //! Asks for the parameters, then runs on `input` (else the last cloud).
    void runInteractively(EntityId input);
    //! Runs with the given parameter text (the dialog's or a test's) on `input`.
    //! Returns false and emits failed() on error or cancellation.
    bool run(EntityId input, const std::map<std::string, std::string>& parameters);

signals:
    void finished(const QString& summary);
    void failed(const QString& message);
    void resultReady(EntityId id);

private:
    const ToolSpec& tool_;
    Document& document_;
    QWidget* parentWindow_;
};

} // namespace scandiff::gui
