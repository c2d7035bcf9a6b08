// SPDX-License-Identifier: GPL-3.0-or-later
#include "view/CloudView.h"
#include "view/ChunkGeometry.h"
#include "view/CloudViewScene.h"

#include <scandiff/core/Log.h>
#include <scandiff/core/distance/DemOfDifference.h>

#include <QResizeEvent>
#include <QTimer>

#include <limits>
#include <QVBoxLayout>
#include <QVTKOpenGLNativeWidget.h>

#include <vtkActor.h>
#include <vtkActor2D.h>
#include <vtkBillboardTextActor3D.h>
#include <vtkLabelPlacementMapper.h>
#include <vtkPointSetToLabelHierarchy.h>
#include <vtkStringArray.h>
#include <vtkBoundingBox.h>
#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkFloatArray.h>
#include <vtkTypeInt32Array.h>
#include <vtkInteractorStyleTrackballCamera.h>
#include <vtkLookupTable.h>
#include <vtkMatrix4x4.h>
#include <vtkEDLShading.h>
#include <vtkTextActor.h>
#include <vtkOpenGLRenderer.h>
#include <vtkRenderStepsPass.h>
#include <vtkBoxRepresentation.h>
#include <vtkBoxWidget2.h>
#include <vtkPlane.h>
#include <vtkPlanes.h>
#include <vtkTransform.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkCellPicker.h>
#include <vtkPointPicker.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkPolyDataMapper2D.h>
#include <vtkProperty.h>
#include <vtkProperty2D.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkShaderProperty.h>
#include <vtkSmartPointer.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkVariant.h>
#include <vtkImageData.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <map>
#include <optional>
#include <vector>

