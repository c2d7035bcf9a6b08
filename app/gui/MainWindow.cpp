// SPDX-License-Identifier: GPL-3.0-or-later
#include "MainWindow.h"

#include "HelpDialogs.h"

#include <algorithm>

#include "controllers/DistanceController.h"
#include "controllers/FileController.h"
#include "controllers/SegmentationController.h"
#include "controllers/SessionController.h"
#include "controllers/SplitController.h"
#include "controllers/ToolController.h"
#include "panels/ConsolePanel.h"
#include "panels/EntityTree.h"
#include "panels/PropertiesPanel.h"
#include "panels/ScalarFieldPanel.h"
#include "tools/MeasurePanel.h"
#include "tools/MoveDialog.h"
#include "tools/TableDialog.h"
#include "view/CloudView.h"
#include "view/EntityColouring.h"

#include <scandiff/core/Error.h>
#include <scandiff/io/DxfWriter.h>
#include <scandiff/io/ResultFiles.h>

#include <QAction>
#include <QCloseEvent>
#include <QColorDialog>
#include <QActionGroup>
#include <QApplication>
#include <QDesktopServices>
#include <QDir>
#include <QDockWidget>
#include <QFileInfo>
#include <QUrl>
#include <QFileDialog>
#include <QDragEnterEvent>
#include <QDropEvent>
#include <QInputDialog>
#include <QLineEdit>
#include <QMenuBar>
#include <QMessageBox>
#include <QMimeData>
#include <QPushButton>
#include <QSettings>
#include <QSplitter>
#include <QStatusBar>
#include <QScrollArea>
#include <QStyle>
#include <QTimer>
#include <QToolBar>

#include <set>

