// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A window showing a tool's table (a histogram, fitted parameters), with a
//! button that saves it as CSV, the file the CLI writes for the same run.

#include <scandiff/core/Table.h>

#include <QDialog>

class QTableWidget;

namespace scandiff::gui {

class TableDialog : public QDialog
{
    Q_OBJECT
public:
    TableDialog(const QString& title, Table table, QWidget* parent = nullptr);
    const Table& table() const { return table_; }
    QTableWidget* view() const { return view_; }
    //! Writes the table as CSV (atomically); returns false and shows why on failure.
    bool saveAs(const QString& path);

private:
    Table table_;
    QTableWidget* view_;
};

} // namespace scandiff::gui