namespace scandiff::gui {

namespace {


// Hidden points carry alpha 0; dropping their fragments hides them without
// touching the geometry (the actor is forced opaque so VTK keeps one pass).
constexpr const char* kDiscardHidden = "//VTK::Light::Impl\n  if (gl_FragData[0].a <= 0.0) { discard; }\n";

} // namespace



//! In pick mode, a left click picks a point and stops there (no rotation).
class CloudView::PickCommand : public vtkCommand
{
public:
    static PickCommand* New() { return new PickCommand; }
    void Execute(vtkObject* caller, unsigned long event, void*) override
    {
        if (!view)
            return;
        const int* pos = static_cast<vtkRenderWindowInteractor*>(caller)->GetEventPosition();
        if (view->scene_->scissorsMode) {
            // Device pixels from the bottom-left to widget pixels from the top-left.
            const double ratio = view->widget_->devicePixelRatioF();
            const int height = view->scene_->window->GetSize()[1];
            if (event == vtkCommand::LeftButtonPressEvent)
                view->addScissorsVertex(pos[0] / ratio, (height - 1 - pos[1]) / ratio);
            else
                view->finishScissors();
            AbortFlagOn();
            return;
        }
        if (!view->scene_->pickMode || event != vtkCommand::LeftButtonPressEvent)
            return;
        view->pickAtDevicePixel(pos[0], pos[1]);
        AbortFlagOn();
    }
    CloudView* view = nullptr;
};

CloudView::CloudView(QWidget* parent) : QWidget(parent), scene_(std::make_unique<Scene>())
{
    settleTimer_ = new QTimer(this);
    settleTimer_->setSingleShot(true);
    settleTimer_->setInterval(250);
    connect(settleTimer_, &QTimer::timeout, this, [this] {
        if (scene_->settling)
            setMoving(false);
    });
    // One slice per event-loop turn: whatever the user did meanwhile is served first.
    sliceTimer_ = new QTimer(this);
    sliceTimer_->setSingleShot(true);
    sliceTimer_->setInterval(0);
    connect(sliceTimer_, &QTimer::timeout, this, &CloudView::drawNextSlice);
    widget_ = new QVTKOpenGLNativeWidget(this);
    auto* layout = new QVBoxLayout(this);
    layout->setContentsMargins(0, 0, 0, 0);
    layout->addWidget(widget_);
    widget_->setRenderWindow(scene_->window);
    scene_->window->AddRenderer(scene_->renderer);
    scene_->window->SetNumberOfLayers(2);
    scene_->overlay->SetLayer(1);
    scene_->overlay->InteractiveOff();
    // Its props are flat and need no depth: the clouds' depth is kept for the
    // slices drawn over the picture at rest (drawNextSlice).
    scene_->overlay->PreserveDepthBufferOn();
    scene_->overlay->SetActiveCamera(scene_->renderer->GetActiveCamera());
    scene_->window->AddRenderer(scene_->overlay);
    scene_->renderer->GradientBackgroundOn();
    scene_->renderer->SetBackground(0.10, 0.11, 0.14);
    scene_->renderer->SetBackground2(0.32, 0.34, 0.40);

    scene_->scalarBar->SetLookupTable(scene_->scalarBarTable);
    scene_->scalarBar->SetNumberOfLabels(6);
    // The labels on the bar's left and the frame wide enough for them and the
    // title: on its right, VTK draws them past the view's edge ("3.789e",
    // "c2c_distanc").
    scene_->scalarBar->SetTextPositionToPrecedeScalarBar();
    scene_->scalarBar->SetMaximumWidthInPixels(150);
    scene_->scalarBar->SetPosition(0.84, 0.1);
    scene_->scalarBar->SetWidth(0.14);
    scene_->scalarBar->SetHeight(0.8);
    scene_->scalarBar->GetLabelTextProperty()->SetFontSize(12);
    scene_->scalarBar->GetTitleTextProperty()->SetFontSize(13);
    scene_->scalarBar->UnconstrainedFontSizeOn();
    scene_->scalarBar->SetLabelFormat("%#.4g");
    scene_->scalarBar->VisibilityOff();
    scene_->overlay->AddViewProp(scene_->scalarBar);
    scene_->picker->SetTolerance(0.005);
    scene_->cellPicker->SetTolerance(0.0);

    // CloudCompare-like navigation: trackball rotation, pan, zoom.
    vtkRenderWindowInteractor* interactor = scene_->window->GetInteractor();
    vtkNew<vtkInteractorStyleTrackballCamera> style;
    interactor->SetInteractorStyle(style);
    auto onMove = vtkSmartPointer<vtkCallbackCommand>::New();
    onMove->SetClientData(this);
    onMove->SetCallback([](vtkObject*, unsigned long event, void* self, void*) {
        auto* view = static_cast<CloudView*>(self);
        if (event == vtkCommand::StartInteractionEvent) {
            view->setMoving(true);
            return;
        }
        // VTK renders once more itself after a move (each wheel notch is one):
        // full detail comes when the moves have stopped for a moment.
        view->scene_->settling = true;
        view->settleTimer_->start();
    });
    style->AddObserver(vtkCommand::StartInteractionEvent, onMove);
    style->AddObserver(vtkCommand::EndInteractionEvent, onMove);
    vtkNew<PickCommand> onClick;
    onClick->view = this;
    interactor->AddObserver(vtkCommand::LeftButtonPressEvent, onClick, 10.0f);
    interactor->AddObserver(vtkCommand::RightButtonPressEvent, onClick, 10.0f);
    vtkNew<vtkPolyDataMapper2D> scissorsMapper;
    scissorsMapper->SetInputData(scene_->scissorsOutline);
    scene_->scissorsActor->SetMapper(scissorsMapper);
    scene_->scissorsActor->GetProperty()->SetColor(1.0, 0.9, 0.2);
    scene_->scissorsActor->GetProperty()->SetLineWidth(2.0f);
    scene_->overlay->AddActor2D(scene_->scissorsActor);
    vtkNew<vtkPolyDataMapper2D> scaleBarMapper;
    scaleBarMapper->SetInputData(scene_->scaleBarLine);
    scene_->scaleBarActor->SetMapper(scaleBarMapper);
    scene_->scaleBarActor->GetProperty()->SetColor(1, 1, 1);
    scene_->scaleBarActor->GetProperty()->SetLineWidth(2.0f);
    scene_->overlay->AddActor2D(scene_->scaleBarActor);
    scene_->scaleBarText->GetTextProperty()->SetFontSize(13);
    scene_->scaleBarText->GetTextProperty()->SetJustificationToCentered();
    scene_->overlay->AddActor2D(scene_->scaleBarText);
    auto beforeFrame = vtkSmartPointer<vtkCallbackCommand>::New();
    beforeFrame->SetClientData(this);
    beforeFrame->SetCallback([](vtkObject*, unsigned long, void* self, void*) { static_cast<CloudView*>(self)->updateScaleBar(); });
    scene_->renderer->AddObserver(vtkCommand::StartEvent, beforeFrame);
    auto cameraMoved = vtkSmartPointer<vtkCallbackCommand>::New();
    cameraMoved->SetClientData(this);
    cameraMoved->SetCallback([](vtkObject*, unsigned long, void* self, void*) { emit static_cast<CloudView*>(self)->cameraChanged(); });
    scene_->renderer->GetActiveCamera()->AddObserver(vtkCommand::ModifiedEvent, cameraMoved);
}

CloudView::~CloudView() = default;

void CloudView::addEntity(const Document::Item& item)
{
    if (item.isGroup())
        return; // its scans are entities of their own
    if (item.isDrawing()) {
        addDrawing(item);
    } else {
        if (!addData(item))
            return;
    }
    refreshEntity(item);
    if (scene_->clipping)
        applyClipping();
}

//! A cloud's or a mesh's actors; false when there is nothing to show.
bool CloudView::addData(const Document::Item& item)
{
    const PointCloud& points = item.points();
    if (points.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
        logWarning(item.name.toStdString() + ": more than 2^31 points cannot be shown (the data stays usable by the tools)");
        return false;
    }
    if (points.empty())
        return false;
    if (!scene_->sceneOrigin) {
        scene_->sceneOrigin = points.origin();
        if (!annotations_.empty())
            setAnnotations(std::vector<Annotation>(annotations_)); // in the new frame
    }
    Shown& s = scene_->shown[item.id];
    s.isCloud = item.cloud() != nullptr;
    s.pointCount = points.size();
    // The document never moves or resizes a shown entity's positions, and the
    // view drops an entity before any further render once it is removed.
    // Each entity keeps its own float positions, exact about its own origin;
    // where that origin lies in the scene is its actor's position, in double.
    // VTK composes the actor's and the camera's matrices in double before the
    // one float matrix the GPU gets, so a local cloud beside UTM ones keeps
    // its millimetres (adding the offset to the floats made it stripes).
    const Eigen::Vector3d offset = points.origin() - *scene_->sceneOrigin;
    static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "positions are packed xyz triples");
    if (!s.isCloud)
        addMeshPiece(s, *item.mesh(), offset);
    else
        addCloudChunks(s, points, offset);
    updateStride();
    setDecimated(s, scene_->moving || refinesInSlices());
    return true;
}

