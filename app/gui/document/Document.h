// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The entities loaded in the workbench (clouds, meshes, drawings) and how each is
//! shown: visibility, active scalar field, colour scale and thresholds per field.
//! Owned here; the view, the panels and the controllers observe the signals.
//! Entities have stable ids; a derived entity (a split part, closest points)
//! names its parent so the tree shows it underneath.

#include "colour/ColourScale.h"

#include <scandiff/core/Drawing.h>
#include <scandiff/io/FileIO.h>

#include <QObject>
#include <QString>

#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <vector>

namespace scandiff::gui {

using EntityId = int;
constexpr EntityId kNoEntity = -1;

//! How one scalar field is shown, as in CloudCompare: the *colour range* the
//! scale spans (values beyond it take the end colours: narrowing it shows the
//! small changes beside large ones) and, independently, the *threshold range*
//! (inclusive) outside which points are hidden or greyed.
struct FieldDisplay
{
    ColourScale scale = ColourScale::defaultScale();
    double low = -std::numeric_limits<double>::infinity();  //!< threshold
    double high = std::numeric_limits<double>::infinity();  //!< threshold
    double colourLow = -std::numeric_limits<double>::infinity();  //!< colour range; infinite: the field's own end
    double colourHigh = std::numeric_limits<double>::infinity();
    //! The colour range made [-m, m] (m its largest magnitude), so 0 sits at the
    //! scale's middle; a diverging scale always is.
    bool symmetric = false;
    //! Values a tool found on this field (a threshold, class means), drawn on its histogram.
    std::vector<std::pair<double, std::string>> marks;
};

struct DisplayState
{
    bool visible = true;
    //! Empty: the entity's colours, else its height (or `neutral`).
    std::string activeField;
    //! Without an active field, one neutral grey instead of colours or height:
    //! how a reference is shown after a comparison, so that no other rainbow
    //! competes with the distances' scale.
    bool neutral = false;
    //! The entity's own point size in pixels; 0: the view's.
    float pointSize = 0;
    //! An active field's colours shaded by the cloud's own (its photo's
    //! lightness), so the field reads over the texture; no effect without colours.
    bool blendColours = false;
    FieldColouring::Outside outside = FieldColouring::Outside::Hide;
    std::map<std::string, FieldDisplay> fields; //!< by field name; absent = defaults
};

class Document : public QObject
{
    Q_OBJECT
public:
    struct Item
    {
        EntityId id = kNoEntity;
        QString name;
        io::Entity entity;
        EntityId parent = kNoEntity;
        QString sourcePath; //!< the file it was read from, empty for derived entities
        DisplayState display;
        //! Holds work that is in no file: a derived entity, computed fields,
        //! moved points. Cleared when it is exported or the session saved.
        bool unsaved = false;

        //! A drawing a tool gave (contours, sections): its polylines, drawn
        //! over the clouds; `entity` is then an empty cloud, and cloud() null.
        std::shared_ptr<const Drawing> drawing;
        //! What the tool that made it said of it (a shape's type, parameters and
        //! uncertainties), listed in the Properties panel, in order.
        std::vector<std::pair<QString, QString>> properties;
        //! A folder of the tree holding the parts of one file (the scans of an
        //! E57): no data of its own (`entity` is an empty cloud, cloud() null).
        bool group = false;

        const PointCloud* cloud() const { return drawing || group ? nullptr : std::get_if<PointCloud>(&entity); }
        const Mesh* mesh() const { return std::get_if<Mesh>(&entity); }
        bool isDrawing() const { return drawing != nullptr; }
        bool isGroup() const { return group; }
        //! Holds points or triangles (not a drawing, not a group).
        bool hasData() const { return !drawing && !group; }
        //! The points of a cloud, or the vertices of a mesh.
        const PointCloud& points() const;
    };

    using Properties = std::vector<std::pair<QString, QString>>;
    //! Takes ownership; returns the new id. A cloud's first scalar field becomes active.
    EntityId add(QString name, io::Entity entity, EntityId parent = kNoEntity, QString sourcePath = {},
                 Properties properties = {});
    //! Takes a drawing (polylines and labels, global coordinates); returns its id.
    EntityId addDrawing(QString name, Drawing drawing, EntityId parent = kNoEntity, QString sourcePath = {});
    //! A group for the parts of one file; its children name it as their parent.
    EntityId addGroup(QString name, EntityId parent = kNoEntity, QString sourcePath = {});
    //! The direct children of an entity, in the order they were added.
    std::vector<EntityId> children(EntityId id) const;
    //! Removes the entity and its descendants.
    void remove(EntityId id);
    void clear();

    std::size_t size() const { return items_.size(); }
    //! In the order they were added.
    std::vector<EntityId> ids() const;
    bool contains(EntityId id) const { return find(id) != nullptr; }
    //! Throws std::out_of_range for an unknown id.
    const Item& item(EntityId id) const;
    const Item* find(EntityId id) const;
    //! The most recently added point cloud, or null.
    const PointCloud* lastCloud() const;
    EntityId lastCloudId() const;

    //! Replaces the data of an entity, keeping its id, name, place in the tree
    //! and the display of the fields it still has (a tool that added normals,
    //! fields or moved the points). A point cloud given for a mesh of the same
    //! size replaces its vertices and keeps its triangles. The first field the
    //! new data has and the old had not becomes active. Observers see
    //! aboutToReplaceData (drop references to the old data) then dataReplaced.
    void replaceData(EntityId id, io::Entity entity);

