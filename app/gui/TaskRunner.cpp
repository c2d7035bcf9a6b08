// SPDX-License-Identifier: GPL-3.0-or-later
#include "TaskRunner.h"

#include <scandiff/core/Error.h>

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

TaskResult runTask(QWidget* parent, const QString& title, const std::function<void(ProgressObserver&)>& work)
{
    ProgressBridge bridge;
    QProgressDialog dialog(title, QObject::tr("Cancel"), 0, 1000, parent);
    dialog.setWindowTitle(title);
    dialog.setWindowModality(Qt::WindowModal);
    dialog.setMinimumDuration(400);
    dialog.setAutoClose(false);
    dialog.setAutoReset(false);
    QObject::connect(&bridge, &ProgressBridge::stageChanged, &dialog, &QProgressDialog::setLabelText, Qt::QueuedConnection);
    QObject::connect(&bridge, &ProgressBridge::progressed, &dialog, &QProgressDialog::setValue, Qt::QueuedConnection);
    QObject::connect(&dialog, &QProgressDialog::canceled, [&bridge] { bridge.requestCancel(); });

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
