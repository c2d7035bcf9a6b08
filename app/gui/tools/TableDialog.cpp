// SPDX-License-Identifier: GPL-3.0-or-later
#include "tools/TableDialog.h"

#include <scandiff/io/ResultFiles.h>

#include <QDialogButtonBox>
#include <QFileDialog>
#include <QHeaderView>
#include <QMessageBox>
#include <QPushButton>
#include <QTableWidget>
#include <QVBoxLayout>

namespace scandiff::gui {

TableDialog::TableDialog(const QString& title, Table table, QWidget* parent) : QDialog(parent), table_(std::move(table))
{
    setWindowTitle(title);
    setAttribute(Qt::WA_DeleteOnClose);
    auto* layout = new QVBoxLayout(this);
    view_ = new QTableWidget(static_cast<int>(table_.rows.size()), static_cast<int>(table_.columns.size()), this);
    QStringList headers;
    for (const auto& c : table_.columns)
        headers << QString::fromStdString(c);
    view_->setHorizontalHeaderLabels(headers);
    for (std::size_t r = 0; r < table_.rows.size(); ++r)
        for (std::size_t c = 0; c < table_.rows[r].size() && c < table_.columns.size(); ++c) {
            const TableCell& cell = table_.rows[r][c];
            const QString text = std::holds_alternative<double>(cell) ? QString::number(std::get<double>(cell), 'g', 10)
                                                                       : QString::fromStdString(std::get<std::string>(cell));
            auto* item = new QTableWidgetItem(text);
            item->setFlags(item->flags() & ~Qt::ItemIsEditable);
            view_->setItem(static_cast<int>(r), static_cast<int>(c), item);
        }
    view_->horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
    layout->addWidget(view_);
    auto* buttons = new QDialogButtonBox(QDialogButtonBox::Close, this);
    QPushButton* save = buttons->addButton(tr("Save as CSV..."), QDialogButtonBox::ActionRole);
    connect(save, &QPushButton::clicked, this, [this] {
        const QString path = QFileDialog::getSaveFileName(this, tr("Save the table"), QString(), tr("CSV (*.csv)"));
        if (!path.isEmpty())
            saveAs(path);
    });
    connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
    layout->addWidget(buttons);
    resize(560, 420);
}

bool TableDialog::saveAs(const QString& path)
{
    try {
        io::writeTable(table_, path.toStdString());
        return true;
    } catch (const std::exception& e) {
        QMessageBox::warning(this, windowTitle(), QString::fromStdString(e.what()));
        return false;
    }
}

} // namespace scandiff::gui
