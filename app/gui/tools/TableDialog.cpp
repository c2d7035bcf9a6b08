// SPDX-License-Identifier: GPL-3.0-or-later
#include "tools/TableDialog.h"

#include <scandiff/io/ResultFiles.h>

#include <QDialogButtonBox>
#include <QFileDialog>
#include <QHeaderView>
#include <QMessageBox>
#include <QPushButton>
#include <QTabBar>
#include <QTabWidget>
#include <QTableWidget>
#include <QVBoxLayout>

namespace scandiff::gui {

void fillTableWidget(QTableWidget& view, const Table& table)
{
    view.clear();
    view.setRowCount(static_cast<int>(table.rows.size()));
    view.setColumnCount(static_cast<int>(table.columns.size()));
    QStringList headers;
    for (const auto& c : table.columns)
        headers << QString::fromStdString(c);
    view.setHorizontalHeaderLabels(headers);
    for (std::size_t r = 0; r < table.rows.size(); ++r)
        for (std::size_t c = 0; c < table.rows[r].size() && c < table.columns.size(); ++c) {
            const TableCell& cell = table.rows[r][c];
            const QString text = std::holds_alternative<double>(cell) ? QString::number(std::get<double>(cell), 'g', 10)
                                                                       : QString::fromStdString(std::get<std::string>(cell));
            auto* item = new QTableWidgetItem(text);
            item->setFlags(item->flags() & ~Qt::ItemIsEditable);
            view.setItem(static_cast<int>(r), static_cast<int>(c), item);
        }
    view.horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
}

TableDialog::TableDialog(const QString& title, NamedTables tables, QWidget* parent) : QDialog(parent), tables_(std::move(tables))
{
    setWindowTitle(title);
    setAttribute(Qt::WA_DeleteOnClose);
    auto* layout = new QVBoxLayout(this);
    tabs_ = new QTabWidget(this);
    for (const auto& [name, table] : tables_) {
        views_.push_back(new QTableWidget(tabs_));
        fillTableWidget(*views_.back(), table);
        tabs_->addTab(views_.back(), QString::fromStdString(name));
    }
    tabs_->tabBar()->setVisible(tables_.size() > 1);
    layout->addWidget(tabs_);
    auto* buttons = new QDialogButtonBox(QDialogButtonBox::Close, this);
    QPushButton* save = buttons->addButton(tr("Save as CSV..."), QDialogButtonBox::ActionRole);
    connect(save, &QPushButton::clicked, this, [this] {
        const QString path = QFileDialog::getSaveFileName(this, tr("Save the table"), QString(), tr("CSV (*.csv)"));
        if (!path.isEmpty())
            saveAs(path);
    });
    connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
    layout->addWidget(buttons);
    resize(620, 460);
}

bool TableDialog::saveAs(const QString& path, int index)
{
    const int which = index >= 0 ? index : tabs_->currentIndex();
    try {
        io::writeTable(tables_.at(static_cast<std::size_t>(which)).second, path.toStdString());
        return true;
    } catch (const std::exception& e) {
        QMessageBox::warning(this, windowTitle(), QString::fromStdString(e.what()));
        return false;
    }
}

} // namespace scandiff::gui