void CloudView::addDrawing(const Document::Item& item)
{
    // Lines over the clouds, in the scene's frame (the first vertex sets
    // it when the drawing comes first), coloured by layer, unlit.
    const Drawing& drawing = *item.drawing;
    const auto first = std::find_if(drawing.polylines.begin(), drawing.polylines.end(),
                                    [](const DrawingPolyline& p) { return p.points.size() >= 2; });
    if (first == drawing.polylines.end())
        return;
    if (!scene_->sceneOrigin)
        scene_->sceneOrigin = first->points.front();
    Shown& s = scene_->shown[item.id];
    s.isCloud = false;
    Shown::Chunk c;
    c.full = drawingLines(drawing, *scene_->sceneOrigin);
    c.fullMapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    c.fullMapper->SetInputData(c.full);
    c.fullMapper->SetScalarModeToUseCellData();
    c.fullMapper->SetColorModeToDirectScalars();
    c.fullMapper->ScalarVisibilityOn();
    // Lines lie on the scanned surface: drawn a little towards the eye so
    // the points do not cover them.
    c.fullMapper->SetResolveCoincidentTopologyToPolygonOffset();
    c.fullMapper->SetRelativeCoincidentTopologyLineOffsetParameters(0.0, -2000.0);
    c.actor = vtkSmartPointer<vtkActor>::New();
    c.actor->SetMapper(c.fullMapper);
    c.actor->GetProperty()->SetLineWidth(2.5f);
    c.actor->GetProperty()->LightingOff();
    c.actor->PickableOff(); // picks answer with a cloud's point, never a drawing's vertex
    scene_->renderer->AddActor(c.actor);
    s.chunks.push_back(c);
    if (!drawing.texts.empty()) {
        vtkNew<vtkPoints> anchors;
        vtkNew<vtkStringArray> texts;
        texts->SetName("text");
        for (const DrawingText& text : drawing.texts) {
            const Eigen::Vector3d local = text.position - *scene_->sceneOrigin; // in double, then small
            anchors->InsertNextPoint(local.x(), local.y(), local.z());
            texts->InsertNextValue(text.text);
        }
        vtkNew<vtkPolyData> labelled;
        labelled->SetPoints(anchors);
        labelled->GetPointData()->AddArray(texts);
        vtkNew<vtkPointSetToLabelHierarchy> hierarchy;
        hierarchy->SetInputData(labelled);
        hierarchy->SetLabelArrayName("text");
        hierarchy->GetTextProperty()->SetFontSize(12);
        hierarchy->GetTextProperty()->SetColor(1.0, 1.0, 0.6);
        hierarchy->GetTextProperty()->SetJustificationToCentered();
        vtkNew<vtkLabelPlacementMapper> placement;
        placement->SetInputConnection(hierarchy->GetOutputPort());
        placement->SetShapeToRoundedRect();
        placement->SetBackgroundColor(0.1, 0.1, 0.1);
        placement->SetBackgroundOpacity(0.6);
        s.labels = vtkSmartPointer<vtkActor2D>::New();
        s.labels->SetMapper(placement);
        s.labels->PickableOff();
        scene_->renderer->AddActor(s.labels);
    }
}

//! A mesh: one piece, its triangles index every vertex.
void CloudView::addMeshPiece(Shown& s, const Mesh& mesh, const Eigen::Vector3d& offset)
{
    Shown::Chunk c;
    c.count = mesh.vertices.size();
    c.full = vtkSmartPointer<vtkPolyData>::New();
    c.full->SetPoints(pointsOver(mesh.vertices.positions().front().data(), c.count));
    vtkNew<vtkCellArray> polys;
    polys->AllocateExact(static_cast<vtkIdType>(mesh.triangles.size()), static_cast<vtkIdType>(3 * mesh.triangles.size()));
    for (const auto& t : mesh.triangles) {
        const vtkIdType ids[3] = {t[0], t[1], t[2]};
        polys->InsertNextCell(3, ids);
    }
    c.full->SetPolys(polys);
    c.fullMapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    c.fullMapper->SetInputData(c.full);
    c.fullMapper->ScalarVisibilityOff();
    c.actor = vtkSmartPointer<vtkActor>::New();
    c.actor->SetPosition(offset.x(), offset.y(), offset.z());
    c.actor->SetMapper(c.fullMapper);
    c.actor->GetProperty()->SetColor(0.85, 0.85, 0.8);
    scene_->renderer->AddActor(c.actor);
    s.chunks.push_back(c);
}

