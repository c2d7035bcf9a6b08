// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The entities loaded in the workbench (clouds and meshes), owned here and
//! shown by the view. Tools read their inputs from it and add their outputs.

#include <scandiff/io/FileIO.h>

#include <QObject>
#include <QString>

#include <memory>
#include <vector>

namespace scandiff::gui {

class Document : public QObject
{
    Q_OBJECT
public:
    struct Item
    {
        QString name;
        io::Entity entity;
    };

    //! Takes ownership; returns the item's index.
    std::size_t add(QString name, io::Entity entity);
    std::size_t size() const { return items_.size(); }
    const Item& item(std::size_t i) const { return *items_.at(i); }
    //! The most recently added point cloud, or null.
    const PointCloud* lastCloud() const;
    void clear();

signals:
    void added(std::size_t index);
    void cleared();

private:
    // unique_ptr keeps each entity in place while the vector grows: the view and
    // running tools may hold references to it.
    std::vector<std::unique_ptr<Item>> items_;
};

} // namespace scandiff::gui
