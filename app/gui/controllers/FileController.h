// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Files in and out of the workbench: open (menu, command line, drag and
//! drop), recent files, export of entities in any format io/ writes. Reading
//! and writing run on a worker thread behind the progress dialog.

#include "document/Document.h"

#include <scandiff/plugins/PluginRegistry.h>

#include <QObject>

#include <Eigen/Core>

#include <optional>
#include <QStringList>

class QMenu;
class QWidget;

namespace scandiff::gui {

class FileController : public QObject
{
    Q_OBJECT
public:
    FileController(const PluginRegistry& registry, Document& document, QWidget* parentWindow);

    //! Loads files; errors go to failed() and, unless `quiet`, a message box.
    //! Returns the ids of the loaded entities.
    std::vector<EntityId> open(const QStringList& paths, bool quiet = false);
    void openWithDialog();
    //! Writes one entity (format from the extension); false and failed() on error.
    bool exportEntity(EntityId id, const QString& path);
    //! Asks where to write the given entities: a file for one, a folder for several.
    void exportWithDialog(const std::vector<EntityId>& ids);

    QStringList recentFiles() const;
    //! Rebuilds `menu` with the recent files (kept in QSettings).
    void fillRecentMenu(QMenu* menu);
    //! "All supported (*.ply *.las ...);;PLY (*.ply);;..." for reading or writing.
    QString fileFilter(bool forWriting) const;

signals:
    void finished(const QString& summary);
    void failed(const QString& message);
    //! The user stopped a run: no error, nothing changed.
    void cancelled(const QString& message);
    void recentFilesChanged();

private:
    void remember(const QString& path);
    //! A cloud far from 0 (the reader chose an origin): the global-shift
    //! question, unless `quiet` or answered for the whole session.
    void chooseOrigin(const QString& path, PointCloud& points, bool quiet);
    //! Moves another part of the same file onto the origin chosen for its first
    //! part, unless float32 could not then hold a millimetre of it.
    void shiftIfPrecise(const QString& path, PointCloud& points, const Eigen::Vector3d& origin);
    std::optional<Eigen::Vector3d> sessionOrigin_; //!< "for every file of this session"
    const PluginRegistry& registry_;
    Document& document_;
    QWidget* parentWindow_;
};

} // namespace scandiff::gui
