// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The main window only assembles menus, docks and the view and wires their
//! signals; files, distances, splits, sessions and plugin tools each have
//! their own controller (controllers/), panels show the document (panels/).

#include "controllers/SplitController.h"
#include "document/Document.h"

#include <scandiff/plugins/PluginRegistry.h>

#include <QColor>

#include <Eigen/Core>
#include <QMainWindow>
#include <QPointer>
#include <QStringList>

#include <map>
#include <optional>
#include <vector>

namespace scandiff::gui {

class CloudView;
class ConsolePanel;
class DistanceController;
class EntityTree;
class FileController;
class MeasurePanel;
class MoveDialog;
class PropertiesPanel;
class ScalarFieldPanel;
class SegmentationController;
class SessionController;
class ToolController;

class MainWindow : public QMainWindow
{
    Q_OBJECT
public:
    explicit MainWindow(const PluginRegistry& registry, QWidget* parent = nullptr);
    //! Empties the view first: its VTK arrays read the document's points, and the
    //! document (a member) goes before the view (a child widget).
    ~MainWindow() override;

    //! Loads files (errors in a message box, or with `quiet` only in the console).
    //! Returns how many loaded.
    int openFiles(const QStringList& paths, bool quiet = false);

    Document& document() { return document_; }
    CloudView* view() const { return view_; }
    //! The right-hand view of View > Second view, null until first shown.
    CloudView* secondView() const { return secondView_; }
    //! Two views side by side with one camera, the first cloud opened on the
    //! left and the others on the right; off: one view showing everything.
    void setSideBySide(bool on);
    EntityTree* tree() const { return tree_; }
    PropertiesPanel* properties() const { return properties_; }
    ScalarFieldPanel* scalarPanel() const { return scalarPanel_; }
    ConsolePanel* console() const { return console_; }
    MeasurePanel* measure() const { return measure_; }
    FileController* files() const { return files_; }
    DistanceController* distances() const { return distances_; }
    SplitController* splits() const { return splits_; }
    SessionController* sessions() const { return sessions_; }
    SegmentationController* segmentation() const { return segmentation_; }
    //! The controller of a registered plugin tool, null if unknown.
    ToolController* toolController(const std::string& toolName) const;

    //! When entities hold work in no file (computed fields, derived clouds),
    //! asks whether to save the session first: true to go on (saved or
    //! discarded), false to stay (Cancel, or the save did not happen).
    bool mayDiscardUnsavedWork();

    // What the File menu and the tree's menu do with the tree's selection
    // (public for tests; the menus call them).
    //! File > Close selected: the selected entities leave the document (one undo step).
    void closeSelected();
    //! File > Close all: everything, after the unsaved-work question; false
    //! when nothing was open or the user stayed. Not undoable (the files stay).
    bool closeEverything();
    //! Hides the selected entities if any is shown, else shows them.
    void toggleSelectedVisibility();
    //! Gives each selected cloud one colour (the set-colour tool) and shows
    //! its colours; returns how many were coloured.
    int colourSelected(const QColor& colour);
    //! A copy of each selected cloud (the clone tool); returns how many.
    int cloneSelected();
    //! Edit > Move / rotate: the dialog for the selected entities (null when
    //! none is selected); it deletes itself when closed.
    MoveDialog* moveSelectedInteractively();
    //! Moves the entities by a global matrix with the transform tool (one undo
    //! step); returns how many moved.
    int applyMotion(const std::vector<EntityId>& ids, const Eigen::Matrix4d& global);

protected:
    void closeEvent(QCloseEvent* event) override;
    void dragEnterEvent(QDragEnterEvent* event) override;
    void dropEvent(QDropEvent* event) override;

private:
    void buildDocks();
    void buildMenus();
    void buildFileMenu();
    QMenu* buildEditMenu();
    void buildViewMenu();
    void buildDisplayOptions(QMenu* viewMenu);
    void buildHelpMenu();
    void buildTreeMenu();
    //! Removes the tree's selected entities as one undo step named by `verb`.
    void removeSelected(const QString& verb);
    void renameCurrent();
    //! The scissors' confirm step: which part to keep, or nothing (Cancel).
    std::optional<SplitController::Keep> askWhatTheScissorsKeep();
    void buildToolsMenu(QMenu* editMenu, QMenu* toolsMenu);
    //! The tree's current entity, then the other selected ones: what a tool proposes as its inputs.
    std::vector<EntityId> toolSelection() const;
    //! Console + status bar for a controller's finished/failed signals.
    template <class Controller> void report(Controller* controller);
    void onCurrentEntityChanged(EntityId id);
    //! The colour bar of the selected entity when it is shown with a field, else
    //! of the last visible one with a field; none otherwise.
    void updateLegend();
    //! Export regions is offered only for a cloud that has regions.
    void updateRegionExport();

    const PluginRegistry& registry_;
    Document document_;
    std::vector<QAction*> regionExportActions_;
    QAction* deleteAction_ = nullptr;
    QAction* renameAction_ = nullptr;
    QAction* zoomSelection_ = nullptr;
    QPointer<MoveDialog> moveDialog_;
    CloudView* view_;
    CloudView* secondView_ = nullptr;
    EntityTree* tree_ = nullptr;
    PropertiesPanel* properties_ = nullptr;
    ScalarFieldPanel* scalarPanel_ = nullptr;
    ConsolePanel* console_ = nullptr;
    MeasurePanel* measure_ = nullptr;
    FileController* files_ = nullptr;
    DistanceController* distances_ = nullptr;
    SplitController* splits_ = nullptr;
    SessionController* sessions_ = nullptr;
    SegmentationController* segmentation_ = nullptr;
    std::map<std::string, ToolController*> tools_;
};

} // namespace scandiff::gui
