// SPDX-License-Identifier: GPL-3.0-or-later
#include "document/Document.h"

#include <scandiff/core/distance/DemOfDifference.h>

#include <QFileInfo>

#include <algorithm>
#include <stdexcept>

namespace scandiff::gui {

const PointCloud& Document::Item::points() const
{
    if (const Mesh* m = mesh())
        return m->vertices;
    return std::get<PointCloud>(entity);
}

EntityId Document::insert(std::unique_ptr<Item> item)
{
    const EntityId id = item->id;
    const QString addedName = item->name;
    items_.push_back(std::move(item));
    emit added(id);
    if (groupDepth_ > 0) { // a tool's outputs, a split's parts: undone with their action
        UndoStep step;
        step.kind = UndoKind::Addition;
        step.name = addedName;
        step.id = id;
        remember(std::move(step));
    }
    return id;
}

EntityId Document::add(QString name, io::Entity entity, EntityId parent, QString sourcePath, Properties properties)
{
    auto item = std::make_unique<Item>();
    item->id = nextId_++;
    item->name = std::move(name);
    item->entity = std::move(entity);
    item->properties = std::move(properties);
    item->parent = contains(parent) ? parent : kNoEntity;
    item->sourcePath = std::move(sourcePath);
    item->unsaved = item->sourcePath.isEmpty();
    // A grid (DEM of difference, raster) shows its difference or height, not
    // its column numbers. A mesh shows its vertices' first field too (a
    // shape's surface, coloured by its primitive_id as its points are).
    if (const PointCloud* cloud = item->hasData() ? &item->points() : nullptr; cloud && !cloud->fields().empty()) {
        const ScalarField* main = mainGridField(*cloud);
        item->display.activeField = main ? main->name() : cloud->fields().front().name();
    }
    return insert(std::move(item));
}

EntityId Document::addDrawing(QString name, Drawing drawing, EntityId parent, QString sourcePath)
{
    auto item = std::make_unique<Item>();
    item->id = nextId_++;
    item->name = std::move(name);
    item->entity = PointCloud{};
    item->drawing = std::make_shared<const Drawing>(std::move(drawing));
    item->parent = contains(parent) ? parent : kNoEntity;
    item->sourcePath = std::move(sourcePath);
    item->unsaved = item->sourcePath.isEmpty();
    return insert(std::move(item));
}

EntityId Document::addGroup(QString name, EntityId parent, QString sourcePath)
{
    auto item = std::make_unique<Item>();
    item->id = nextId_++;
    item->name = std::move(name);
    item->entity = PointCloud{};
    item->group = true;
    item->parent = contains(parent) ? parent : kNoEntity;
    item->sourcePath = std::move(sourcePath);
    return insert(std::move(item));
}

std::vector<EntityId> Document::children(EntityId id) const
{
    std::vector<EntityId> out;
    for (const auto& item : items_)
        if (item->parent == id)
            out.push_back(item->id);
    return out;
}

void Document::remove(EntityId id)
{
    const Item* item = find(id);
    if (!item)
        return;
    UndoStep step;
    step.kind = UndoKind::Removal;
    step.name = item->name;
    removeWithoutUndo(id, step.removed);
    remember(std::move(step));
}

void Document::removeWithoutUndo(EntityId id, std::vector<std::unique_ptr<Item>>& taken)
{
    // Children first, so observers never see an orphan.
    std::vector<EntityId> children;
    for (const auto& item : items_)
        if (item->parent == id)
            children.push_back(item->id);
    for (EntityId child : children)
        removeWithoutUndo(child, taken);
    const auto it = std::find_if(items_.begin(), items_.end(), [id](const auto& item) { return item->id == id; });
    if (it == items_.end())
        return;
    taken.push_back(std::move(*it));
    items_.erase(it);
    emit removed(id);
}

void Document::clear()
{
    items_.clear();
    forgetUndo();
    emit cleared();
}

std::vector<EntityId> Document::ids() const
{
    std::vector<EntityId> out;
    for (const auto& item : items_)
        out.push_back(item->id);
    return out;
}

const Document::Item* Document::find(EntityId id) const
{
    for (const auto& item : items_)
        if (item->id == id)
            return item.get();
    return nullptr;
}

Document::Item* Document::findMutable(EntityId id) { return const_cast<Item*>(find(id)); }

template <class Value> void Document::setDisplayMember(EntityId id, Value DisplayState::*member, const Value& value)
{
    Item* item = findMutable(id);
    if (!item || item->display.*member == value)
        return;
    item->display.*member = value;
    emit displayChanged(id);
}

const Document::Item& Document::item(EntityId id) const
{
    const Item* item = find(id);
    if (!item)
        throw std::out_of_range("no entity with id " + std::to_string(id));
    return *item;
}

const PointCloud* Document::lastCloud() const
{
    const EntityId id = lastCloudId();
    return id == kNoEntity ? nullptr : item(id).cloud();
}

EntityId Document::lastCloudId() const
{
    for (auto it = items_.rbegin(); it != items_.rend(); ++it)
        if ((*it)->cloud())
            return (*it)->id;
    return kNoEntity;
}

void Document::replaceData(EntityId id, io::Entity entity)
{
    Item* item = findMutable(id);
    if (!item)
        return;
    std::vector<std::string> oldFields;
    for (const auto& f : item->points().fields())
        oldFields.push_back(f.name());
    emit aboutToReplaceData(id);
    UndoStep step;
    step.kind = UndoKind::Replacement;
    step.name = item->name;
    step.id = id;
    step.previousDisplay = item->display;
    io::Entity previous = std::move(item->entity);
    const Mesh* oldMesh = std::get_if<Mesh>(&previous);
    PointCloud* cloud = std::get_if<PointCloud>(&entity);
    if (oldMesh && cloud && cloud->size() == oldMesh->vertices.size()) {
        // New vertices for a mesh: its triangles stay.
        Mesh mesh;
        mesh.name = oldMesh->name;
        mesh.triangles = oldMesh->triangles;
        mesh.vertices = std::move(*cloud);
        item->entity = std::move(mesh);
    } else {
        item->entity = std::move(entity);
    }
    step.previousData = std::move(previous);
    remember(std::move(step));
    const auto& fields = item->points().fields();
    const auto has = [&](const std::string& name) {
        return std::any_of(fields.begin(), fields.end(), [&](const ScalarField& f) { return f.name() == name; });
    };
    for (auto it = item->display.fields.begin(); it != item->display.fields.end();)
        it = has(it->first) ? std::next(it) : item->display.fields.erase(it);
    for (const auto& f : fields)
        if (std::find(oldFields.begin(), oldFields.end(), f.name()) == oldFields.end()) {
            item->display.activeField = f.name();
            break;
        }
    if (!item->display.activeField.empty() && !has(item->display.activeField))
        item->display.activeField = fields.empty() ? std::string() : fields.front().name();
    item->unsaved = true;
    emit dataReplaced(id);
    emit fieldsChanged(id);
    emit displayChanged(id);
}

void Document::addField(EntityId id, ScalarField field)
{
    Item* item = findMutable(id);
    auto* cloud = item ? std::get_if<PointCloud>(&item->entity) : nullptr;
    if (!cloud)
        return;
    const std::string name = field.name();
    UndoStep step;
    step.kind = UndoKind::Field;
    step.name = item->name;
    step.id = id;
    step.fieldName = name;
    step.previousDisplay = item->display;
    if (const ScalarField* previous = cloud->field(name))
        step.previousField = *previous;
    cloud->addField(std::move(field)); // may throw (a size mismatch): nothing is remembered then
    remember(std::move(step));
    item->unsaved = true;
    // A recomputed field starts again from its full range.
    item->display.fields.erase(name);
    item->display.activeField = name;
    emit fieldsChanged(id);
    emit displayChanged(id);
}

void Document::setVisible(EntityId id, bool visible)
{
    if (const Item* item = find(id); item && groupDepth_ > 0 && item->display.visible != visible) {
        UndoStep step; // a parent a split hides comes back with the undo
        step.kind = UndoKind::Visibility;
        step.name = item->name;
        step.id = id;
        step.previousVisible = item->display.visible;
        remember(std::move(step));
    }
    setDisplayMember(id, &DisplayState::visible, visible);
    // A group's checkbox is its scans'.
    if (const Item* item = find(id); item && item->isGroup())
        for (EntityId child : children(id))
            setVisible(child, visible);
}

bool Document::revealResult(EntityId id)
{
    const Item* item = find(id);
    if (!item || item->display.visible)
        return false;
    for (std::vector<EntityId> pending = children(id); !pending.empty();) {
        const EntityId child = pending.back();
        pending.pop_back();
        setVisible(child, false);
        for (EntityId grandChild : children(child))
            pending.push_back(grandChild);
    }
    setVisible(id, true);
    return true;
}

void Document::setActiveField(EntityId id, const std::string& fieldName)
{
    Item* item = findMutable(id);
    if (!item || item->display.activeField == fieldName)
        return;
    if (!fieldName.empty() && !item->points().field(fieldName))
        return;
    item->display.activeField = fieldName;
    emit displayChanged(id);
}

void Document::setFieldDisplay(EntityId id, const std::string& fieldName, const FieldDisplay& display)
{
    Item* item = findMutable(id);
    if (!item)
        return;
    item->display.fields[fieldName] = display;
    emit displayChanged(id);
}

void Document::setOutsideMode(EntityId id, FieldColouring::Outside mode)
{
    setDisplayMember(id, &DisplayState::outside, mode);
}

void Document::setNeutral(EntityId id, bool neutral)
{
    setDisplayMember(id, &DisplayState::neutral, neutral);
}

void Document::setBlendColours(EntityId id, bool blend)
{
    setDisplayMember(id, &DisplayState::blendColours, blend);
}

void Document::setPointSize(EntityId id, float pixels)
{
    setDisplayMember(id, &DisplayState::pointSize, pixels);
}

FieldDisplay Document::fieldDisplay(EntityId id, const std::string& fieldName) const
{
    const Item* item = find(id);
    if (!item)
        return {};
    const auto it = item->display.fields.find(fieldName);
    return it == item->display.fields.end() ? FieldDisplay{} : it->second;
}

void Document::rename(EntityId id, const QString& name)
{
    Item* item = findMutable(id);
    if (!item || item->name == name)
        return;
    UndoStep step;
    step.kind = UndoKind::Rename;
    step.name = name;
    step.id = id;
    step.previousName = item->name;
    item->name = name;
    remember(std::move(step));
    emit renamed(id);
}

std::vector<EntityId> Document::unsavedIds() const
{
    std::vector<EntityId> out;
    for (const auto& item : items_)
        if (item->unsaved)
            out.push_back(item->id);
    return out;
}

void Document::markSaved(EntityId id, const QString& path)
{
    Item* item = findMutable(id);
    if (!item)
        return;
    item->unsaved = false;
    if (path.isEmpty())
        return;
    item->sourcePath = QFileInfo(path).absoluteFilePath();
    if (item->isGroup())
        for (EntityId child : children(id))
            if (Item* scan = findMutable(child)) {
                scan->sourcePath = item->sourcePath;
                scan->unsaved = false;
            }
}

void Document::markAllSaved()
{
    for (const auto& item : items_)
        item->unsaved = false;
}

Document::UndoGroup::UndoGroup(Document& document, QString text) : document_(document)
{
    // The redo history goes once the group records something (in remember()):
    // a run that changes nothing (a table, a cut of nothing) keeps it.
    if (document_.groupDepth_++ == 0 && !document_.reverting_)
        document_.undoStack_.push_back(UndoAction{std::move(text), {}});
}

Document::UndoGroup::~UndoGroup()
{
    if (--document_.groupDepth_ == 0 && !document_.reverting_) {
        if (!document_.undoStack_.empty() && document_.undoStack_.back().steps.empty())
            document_.undoStack_.pop_back(); // nothing to undo: no entry in the menu
        emit document_.undoChanged();
    }
}

void Document::remember(UndoStep step)
{
    if (step.kind == UndoKind::None)
        return;
    if (reverting_) {
        reverted_.push_back(std::move(step));
        return;
    }
    if (groupDepth_ == 0 || undoStack_.empty())
        undoStack_.push_back(UndoAction{QString(), {}});
    if (undoStack_.back().steps.empty())
        redoStack_.clear(); // a new action: what was undone can no longer be redone
    undoStack_.back().steps.push_back(std::move(step));
    if (undoStack_.size() > kUndoLevels)
        undoStack_.erase(undoStack_.begin()); // the oldest goes, with the data it held
    emit undoChanged();
}

void Document::forgetUndo()
{
    undoStack_.clear();
    redoStack_.clear();
    emit undoChanged();
}

QString Document::describe(const UndoAction& action)
{
    if (!action.text.isEmpty())
        return action.text;
    if (action.steps.empty())
        return QString();
    const UndoStep& step = action.steps.back();
    switch (step.kind) {
    case UndoKind::Removal: return tr("delete '%1'").arg(step.name);
    case UndoKind::Addition: return tr("add '%1'").arg(step.name);
    case UndoKind::Replacement: return tr("the change of '%1'").arg(step.name);
    case UndoKind::Field: return tr("field %1 of '%2'").arg(QString::fromStdString(step.fieldName), step.name);
    case UndoKind::Visibility: return tr("showing '%1'").arg(step.name);
    case UndoKind::Rename: return tr("rename to '%1'").arg(step.name);
    case UndoKind::None: break;
    }
    return QString();
}

QString Document::undoText() const
{
    return undoStack_.empty() ? tr("Undo") : tr("Undo %1").arg(describe(undoStack_.back())).trimmed();
}

QString Document::redoText() const
{
    return redoStack_.empty() ? tr("Redo") : tr("Redo %1").arg(describe(redoStack_.back())).trimmed();
}

void Document::undo() { revertLast(undoStack_, redoStack_); }

void Document::redo() { revertLast(redoStack_, undoStack_); }

void Document::revertLast(std::vector<UndoAction>& from, std::vector<UndoAction>& to)
{
    if (from.empty() || groupDepth_ > 0)
        return;
    UndoAction action = std::move(from.back());
    from.pop_back();
    to.push_back(revert(std::move(action)));
    emit undoChanged();
}

Document::UndoAction Document::revert(UndoAction action)
{
    // Newest first; each reverted step gives the step that makes it again,
    // kept in the order made so that reverting those is the forward order.
    UndoAction inverse{describe(action), {}}; // named as the action the user made, both ways
    struct Reverting // back to recording however a step ends (a throw included)
    {
        Document& document;
        ~Reverting()
        {
            document.reverting_ = false;
            document.reverted_.clear();
        }
    } reverting{*this};
    reverting_ = true;
    for (auto it = action.steps.rbegin(); it != action.steps.rend(); ++it)
        inverse.steps.push_back(revertStep(*it));
    return inverse;
}

Document::UndoStep Document::revertStep(UndoStep& step)
{
    UndoStep inverse;
    inverse.name = step.name;
    switch (step.kind) {
    case UndoKind::Removal: {
        // Parents first (they were removed last), each with its id, parent and display.
        inverse.kind = UndoKind::Addition;
        inverse.id = step.removed.empty() ? kNoEntity : step.removed.back()->id;
        for (auto it = step.removed.rbegin(); it != step.removed.rend(); ++it) {
            const EntityId id = (*it)->id;
            items_.push_back(std::move(*it));
            emit added(id);
        }
        break;
    }
    case UndoKind::Addition:
        inverse.kind = UndoKind::Removal;
        removeWithoutUndo(step.id, inverse.removed);
        break;
    case UndoKind::Replacement:
        if (Item* item = findMutable(step.id)) {
            // The data and the display of its fields come back; visibility,
            // point size and the like stay as the user has set them since.
            const bool visible = item->display.visible, neutral = item->display.neutral;
            const float pointSize = item->display.pointSize;
            const DisplayState current = item->display;
            reverted_.clear();
            replaceData(step.id, std::move(*step.previousData));
            if (!reverted_.empty()) {
                inverse = std::move(reverted_.back()); // the data it replaced
                inverse.previousDisplay = current;
            }
            item->display = step.previousDisplay;
            item->display.visible = visible;
            item->display.neutral = neutral;
            item->display.pointSize = pointSize;
            emit displayChanged(step.id);
        }
        break;
    case UndoKind::Field:
        if (Item* item = findMutable(step.id); item && item->cloud()) {
            auto& cloud = std::get<PointCloud>(item->entity);
            inverse.kind = UndoKind::Field;
            inverse.id = step.id;
            inverse.fieldName = step.fieldName;
            inverse.previousDisplay = item->display;
            if (const ScalarField* current = cloud.field(step.fieldName))
                inverse.previousField = *current;
            if (step.previousField)
                cloud.addField(std::move(*step.previousField));
            else
                cloud.removeField(step.fieldName);
            // Only this field's display and the choice of the active field go back.
            const auto previous = step.previousDisplay.fields.find(step.fieldName);
            if (previous != step.previousDisplay.fields.end())
                item->display.fields[step.fieldName] = previous->second;
            else
                item->display.fields.erase(step.fieldName);
            item->display.activeField = step.previousDisplay.activeField;
            if (!item->display.activeField.empty() && !cloud.field(item->display.activeField))
                item->display.activeField.clear();
            emit fieldsChanged(step.id);
            emit displayChanged(step.id);
        }
        break;
    case UndoKind::Visibility:
        if (const Item* item = find(step.id)) {
            inverse.kind = UndoKind::Visibility;
            inverse.id = step.id;
            inverse.previousVisible = item->display.visible;
            setDisplayMember(step.id, &DisplayState::visible, step.previousVisible);
        }
        break;
    case UndoKind::Rename:
        if (Item* item = findMutable(step.id)) {
            inverse.kind = UndoKind::Rename;
            inverse.id = step.id;
            inverse.name = item->name; // redo renames to it again
            inverse.previousName = item->name;
            item->name = step.previousName;
            emit renamed(step.id);
        }
        break;
    case UndoKind::None: break;
    }
    return inverse;
}

} // namespace scandiff::gui
