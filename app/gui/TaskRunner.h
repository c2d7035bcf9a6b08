// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Runs a long operation on a worker thread behind a modal progress dialog with
//! a working Cancel button: the GUI adapter of scandiff's ProgressObserver.

#include <scandiff/core/Progress.h>

#include <QObject>
#include <QString>

#include <atomic>
#include <functional>

class QWidget;

namespace scandiff::gui {

//! Thread-safe bridge: the worker calls report(); the dialog, in the GUI thread,
//! receives the signals queued; Cancel sets a flag the worker polls.
class ProgressBridge : public QObject, public ProgressObserver
{
    Q_OBJECT
public:
    void beginStage(const std::string& title) override;
    void report(double fraction) override;
    bool cancelRequested() const override { return cancel_.load(); }
    void requestCancel() { cancel_ = true; }

signals:
    void stageChanged(QString title);
    void progressed(int permille);

private:
    std::atomic<bool> cancel_{false};
};

enum class TaskOutcome { Done, Cancelled, Failed };

struct TaskResult
{
    TaskOutcome outcome = TaskOutcome::Done;
    QString error; //!< the message of the scandiff::Error (or other exception) when Failed
};

//! Runs `work` on a worker thread and waits, keeping the GUI responsive; the
//! dialog appears only if the work lasts more than a moment.
TaskResult runTask(QWidget* parent, const QString& title, const std::function<void(ProgressObserver&)>& work);

} // namespace scandiff::gui
