// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The main window only assembles menus, the view and the status bar; reading
//! goes through io::, tools through their controllers (tools/).

#include "document/Document.h"

#include <scandiff/plugins/PluginRegistry.h>

#include <QMainWindow>
#include <QStringList>

namespace scandiff::gui {

class CloudView;
class ToolController;

class MainWindow : public QMainWindow
{
    Q_OBJECT
public:
    explicit MainWindow(const PluginRegistry& registry, QWidget* parent = nullptr);

    //! Loads files into the document; errors are shown in a message box (or, with
    //! `quiet`, only in the status bar and on stderr). Returns how many loaded.
    int openFiles(const QStringList& paths, bool quiet = false);
    CloudView* view() const { return view_; }
    Document& document() { return document_; }
    //! The controller of a registered tool, null if unknown.
    ToolController* toolController(const std::string& toolName) const;

private:
    void openWithDialog();
    void buildToolsMenu();
    void showEntity(std::size_t index);
    QString fileDialogFilter() const;

    const PluginRegistry& registry_;
    Document document_;
    CloudView* view_;
    std::map<std::string, ToolController*> tools_;
};

} // namespace scandiff::gui