//! A cloud's chunks, each drawing a range of its points (a grid's as cells).
void CloudView::addCloudChunks(Shown& s, const PointCloud& points, const Eigen::Vector3d& offset)
{
    const float* xyz = points.positions().front().data();
    s.rgba.assign(4 * points.size(), 255);
    // A grid (DEM of difference, raster) is drawn as its cells, an image on the ground.
    const std::optional<double> rasterCell = gridCellSize(points);
    for (std::size_t begin = 0; begin < points.size(); begin += kChunkPoints) {
        Shown::Chunk c;
        c.begin = begin;
        c.count = std::min(kChunkPoints, points.size() - begin);
        c.full = vtkSmartPointer<vtkPolyData>::New();
        c.colours = vtkSmartPointer<vtkUnsignedCharArray>::New();
        c.colours->SetNumberOfComponents(4);
        c.colours->SetName("display colours");
        c.raster = rasterCell.has_value();
        if (c.raster) {
            makeRasterGeometry(*c.full, points, begin, c.count, *rasterCell);
            c.colours->SetNumberOfTuples(static_cast<vtkIdType>(4 * c.count));
        } else {
            c.full->SetPoints(pointsOver(xyz + 3 * begin, c.count)); // its vertices when drawn in full (setDecimated)
            c.colours->SetArray(s.rgba.data() + 4 * begin, static_cast<vtkIdType>(4 * c.count), /*save*/ 1);
        }
        c.full->GetPointData()->SetScalars(c.colours);
        if (points.hasNormals() && !c.raster) {
            // Shading by the normals, as CloudCompare lights clouds that have them:
            // the shape reads at once. A view on the cloud's normals, no copy.
            c.normals = vtkSmartPointer<vtkFloatArray>::New();
            c.normals->SetNumberOfComponents(3);
            c.normals->SetArray(const_cast<float*>(points.normals()[begin].data()), static_cast<vtkIdType>(3 * c.count), 1);
            c.full->GetPointData()->SetNormals(c.normals);
        }
        c.fullMapper = chunkMapper(c.full);
        c.actor = vtkSmartPointer<vtkActor>::New();
        c.actor->SetPosition(offset.x(), offset.y(), offset.z());
        c.actor->SetMapper(c.fullMapper);
        c.actor->GetProperty()->SetPointSize(scene_->pointSize);
        if (c.raster)
            c.actor->GetProperty()->LightingOff(); // the colours of the scale, unshaded
        c.actor->ForceOpaqueOn();
        c.actor->GetShaderProperty()->AddFragmentShaderReplacement("//VTK::Light::Impl", true, kDiscardHidden, false);
        scene_->renderer->AddActor(c.actor);
        s.chunks.push_back(c);
    }
}

void CloudView::refreshEntity(const Document::Item& item)
{
    const auto it = scene_->shown.find(item.id);
    if (it == scene_->shown.end())
        return;
    Shown& s = it->second;
    s.documentVisible = item.display.visible;
    const bool visible = item.display.visible && !hiddenHere_.count(item.id);
    const bool visibilityChanged = s.chunks.front().actor->GetVisibility() != int(visible);
    s.ownPointSize = item.display.pointSize;
    for (auto& c : s.chunks) {
        c.actor->SetVisibility(visible);
        if (s.isCloud)
            c.actor->GetProperty()->SetPointSize(s.ownPointSize > 0 ? s.ownPointSize : scene_->pointSize);
    }
    if (s.labels)
        s.labels->SetVisibility(visible);
    if (visibilityChanged)
        updateStride();
    if (s.isCloud) {
        // Written in place: VTK re-uploads the colours only, never the points.
        EntityColourer colourer(item.points(), item.display);
        const bool rasters = std::any_of(s.chunks.begin(), s.chunks.end(), [](const Shown::Chunk& c) { return c.raster; });
        s.pendingColours.reset();
        if (colourer.colouredInParts() && refinesInSlices() && !rasters)
            s.pendingColours.emplace(std::move(colourer)); // the decimated frame's points below, the slices' as they come
        else
            colourer.colourAll(s.rgba.data());
        for (auto& c : s.chunks) {
            if (c.raster) { // each cell's colour on its four corners
                std::uint8_t* corners = c.colours->GetPointer(0);
                for (std::size_t i = 0; i < c.count; ++i)
                    for (int k = 0; k < 4; ++k)
                        std::copy_n(&s.rgba[4 * (c.begin + i)], 4, corners + 16 * i + 4 * k);
            }
            c.colours->Modified();
            if (c.decimated) {
                s.colourForGather(c, c.decimatedStride);
                gatherColours(*c.decimated, c.arrays(s), c.decimatedStride);
            }
        }
    }
    renderInteractively();
}

