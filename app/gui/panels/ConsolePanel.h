// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The console: what each tool did, with its parameters and timings, and the
//! warnings of scandiff's log (from any thread).

#include <scandiff/core/Log.h>

#include <QPlainTextEdit>

namespace scandiff::gui {

class ConsolePanel : public QPlainTextEdit
{
    Q_OBJECT
public:
    explicit ConsolePanel(QWidget* parent = nullptr);
    ~ConsolePanel() override;

public slots:
    //! Appends a time-stamped line; safe to call from the GUI thread only
    //! (other threads go through scandiff's log sink, queued here).
    void info(const QString& message);
    void warning(const QString& message);
    void error(const QString& message);

private:
    LogSink previousSink_;
};

} // namespace scandiff::gui
