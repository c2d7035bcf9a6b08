// SPDX-License-Identifier: GPL-3.0-or-later
#include "document/Document.h"

namespace scandiff::gui {

std::size_t Document::add(QString name, io::Entity entity)
{
    items_.push_back(std::make_unique<Item>(Item{std::move(name), std::move(entity)}));
    emit added(items_.size() - 1);
    return items_.size() - 1;
}

const PointCloud* Document::lastCloud() const
{
    for (auto it = items_.rbegin(); it != items_.rend(); ++it)
        if (const auto* cloud = std::get_if<PointCloud>(&(*it)->entity))
            return cloud;
    return nullptr;
}

void Document::clear()
{
    items_.clear();
    emit cleared();
}

} // namespace scandiff::gui
