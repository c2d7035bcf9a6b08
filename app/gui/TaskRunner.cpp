// SPDX-License-Identifier: GPL-3.0-or-later
#include "TaskRunner.h"

#include <limits>

#include <scandiff/core/Error.h>

#include <QApplication>
#include <QEvent>
#include <QEventLoop>
#include <QKeyEvent>
#include <QProgressDialog>
#include <QThread>
#include <QTimer>
#include <QWindow>

namespace scandiff::gui {

void ProgressBridge::beginStage(const std::string& title)
{
    emit stageChanged(QString::fromStdString(title));
}

void ProgressBridge::report(double fraction)
{
    emit progressed(static_cast<int>(fraction * 1000.0));
}

namespace {

//! While a task runs, the user can reach nothing but its progress dialog:
//! the work reads entities of the document, which must not change or vanish
//! under it. The dialog appears only after a moment (short tasks do not
//! flash), so until then, and after Cancel, input is swallowed here.
//! Qt delivers a mouse click or a key first to the native window (a QWindow,
//! not a widget), then to the widget under it: both must be let through for
//! the dialog. Escape cancels wherever the keyboard focus is: before the
//! dialog shows, it is still in the main window.
class InputBlocker : public QObject
{
public:
    InputBlocker(QWidget* allowed, std::function<void()> onEscape) : allowed_(allowed), onEscape_(std::move(onEscape))
    {
        qApp->installEventFilter(this);
    }
    ~InputBlocker() override { qApp->removeEventFilter(this); }

protected:
    bool eventFilter(QObject* target, QEvent* event) override
    {
        switch (event->type()) {
        case QEvent::Show:
            // The keyboard goes to the dialog when it shows: a modal dialog
            // blocks the keys of the window under it before any filter sees
            // them, so Escape would be lost if the focus stayed there.
            if (target == allowed_)
                allowed_->activateWindow();
            return false;
        case QEvent::KeyPress:
            if (static_cast<QKeyEvent*>(event)->key() == Qt::Key_Escape) {
                if (!static_cast<QKeyEvent*>(event)->isAutoRepeat())
                    onEscape_();
                return true;
            }
            return !inDialog(target);
        case QEvent::MouseButtonPress:
        case QEvent::MouseButtonRelease:
        case QEvent::MouseButtonDblClick:
        case QEvent::MouseMove:
        case QEvent::Wheel:
        case QEvent::KeyRelease:
        case QEvent::Shortcut:
        case QEvent::ShortcutOverride:
        case QEvent::DragEnter:
        case QEvent::DragMove:
        case QEvent::Drop:
        case QEvent::Close:
            return !inDialog(target);
        default:
            return false;
        }
    }

private:
    bool inDialog(const QObject* target) const
    {
        if (const auto* window = qobject_cast<const QWindow*>(target))
            return window == allowed_->windowHandle();
        // Widgets, and the dialog's Escape shortcut (a QObject child of it).
        for (const QObject* object = target; object; object = object->parent())
            if (object == allowed_)
                return true;
        return false;
    }

    QWidget* allowed_;
    std::function<void()> onEscape_;
};

} // namespace

TaskResult runTask(QWidget* parent, const QString& title, const std::function<void(ProgressObserver&)>& work)
{
    ProgressBridge bridge;
    QProgressDialog dialog(title, QObject::tr("Cancel"), 0, 1000, parent);
    dialog.setWindowTitle(title);
    dialog.setWindowModality(Qt::ApplicationModal);
    // Shown after 400 ms whatever the progress says: QProgressDialog's own rule
    // (shown once the estimated total exceeds the delay) left the first read
    // of a session with an empty window and no dialog.
    dialog.setMinimumDuration(std::numeric_limits<int>::max());
    QTimer::singleShot(400, &dialog, [&dialog] { dialog.show(); });
    dialog.setAutoClose(false);
    dialog.setAutoReset(false);
    QObject::connect(
        &bridge, &ProgressBridge::stageChanged, &dialog,
        [&bridge, &dialog](const QString& stage) {
            if (!bridge.cancelRequested())
                dialog.setLabelText(stage);
        },
        Qt::QueuedConnection);
    QObject::connect(&bridge, &ProgressBridge::progressed, &dialog, &QProgressDialog::setValue, Qt::QueuedConnection);
    // Cancel asks the work to stop; the dialog stays until it has (Qt would hide it at once).
    QObject::disconnect(&dialog, &QProgressDialog::canceled, &dialog, &QProgressDialog::cancel);
    // Once cancelled, the label says so and stays: a stage starting meanwhile
    // (the work hears Cancel at its next check) must not overwrite it.
    const auto cancel = [&bridge, &dialog] {
        bridge.requestCancel();
        dialog.setLabelText(QObject::tr("Cancelling..."));
    };
    QObject::connect(&dialog, &QProgressDialog::canceled, &dialog, cancel);
    const InputBlocker blocker(&dialog, cancel);

    TaskResult result;
    QThread* worker = QThread::create([&] {
        try {
            work(bridge);
        } catch (const Error& e) {
            result.outcome = e.code() == ErrorCode::Cancelled ? TaskOutcome::Cancelled : TaskOutcome::Failed;
            result.error = QString::fromStdString(e.what());
        } catch (const std::exception& e) {
            result.outcome = TaskOutcome::Failed;
            result.error = QString::fromStdString(e.what());
        } catch (...) {
            // A thread must not let anything escape: std::terminate would follow.
            result.outcome = TaskOutcome::Failed;
            result.error = QObject::tr("%1: unknown error").arg(title);
        }
    });
    QEventLoop loop;
    QObject::connect(worker, &QThread::finished, &loop, &QEventLoop::quit);
    worker->start();
    loop.exec();
    worker->wait();
    delete worker;
    dialog.close();
    return result;
}

} // namespace scandiff::gui