void CloudView::removeEntity(EntityId id)
{
    const auto it = scene_->shown.find(id);
    if (it == scene_->shown.end())
        return;
    for (auto& c : it->second.chunks)
        scene_->renderer->RemoveActor(c.actor);
    if (it->second.labels)
        scene_->renderer->RemoveActor(it->second.labels);
    scene_->shown.erase(it);
    if (scene_->shown.empty())
        scene_->sceneOrigin.reset();
    updateStride();
    renderSoon(); // deleting a cloud and its 100 regions draws once
}

void CloudView::clear()
{
    for (auto& [id, s] : scene_->shown) {
        for (auto& c : s.chunks)
            scene_->renderer->RemoveActor(c.actor);
        if (s.labels)
            scene_->renderer->RemoveActor(s.labels);
    }
    scene_->shown.clear();
    scene_->sceneOrigin.reset();
    scene_->scalarBar->VisibilityOff();
    legend_ = {};
    setAnnotations(std::vector<Annotation>(annotations_)); // the frame is gone: redrawn once a cloud sets one
    updateStride();
    render();
}

void CloudView::resetCamera()
{
    scene_->renderer->ResetCamera();
    resetClippingRange();
    // Decimated first, full detail once nothing else happens: opening big
    // files shows each cloud at once instead of an empty window while a
    // software renderer draws millions of points.
    renderInteractively();
}

void CloudView::zoomToEntity(EntityId id)
{
    const auto it = scene_->shown.find(id);
    if (it == scene_->shown.end())
        return;
    vtkBoundingBox box;
    for (auto& c : it->second.chunks)
        box.AddBounds(c.actor->GetBounds());
    double bounds[6];
    box.GetBounds(bounds);
    scene_->renderer->ResetCamera(bounds);
    resetClippingRange();
    render();
}

void CloudView::setStandardView(StandardView view)
{
    // Direction from the focal point to the camera, and the up vector.
    Eigen::Vector3d eye(0, 0, 1), up(0, 0, 1);
    switch (view) {
    case StandardView::Top: eye = {0, 0, 1}; up = {0, 1, 0}; break;
    case StandardView::Bottom: eye = {0, 0, -1}; up = {0, 1, 0}; break;
    case StandardView::Front: eye = {0, -1, 0}; break;
    case StandardView::Back: eye = {0, 1, 0}; break;
    case StandardView::Left: eye = {-1, 0, 0}; break;
    case StandardView::Right: eye = {1, 0, 0}; break;
    case StandardView::Iso: eye = Eigen::Vector3d(1, -1, 1).normalized(); break;
    }
    vtkCamera* camera = scene_->renderer->GetActiveCamera();
    camera->SetFocalPoint(0, 0, 0);
    camera->SetPosition(eye.x(), eye.y(), eye.z());
    camera->SetViewUp(up.x(), up.y(), up.z());
    resetCamera();
}

void CloudView::setPointSize(float size)
{
    if (size != scene_->pointSize) {
        scene_->pointSize = size;
        emit pointSizeChanged(size);
    }
    for (auto& [id, s] : scene_->shown)
        if (s.isCloud && s.ownPointSize <= 0) // an entity with its own size keeps it
            for (auto& c : s.chunks)
                c.actor->GetProperty()->SetPointSize(size);
    render();
}

float CloudView::pointSize() const { return scene_->pointSize; }

void CloudView::setParallelProjection(bool parallel)
{
    if (parallel != parallelProjection()) {
        scene_->renderer->GetActiveCamera()->SetParallelProjection(parallel);
        emit projectionChanged(parallel);
    }
    resetClippingRange();
    render();
}

bool CloudView::parallelProjection() const { return scene_->renderer->GetActiveCamera()->GetParallelProjection() != 0; }

void CloudView::resetClippingRange()
{
    // The measurements count for the near and far planes (not for "zoom to
    // all"): one taken on a cloud hidden since, or restored with a session
    // before its clouds are shown, stays drawn wherever the camera is.
    double bounds[6];
    scene_->renderer->ComputeVisiblePropBounds(bounds);
    if (annotationCount_ > 0 && scene_->annotations->GetNumberOfPoints() > 0) {
        double marks[6];
        scene_->annotations->GetBounds(marks);
        const bool none = !(bounds[0] <= bounds[1]);
        for (int a = 0; a < 3; ++a) {
            bounds[2 * a] = none ? marks[2 * a] : std::min(bounds[2 * a], marks[2 * a]);
            bounds[2 * a + 1] = none ? marks[2 * a + 1] : std::max(bounds[2 * a + 1], marks[2 * a + 1]);
        }
    }
    if (bounds[0] <= bounds[1])
        scene_->renderer->ResetCameraClippingRange(bounds);
    else
        scene_->renderer->ResetCameraClippingRange();
}