    //! Adds (or replaces) a scalar field of a cloud and makes it active.
    void addField(EntityId id, ScalarField field);
    void setVisible(EntityId id, bool visible);
    //! Shows an entity a tool has just put its result on when it was hidden
    //! (a parent after a split), hiding its shown descendants (the split's
    //! parts) so that the result is what the view draws. Returns whether it
    //! was hidden, for the tool's message.
    bool revealResult(EntityId id);
    //! Empty name: colours / height. Unknown names are ignored.
    void setActiveField(EntityId id, const std::string& fieldName);
    void setFieldDisplay(EntityId id, const std::string& fieldName, const FieldDisplay& display);
    void setOutsideMode(EntityId id, FieldColouring::Outside mode);
    void setNeutral(EntityId id, bool neutral);
    void setBlendColours(EntityId id, bool blend);
    void setPointSize(EntityId id, float pixels);
    //! The display of a field (defaults when never set).
    FieldDisplay fieldDisplay(EntityId id, const std::string& fieldName) const;
    void rename(EntityId id, const QString& name);

    //! An undo history, and its redo, of what changes data: a removal (with
    //! the entity's descendants), a replacement of an entity's data (a tool
    //! that moved or edited it), a field added or recomputed, a rename; inside an
    //! UndoGroup also the entities added (a tool's outputs, a split's or the
    //! scissors' parts) and the visibility changed (the parent they hide). Up
    //! to kUndoLevels actions; a new action empties the redo history; clear()
    //! forgets both. What is undone or redone comes back with its id, place in
    //! the tree and display.
    static constexpr std::size_t kUndoLevels = 20;
    bool canUndo() const { return !undoStack_.empty(); }
    bool canRedo() const { return !redoStack_.empty(); }
    //! "Undo delete 'site-2019'", "Redo Cut by polygon", for the menu.
    QString undoText() const;
    QString redoText() const;
    void undo();
    void redo();
    //! Forgets the undo and redo histories (a controller whose own state would
    //! no longer match the data they would bring back).
    void forgetUndo();

    class UndoGroup
    {
    public:
        UndoGroup(Document& document, QString text);
        ~UndoGroup();
        UndoGroup(const UndoGroup&) = delete;
        UndoGroup& operator=(const UndoGroup&) = delete;

    private:
        Document& document_;
    };
    //! The entities whose work would be lost on quitting, in tree order.
    std::vector<EntityId> unsavedIds() const;
    //! The entity's data is now in a file (exported). With a path, that file
    //! is its file from now on (logged command lines name it, not the file
    //! it was opened from, which no longer holds the same data); a group's
    //! scans share it.
    void markSaved(EntityId id, const QString& path = QString());
    //! Everything is in a file (the session was saved or just opened).
    void markAllSaved();

signals:
    void added(EntityId id);
    void removed(EntityId id);
    void fieldsChanged(EntityId id);
    //! Visibility, active field, scale, thresholds or outside mode changed.
    void displayChanged(EntityId id);
    void renamed(EntityId id);
    void cleared();
    void aboutToReplaceData(EntityId id);
    void dataReplaced(EntityId id);
    //! What undo() or redo() would do changed.
    void undoChanged();

private:
    Item* findMutable(EntityId id);
    //! Puts a new entity in the document (an undo step inside an UndoGroup); returns its id.
    EntityId insert(std::unique_ptr<Item> item);
    //! Sets one member of an entity's display state; signals only a real change.
    template <class Value> void setDisplayMember(EntityId id, Value DisplayState::*member, const Value& value);
    void removeWithoutUndo(EntityId id, std::vector<std::unique_ptr<Item>>& taken);
    enum class UndoKind { None, Removal, Addition, Replacement, Field, Visibility, Rename };
    struct UndoStep
    {
        UndoKind kind = UndoKind::None;
        QString name;                                //!< the entity's, for the menu
        std::vector<std::unique_ptr<Item>> removed;  //!< Removal: the entity and its descendants, children first
        EntityId id = kNoEntity;                     //!< Addition, Replacement, Field, Visibility, Rename
        std::optional<io::Entity> previousData;      //!< Replacement
        DisplayState previousDisplay;                //!< Replacement, Field
        std::string fieldName;                       //!< Field
        std::optional<ScalarField> previousField;    //!< Field: the one it replaced, if any
        bool previousVisible = true;                 //!< Visibility
        QString previousName;                        //!< Rename
    };
    //! One user action: its steps in the order made, and its menu text.
    struct UndoAction
    {
        QString text;
        std::vector<UndoStep> steps;
    };
    void remember(UndoStep step);
    //! Reverts one step; returns the step that makes it again.
    UndoStep revertStep(UndoStep& step);
    //! Reverts an action's steps newest first; returns the action that makes them again.
    UndoAction revert(UndoAction action);
    //! Reverts the last action of `from` and puts its inverse on `to` (undo, redo).
    void revertLast(std::vector<UndoAction>& from, std::vector<UndoAction>& to);
    static QString describe(const UndoAction& action);
    std::vector<UndoAction> undoStack_, redoStack_;
    int groupDepth_ = 0;
    bool reverting_ = false;
    std::vector<UndoStep> reverted_; //!< while reverting: the steps a reverting change would remember
    // unique_ptr keeps each entity in place while the vector grows: the view and
    // running tools may hold references to it.
    std::vector<std::unique_ptr<Item>> items_;
    EntityId nextId_ = 1;
};

} // namespace scandiff::gui
