// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Save and restore a session: every entity (written as PLY beside the session
//! file, so computed fields and split parts survive), the tree's parent links,
//! visibility, active fields, colour scales, thresholds, the camera and the
//! point size. The session file is JSON (`.scandiff`), its data in
//! `<name>.scandiff.data/`.

#include "document/Document.h"

#include <scandiff/plugins/PluginRegistry.h>

#include <QObject>

#include <functional>

class QWidget;

namespace scandiff::gui {

class MeasurePanel;

class CloudView;
class ScalarFieldPanel;

class SessionController : public QObject
{
    Q_OBJECT
public:
    SessionController(const PluginRegistry& registry, Document& document, CloudView& view, ScalarFieldPanel& scalarPanel,
                      QWidget* parentWindow);

    bool save(const QString& path);
    //! Replaces the document's content with the session's.
    bool restore(const QString& path);
    //! True once saved (false if the user cancelled the file dialog or the save failed).
    bool saveWithDialog();
    //! Asks `mayDiscard` first (when set): opening a session replaces the document.
    void restoreWithDialog();
    //! The measurements saved and restored with the session (none when unset).
    void setMeasurePanel(MeasurePanel* panel) { measure_ = panel; }
    //! Asked before the document is replaced; false keeps it.
    void setDiscardCheck(std::function<bool()> mayDiscard) { mayDiscard_ = std::move(mayDiscard); }

signals:
    void finished(const QString& summary);
    void failed(const QString& message);
    //! The user stopped a run: no error, nothing changed.
    void cancelled(const QString& message);

private:
    const PluginRegistry& registry_;
    Document& document_;
    CloudView& view_;
    ScalarFieldPanel& scalarPanel_;
    QWidget* parentWindow_;
    std::function<bool()> mayDiscard_;
    MeasurePanel* measure_ = nullptr;
};

} // namespace scandiff::gui
