// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The Help menu's windows: About, the user guide's pages, and the keyboard
//! shortcuts, listed from the menus themselves (so the list cannot go stale).

#include <QString>
#include <QStringList>

#include <utility>
#include <vector>

class QMenuBar;
class QWidget;

namespace scandiff::gui {

//! The folder holding the user guide (docs/*.md): the source tree's for a
//! build, else share/doc/scandiff beside the executable's folder. Empty when
//! neither exists.
QString documentationFolder();

//! Every menu action with a shortcut, as (menu path, shortcut text), e.g.
//! ("File > Open...", "Ctrl+O"), in menu order; then the view's own keys and
//! mouse gestures.
std::vector<std::pair<QString, QString>> shortcutList(const QMenuBar& menus);

//! A window listing shortcutList (a table, one row per shortcut).
void showShortcuts(QWidget* parent, const QMenuBar& menus);
//! Version, licence, the libraries it is built on, and where the guide is.
void showAbout(QWidget* parent);

} // namespace scandiff::gui
