// SPDX-License-Identifier: GPL-3.0-or-later
#include "controllers/ToolController.h"

#include "TaskRunner.h"
#include "tools/ParameterForm.h"
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

void ToolController::runInteractively(EntityId input)
{
    const Document::Item* item = document_.find(input);
    if (!item || !item->cloud())
        input = document_.lastCloudId();
    if (input == kNoEntity) {
        QMessageBox::information(parentWindow_, QString::fromStdString(tool_.title), tr("Open a point cloud first."));
        return;
    }
    ToolDialog dialog(tool_, parentWindow_);
    if (dialog.exec() == QDialog::Accepted)
        run(input, dialog.values());
}

bool ToolController::run(EntityId inputId, const std::map<std::string, std::string>& parameters)
{
    const Document::Item* item = document_.find(inputId);
    if (!item || !item->cloud()) {
        emit failed(tr("%1 needs a point cloud").arg(QString::fromStdString(tool_.title)));
        return false;
    }
    std::optional<ToolResult> result;
    QElapsedTimer clock;
    clock.start();
    const TaskResult outcome = runTask(parentWindow_, QString::fromStdString(tool_.title), [&](ProgressObserver& progress) {
        const ParameterValues values = tool_.resolve(parameters);
        result = tool_.run(*item->cloud(), values, &progress);
    });
    if (outcome.outcome != TaskOutcome::Done) {
        emit failed(outcome.outcome == TaskOutcome::Cancelled ? tr("%1 was cancelled").arg(QString::fromStdString(tool_.title))
                                                               : outcome.error);
        return false;
    }
    const QString name = QString::fromStdString(result->cloud.name.empty() ? tool_.name : result->cloud.name);
    const EntityId output = document_.add(name, std::move(result->cloud), inputId);
    emit finished(QString("%1 on %2 [%3]: %4; %5 s")
                      .arg(QString::fromStdString(tool_.name), item->name, commandLineText(parameters),
                           QString::fromStdString(result->summary))
                      .arg(clock.elapsed() / 1000.0, 0, 'f', 3));
    emit resultReady(output);
    return true;
}

} // namespace scandiff::gui
