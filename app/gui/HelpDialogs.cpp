// SPDX-License-Identifier: GPL-3.0-or-later
#include "HelpDialogs.h"

#include <QAction>
#include <QApplication>
#include <QDialog>
#include <QDialogButtonBox>
#include <QDir>
#include <QFileInfo>
#include <QHeaderView>
#include <QMenu>
#include <QMenuBar>
#include <QMessageBox>
#include <QTableWidget>
#include <QVBoxLayout>

#include <vtkVersion.h>

#include <Eigen/Core>

namespace scandiff::gui {

namespace {

void collectShortcuts(const QMenu& menu, const QString& path, std::vector<std::pair<QString, QString>>& out)
{
    for (QAction* action : menu.actions()) {
        const QString name = action->text().remove('&');
        if (action->menu()) {
            collectShortcuts(*action->menu(), path + " > " + name, out);
            continue;
        }
        QStringList keys;
        for (const QKeySequence& key : action->shortcuts())
            keys << key.toString(QKeySequence::NativeText);
        if (!keys.isEmpty())
            out.emplace_back(path + " > " + name, keys.join(QObject::tr(" or ")));
    }
}

} // namespace

QString documentationFolder()
{
    const QStringList candidates{QStringLiteral(SCANDIFF_SOURCE_DOCS),
                                 QCoreApplication::applicationDirPath() + "/../share/doc/scandiff"};
    for (const QString& folder : candidates)
        if (QFileInfo::exists(folder + "/workbench.md"))
            return QDir(folder).canonicalPath();
    return {};
}

std::vector<std::pair<QString, QString>> shortcutList(const QMenuBar& menus)
{
    std::vector<std::pair<QString, QString>> out;
    for (QAction* action : menus.actions())
        if (action->menu())
            collectShortcuts(*action->menu(), action->text().remove('&'), out);
    // The view's own (VTK's trackball camera style, CloudView), not in any menu.
    const std::pair<const char*, const char*> view[] = {
        {QT_TRANSLATE_NOOP("Help", "View: turn about the centre"), QT_TRANSLATE_NOOP("Help", "Left drag")},
        {QT_TRANSLATE_NOOP("Help", "View: pan"), QT_TRANSLATE_NOOP("Help", "Middle drag, or Shift + left drag")},
        {QT_TRANSLATE_NOOP("Help", "View: zoom"), QT_TRANSLATE_NOOP("Help", "Wheel, or right drag")},
        {QT_TRANSLATE_NOOP("Help", "Scissors: add a corner / close the polygon"), QT_TRANSLATE_NOOP("Help", "Left click / right click")},
        {QT_TRANSLATE_NOOP("Help", "View: roll about the line of sight"), QT_TRANSLATE_NOOP("Help", "Ctrl + left drag")},
    };
    for (const auto& [what, keys] : view)
        out.emplace_back(QCoreApplication::translate("Help", what), QCoreApplication::translate("Help", keys));
    return out;
}

void showShortcuts(QWidget* parent, const QMenuBar& menus)
{
    auto* dialog = new QDialog(parent);
    dialog->setObjectName("shortcuts");
    dialog->setAttribute(Qt::WA_DeleteOnClose);
    dialog->setWindowTitle(QObject::tr("Keyboard shortcuts"));
    const auto list = shortcutList(menus);
    auto* table = new QTableWidget(static_cast<int>(list.size()), 2, dialog);
    table->setHorizontalHeaderLabels({QObject::tr("Action"), QObject::tr("Keys")});
    table->verticalHeader()->hide();
    table->setEditTriggers(QAbstractItemView::NoEditTriggers);
    for (int row = 0; row < static_cast<int>(list.size()); ++row) {
        table->setItem(row, 0, new QTableWidgetItem(list[static_cast<std::size_t>(row)].first));
        table->setItem(row, 1, new QTableWidgetItem(list[static_cast<std::size_t>(row)].second));
    }
    table->resizeColumnsToContents();
    table->horizontalHeader()->setStretchLastSection(true);
    auto* buttons = new QDialogButtonBox(QDialogButtonBox::Close, dialog);
    QObject::connect(buttons, &QDialogButtonBox::rejected, dialog, &QDialog::close);
    auto* layout = new QVBoxLayout(dialog);
    layout->addWidget(table);
    layout->addWidget(buttons);
    dialog->resize(620, 560);
    dialog->show();
}

void showAbout(QWidget* parent)
{
    const QString docs = documentationFolder();
    QMessageBox::about(
        parent, QObject::tr("About scandiff"),
        QObject::tr("<h3>scandiff %1</h3>"
                    "<p>A workbench for comparing 3D scans: alignment, distances (C2C, C2M, M3C2), "
                    "change segmentation, primitives, contours and their export.</p>"
                    "<p>Licence: GNU GPL version 3 or later.</p>"
                    "<p>Built with Qt %2, VTK %3, Eigen %4.%5.%6.</p>"
                    "<p>User guide: %7</p>")
            .arg(QApplication::applicationVersion(), QString::fromLatin1(qVersion()), QString::fromLatin1(vtkVersion::GetVTKVersion()))
            .arg(EIGEN_WORLD_VERSION)
            .arg(EIGEN_MAJOR_VERSION)
            .arg(EIGEN_MINOR_VERSION)
            .arg(docs.isEmpty() ? QObject::tr("not installed with this build") : docs.toHtmlEscaped()));
}

} // namespace scandiff::gui