void CloudView::setShownHere(EntityId id, bool shown)
{
    if (shown)
        hiddenHere_.erase(id);
    else
        hiddenHere_.insert(id);
    const auto it = scene_->shown.find(id);
    if (it == scene_->shown.end())
        return;
    // The slices drawn so far did not colour a cloud hidden then: start them again.
    stopRefinement();
    for (auto& c : it->second.chunks)
        c.actor->SetVisibility(shown && it->second.documentVisible);
    if (it->second.labels)
        it->second.labels->SetVisibility(shown && it->second.documentVisible);
    updateStride();
    renderSoon();
}

std::size_t CloudView::labelCount(EntityId id) const
{
    const auto it = scene_->shown.find(id);
    if (it == scene_->shown.end() || !it->second.labels)
        return 0;
    auto* placement = vtkLabelPlacementMapper::SafeDownCast(it->second.labels->GetMapper());
    auto* hierarchy = placement ? vtkPointSetToLabelHierarchy::SafeDownCast(placement->GetInputAlgorithm()) : nullptr;
    auto* labelled = hierarchy ? vtkPolyData::SafeDownCast(hierarchy->GetInputDataObject(0, 0)) : nullptr;
    return labelled ? static_cast<std::size_t>(labelled->GetNumberOfPoints()) : 0;
}

bool CloudView::labelsVisible(EntityId id) const
{
    const auto it = scene_->shown.find(id);
    return it != scene_->shown.end() && it->second.labels && it->second.labels->GetVisibility();
}

bool CloudView::isShownHere(EntityId id) const
{
    const auto it = scene_->shown.find(id);
    return it != scene_->shown.end() && !it->second.chunks.empty() && it->second.chunks.front().actor->GetVisibility();
}

bool CloudView::isOnScreen(EntityId id) const
{
    if (!isShownHere(id))
        return false;
    const Eigen::Matrix4d toPixels = globalToWidgetPixels();
    const Eigen::Vector3d origin = scene_->sceneOrigin.value_or(Eigen::Vector3d::Zero());
    const double width = widget_->width(), height = widget_->height();
    for (const auto& c : scene_->shown.at(id).chunks) {
        double b[6];
        c.actor->GetBounds(b); // scene coordinates, kept by VTK
        if (!(b[0] <= b[1]))
            continue;
        double left = std::numeric_limits<double>::infinity(), right = -left, top = left, bottom = -left;
        int behind = 0;
        for (int corner = 0; corner < 8; ++corner) {
            const Eigen::Vector4d global(b[corner & 1] + origin.x(), b[2 + ((corner >> 1) & 1)] + origin.y(),
                                         b[4 + ((corner >> 2) & 1)] + origin.z(), 1.0);
            const Eigen::Vector4d pixel = toPixels * global;
            if (pixel.w() <= 0.0) {
                ++behind;
                continue;
            }
            left = std::min(left, pixel.x() / pixel.w());
            right = std::max(right, pixel.x() / pixel.w());
            top = std::min(top, pixel.y() / pixel.w());
            bottom = std::max(bottom, pixel.y() / pixel.w());
        }
        if (behind == 8)
            continue; // wholly behind the camera
        if (behind > 0 || (right >= 0 && left <= width && bottom >= 0 && top <= height))
            return true; // some behind, some in front: the camera is among the points
    }
    return false;
}

void CloudView::followCamera(CloudView& leader)
{
    // One camera for both: a move in either view moves the other.
    vtkCamera* camera = leader.scene_->renderer->GetActiveCamera();
    scene_->renderer->SetActiveCamera(camera);
    scene_->overlay->SetActiveCamera(camera);
    for (CloudView* view : {this, &leader}) {
        auto redraw = vtkSmartPointer<vtkCallbackCommand>::New();
        redraw->SetClientData(view);
        redraw->SetCallback([](vtkObject*, unsigned long, void* self, void*) { static_cast<CloudView*>(self)->renderSoon(); });
        camera->AddObserver(vtkCommand::ModifiedEvent, redraw);
    }
    renderSoon();
}

void CloudView::setEyeDomeLighting(bool on)
{
    scene_->eyeDomeLighting = on;
    auto* renderer = vtkOpenGLRenderer::SafeDownCast(scene_->renderer);
    if (!renderer)
        return;
    if (on) {
        // The usual steps (opaque, translucent, overlays) rendered through EDL.
        vtkNew<vtkRenderStepsPass> steps;
        scene_->edl = vtkSmartPointer<vtkEDLShading>::New();
        scene_->edl->SetDelegatePass(steps);
        renderer->SetPass(scene_->edl);
    } else {
        renderer->SetPass(nullptr);
        if (scene_->edl) // its framebuffers go with the GL context it made them in
            scene_->edl->ReleaseGraphicsResources(scene_->window);
        scene_->edl = nullptr;
    }
    render();
}

bool CloudView::eyeDomeLighting() const { return scene_->eyeDomeLighting; }

