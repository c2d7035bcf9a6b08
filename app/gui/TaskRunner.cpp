// SPDX-License-Identifier: GPL-3.0-or-later
#include "TaskRunner.h"

#include <scandiff/core/Error.h>

#include <QApplication>
#include <QEvent>
#include <QEventLoop>
#include <QProgressDialog>
#include <QThread>

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
class InputBlocker : public QObject
{
public:
    explicit InputBlocker(const QWidget* allowed) : allowed_(allowed) { qApp->installEventFilter(this); }
    ~InputBlocker() override { qApp->removeEventFilter(this); }

protected:
    bool eventFilter(QObject* target, QEvent* event) override
    {
        switch (event->type()) {
        case QEvent::MouseButtonPress:
        case QEvent::MouseButtonRelease:
        case QEvent::MouseButtonDblClick:
        case QEvent::MouseMove:
        case QEvent::Wheel:
        case QEvent::KeyPress:
        case QEvent::KeyRelease:
        case QEvent::Shortcut:
        case QEvent::ShortcutOverride:
        case QEvent::DragEnter:
        case QEvent::DragMove:
        case QEvent::Drop:
        case QEvent::Close: {
            const auto* widget = qobject_cast<const QWidget*>(target);
            const bool inDialog = widget && (widget == allowed_ || allowed_->isAncestorOf(widget));
            return !inDialog;
        }
        default:
            return false;
        }
    }

private:
    const QWidget* allowed_;
};

} // namespace

TaskResult runTask(QWidget* parent, const QString& title, const std::function<void(ProgressObserver&)>& work)
{
    ProgressBridge bridge;
    QProgressDialog dialog(title, QObject::tr("Cancel"), 0, 1000, parent);
    dialog.setWindowTitle(title);
    dialog.setWindowModality(Qt::ApplicationModal);
    dialog.setMinimumDuration(400);
    dialog.setAutoClose(false);
    dialog.setAutoReset(false);
    QObject::connect(&bridge, &ProgressBridge::stageChanged, &dialog, &QProgressDialog::setLabelText, Qt::QueuedConnection);
    QObject::connect(&bridge, &ProgressBridge::progressed, &dialog, &QProgressDialog::setValue, Qt::QueuedConnection);
    // Cancel asks the work to stop; the dialog stays until it has (Qt would hide it at once).
    QObject::disconnect(&dialog, &QProgressDialog::canceled, &dialog, &QProgressDialog::cancel);
    QObject::connect(&dialog, &QProgressDialog::canceled, &dialog, [&bridge, &dialog] {
        bridge.requestCancel();
        dialog.setLabelText(QObject::tr("Cancelling..."));
    });
    const InputBlocker blocker(&dialog);

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