namespace scandiff::gui {

namespace {
constexpr const char* kGeometrySetting = "window/geometry";
constexpr const char* kLayoutSetting = "window/layout";
constexpr const char* kBackgroundSetting = "display/background";
constexpr const char* kEdlSetting = "display/eyeDomeLighting";
constexpr const char* kScaleBarSetting = "display/scaleBar";
} // namespace


MainWindow::MainWindow(const PluginRegistry& registry, QWidget* parent)
    : QMainWindow(parent), registry_(registry), view_(new CloudView(this))
{
    setWindowTitle(tr("scandiff"));
    setCentralWidget(view_);
    setAcceptDrops(true);
    resize(1400, 900);
    buildDocks();

    files_ = new FileController(registry_, document_, this);
    distances_ = new DistanceController(document_, this);
    splits_ = new SplitController(document_, this);
    sessions_ = new SessionController(registry_, document_, *view_, *scalarPanel_, this);
    sessions_->setDiscardCheck([this] { return mayDiscardUnsavedWork(); });
    sessions_->setMeasurePanel(measure_);
    report(files_);
    report(distances_);
    report(splits_);
    report(sessions_);
    segmentation_ = new SegmentationController(registry_, document_, this);
    report(segmentation_);
    connect(segmentation_, &SegmentationController::resultReady, tree_, &EntityTree::selectEntity);
    buildMenus();

    // The view follows the document.
    connect(&document_, &Document::added, this, [this](EntityId id) {
        // The first entity with points frames the view (a group before its scans does not count).
        bool first = document_.item(id).hasData();
        for (EntityId other : document_.ids())
            first = first && (other == id || !document_.item(other).hasData());
        view_->addEntity(document_.item(id));
        if (first)
            view_->resetCamera();
        tree_->selectEntity(id);
    });
    connect(&document_, &Document::removed, view_, &CloudView::removeEntity);
    // A tool changed an entity's data: the view drops the old arrays before
    // they go, then uploads the new ones.
    connect(&document_, &Document::aboutToReplaceData, view_, &CloudView::removeEntity);
    connect(&document_, &Document::dataReplaced, this, [this](EntityId id) { view_->addEntity(document_.item(id)); });
    connect(&document_, &Document::cleared, view_, &CloudView::clear);
    // The colour bar reads the field's range (every value): once, when the
    // event loop turns, for the several display changes a tool makes at once.
    auto* legendSoon = new QTimer(this);
    legendSoon->setSingleShot(true);
    legendSoon->setInterval(0);
    connect(legendSoon, &QTimer::timeout, this, &MainWindow::updateLegend);
    connect(&document_, &Document::displayChanged, this, [this, legendSoon](EntityId id) {
        view_->refreshEntity(document_.item(id));
        legendSoon->start();
    });
    connect(&document_, &Document::removed, this, [this] { updateLegend(); });
    // Which clouds are in the frame changes with the camera: the bar follows
    // once a move has stopped (not at each of its frames).
    auto* legendTimer = new QTimer(this);
    legendTimer->setSingleShot(true);
    legendTimer->setInterval(150);
    connect(legendTimer, &QTimer::timeout, this, &MainWindow::updateLegend);
    connect(view_, &CloudView::cameraChanged, legendTimer, qOverload<>(&QTimer::start));
    connect(&document_, &Document::fieldsChanged, this, [this] { updateRegionExport(); });
    connect(tree_, &EntityTree::currentEntityChanged, this, &MainWindow::onCurrentEntityChanged);
    connect(scalarPanel_, &ScalarFieldPanel::splitRequested, splits_, &SplitController::split);
    connect(distances_, &DistanceController::resultReady, tree_, &EntityTree::selectEntity);
    connect(splits_, &SplitController::resultReady, tree_, &EntityTree::selectEntity);
    connect(view_, &CloudView::pointPicked, measure_, &MeasurePanel::addPick);
    connect(view_, &CloudView::pickModeChanged, this, [this](bool on) {
        if (!on) // picking turned off (P, Escape...): measuring ends with it
            measure_->setMeasuring(false);
    });
    connect(measure_, &MeasurePanel::annotationsChanged, view_, &CloudView::setAnnotations);
    connect(view_, &CloudView::pointPicked, this, [this](EntityId id, std::size_t index) {
        properties_->showPickedPoint(id, index);
        const QString text = describePoint(document_.item(id), index);
        console_->info(tr("picked ") + text);
        statusBar()->showMessage(text);
    });
    statusBar()->showMessage(tr("Open clouds or meshes (File > Open, or drop files here)"));
}

MainWindow::~MainWindow()
{
    disconnect(&document_, nullptr, this, nullptr);
    view_->clear();
    if (secondView_) { // its arrays, too, view the document's points
        disconnect(&document_, nullptr, secondView_, nullptr);
        secondView_->clear();
    }
}

template <class Controller> void MainWindow::report(Controller* controller)
{
    connect(controller, &Controller::finished, this, [this](const QString& summary) {
        console_->info(summary);
        statusBar()->showMessage(summary);
    });
    connect(controller, &Controller::failed, this, [this](const QString& message) {
        console_->error(message);
        statusBar()->showMessage(message);
    });
    // The user stopping a run is no error.
    connect(controller, &Controller::cancelled, this, [this](const QString& message) {
        console_->info(message);
        statusBar()->showMessage(message);
    });
}

void MainWindow::buildDocks()
{
    const auto dock = [this](const QString& title, QWidget* widget, Qt::DockWidgetArea area, bool scrolls = false) {
        auto* d = new QDockWidget(title, this);
        d->setObjectName(title);
        if (scrolls) {
            // A tall panel scrolls rather than raising the window's minimum
            // height (the window grew by itself when Measure opened).
            auto* area = new QScrollArea(d);
            area->setWidgetResizable(true);
            area->setFrameShape(QFrame::NoFrame);
            area->setHorizontalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
            area->setWidget(widget);
            // As wide as the panel needs: only its height scrolls.
            area->setMinimumWidth(widget->minimumSizeHint().width() + area->style()->pixelMetric(QStyle::PM_ScrollBarExtent));
            d->setWidget(area);
        } else {
            d->setWidget(widget);
        }
        addDockWidget(area, d);
        return d;
    };
    tree_ = new EntityTree(document_, this);
    properties_ = new PropertiesPanel(document_, this);
    scalarPanel_ = new ScalarFieldPanel(document_, this);
    console_ = new ConsolePanel(this);
    QDockWidget* entitiesDock = dock(tr("Entities"), tree_, Qt::LeftDockWidgetArea);
    dock(tr("Properties"), properties_, Qt::LeftDockWidgetArea);
    QDockWidget* scalarDock = dock(tr("Scalar field"), scalarPanel_, Qt::RightDockWidgetArea, true);
    QDockWidget* consoleDock = dock(tr("Console"), console_, Qt::BottomDockWidgetArea);
    measure_ = new MeasurePanel(document_, this);
    QDockWidget* measureDock = dock(tr("Measure"), measure_, Qt::RightDockWidgetArea, true);
    // A tab beside the scalar field's: stacked under it, the two panels'
    // minimum heights made the window grow by itself when Measure opened.
    tabifyDockWidget(scalarDock, measureDock);
    measureDock->hide(); // until View > Measure
    // Wide enough for names, UTM coordinates and field ranges at 1680 px.
    resizeDocks({entitiesDock, scalarDock}, {340, 360}, Qt::Horizontal);
    resizeDocks({consoleDock}, {140}, Qt::Vertical);
    // Then the layout the user left last time, if any.
    const QSettings settings;
    restoreGeometry(settings.value(kGeometrySetting).toByteArray());
    restoreState(settings.value(kLayoutSetting).toByteArray());
}

void MainWindow::buildMenus()
{
    buildFileMenu();
    QMenu* edit = buildEditMenu();
    buildViewMenu();
    QMenu* tools = menuBar()->addMenu(tr("&Tools"));
    QMenu* distances = tools->addMenu(tr("&Distances"));
    distances->addAction(tr("&Cloud/cloud distance (C2C)..."), this,
                         [this] { distances_->runInteractively(DistanceKind::CloudToCloud, tree_->currentEntity()); });
    distances->addAction(tr("Cloud/&mesh distance (C2M)..."), this,
                         [this] { distances_->runInteractively(DistanceKind::CloudToMesh, tree_->currentEntity()); });
    tools->addAction(tr("S&egment the changes..."), this, [this] { segmentation_->runInteractively(tree_->currentEntity()); });
    // The panel's own button: one place decides what a split takes.
    tools->addAction(tr("&Split at thresholds"), scalarPanel_->splitButton(), &QPushButton::click);
    buildToolsMenu(edit, tools);

    buildHelpMenu();
    buildTreeMenu();
}

void MainWindow::buildFileMenu()
{
    QMenu* file = menuBar()->addMenu(tr("&File"));
    file->addAction(tr("&Open..."), files_, &FileController::openWithDialog)->setShortcut(QKeySequence::Open);
    QMenu* recent = file->addMenu(tr("Open &recent"));
    files_->fillRecentMenu(recent);
    connect(files_, &FileController::recentFilesChanged, this, [this, recent] { files_->fillRecentMenu(recent); });
    file->addAction(tr("&Export selected..."), this, [this] { files_->exportWithDialog(tree_->selectedEntities()); })
        ->setShortcut(QKeySequence(tr("Ctrl+E")));
    regionExportActions_.push_back(
        file->addAction(tr("Export re&gions (PLY, DXF, CSV)..."), this, [this] { segmentation_->exportRegionsWithDialog(tree_->currentEntity()); }));
    file->addSeparator();
    QAction* closeSelected = file->addAction(tr("&Close selected"), this, &MainWindow::closeSelected);
    closeSelected->setObjectName("closeSelectedAction");
    closeSelected->setShortcut(QKeySequence::Close);
    QAction* closeAll = file->addAction(tr("Close a&ll"), this, [this] { closeEverything(); });
    closeAll->setObjectName("closeAllAction");
    closeAll->setShortcut(QKeySequence(tr("Ctrl+Shift+W")));
    file->addSeparator();
    file->addAction(tr("Open &session..."), sessions_, &SessionController::restoreWithDialog);
    file->addAction(tr("&Save session..."), sessions_, &SessionController::saveWithDialog)->setShortcut(QKeySequence::Save);
    file->addSeparator();
    // Through close(), so unsaved work is asked about whichever way one quits.
    file->addAction(tr("&Quit"), this, &QWidget::close)->setShortcut(QKeySequence::Quit);

}

QMenu* MainWindow::buildEditMenu()
{
    QMenu* edit = menuBar()->addMenu(tr("&Edit"));
    // Undo and redo histories: deletions, tools' changes and outputs, fields, splits, the scissors.
    QAction* undo = edit->addAction(tr("Undo"), &document_, &Document::undo);
    undo->setObjectName("undoAction");
    undo->setShortcut(QKeySequence::Undo);
    QAction* redo = edit->addAction(tr("Redo"), &document_, &Document::redo);
    redo->setObjectName("redoAction");
    redo->setShortcuts({QKeySequence::Redo, QKeySequence(tr("Ctrl+Y"))});
    const auto followUndo = [this, undo, redo] {
        undo->setEnabled(document_.canUndo());
        undo->setText(document_.undoText());
        redo->setEnabled(document_.canRedo());
        redo->setText(document_.redoText());
    };
    connect(&document_, &Document::undoChanged, undo, followUndo);
    followUndo();
    QAction* extract = edit->addAction(tr("Extract inside the clipping box"), this, [this] { splits_->extractInBox(view_->clippingBox()); });
    extract->setObjectName("extractInBoxAction");
    // The box by numbers, as the crop tool's --obox takes them.
    QAction* boxNumbers = edit->addAction(tr("Clipping box by numbers..."), this, [this] {
        bool ok = false;
        const QString text = QInputDialog::getText(this, tr("Clipping box"),
                                                   tr("Centre X,Y,Z, sizes X,Y,Z (m), heading, pitch, roll (degrees):"),
                                                   QLineEdit::Normal, QString::fromStdString(orientedBoxText(view_->clippingBox())), &ok);
        if (!ok)
            return;
        try {
            view_->setClippingBox(parseOrientedBox(text.toStdString()));
        } catch (const Error& e) {
            QMessageBox::warning(this, tr("Clipping box"), QString::fromStdString(e.what()));
        }
    });
    boxNumbers->setEnabled(false);
    connect(view_, &CloudView::clippingBoxChanged, boxNumbers, &QAction::setEnabled);
    extract->setEnabled(false);
    connect(view_, &CloudView::clippingBoxChanged, extract, &QAction::setEnabled);
    edit->addSeparator();
    deleteAction_ = edit->addAction(tr("&Delete selected"), this, [this] { removeSelected(tr("delete")); });
    deleteAction_->setShortcut(QKeySequence::Delete);
    renameAction_ = edit->addAction(tr("&Rename..."), this, &MainWindow::renameCurrent);
    renameAction_->setShortcut(QKeySequence(Qt::Key_F2));
    QAction* move = edit->addAction(tr("&Move / rotate..."), this, [this] { moveSelectedInteractively(); });
    move->setObjectName("moveAction");
    move->setShortcut(QKeySequence(tr("Ctrl+T")));
    move->setStatusTip(tr("Move and turn the selected entities with the mouse or by typed values, then apply"));
    return edit;

}

void MainWindow::buildViewMenu()
{
    QMenu* viewMenu = menuBar()->addMenu(tr("&View"));
    QToolBar* viewBar = addToolBar(tr("View"));
    viewBar->setObjectName("viewToolBar");
    // Keys laid out as the views are on a numeric keypad: 8 from above, 2
    // from below, 4 and 6 from the sides, 5 from the front, 0 from the back.
    struct Standard
    {
        QString label;
        StandardView which;
        Qt::Key key;
    };
    const Standard views[] = {{tr("Top"), StandardView::Top, Qt::Key_8},       {tr("Front"), StandardView::Front, Qt::Key_5},
                              {tr("Left"), StandardView::Left, Qt::Key_4},     {tr("Right"), StandardView::Right, Qt::Key_6},
                              {tr("Back"), StandardView::Back, Qt::Key_0},     {tr("Bottom"), StandardView::Bottom, Qt::Key_2},
                              {tr("Iso"), StandardView::Iso, Qt::Key_7}};
    QMenu* standard = viewMenu->addMenu(tr("&Standard views"));
    for (const Standard& view : views) {
        const StandardView v = view.which;
        QAction* a = standard->addAction(view.label, this, [this, v] { view_->setStandardView(v); });
        a->setShortcut(QKeySequence(view.key));
        a->setToolTip(tr("%1 view (%2)").arg(view.label, QKeySequence(view.key).toString()));
        viewBar->addAction(a);
    }
    viewBar->addSeparator();
    QAction* zoomAll = viewMenu->addAction(tr("Zoom to &all"), view_, &CloudView::resetCamera);
    zoomAll->setShortcut(QKeySequence(tr("Ctrl+0")));
    viewBar->addAction(zoomAll);
    zoomSelection_ = viewMenu->addAction(tr("Zoom to &selection"), this, [this] {
        if (document_.contains(tree_->currentEntity()))
            view_->zoomToEntity(tree_->currentEntity());
    });
    viewBar->addAction(zoomSelection_);
    QAction* ortho = viewMenu->addAction(tr("&Orthographic projection"));
    ortho->setCheckable(true);
    connect(ortho, &QAction::toggled, view_, &CloudView::setParallelProjection);
    connect(view_, &CloudView::projectionChanged, ortho, &QAction::setChecked);
    viewBar->addAction(ortho);
    QAction* pick = viewMenu->addAction(tr("&Pick a point"));
    pick->setCheckable(true);
    pick->setShortcut(QKeySequence(tr("P")));
    pick->setToolTip(tr("Click a point to see its coordinates and field values"));
    connect(pick, &QAction::toggled, view_, &CloudView::setPickMode);
    connect(view_, &CloudView::pickModeChanged, pick, &QAction::setChecked);
    viewBar->addAction(pick);
    QAction* scissors = viewMenu->addAction(tr("Segment by polygon (scissors)"));
    scissors->setObjectName("scissorsAction");
    scissors->setCheckable(true);
    scissors->setShortcut(QKeySequence(tr("T")));
    scissors->setToolTip(tr("Left clicks draw a polygon, a right click closes it: what is shown inside becomes a cloud of its own"));
    connect(scissors, &QAction::toggled, view_, &CloudView::setScissorsMode);
    connect(view_, &CloudView::scissorsModeChanged, scissors, &QAction::setChecked);
    // Deferred: the cut changes the document, which must not happen inside VTK's mouse event.
    connect(view_, &CloudView::polygonDrawn, this, [this](const std::vector<Eigen::Vector2d>& polygon, const Eigen::Matrix4d& projection) {
        QTimer::singleShot(0, this, [this, polygon, projection] {
            const std::optional<SplitController::Keep> keep = askWhatTheScissorsKeep();
            if (!keep) {
                statusBar()->showMessage(tr("Scissors: nothing cut; draw another polygon, or T to stop"));
                return;
            }
            splits_->cutWithPolygon(polygon, projection, [this](EntityId id, std::size_t i) { return view_->isPointShown(id, i); }, *keep);
        });
    });
    viewBar->addAction(scissors);
    QAction* clipping = viewMenu->addAction(tr("&Clipping box"));
    clipping->setObjectName("clippingAction");
    clipping->setCheckable(true);
    clipping->setToolTip(tr("A box with handles: only what is inside is drawn; Edit > Extract inside the clipping box cuts it out"));
    connect(clipping, &QAction::toggled, view_, [this](bool on) { view_->setClippingBox(on); });
    connect(view_, &CloudView::clippingBoxChanged, clipping, &QAction::setChecked);
    viewBar->addAction(clipping);
    QAction* sideBySide = viewMenu->addAction(tr("Second &view, side by side"));
    sideBySide->setObjectName("sideBySideAction");
    sideBySide->setCheckable(true);
    sideBySide->setToolTip(tr("Two views with one camera: the first cloud opened on the left, the others on the right"));
    connect(sideBySide, &QAction::toggled, this, &MainWindow::setSideBySide);
    QAction* measure = viewMenu->addAction(tr("&Measure"));
    measure->setObjectName("measureAction");
    measure->setCheckable(true);
    measure->setShortcut(QKeySequence(tr("M")));
    measure->setToolTip(tr("Click points: a distance (with dX, dY, dZ), an angle, a polygon's area"));
    connect(measure, &QAction::toggled, this, [this](bool on) {
        if (on) {
            // A tab beside the scalar field's, even when a layout saved by an
            // earlier version stacked them (that made the window grow).
            QDockWidget* panel = findChild<QDockWidget*>("Measure");
            QDockWidget* scalar = findChild<QDockWidget*>("Scalar field");
            if (scalar && !panel->isFloating() && tabifiedDockWidgets(panel).isEmpty() && dockWidgetArea(scalar) == dockWidgetArea(panel))
                tabifyDockWidget(scalar, panel);
            panel->show();
            panel->raise(); // its tab in front
        }
        measure_->setMeasuring(on);
    });
    connect(measure_, &MeasurePanel::measuringChanged, this, [this, measure](bool on) {
        measure->setChecked(on);
        view_->setPickMode(on);
    });
    viewBar->addAction(measure);
    QMenu* sizes = viewMenu->addMenu(tr("Point si&ze"));
    auto* sizeGroup = new QActionGroup(this);
    for (int size : {1, 2, 3, 4, 6, 8}) {
        QAction* a = sizes->addAction(QString::number(size), this, [this, size] { view_->setPointSize(float(size)); });
        a->setCheckable(true);
        a->setChecked(size == int(view_->pointSize()));
        sizeGroup->addAction(a);
        connect(view_, &CloudView::pointSizeChanged, a, [a, size](float now) { a->setChecked(int(now) == size); });
    }
    buildDisplayOptions(viewMenu);
    viewMenu->addSeparator();
    for (QDockWidget* d : findChildren<QDockWidget*>())
        viewMenu->addAction(d->toggleViewAction());

}

//! View > Eye-Dome Lighting, scale bar, background, and how a reference looks
//! after a comparison: remembered from one start to the next.
void MainWindow::buildDisplayOptions(QMenu* viewMenu)
{
    QAction* edl = viewMenu->addAction(tr("&Eye-Dome Lighting"));
    edl->setObjectName("edlAction");
    edl->setCheckable(true);
    edl->setToolTip(tr("Shade clouds by their depth on screen: reliefs read without normals"));
    connect(edl, &QAction::toggled, this, [this](bool on) {
        QSettings().setValue(kEdlSetting, on);
        view_->setEyeDomeLighting(on);
    });
    edl->setChecked(QSettings().value(kEdlSetting, false).toBool());
    QAction* scaleBar = viewMenu->addAction(tr("S&cale bar"));
    scaleBar->setObjectName("scaleBarAction");
    scaleBar->setCheckable(true);
    connect(scaleBar, &QAction::toggled, this, [this](bool on) {
        QSettings().setValue(kScaleBarSetting, on);
        view_->setScaleBar(on);
    });
    scaleBar->setChecked(QSettings().value(kScaleBarSetting, true).toBool());
    view_->setScaleBar(scaleBar->isChecked());
    viewMenu->addAction(tr("&Background colour..."), this, [this] {
        const QColor chosen = QColorDialog::getColor(QSettings().value(kBackgroundSetting).value<QColor>(), this, tr("Background colour"));
        if (!chosen.isValid())
            return; // the dialog was cancelled
        QSettings().setValue(kBackgroundSetting, chosen);
        view_->setBackground(chosen);
    });
    viewMenu->addAction(tr("Default &background"), this, [this] {
        QSettings().remove(kBackgroundSetting);
        view_->setBackground(QColor());
    });
    view_->setBackground(QSettings().value(kBackgroundSetting).value<QColor>());
    QMenu* afterComparison = viewMenu->addMenu(tr("&Reference after a comparison"));
    auto* afterGroup = new QActionGroup(this);
    const std::pair<QString, ReferenceAfterComparison> choices[] = {
        {tr("In neutral grey"), ReferenceAfterComparison::Grey},
        {tr("Hidden"), ReferenceAfterComparison::Hide},
        {tr("Unchanged"), ReferenceAfterComparison::Keep}};
    for (const auto& [label, choice] : choices) {
        QAction* a = afterComparison->addAction(label, this, [choice = choice] { DistanceController::setReferenceAfterComparison(choice); });
        a->setCheckable(true);
        a->setChecked(DistanceController::referenceAfterComparison() == choice);
        afterGroup->addAction(a);
    }
}

void MainWindow::buildTreeMenu()
{
    // The tree's own menu: what applies to the entities under the mouse, as
    // CloudCompare's tree offers it.
    tree_->setContextMenuPolicy(Qt::ActionsContextMenu);
    const auto treeAction = [this](const QString& text, const char* name, auto slot) {
        auto* action = new QAction(text, tree_);
        action->setObjectName(name);
        connect(action, &QAction::triggered, this, slot);
        tree_->addAction(action);
        return action;
    };
    treeAction(tr("Show / hide"), "treeShowHide", [this] { toggleSelectedVisibility(); });
    treeAction(tr("Colour..."), "treeColour", [this] {
        const QColor chosen = QColorDialog::getColor(QColor(255, 200, 0), this, tr("One colour for the selected clouds"));
        if (chosen.isValid())
            colourSelected(chosen);
    });
    treeAction(tr("Properties"), "treeProperties", [this] {
        if (auto* dock = findChild<QDockWidget*>("Properties")) {
            dock->show();
            dock->raise();
        }
    });
    tree_->addAction(renameAction_);
    treeAction(tr("Clone"), "treeClone", [this] { cloneSelected(); });
    treeAction(tr("Merge..."), "treeMerge", [this] {
        if (ToolController* merge = toolController("merge"))
            merge->runInteractively(toolSelection());
    });
    auto* separator = new QAction(tree_);
    separator->setSeparator(true);
    tree_->addAction(separator);
    tree_->addAction(zoomSelection_);
    treeAction(tr("Export..."), "treeExport", [this] { files_->exportWithDialog(tree_->selectedEntities()); });
    QAction* exportRegions =
        treeAction(tr("Export regions (PLY, DXF, CSV)..."), "treeExportRegions", [this] { segmentation_->exportRegionsWithDialog(tree_->currentEntity()); });
    regionExportActions_.push_back(exportRegions);
    updateRegionExport();
    treeAction(tr("Point size..."), "treePointSize", [this] {
        const std::vector<EntityId> ids = tree_->selectedEntities(false);
        if (ids.empty())
            return;
        bool ok = false;
        const int size = QInputDialog::getInt(this, tr("Point size"), tr("Pixels for the selected entities (0: the view's size)"),
                                              static_cast<int>(document_.item(ids.front()).display.pointSize), 0, 20, 1, &ok);
        if (ok)
            for (EntityId id : ids)
                document_.setPointSize(id, static_cast<float>(size));
    });
    treeAction(tr("Delete"), "treeDelete", [this] { removeSelected(tr("delete")); });
}

void MainWindow::buildHelpMenu()
{
    QMenu* help = menuBar()->addMenu(tr("&Help"));
    const QString docs = documentationFolder();
    // The guide's pages, opened by the desktop's viewer for Markdown (or its browser).
    const std::pair<QString, QString> pages[] = {{tr("&User guide (the workbench step by step)"), "workbench.md"},
                                                 {tr("&Command line and formats (README)"), "../README.md"},
                                                 {tr("&Distances"), "distances.md"},
                                                 {tr("&M3C2 and the DEM of difference"), "m3c2.md"},
                                                 {tr("&Segmentation"), "segmentation.md"},
                                                 {tr("&Registration"), "registration.md"},
                                                 {tr("&Primitives"), "primitives.md"},
                                                 {tr("C&ontours"), "contours.md"},
                                                 {tr("Processing &tools"), "processing.md"},
                                                 {tr("Cl&assification"), "classification.md"},
                                                 {tr("&Benchmarks"), "benchmarks.md"}};
    for (const auto& [label, page] : pages) {
        const QString path = QDir::cleanPath(docs + "/" + page);
        if (docs.isEmpty() || !QFileInfo::exists(path))
            continue;
        QAction* a = help->addAction(label, this, [path] { QDesktopServices::openUrl(QUrl::fromLocalFile(path)); });
        a->setStatusTip(path);
    }
    if (!help->actions().isEmpty())
        help->actions().front()->setShortcut(QKeySequence::HelpContents); // F1: the user guide
    help->addSeparator();
    QAction* keys = help->addAction(tr("&Keyboard shortcuts"), this, [this] { showShortcuts(this, *menuBar()); });
    keys->setObjectName("shortcutsAction");
    help->addAction(tr("&About scandiff"), this, [this] { showAbout(this); });
}

std::optional<SplitController::Keep> MainWindow::askWhatTheScissorsKeep()
{
    QMessageBox box(QMessageBox::Question, tr("Segment by polygon"), tr("What becomes a cloud of its own?"), QMessageBox::NoButton, this);
    box.setObjectName("scissors-question");
    box.setInformativeText(tr("The cloud cut stays in the tree, hidden; Undo takes the cut back."));
    QPushButton* inside = box.addButton(tr("Keep &inside"), QMessageBox::AcceptRole);
    inside->setObjectName("keepInside");
    QPushButton* outside = box.addButton(tr("Keep &outside"), QMessageBox::AcceptRole);
    outside->setObjectName("keepOutside");
    QPushButton* both = box.addButton(tr("&Both parts"), QMessageBox::AcceptRole);
    both->setObjectName("keepBoth");
    box.addButton(QMessageBox::Cancel);
    box.setDefaultButton(inside);
    box.exec();
    if (box.clickedButton() == inside)
        return SplitController::Keep::Inside;
    if (box.clickedButton() == outside)
        return SplitController::Keep::Outside;
    if (box.clickedButton() == both)
        return SplitController::Keep::Both;
    return std::nullopt;
}

void MainWindow::removeSelected(const QString& verb)
{
    const std::vector<EntityId> ids = tree_->selectedEntities(false);
    if (ids.empty())
        return;
    // One Ctrl+Z brings back everything this took.
    const Document::UndoGroup group(document_, ids.size() == 1 && document_.find(ids.front())
                                                   ? tr("%1 '%2'").arg(verb, document_.item(ids.front()).name)
                                                   : tr("%1 of %2 entities").arg(verb).arg(ids.size()));
    for (EntityId id : ids)
        document_.remove(id);
}

void MainWindow::closeSelected() { removeSelected(tr("close")); }

bool MainWindow::closeEverything()
{
    if (document_.size() == 0 || !mayDiscardUnsavedWork())
        return false;
    document_.clear();
    statusBar()->showMessage(tr("Everything closed (File > Open recent brings the files back)"));
    return true;
}

void MainWindow::renameCurrent()
{
    const EntityId id = tree_->currentEntity();
    if (!document_.contains(id))
        return;
    bool ok = false;
    const QString name = QInputDialog::getText(this, tr("Rename"), tr("Name"), QLineEdit::Normal, document_.item(id).name, &ok);
    if (ok && !name.isEmpty())
        document_.rename(id, name);
}

void MainWindow::toggleSelectedVisibility()
{
    const std::vector<EntityId> ids = tree_->selectedEntities(false);
    // Any shown: hide them all; all hidden: show them.
    const bool anyShown = std::any_of(ids.begin(), ids.end(), [this](EntityId id) { return document_.item(id).display.visible; });
    for (EntityId id : ids)
        document_.setVisible(id, !anyShown);
}

int MainWindow::colourSelected(const QColor& colour)
{
    ToolController* setColour = toolController("set-colour");
    int coloured = 0;
    const Document::UndoGroup group(document_, tr("colour"));
    for (EntityId id : tree_->selectedEntities(false)) {
        if (!setColour || !document_.item(id).cloud())
            continue;
        if (setColour->run(id, {{"colour", colour.name().toStdString()}})) {
            document_.setActiveField(id, {}); // the colour just given is what the user wants to see
            ++coloured;
        }
    }
    return coloured;
}

MoveDialog* MainWindow::moveSelectedInteractively()
{
    std::vector<EntityId> ids;
    for (EntityId id : tree_->selectedEntities(true)) // a field's row stands for its cloud
        if (document_.item(id).hasData())
            ids.push_back(id);
    if (ids.empty()) {
        statusBar()->showMessage(tr("Move / rotate: select the clouds or meshes to move first"));
        return nullptr;
    }
    if (moveDialog_ && moveDialog_->isVisible()) { // one at a time: the view has one box
        moveDialog_->raise();
        moveDialog_->activateWindow();
        return moveDialog_;
    }
    auto* dialog = new MoveDialog(*view_, ids, this);
    if (!view_->movingEntities()) { // none of them is drawn: nothing to turn about
        delete dialog;
        statusBar()->showMessage(tr("Move / rotate: the selected entities are not shown in the view"));
        return nullptr;
    }
    moveDialog_ = dialog;
    dialog->setAttribute(Qt::WA_DeleteOnClose);
    connect(dialog, &MoveDialog::applyRequested, this, [this, ids](const Eigen::Matrix4d& global) { applyMotion(ids, global); });
    dialog->show();
    // Beside what it moves, not over it: the view's top right corner.
    dialog->move(view_->mapToGlobal(QPoint(std::max(0, view_->width() - dialog->width() - 12), 12)));
    return dialog;
}

int MainWindow::applyMotion(const std::vector<EntityId>& ids, const Eigen::Matrix4d& global)
{
    // Through the transform tool: in double, kept in each cloud's history,
    // logged as the command line that repeats it, undone as one step.
    ToolController* transform = toolController("transform");
    if (!transform)
        return 0;
    // The matrix as the CLI writes it (every double given back exactly), on one line.
    const QString matrix = QString::fromStdString(io::matrixText(global)).simplified();
    const Document::UndoGroup group(document_, tr("move"));
    int moved = 0;
    for (EntityId id : ids)
        if (document_.contains(id) && transform->run(id, {{"matrix", matrix.toStdString()}}))
            ++moved;
    return moved;
}

int MainWindow::cloneSelected()
{
    ToolController* clone = toolController("clone");
    int cloned = 0;
    for (EntityId id : tree_->selectedEntities(false))
        if (clone && document_.item(id).cloud() && clone->run(id, {}))
            ++cloned;
    return cloned;
}

void MainWindow::buildToolsMenu(QMenu* editMenu, QMenu* toolsMenu)
{
    // Where a CloudCompare user looks for them: editing a cloud (its normals,
    // its fields, copies, merges, moves, crops, subsampling) under Edit, the
    // rest under Tools, one submenu per category. The "Edit" category's tools
    // go straight into the Edit menu.
    const std::set<std::string> underEdit{"Edit", "Normals", "Subsample", "Scalar fields"};
    std::map<std::string, QMenu*> categories;
    // A category named like a submenu already there (Distances: C2C and C2M)
    // joins it rather than making a second one of the same name.
    for (QMenu* parent : {editMenu, toolsMenu})
        for (QAction* existing : parent->actions())
            if (existing->menu())
                categories[existing->text().remove('&').toStdString()] = existing->menu();
    editMenu->addSeparator();
    for (const ToolSpec& tool : registry_.tools.tools()) {
        // Drawings are files of the command line, not entities of the workbench (yet).
        if (std::any_of(tool.inputs.begin(), tool.inputs.end(), [](const InputSpec& in) { return in.kind == DataKind::Drawing; }))
            continue;
        QMenu*& menu = categories[tool.category];
        if (!menu) {
            QMenu* parent = underEdit.count(tool.category) ? editMenu : toolsMenu;
            menu = tool.category.empty() ? toolsMenu
                   : tool.category == "Edit" ? editMenu
                                             : parent->addMenu(QString::fromStdString(tool.category));
        }
        auto* controller = new ToolController(tool, document_, this);
        tools_[tool.name] = controller;
        QAction* action = menu->addAction(QString::fromStdString(tool.title) + "...", this,
                                          [this, controller] { controller->runInteractively(toolSelection()); });
        action->setStatusTip(QString::fromStdString(tool.description));
        report(controller);
        connect(controller, &ToolController::resultReady, tree_, &EntityTree::selectEntity);
        // A tool that picks points in the view (point pairs) gets the view's picks.
        connect(view_, &CloudView::pointPicked, controller, &ToolController::pointPicked);
        connect(controller, &ToolController::pickModeRequested, view_, &CloudView::setPickMode);
        connect(controller, &ToolController::tablesReady, this, [this](const QString& title, const NamedTables& tables) {
            auto* window = new TableDialog(title, tables, this);
            window->show();
        });
    }
}

std::vector<EntityId> MainWindow::toolSelection() const
{
    std::vector<EntityId> selection;
    const EntityId current = tree_->currentEntity();
    if (current != kNoEntity)
        selection.push_back(current);
    for (EntityId id : tree_->selectedEntities(false))
        if (id != current)
            selection.push_back(id);
    return selection;
}

ToolController* MainWindow::toolController(const std::string& toolName) const
{
    const auto it = tools_.find(toolName);
    return it == tools_.end() ? nullptr : it->second;
}

void MainWindow::onCurrentEntityChanged(EntityId id)
{
    properties_->showEntity(id);
    scalarPanel_->showEntity(id);
    updateLegend();
    updateRegionExport();
}

void MainWindow::updateRegionExport()
{
    // Only a cloud with regions can export them (it would ask for a folder, then fail).
    const bool possible = segmentation_->hasRegions(tree_->currentEntity());
    for (QAction* action : regionExportActions_) {
        action->setEnabled(possible);
        action->setToolTip(possible ? QString() : tr("Segment the changes first: the selected cloud has no regions"));
    }
}

void MainWindow::setSideBySide(bool on)
{
    if (on && !secondView_) {
        // The second view follows the document as the first does, with its camera.
        secondView_ = new CloudView(this);
        auto* splitter = new QSplitter(Qt::Horizontal, this);
        takeCentralWidget();
        splitter->addWidget(view_);
        splitter->addWidget(secondView_);
        setCentralWidget(splitter);
        splitter->show();
        view_->show();
        CloudView* second = secondView_;
        connect(&document_, &Document::added, second, [this, second](EntityId id) { second->addEntity(document_.item(id)); });
        connect(&document_, &Document::removed, second, &CloudView::removeEntity);
        connect(&document_, &Document::aboutToReplaceData, second, &CloudView::removeEntity);
        connect(&document_, &Document::dataReplaced, second, [this, second](EntityId id) { second->addEntity(document_.item(id)); });
        connect(&document_, &Document::cleared, second, &CloudView::clear);
        connect(&document_, &Document::displayChanged, second, [this, second](EntityId id) { second->refreshEntity(document_.item(id)); });
        for (EntityId id : document_.ids())
            second->addEntity(document_.item(id));
        second->followCamera(*view_);
    }
    if (!secondView_)
        return;
    // One epoch on each side: the first cloud opened on the left, the others on the right.
    std::vector<EntityId> clouds;
    for (EntityId id : document_.ids())
        if (document_.item(id).cloud() && document_.item(id).parent == kNoEntity)
            clouds.push_back(id);
    for (EntityId id : document_.ids()) {
        const bool left = !clouds.empty() && id == clouds.front();
        view_->setShownHere(id, !on || left || clouds.size() < 2);
        secondView_->setShownHere(id, !left || clouds.size() < 2);
    }
    secondView_->setVisible(on);
    if (on)
        if (auto* splitter = qobject_cast<QSplitter*>(centralWidget())) {
            const int half = std::max(1, splitter->width() / 2);
            splitter->setSizes({half, half}); // two equal halves, whatever the views' size hints
        }
}

void MainWindow::updateLegend()
{
    // The bar belongs to what is on screen: the selected entity if it is shown
    // with a field; else, of the entities in the view's frame with a field, the
    // selected group's parts first, then the last added. Never a cloud outside
    // the frame (two LAZ side by side, one zoomed to: not the other's scale).
    auto legendFor = [this](EntityId id, bool onScreen) {
        const Document::Item* item = document_.find(id);
        if (!item || !item->display.visible || !item->cloud() || (onScreen && !view_->isOnScreen(id)))
            return ColourLegend{};
        return legendOf(item->points(), item->display);
    };
    const EntityId current = tree_->currentEntity();
    ColourLegend legend = legendFor(current, false);
    std::vector<EntityId> parts;
    for (std::vector<EntityId> pending{current}; current != kNoEntity && !pending.empty();) {
        const EntityId id = pending.back();
        pending.pop_back();
        for (EntityId child : document_.children(id)) {
            parts.push_back(child);
            pending.push_back(child);
        }
    }
    for (auto it = parts.begin(); !legend.shown && it != parts.end(); ++it)
        legend = legendFor(*it, true);
    const std::vector<EntityId> ids = document_.ids();
    for (auto it = ids.rbegin(); !legend.shown && it != ids.rend(); ++it)
        legend = legendFor(*it, true);
    view_->setLegend(legend);
}

int MainWindow::openFiles(const QStringList& paths, bool quiet)
{
    return static_cast<int>(files_->open(paths, quiet).size());
}

void MainWindow::dragEnterEvent(QDragEnterEvent* event)
{
    if (event->mimeData()->hasUrls())
        event->acceptProposedAction();
}

void MainWindow::dropEvent(QDropEvent* event)
{
    QStringList paths;
    for (const QUrl& url : event->mimeData()->urls())
        if (url.isLocalFile())
            paths << url.toLocalFile();
    if (!paths.isEmpty()) {
        files_->open(paths);
        event->acceptProposedAction();
    }
}

bool MainWindow::mayDiscardUnsavedWork()
{
    const std::vector<EntityId> unsaved = document_.unsavedIds();
    if (unsaved.empty())
        return true;
    QStringList names;
    for (EntityId id : unsaved)
        names << document_.item(id).name;
    QMessageBox box(QMessageBox::Warning, tr("Unsaved work"),
                    unsaved.size() == 1 ? tr("One entity holds results that are in no file:")
                                        : tr("%1 entities hold results that are in no file:").arg(unsaved.size()),
                    QMessageBox::NoButton, this);
    box.setObjectName("unsaved-work");
    constexpr int kShownNames = 8;
    QString list = names.mid(0, kShownNames).join("\n");
    if (names.size() > kShownNames)
        list += tr("\nand %1 more").arg(names.size() - kShownNames);
    box.setInformativeText(list + tr("\n\nSave them in a session first?"));
    box.setStandardButtons(QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel);
    box.setDefaultButton(QMessageBox::Save);
    switch (box.exec()) {
    case QMessageBox::Save: return sessions_->saveWithDialog();
    case QMessageBox::Discard: return true;
    default: return false;
    }
}

void MainWindow::closeEvent(QCloseEvent* event)
{
    if (!mayDiscardUnsavedWork()) {
        event->ignore();
        return;
    }
    QSettings settings; // the panels where the user put them, for next time
    settings.setValue(kGeometrySetting, saveGeometry());
    settings.setValue(kLayoutSetting, saveState());
    event->accept();
}

} // namespace scandiff::gui