void CloudView::setBackground(const QColor& colour)
{
    // Invalid: the default gradient, dark at the bottom.
    scene_->renderer->SetGradientBackground(!colour.isValid());
    if (colour.isValid()) {
        scene_->renderer->SetBackground(colour.redF(), colour.greenF(), colour.blueF());
    } else {
        scene_->renderer->SetBackground(0.10, 0.11, 0.14);
        scene_->renderer->SetBackground2(0.32, 0.34, 0.40);
    }
    render();
}

QColor CloudView::background() const
{
    if (scene_->renderer->GetGradientBackground())
        return {};
    double rgb[3];
    scene_->renderer->GetBackground(rgb);
    return QColor::fromRgbF(rgb[0], rgb[1], rgb[2]);
}

bool CloudView::isShaded(EntityId id) const
{
    const auto it = scene_->shown.find(id);
    return it != scene_->shown.end() && !it->second.chunks.empty() && it->second.chunks.front().normals;
}

float CloudView::entityPointSize(EntityId id) const
{
    const auto it = scene_->shown.find(id);
    if (it == scene_->shown.end() || it->second.chunks.empty())
        return 0;
    return static_cast<float>(it->second.chunks.front().actor->GetProperty()->GetPointSize());
}

bool CloudView::shownFrame(EntityId id, Eigen::Vector3d& offset, Eigen::Vector3f& firstPosition) const
{
    const auto it = scene_->shown.find(id);
    if (it == scene_->shown.end() || it->second.chunks.empty())
        return false;
    const Shown::Chunk& c = it->second.chunks.front();
    double position[3];
    c.actor->GetPosition(position);
    offset = {position[0], position[1], position[2]};
    Eigen::Vector3d first = Eigen::Vector3d::Zero();
    const int corners = c.raster ? 4 : 1; // a cell's centre is the mean of its corners
    for (int k = 0; k < corners; ++k) {
        double p[3];
        c.full->GetPoints()->GetPoint(k, p);
        first += Eigen::Vector3d(p[0], p[1], p[2]) / corners;
    }
    firstPosition = first.cast<float>();
    return true;
}

CameraState CloudView::camera() const
{
    vtkCamera* c = scene_->renderer->GetActiveCamera();
    CameraState s;
    c->GetPosition(s.position.data());
    c->GetFocalPoint(s.focalPoint.data());
    // Global coordinates: the scene's origin depends on which entity came first.
    const Eigen::Vector3d origin = scene_->sceneOrigin.value_or(Eigen::Vector3d::Zero());
    for (int k = 0; k < 3; ++k) {
        s.position[k] += origin[k];
        s.focalPoint[k] += origin[k];
    }
    c->GetViewUp(s.viewUp.data());
    s.viewAngle = c->GetViewAngle();
    s.parallel = c->GetParallelProjection() != 0;
    s.parallelScale = c->GetParallelScale();
    return s;
}

void CloudView::setCamera(const CameraState& s)
{
    vtkCamera* c = scene_->renderer->GetActiveCamera();
    const Eigen::Vector3d origin = scene_->sceneOrigin.value_or(Eigen::Vector3d::Zero());
    c->SetPosition(s.position[0] - origin.x(), s.position[1] - origin.y(), s.position[2] - origin.z());
    c->SetFocalPoint(s.focalPoint[0] - origin.x(), s.focalPoint[1] - origin.y(), s.focalPoint[2] - origin.z());
    c->SetViewUp(s.viewUp.data());
    c->SetViewAngle(s.viewAngle);
    if (bool(c->GetParallelProjection()) != s.parallel) {
        c->SetParallelProjection(s.parallel);
        emit projectionChanged(s.parallel);
    }
    c->SetParallelScale(s.parallelScale);
    resetClippingRange();
    render();
}

void CloudView::setInteractiveBudget(std::size_t points)
{
    scene_->budget = std::max<std::size_t>(points, 1);
    scene_->adaptiveBudget = false;
    updateStride();
}

std::size_t CloudView::interactiveBudget() const { return scene_->budget; }

std::size_t CloudView::interactiveStride() const { return scene_->stride; }

void CloudView::updateStride()
{
    std::size_t total = 0; // what is drawn: hidden clouds cost nothing
    for (const auto& [id, s] : scene_->shown)
        if (s.isCloud && s.chunks.front().actor->GetVisibility())
            total += s.pointCount;
    scene_->stride = std::max<std::size_t>(1, (total + scene_->budget - 1) / scene_->budget);
}

void CloudView::setMoving(bool moving)
{
    stopRefinement();
    scene_->moving = moving;
    scene_->settling = false;
    settleTimer_->stop();
    for (auto& [id, s] : scene_->shown)
        setDecimated(s, moving || refinesInSlices());
    if (!moving) {
        resetClippingRange(); // the measurements too, once the move is over
        render(); // full detail at rest, at once or slice by slice
    }
}

