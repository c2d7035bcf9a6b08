// SPDX-License-Identifier: GPL-3.0-or-later
#include "tools/ToolController.h"

#include "TaskRunner.h"
#include "tools/ToolDialog.h"

#include <scandiff/core/Error.h>

#include <QElapsedTimer>
#include <QMessageBox>

#include <optional>

namespace scandiff::gui {

ToolController::ToolController(const ToolSpec& tool, Document& document, QWidget* parentWindow)
    : QObject(parentWindow), tool_(tool), document_(document), parentWindow_(parentWindow)
{
}

void ToolController::runInteractively()
{
    const PointCloud* input = document_.lastCloud();
    if (!input) {
        QMessageBox::information(parentWindow_, QString::fromStdString(tool_.title), tr("Open a point cloud first."));
        return;
    }
    ToolDialog dialog(tool_, parentWindow_);
    if (dialog.exec() != QDialog::Accepted)
        return;
    if (!run(*input, dialog.values()))
        QMessageBox::warning(parentWindow_, QString::fromStdString(tool_.title), tr("The tool did not complete."));
}

bool ToolController::run(const PointCloud& input, const std::map<std::string, std::string>& parameters)
{
    std::optional<ToolResult> result;
    QElapsedTimer clock;
    clock.start();
    const TaskResult outcome = runTask(parentWindow_, QString::fromStdString(tool_.title), [&](ProgressObserver& progress) {
        const ParameterValues values = tool_.resolve(parameters);
        result = tool_.run(input, values, &progress);
    });
    if (outcome.outcome != TaskOutcome::Done) {
        emit failed(outcome.outcome == TaskOutcome::Cancelled ? tr("%1 was cancelled").arg(QString::fromStdString(tool_.title))
                                                               : outcome.error);
        return false;
    }
    const QString name = QString::fromStdString(result->cloud.name.empty() ? tool_.name : result->cloud.name);
    document_.add(name, std::move(result->cloud));
    emit finished(QString("%1: %2 [%3 s]")
                      .arg(QString::fromStdString(tool_.name), QString::fromStdString(result->summary))
                      .arg(clock.elapsed() / 1000.0, 0, 'f', 3));
    return true;
}

} // namespace scandiff::gui
