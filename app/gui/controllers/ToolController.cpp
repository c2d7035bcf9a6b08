// SPDX-License-Identifier: GPL-3.0-or-later
#include "controllers/ToolController.h"

#include "TaskRunner.h"
#include "tools/ParameterForm.h"
#include "tools/ToolDialog.h"

#include <scandiff/core/Error.h>
#include <scandiff/io/ResultFiles.h>

#include <QElapsedTimer>
#include <QMessageBox>

#include <optional>

namespace scandiff::gui {

ToolController::ToolController(const ToolSpec& tool, Document& document, QWidget* parentWindow)
    : QObject(parentWindow), tool_(tool), document_(document), parentWindow_(parentWindow)
{
}

void ToolController::runInteractively(const std::vector<EntityId>& selection)
{
    const ToolInputChoice proposed = proposeInputs(document_, tool_, selection);
    for (const InputSpec& input : tool_.inputs)
        if (!input.optional && proposed.at(input.role).empty()) {
            QMessageBox::information(parentWindow_, QString::fromStdString(tool_.title),
                                     input.kind == DataKind::Mesh ? tr("Open a mesh first.") : tr("Open a point cloud first."));
            return;
        }
    ToolDialog dialog(tool_, document_, proposed, parentWindow_);
    if (dialog.exec() == QDialog::Accepted)
        run(dialog.inputs(), dialog.values());
}

bool ToolController::run(EntityId input, const std::map<std::string, std::string>& parameters)
{
    if (tool_.inputs.empty())
        return run(ToolInputChoice{}, parameters);
    return run(ToolInputChoice{{tool_.inputs.front().role, {input}}}, parameters);
}

QString ToolController::commandLine(const ToolInputChoice& inputs, const std::map<std::string, std::string>& parameters) const
{
    QStringList parts{"scandiff-cli", QString::fromStdString(tool_.name)};
    for (const InputSpec& spec : tool_.inputs) {
        const auto it = inputs.find(spec.role);
        if (it == inputs.end())
            continue;
        for (EntityId id : it->second) {
            const Document::Item& item = document_.item(id);
            const QString file = item.sourcePath.isEmpty() ? item.name : item.sourcePath;
            parts << (spec.role == "input" ? file : QString("--%1 %2").arg(QString::fromStdString(spec.role), file));
        }
    }
    const QString options = commandLineText(parameters);
    if (!options.isEmpty())
        parts << options;
    return parts.join(' ');
}

bool ToolController::run(const ToolInputChoice& choice, const std::map<std::string, std::string>& parameters)
{
    const QString title = QString::fromStdString(tool_.title);
    ToolInputs inputs;
    EntityId firstInput = kNoEntity;
    for (const InputSpec& spec : tool_.inputs) {
        const auto it = choice.find(spec.role);
        if (it == choice.end())
            continue;
        for (EntityId id : it->second) {
            const Document::Item* item = document_.find(id);
            if (!item) {
                emit failed(tr("%1: the chosen entity no longer exists").arg(title));
                return false;
            }
            inputs.add(spec.role, item->entity);
            if (firstInput == kNoEntity)
                firstInput = id;
        }
    }
    std::optional<ToolResult> result;
    QElapsedTimer clock;
    clock.start();
    const TaskResult outcome = runTask(parentWindow_, title, [&](ProgressObserver& progress) {
        const ParameterValues values = tool_.resolve(parameters);
        result = tool_.execute(inputs, values, &progress);
    });
    if (outcome.outcome != TaskOutcome::Done) {
        emit failed(outcome.outcome == TaskOutcome::Cancelled ? tr("%1 was cancelled").arg(title) : outcome.error);
        return false;
    }
    const double seconds = clock.elapsed() / 1000.0;

    QString notes;
    EntityId last = kNoEntity;
    NamedTables tables;
    for (const OutputSpec& spec : tool_.outputs) {
        for (ToolOutput* output : result->findAll(spec.role)) {
            if (auto* table = std::get_if<Table>(&output->data)) {
                tables.emplace_back(spec.label, std::move(*table));
                continue;
            }
            if (auto* matrix = std::get_if<Eigen::Matrix4d>(&output->data)) {
                notes += QString("\n%1:\n%2").arg(QString::fromStdString(spec.label), QString::fromStdString(io::matrixText(*matrix)).trimmed());
                continue;
            }
            io::Entity entity = std::holds_alternative<PointCloud>(output->data) ? io::Entity(std::move(std::get<PointCloud>(output->data)))
                                                                                 : io::Entity(std::move(std::get<Mesh>(output->data)));
            if (spec.updatesInput && firstInput != kNoEntity) {
                document_.replaceData(firstInput, std::move(entity));
                last = firstInput;
                continue;
            }
            const std::string& dataName = pointsOf(entity).name;
            const auto* mesh = std::get_if<Mesh>(&entity);
            const std::string name = mesh && !mesh->name.empty() ? mesh->name : dataName.empty() ? tool_.name : dataName;
            last = document_.add(QString::fromStdString(name), std::move(entity), firstInput);
        }
    }
    if (!tables.empty())
        emit tablesReady(title, tables);
    emit finished(QString("%1 [%2]: %3; %4 s%5")
                      .arg(QString::fromStdString(tool_.name), commandLine(choice, parameters),
                           QString::fromStdString(result->summary))
                      .arg(seconds, 0, 'f', 3)
                      .arg(notes));
    if (last != kNoEntity)
        emit resultReady(last);
    return true;
}

} // namespace scandiff::gui
