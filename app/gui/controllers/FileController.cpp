// SPDX-License-Identifier: GPL-3.0-or-later
#include "controllers/FileController.h"
#include "controllers/GlobalShiftDialog.h"

#include "TaskRunner.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/DemOfDifference.h>
#include <scandiff/io/DxfWriter.h>
#include <scandiff/io/FileIO.h>

#include <QDir>
#include <QRegularExpression>
#include <QSet>
#include <QElapsedTimer>
#include <QFileDialog>
#include <QFileInfo>
#include <QMenu>
#include <QMessageBox>
#include <QSettings>

#include <optional>

namespace scandiff::gui {

namespace {

constexpr int kRecentFiles = 10;

//! Beyond this distance from their origin float32 coordinates no longer hold a millimetre.
constexpr double kPreciseReach = 8192.0;

//! How far the cloud's points lie from `origin` along the worst axis.
double reachFrom(const PointCloud& points, const Eigen::Vector3d& origin)
{
    const BoundingBox box = points.bounds();
    return std::max((box.min - origin).cwiseAbs().maxCoeff(), (box.max - origin).cwiseAbs().maxCoeff());
}
const char* kRecentKey = "recentFiles";

} // namespace

FileController::FileController(const PluginRegistry& registry, Document& document, QWidget* parentWindow)
    : QObject(parentWindow), registry_(registry), document_(document), parentWindow_(parentWindow)
{
}

QString FileController::fileFilter(bool forWriting) const
{
    QStringList patterns;
    QStringList perFormat;
    for (const auto& handler : registry_.formats.handlers()) {
        if (forWriting ? !(handler.writeCloud || handler.writeMesh) : !handler.read)
            continue;
        QStringList mine;
        for (const auto& ext : handler.extensions)
            mine << "*." + QString::fromStdString(ext);
        patterns << mine;
        perFormat << QString::fromStdString(handler.name) + " (" + mine.join(' ') + ")";
    }
    if (forWriting)
        return perFormat.join(";;");
    return tr("All supported (%1)").arg(patterns.join(' ')) + ";;" + perFormat.join(";;") + ";;" + tr("All files (*)");
}

std::vector<EntityId> FileController::open(const QStringList& paths, bool quiet)
{
    std::vector<EntityId> loaded;
    for (const QString& path : paths) {
        std::vector<io::Entity> entities;
        QElapsedTimer clock;
        clock.start();
        const TaskResult result = runTask(parentWindow_, tr("Opening %1").arg(QFileInfo(path).fileName()), [&](ProgressObserver& progress) {
            io::ReadOptions options;
            options.progress = &progress;
            entities = io::readEntities(registry_.formats, path.toStdString(), options);
        });
        if (result.outcome != TaskOutcome::Done) {
            if (result.outcome == TaskOutcome::Cancelled) {
                emit cancelled(tr("Opening %1 was cancelled").arg(path));
                continue;
            }
            emit failed(result.error);
            if (!quiet)
                QMessageBox::warning(parentWindow_, tr("Cannot open file"), result.error);
            continue;
        }
        // The time the user takes to answer the global-shift question is not the file's.
        const qint64 readMilliseconds = clock.elapsed();
        // The scans of one file share their origin (the reader chose one for
        // all): one question, and the answer applied to every scan.
        std::optional<Eigen::Vector3d> chosen;
        for (io::Entity& entity : entities) {
            PointCloud& points = pointsOf(entity);
            if (!chosen) {
                chooseOrigin(path, points, quiet);
                chosen = points.origin();
            } else if (!points.empty() && points.origin() != *chosen) {
                shiftIfPrecise(path, points, *chosen);
            }
        }
        clock.restart();
        const bool isMesh = entities.size() == 1 && std::holds_alternative<Mesh>(entities.front());
        std::size_t points = 0;
        for (const io::Entity& entity : entities)
            points += pointsOf(entity).size();
        const QString absolute = QFileInfo(path).absoluteFilePath();
        if (entities.size() == 1) {
            loaded.push_back(document_.add(QFileInfo(path).completeBaseName(), std::move(entities.front()), kNoEntity, absolute));
        } else {
            // One entity per part (scan), grouped under the file as CloudCompare users expect.
            Document::UndoGroup step(document_, tr("Open %1").arg(QFileInfo(path).fileName()));
            const EntityId group = document_.addGroup(QFileInfo(path).completeBaseName(), kNoEntity, absolute);
            for (io::Entity& entity : entities) {
                const QString name = QString::fromStdString(pointsOf(entity).name);
                loaded.push_back(document_.add(name, std::move(entity), group, absolute));
            }
        }
        // A cloud that has colours opens in its colours, as in CloudCompare
        // (an RGB LAZ is not shown by its intensity); a grid keeps its main field.
        for (EntityId id : loaded) {
            const Document::Item& item = document_.item(id);
            if (item.sourcePath == absolute && item.cloud() && item.cloud()->hasColors() && !mainGridField(*item.cloud()))
                document_.setActiveField(id, std::string());
        }
        remember(absolute);
        emit finished(tr("opened %1: %2 %3%4 in %5 s")
                          .arg(absolute)
                          .arg(points)
                          .arg(isMesh ? tr("vertices") : tr("points"))
                          .arg(entities.size() > 1 ? tr(" in %1 scans").arg(entities.size()) : QString())
                          .arg((readMilliseconds + clock.elapsed()) / 1000.0, 0, 'f', 3));
    }
    return loaded;
}

void FileController::shiftIfPrecise(const QString& path, PointCloud& points, const Eigen::Vector3d& origin)
{
    const double reach = reachFrom(points, origin);
    if (reach > kPreciseReach) {
        emit failed(tr("%1: '%2' is %3 m from the origin of the file's other scans; kept its own origin to keep every millimetre")
                        .arg(QFileInfo(path).fileName(), QString::fromStdString(points.name))
                        .arg(reach, 0, 'f', 0));
        return;
    }
    points.shiftOrigin(origin);
}

void FileController::chooseOrigin(const QString& path, PointCloud& points, bool quiet)
{
    // Small coordinates need no question: the reader kept the origin at 0.
    if (points.empty() || points.origin().cwiseAbs().maxCoeff() < 1.0)
        return;
    std::optional<Eigen::Vector3d> origin = sessionOrigin_;
    if (!origin && !quiet) {
        GlobalShiftDialog dialog(path, points.origin(), points.globalPosition(0), parentWindow_);
        if (dialog.exec() == QDialog::Accepted) {
            origin = dialog.origin();
            GlobalShiftDialog::rememberOrigin(*origin); // for "Same as last"
            if (dialog.forTheWholeSession())
                sessionOrigin_ = origin;
        }
    }
    if (!origin || *origin == points.origin())
        return;
    // The floats become relative to the chosen origin; refused when that would
    // put them so far from it that float32 could not hold a millimetre.
    const double reach = reachFrom(points, *origin);
    if (reach > kPreciseReach) {
        emit failed(tr("%1: the origin %2, %3, %4 is %5 m from the points; kept the suggested one to keep every millimetre")
                        .arg(QFileInfo(path).fileName())
                        .arg(origin->x(), 0, 'f', 3)
                        .arg(origin->y(), 0, 'f', 3)
                        .arg(origin->z(), 0, 'f', 3)
                        .arg(reach, 0, 'f', 0));
        return;
    }
    points.shiftOrigin(*origin);
}

void FileController::openWithDialog()
{
    const QStringList paths = QFileDialog::getOpenFileNames(parentWindow_, tr("Open clouds or meshes"), QString(), fileFilter(false));
    if (!paths.isEmpty())
        open(paths);
}

bool FileController::exportEntity(EntityId id, const QString& path)
{
    const Document::Item* item = document_.find(id);
    if (!item) {
        emit failed(tr("Nothing to export"));
        return false;
    }
    if (item->isDrawing()) {
        try {
            io::writeDrawingDxf(*item->drawing, path.toStdString());
        } catch (const Error& e) {
            emit failed(QString::fromStdString(e.what()));
            return false;
        }
        document_.markSaved(id);
        emit finished(tr("exported %1 to %2 (%3 polylines)").arg(item->name, path).arg(item->drawing->polylines.size()));
        return true;
    }
    // A group's scans go together into one file of a format that holds several (E57).
    std::vector<const PointCloud*> scans;
    if (item->isGroup())
        for (EntityId child : document_.children(id))
            if (const PointCloud* cloud = document_.item(child).cloud())
                scans.push_back(cloud);
    if (item->isGroup() && scans.empty()) {
        emit failed(tr("%1 holds no point cloud to export").arg(item->name));
        return false;
    }
    QElapsedTimer clock;
    clock.start();
    const TaskResult result = runTask(parentWindow_, tr("Writing %1").arg(QFileInfo(path).fileName()), [&](ProgressObserver& progress) {
        io::WriteOptions options;
        options.progress = &progress;
        if (item->isGroup())
            io::writePointClouds(registry_.formats, scans, path.toStdString(), options);
        else
            io::writeFile(registry_.formats, item->entity, path.toStdString(), options);
    });
    if (result.outcome != TaskOutcome::Done) {
        if (result.outcome == TaskOutcome::Cancelled)
            emit cancelled(tr("Writing %1 was cancelled").arg(path));
        else
            emit failed(result.error);
        return false;
    }
    document_.markSaved(id, path);
    std::size_t points = item->points().size();
    for (const PointCloud* scan : scans)
        points += scan->size();
    emit finished(tr("exported %1 to %2 (%3 points, %4 fields) in %5 s")
                      .arg(item->name, path)
                      .arg(points)
                      .arg(item->points().fields().size())
                      .arg(clock.elapsed() / 1000.0, 0, 'f', 3));
    return true;
}

void FileController::exportWithDialog(const std::vector<EntityId>& ids)
{
    if (ids.empty()) {
        QMessageBox::information(parentWindow_, tr("Export"), tr("Select the entities to export in the tree first."));
        return;
    }
    if (ids.size() == 1) {
        const Document::Item& item = document_.item(ids.front());
        // A group (the scans of one file) goes to E57, which holds several scans.
        QString selectedFilter = item.isDrawing() ? "DXF drawing (*.dxf)" : item.isGroup() ? "E57 (*.e57)" : "PLY (*.ply)";
        const QString path = QFileDialog::getSaveFileName(parentWindow_, tr("Export %1").arg(item.name),
                                                          item.name + (item.isDrawing() ? ".dxf" : item.isGroup() ? ".e57" : ".ply"),
                                                          item.isDrawing() ? selectedFilter : fileFilter(true), &selectedFilter);
        if (!path.isEmpty() && exportEntity(ids.front(), path))
            return;
        return;
    }
    const QString folder = QFileDialog::getExistingDirectory(parentWindow_, tr("Export %1 entities as PLY into").arg(ids.size()));
    if (folder.isEmpty())
        return;
    QSet<QString> used;
    for (EntityId id : ids) {
        // Names become file names: no separators, and two entities never share a file.
        QString base = document_.item(id).name;
        base.replace(QRegularExpression(R"([/\\:*?"<>|])"), "_");
        const QString extension = document_.item(id).isDrawing() ? ".dxf" : document_.item(id).isGroup() ? ".e57" : ".ply";
        QString name = base + extension;
        for (int n = 2; used.contains(name) || QFileInfo::exists(QDir(folder).filePath(name)); ++n)
            name = QString("%1_%2%3").arg(base).arg(n).arg(extension);
        used.insert(name);
        if (!exportEntity(id, QDir(folder).filePath(name)))
            break;
    }
}

QStringList FileController::recentFiles() const { return QSettings().value(kRecentKey).toStringList(); }

void FileController::remember(const QString& path)
{
    QStringList files = recentFiles();
    files.removeAll(path);
    files.prepend(path);
    while (files.size() > kRecentFiles)
        files.removeLast();
    QSettings().setValue(kRecentKey, files);
    emit recentFilesChanged();
}

void FileController::fillRecentMenu(QMenu* menu)
{
    menu->clear();
    const QStringList files = recentFiles();
    for (const QString& file : files)
        menu->addAction(file, this, [this, file] { open({file}); });
    menu->setEnabled(!files.isEmpty());
}

} // namespace scandiff::gui
