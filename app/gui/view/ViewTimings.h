// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! `scandiff --measure-view FILE...`: how long the view takes to draw the
//! loaded clouds at rest and while the camera moves, and to show a threshold
//! change, printed for docs/benchmarks.md.

namespace scandiff::gui {

class MainWindow;

//! Prints the timings on stdout; returns the process exit status.
int measureView(MainWindow& window);

} // namespace scandiff::gui