void CloudView::setDecimated(Shown& s, bool moving)
{
    if (!s.isCloud)
        return;
    const bool decimate = moving && scene_->stride > 1;
    if (!decimate)
        s.settleColours(); // every point drawn
    for (auto& c : s.chunks) {
        if (c.raster)
            continue; // one quad per cell: already light
        // A vertex list of every point (8 bytes a point) exists only while
        // the chunk is drawn in full: a cloud refined in slices never is,
        // but for a screenshot.
        if (!decimate && c.full->GetNumberOfVerts() == 0)
            c.full->SetVerts(vertexCells(c.count, 1));
        else if (decimate && c.full->GetNumberOfVerts() > 0)
            c.full->SetVerts(vtkSmartPointer<vtkCellArray>::New());
        if (decimate && c.decimatedStride != scene_->stride) {
            if (!c.decimated) {
                c.decimated = vtkSmartPointer<vtkPolyData>::New();
                c.decimatedMapper = chunkMapper(c.decimated);
            }
            s.colourForGather(c, scene_->stride);
            gatherPoints(*c.decimated, c.arrays(s), scene_->stride);
            c.decimatedMapper->SetClippingPlanes(c.fullMapper->GetClippingPlanes()); // the clipping box holds for it too
            c.decimatedStride = scene_->stride;
        }
        c.actor->SetMapper(decimate ? c.decimatedMapper.Get() : c.fullMapper.Get());
    }
}

void CloudView::render()
{
    scene_->renderPending = false;
    if (scene_->moving) {
        scene_->window->Render();
        return;
    }
    if (refinesInSlices()) {
        startRefinement();
        return;
    }
    stopRefinement();
    std::size_t drawn = 0;
    for (auto& [id, s] : scene_->shown) {
        setDecimated(s, false);
        if (s.isCloud && s.chunks.front().actor->GetVisibility())
            drawn += s.pointCount;
    }
    timedRender(drawn);
}

void CloudView::resizeEvent(QResizeEvent* event)
{
    QWidget::resizeEvent(event);
    // The widget redraws a resized window itself, from what the actors hold
    // (the decimated clouds after slices): the picture at rest again.
    if (!scene_->moving)
        renderSoon();
}

void CloudView::renderSoon()
{
    if (scene_->renderPending)
        return;
    scene_->renderPending = true;
    QTimer::singleShot(0, this, [this] {
        if (scene_->renderPending)
            render();
    });
}

void CloudView::renderInteractively()
{
    // A threshold drag or a colour change redraws at once with the decimated
    // clouds, and in full once the changes stop for a moment.
    stopRefinement();
    if (scene_->stride <= 1) {
        render();
        return;
    }
    if (!scene_->moving || scene_->settling) {
        scene_->settling = true;
        for (auto& [id, s] : scene_->shown)
            setDecimated(s, true);
        scene_->moving = true;
    }
    settleTimer_->start();
    // One frame for the changes of one turn of the event loop (a tool's
    // results recolour the compared and the reference clouds one after the
    // other), drawn in a turn of its own.
    if (scene_->interactiveRenderPending)
        return;
    scene_->interactiveRenderPending = true;
    QTimer::singleShot(1, this, [this] {
        scene_->interactiveRenderPending = false;
        if (scene_->moving)
            scene_->window->Render();
    });
}

bool CloudView::saveScreenshot(const QString& path)
{
    // A picture shows every point: one full frame, however long it takes.
    stopRefinement();
    scene_->moving = scene_->settling = false;
    settleTimer_->stop();
    for (auto& [id, s] : scene_->shown)
        setDecimated(s, false);
    scene_->window->Render();
    vtkNew<vtkWindowToImageFilter> grab;
    grab->SetInput(scene_->window);
    grab->ReadFrontBufferOff();
    grab->Update();
    vtkNew<vtkPNGWriter> writer;
    writer->SetFileName(path.toStdString().c_str());
    writer->SetInputConnection(grab->GetOutputPort());
    writer->Write();
    for (auto& [id, s] : scene_->shown)
        setDecimated(s, refinesInSlices()); // the next frame at rest is refined again
    return writer->GetErrorCode() == 0;
}

QImage CloudView::shownPicture() const
{
    vtkNew<vtkWindowToImageFilter> grab;
    grab->SetInput(scene_->window);
    grab->ShouldRerenderOff();
    grab->ReadFrontBufferOff();
    grab->SetInputBufferTypeToRGB();
    grab->Update();
    vtkImageData* image = grab->GetOutput();
    int size[3] = {0, 0, 0};
    image->GetDimensions(size);
    QImage picture(size[0], size[1], QImage::Format_RGB888);
    const auto* pixels = static_cast<const std::uint8_t*>(image->GetScalarPointer());
    for (int y = 0; y < size[1]; ++y) // VTK's rows run bottom-up
        std::copy_n(pixels + 3 * static_cast<std::size_t>(y) * size[0], 3 * size[0], picture.scanLine(size[1] - 1 - y));
    return picture;
}

QSurfaceFormat CloudView::defaultSurfaceFormat() { return QVTKOpenGLNativeWidget::defaultFormat(); }

} // namespace scandiff::gui
