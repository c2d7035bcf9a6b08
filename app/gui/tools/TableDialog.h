// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A window showing a tool's tables (a histogram, fitted parameters, a
//! registration's report and trace), one tab each, with a button that saves
//! the shown one as CSV, the file the CLI writes for the same run.

#include <scandiff/core/Table.h>

#include <QDialog>

#include <string>
#include <utility>
#include <vector>

class QTabWidget;
class QTableWidget;

namespace scandiff::gui {

//! Tables by name, in the order a tool gave them.
using NamedTables = std::vector<std::pair<std::string, Table>>;

//! Shows `table` in `view` (its columns as headers, cells read-only, numbers
//! to 10 significant digits), replacing what it showed.
void fillTableWidget(QTableWidget& view, const Table& table);

class TableDialog : public QDialog
{
    Q_OBJECT
public:
    TableDialog(const QString& title, NamedTables tables, QWidget* parent = nullptr);
    const Table& table(int index = 0) const { return tables_.at(static_cast<std::size_t>(index)).second; }
    int count() const { return static_cast<int>(tables_.size()); }
    //! The widget showing table `index`.
    QTableWidget* view(int index = 0) const { return views_.at(static_cast<std::size_t>(index)); }
    //! Writes table `index` (the shown one by default) as CSV (atomically);
    //! returns false and shows why on failure.
    bool saveAs(const QString& path, int index = -1);

private:
    NamedTables tables_;
    QTabWidget* tabs_;
    std::vector<QTableWidget*> views_;
};

} // namespace scandiff::gui
