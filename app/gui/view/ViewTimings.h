// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! `scandiff --measure-view FILE...`: how long the view takes to draw the
//! loaded clouds at rest and while the camera moves, and to show a threshold
//! change, printed for docs/benchmarks.md; `scandiff --measure-c2c REF COMPARED`:
//! C2C run from the workbench, and how long the interface waits meanwhile.

namespace scandiff::gui {

class MainWindow;

//! Prints the timings on stdout; returns the process exit status.
int measureView(MainWindow& window);

//! Runs C2C of the second loaded cloud against the first through the
//! workbench's own path (the worker thread behind the progress dialog, the
//! fields added to the document, the view recoloured and refined), with a
//! 10 ms heartbeat on the event loop; prints the run's time, the longest gap
//! between two beats (the longest the interface waited, 10 ms included)
//! during the run and until the result is drawn, and the resident memory and
//! its peak. Returns the process exit status.
int measureCloudToCloud(MainWindow& window);

} // namespace scandiff::gui
