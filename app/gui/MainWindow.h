// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The main window only assembles menus, the view and the status bar; the work
//! is done by the library (reading through io::, tools through the registry).

#include <scandiff/plugins/PluginRegistry.h>

#include <QMainWindow>
#include <QStringList>

namespace scandiff::gui {

class CloudView;

class MainWindow : public QMainWindow
{
    Q_OBJECT
public:
    explicit MainWindow(const PluginRegistry& registry, QWidget* parent = nullptr);

    //! Loads files into the view; errors are shown in a message box (or, with
    //! `quiet`, only in the status bar and on stderr). Returns how many loaded.
    int openFiles(const QStringList& paths, bool quiet = false);
    CloudView* view() const { return view_; }

private:
    void openWithDialog();
    QString fileDialogFilter() const;

    const PluginRegistry& registry_;
    CloudView* view_;
};

} // namespace scandiff::gui
