// SPDX-License-Identifier: GPL-3.0-or-later
#include "controllers/ToolController.h"
#include "controllers/CommandLine.h"

#include "TaskRunner.h"
#include "tools/ParameterForm.h"
#include "tools/ToolDialog.h"

#include <scandiff/core/Error.h>
#include <scandiff/io/ResultFiles.h>

#include <QElapsedTimer>

#include <algorithm>
#include <map>
#include <QMessageBox>
#include <QTimer>

#include <optional>

namespace scandiff::gui {

ToolController::ToolController(const ToolSpec& tool, Document& document, QWidget* parentWindow)
    : QObject(parentWindow), tool_(tool), document_(document), parentWindow_(parentWindow)
{
}

ToolController::~ToolController()
{
    // An open picking dialog refers to the tool and the document.
    delete openDialog_.data();
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
    const bool picks = std::any_of(tool_.parameters.begin(), tool_.parameters.end(),
                                   [](const ParameterSpec& p) { return !p.pickedOn.empty(); });
    if (!picks) {
        ToolDialog dialog(tool_, document_, proposed, parentWindow_);
        if (dialog.exec() == QDialog::Accepted)
            run(dialog.inputs(), dialog.values());
        return;
    }
    // Points are picked in the view while the dialog is open: it must not block it.
    if (openDialog_) {
        openDialog_->raise();
        openDialog_->activateWindow();
        return;
    }
    auto* dialog = new ToolDialog(tool_, document_, proposed, parentWindow_);
    dialog->setAttribute(Qt::WA_DeleteOnClose);
    dialog->setModal(false);
    openDialog_ = dialog;
    connect(dialog, &ToolDialog::pickModeRequested, this, &ToolController::pickModeRequested);
    // Run once the dialog has closed: the run's progress loop may delete it
    // (WA_DeleteOnClose) and must not do so while it is still emitting.
    connect(dialog, &QDialog::accepted, this, [this, dialog] {
        QTimer::singleShot(0, this, [this, inputs = dialog->inputs(), values = dialog->values()] { run(inputs, values); });
    });
    dialog->show();
}

void ToolController::pointPicked(EntityId id, std::size_t index)
{
    if (openDialog_)
        openDialog_->pointPicked(id, index);
}

bool ToolController::run(EntityId input, const std::map<std::string, std::string>& parameters)
{
    if (tool_.inputs.empty())
        return run(ToolInputChoice{}, parameters);
    return run(ToolInputChoice{{tool_.inputs.front().role, {input}}}, parameters);
}

QString ToolController::commandLine(const ToolInputChoice& inputs, const std::map<std::string, std::string>& parameters) const
{
    CommandLine command(document_, "scandiff-cli " + QString::fromStdString(tool_.name));
    const Document::Item* first = nullptr;
    for (const InputSpec& spec : tool_.inputs) {
        const auto it = inputs.find(spec.role);
        if (it == inputs.end())
            continue;
        for (EntityId id : it->second) {
            const Document::Item& item = document_.item(id);
            if (spec.role != "input")
                command.word("--" + QString::fromStdString(spec.role));
            command.file(item);
            if (!first)
                first = &item;
        }
    }
    // Where the outputs go: a folder for a tool of several files, else one file by its kind.
    if (first && !tool_.outputs.empty()) {
        const OutputSpec& output = tool_.outputs.front();
        const bool several = std::any_of(tool_.outputs.begin(), tool_.outputs.end(), [](const OutputSpec& o) { return o.repeated; });
        const QString suffix = "_" + QString::fromStdString(tool_.name);
        if (several)
            command.outputBeside("--out-dir", *first, suffix, QString());
        else
            command.outputBeside("-o", *first, suffix,
                                 output.kind == DataKind::Table       ? ".csv"
                                 : output.kind == DataKind::Transform ? ".txt"
                                 : output.kind == DataKind::Drawing   ? ".dxf"
                                 : output.kind == DataKind::Document  ? ".json"
                                                                      : ".ply");
    }
    command.options(parameters, tool_.parameters);
    return command.text();
}

bool ToolController::run(const ToolInputChoice& choice, const std::map<std::string, std::string>& parameters)
{
    const QString title = QString::fromStdString(tool_.title);
    ToolInputs inputs;
    // The entities of the first role: an output that updates its input
    // replaces the first of them, the k-th of a repeated output the k-th.
    std::vector<EntityId> firstRole;
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
            if (&spec == &tool_.inputs.front())
                firstRole.push_back(id);
        }
    }
    const EntityId firstInput = firstRole.empty() ? kNoEntity : firstRole.front();
    const QString command = commandLine(choice, parameters); // the inputs as they are before the run
    std::optional<ToolResult> result;
    QElapsedTimer clock;
    clock.start();
    const TaskResult outcome = runTask(parentWindow_, title, [&](ProgressObserver& progress) {
        const ParameterValues values = tool_.resolve(parameters);
        result = tool_.execute(inputs, values, &progress);
    });
    if (outcome.outcome != TaskOutcome::Done) {
        if (outcome.outcome == TaskOutcome::Cancelled)
            emit cancelled(tr("%1 was cancelled").arg(title));
        else
            emit failed(outcome.error);
        return false;
    }
    const double seconds = clock.elapsed() / 1000.0;

    QString notes;
    const Document::UndoGroup group(document_, title);
    EntityId last = kNoEntity;
    bool addedEntities = false, updatedInputs = false;
    NamedTables tables;
    std::map<std::string, std::vector<EntityId>> addedByRole; // for the outputs that go under another's
    for (const OutputSpec& spec : tool_.outputs) {
        std::size_t repeat = 0;
        for (ToolOutput* output : result->findAll(spec.role)) {
            const std::size_t k = repeat++;
            if (auto* table = std::get_if<Table>(&output->data)) {
                tables.emplace_back(spec.label, std::move(*table));
                continue;
            }
            if (auto* drawing = std::get_if<Drawing>(&output->data)) {
                // Drawn over its cloud and listed under it; File > Export writes it as DXF.
                // It leaves its cloud shown (unlike a new cloud, which replaces its input on screen).
                if (!drawing->polylines.empty() || !drawing->texts.empty()) {
                    const EntityId added = document_.addDrawing(QString::fromStdString(spec.label), std::move(*drawing), firstInput);
                    if (last == kNoEntity)
                        last = added; // a cloud the run gave stays the one selected
                }
                continue;
            }
            if (std::holds_alternative<TextDocument>(output->data))
                continue; // the same results as the tables and drawings, for scripts
            if (auto* matrix = std::get_if<Eigen::Matrix4d>(&output->data)) {
                notes += QString("\n%1:\n%2").arg(QString::fromStdString(spec.label), QString::fromStdString(io::matrixText(*matrix)).trimmed());
                continue;
            }
            io::Entity entity = std::holds_alternative<PointCloud>(output->data) ? io::Entity(std::move(std::get<PointCloud>(output->data)))
                                                                                 : io::Entity(std::move(std::get<Mesh>(output->data)));
            if (spec.updatesInput && k < firstRole.size()) {
                document_.replaceData(firstRole[k], std::move(entity));
                last = firstRole[k];
                updatedInputs = true;
                if (document_.revealResult(last))
                    notes += tr("; %1 was hidden: shown with the result").arg(document_.item(last).name);
                continue;
            }
            const std::string& dataName = pointsOf(entity).name;
            const auto* mesh = std::get_if<Mesh>(&entity);
            const std::string name = mesh && !mesh->name.empty() ? mesh->name : dataName.empty() ? tool_.name : dataName;
            Document::Properties properties;
            for (const auto& [key, value] : output->properties)
                properties.emplace_back(QString::fromStdString(key), QString::fromStdString(value));
            // A shape's surface goes under its points: the k-th entity of the output it belongs to.
            EntityId parent = firstInput;
            if (!spec.under.empty()) {
                const std::vector<EntityId>& owners = addedByRole[spec.under];
                if (k < owners.size())
                    parent = owners[k];
            }
            last = document_.add(QString::fromStdString(name), std::move(entity), parent, {}, std::move(properties));
            if (!spec.showsField.empty())
                document_.setActiveField(last, spec.showsField); // ignored when it has no such field
            addedByRole[spec.role].push_back(last);
            addedEntities = true;
        }
    }
    // What the tool found on an input's field (a threshold, the modes it
    // separated) goes on that field's histogram; a new run's replace the old.
    std::map<std::pair<EntityId, std::string>, std::vector<std::pair<double, std::string>>> marks;
    for (const FieldMark& mark : result->marks) {
        const auto role = choice.find(mark.role);
        if (role != choice.end() && !role->second.empty())
            marks[{role->second.front(), mark.field}].emplace_back(mark.value, mark.label);
    }
    for (auto& [where, values] : marks) {
        const Document::Item* item = document_.find(where.first);
        if (!item || !item->points().field(where.second))
            continue;
        FieldDisplay display = document_.fieldDisplay(where.first, where.second);
        display.marks = std::move(values);
        document_.setFieldDisplay(where.first, where.second, display);
    }
    // A filter's result replaces its input on screen (it stays in the tree, unticked),
    // rather than being drawn over it.
    if (addedEntities && !updatedInputs)
        for (EntityId input : firstRole)
            document_.setVisible(input, false);
    if (!tables.empty())
        emit tablesReady(title, tables);
    emit finished(QString("%1 [%2]: %3; %4 s%5")
                      .arg(QString::fromStdString(tool_.name), command,
                           QString::fromStdString(result->summary))
                      .arg(seconds, 0, 'f', 3)
                      .arg(notes));
    if (last != kNoEntity)
        emit resultReady(last);
    return true;
}

} // namespace scandiff::gui
