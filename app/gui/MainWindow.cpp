// SPDX-License-Identifier: GPL-3.0-or-later
#include "MainWindow.h"

#include "TaskRunner.h"
#include "tools/ToolController.h"
#include "view/CloudView.h"

#include <scandiff/io/FileIO.h>

#include <QAction>
#include <QApplication>
#include <QFileDialog>
#include <QFileInfo>
#include <QMenuBar>
#include <QMessageBox>
#include <QStatusBar>

#include <iostream>
#include <optional>

namespace scandiff::gui {

MainWindow::MainWindow(const PluginRegistry& registry, QWidget* parent)
    : QMainWindow(parent), registry_(registry), view_(new CloudView(this))
{
    setWindowTitle(tr("scandiff"));
    setCentralWidget(view_);
    resize(1200, 800);

    QMenu* file = menuBar()->addMenu(tr("&File"));
    QAction* open = file->addAction(tr("&Open..."), this, &MainWindow::openWithDialog);
    open->setShortcut(QKeySequence::Open);
    file->addSeparator();
    QAction* quit = file->addAction(tr("&Quit"), qApp, &QApplication::quit);
    quit->setShortcut(QKeySequence::Quit);

    QMenu* viewMenu = menuBar()->addMenu(tr("&View"));
    viewMenu->addAction(tr("&Reset camera"), view_, &CloudView::resetCamera);
    viewMenu->addAction(tr("&Clear"), &document_, &Document::clear);

    connect(&document_, &Document::added, this, &MainWindow::showEntity);
    connect(&document_, &Document::cleared, view_, &CloudView::clear);
    buildToolsMenu();

    statusBar()->showMessage(tr("Open a cloud or a mesh (File > Open)"));
}

void MainWindow::buildToolsMenu()
{
    QMenu* toolsMenu = menuBar()->addMenu(tr("&Tools"));
    std::map<std::string, QMenu*> categories;
    for (const ToolSpec& tool : registry_.tools.tools()) {
        QMenu*& menu = categories[tool.category];
        if (!menu)
            menu = tool.category.empty() ? toolsMenu : toolsMenu->addMenu(QString::fromStdString(tool.category));
        auto* controller = new ToolController(tool, document_, this);
        tools_[tool.name] = controller;
        QAction* action = menu->addAction(QString::fromStdString(tool.title) + "...", controller, &ToolController::runInteractively);
        action->setStatusTip(QString::fromStdString(tool.description));
        connect(controller, &ToolController::finished, this, [this](const QString& summary) { statusBar()->showMessage(summary); });
        connect(controller, &ToolController::failed, this, [this](const QString& message) {
            statusBar()->showMessage(message);
            std::cerr << "error: " << message.toStdString() << '\n';
        });
    }
}

ToolController* MainWindow::toolController(const std::string& toolName) const
{
    const auto it = tools_.find(toolName);
    return it == tools_.end() ? nullptr : it->second;
}

void MainWindow::showEntity(std::size_t index)
{
    const Document::Item& item = document_.item(index);
    if (const auto* mesh = std::get_if<Mesh>(&item.entity))
        view_->addMesh(*mesh);
    else
        view_->addCloud(std::get<PointCloud>(item.entity));
    view_->resetCamera();
}

QString MainWindow::fileDialogFilter() const
{
    QStringList patterns;
    QStringList perFormat;
    for (const auto& handler : registry_.formats.handlers()) {
        if (!handler.read)
            continue;
        QStringList mine;
        for (const auto& ext : handler.extensions)
            mine << "*." + QString::fromStdString(ext);
        patterns << mine;
        perFormat << QString::fromStdString(handler.name) + " (" + mine.join(' ') + ")";
    }
    return tr("All supported (%1)").arg(patterns.join(' ')) + ";;" + perFormat.join(";;") + ";;" + tr("All files (*)");
}

void MainWindow::openWithDialog()
{
    const QStringList paths = QFileDialog::getOpenFileNames(this, tr("Open clouds or meshes"), QString(), fileDialogFilter());
    if (!paths.isEmpty())
        openFiles(paths);
}

int MainWindow::openFiles(const QStringList& paths, bool quiet)
{
    int loaded = 0;
    for (const QString& path : paths) {
        std::optional<io::Entity> entity;
        const TaskResult result = runTask(this, tr("Opening %1").arg(QFileInfo(path).fileName()), [&](ProgressObserver& progress) {
            io::ReadOptions options;
            options.progress = &progress;
            entity = io::readFile(registry_.formats, path.toStdString(), options);
        });
        if (result.outcome != TaskOutcome::Done) {
            const QString message = result.outcome == TaskOutcome::Cancelled ? tr("Opening %1 was cancelled").arg(path) : result.error;
            statusBar()->showMessage(message);
            std::cerr << "error: " << message.toStdString() << '\n';
            if (!quiet && result.outcome == TaskOutcome::Failed)
                QMessageBox::warning(this, tr("Cannot open file"), message);
            continue;
        }
        const std::size_t points = std::holds_alternative<Mesh>(*entity) ? std::get<Mesh>(*entity).vertices.size()
                                                                          : std::get<PointCloud>(*entity).size();
        document_.add(QFileInfo(path).completeBaseName(), std::move(*entity));
        statusBar()->showMessage(tr("%1: %2 points").arg(QFileInfo(path).fileName()).arg(points));
        ++loaded;
    }
    return loaded;
}

} // namespace scandiff::gui
