// SPDX-License-Identifier: GPL-3.0-or-later
#include "view/CloudView.h"

#include <QVBoxLayout>
#include <QVTKOpenGLNativeWidget.h>

#include <vtkActor.h>
#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkIdTypeArray.h>
#include <vtkInteractorStyleTrackballCamera.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkPointPicker.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkShaderProperty.h>
#include <vtkSmartPointer.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <map>
#include <optional>
#include <vector>

namespace scandiff::gui {

namespace {

//! One shown entity. A cloud's decimated twin shares its points and colour
//! arrays and only holds every stride-th vertex, so colour changes reach both
//! and VTK uploads the arrays once.
struct Shown
{
    bool isCloud = true;
    std::size_t pointCount = 0;
    vtkSmartPointer<vtkPolyData> full;
    vtkSmartPointer<vtkPolyData> decimated;
    vtkSmartPointer<vtkPolyDataMapper> fullMapper;
    vtkSmartPointer<vtkPolyDataMapper> decimatedMapper;
    vtkSmartPointer<vtkUnsignedCharArray> colours;
    vtkSmartPointer<vtkActor> actor;
    std::size_t decimatedStride = 0;
};

vtkSmartPointer<vtkPoints> toVtkPoints(const PointCloud& cloud, const Eigen::Vector3d& sceneOrigin)
{
    auto points = vtkSmartPointer<vtkPoints>::New();
    points->SetDataTypeToFloat();
    points->SetNumberOfPoints(static_cast<vtkIdType>(cloud.size()));
    const Eigen::Vector3f delta = (cloud.origin() - sceneOrigin).cast<float>();
    auto* raw = static_cast<float*>(points->GetVoidPointer(0));
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3f p = cloud.positions()[i] + delta;
        raw[3 * i] = p.x();
        raw[3 * i + 1] = p.y();
        raw[3 * i + 2] = p.z();
    }
    return points;
}

//! Vertex cells for every stride-th point, built as two flat arrays.
vtkSmartPointer<vtkCellArray> vertexCells(std::size_t count, std::size_t stride)
{
    const auto n = static_cast<vtkIdType>((count + stride - 1) / stride);
    vtkNew<vtkIdTypeArray> offsets;
    vtkNew<vtkIdTypeArray> connectivity;
    offsets->SetNumberOfValues(n + 1);
    connectivity->SetNumberOfValues(n);
    for (vtkIdType i = 0; i < n; ++i) {
        offsets->SetValue(i, i);
        connectivity->SetValue(i, i * static_cast<vtkIdType>(stride));
    }
    offsets->SetValue(n, n);
    auto cells = vtkSmartPointer<vtkCellArray>::New();
    cells->SetData(offsets, connectivity);
    return cells;
}

// Hidden points carry alpha 0; dropping their fragments hides them without
// touching the geometry (the actor is forced opaque so VTK keeps one pass).
constexpr const char* kDiscardHidden = "//VTK::Light::Impl\n  if (gl_FragData[0].a <= 0.0) { discard; }\n";

} // namespace

struct CloudView::Scene
{
    vtkNew<vtkGenericOpenGLRenderWindow> window;
    vtkNew<vtkRenderer> renderer;
    vtkNew<vtkScalarBarActor> scalarBar;
    vtkNew<vtkLookupTable> scalarBarTable;
    vtkNew<vtkPointPicker> picker;
    std::map<EntityId, Shown> shown;
    std::optional<Eigen::Vector3d> sceneOrigin;
    float pointSize = 2.0f;
    std::size_t budget = 1'500'000;
    std::size_t stride = 1;
    bool moving = false;
    bool pickMode = false;
};

//! In pick mode, a left click picks a point and stops there (no rotation).
class CloudView::PickCommand : public vtkCommand
{
public:
    static PickCommand* New() { return new PickCommand; }
    void Execute(vtkObject* caller, unsigned long, void*) override
    {
        if (!view || !view->scene_->pickMode)
            return;
        const int* pos = static_cast<vtkRenderWindowInteractor*>(caller)->GetEventPosition();
        view->pickAtDevicePixel(pos[0], pos[1]);
        AbortFlagOn();
    }
    CloudView* view = nullptr;
};

CloudView::CloudView(QWidget* parent) : QWidget(parent), scene_(std::make_unique<Scene>())
{
    widget_ = new QVTKOpenGLNativeWidget(this);
    auto* layout = new QVBoxLayout(this);
    layout->setContentsMargins(0, 0, 0, 0);
    layout->addWidget(widget_);
    widget_->setRenderWindow(scene_->window);
    scene_->window->AddRenderer(scene_->renderer);
    scene_->renderer->GradientBackgroundOn();
    scene_->renderer->SetBackground(0.10, 0.11, 0.14);
    scene_->renderer->SetBackground2(0.32, 0.34, 0.40);

    scene_->scalarBar->SetLookupTable(scene_->scalarBarTable);
    scene_->scalarBar->SetNumberOfLabels(6);
    scene_->scalarBar->SetMaximumWidthInPixels(90);
    scene_->scalarBar->SetPosition(0.90, 0.1);
    scene_->scalarBar->SetWidth(0.08);
    scene_->scalarBar->SetHeight(0.8);
    scene_->scalarBar->GetLabelTextProperty()->SetFontSize(12);
    scene_->scalarBar->UnconstrainedFontSizeOn();
    scene_->scalarBar->SetLabelFormat("%-#8.4g");
    scene_->scalarBar->VisibilityOff();
    scene_->renderer->AddViewProp(scene_->scalarBar);
    scene_->picker->SetTolerance(0.005);

    // CloudCompare-like navigation: trackball rotation, pan, zoom.
    vtkRenderWindowInteractor* interactor = scene_->window->GetInteractor();
    vtkNew<vtkInteractorStyleTrackballCamera> style;
    interactor->SetInteractorStyle(style);
    auto onMove = vtkSmartPointer<vtkCallbackCommand>::New();
    onMove->SetClientData(this);
    onMove->SetCallback([](vtkObject*, unsigned long event, void* self, void*) {
        static_cast<CloudView*>(self)->setMoving(event == vtkCommand::StartInteractionEvent);
    });
    style->AddObserver(vtkCommand::StartInteractionEvent, onMove);
    style->AddObserver(vtkCommand::EndInteractionEvent, onMove);
    vtkNew<PickCommand> onClick;
    onClick->view = this;
    interactor->AddObserver(vtkCommand::LeftButtonPressEvent, onClick, 10.0f);
}

CloudView::~CloudView() = default;

void CloudView::addEntity(const Document::Item& item)
{
    const PointCloud& points = item.points();
    if (!scene_->sceneOrigin)
        scene_->sceneOrigin = points.origin();
    Shown s;
    s.isCloud = item.cloud() != nullptr;
    s.pointCount = points.size();
    s.full = vtkSmartPointer<vtkPolyData>::New();
    s.full->SetPoints(toVtkPoints(points, *scene_->sceneOrigin));
    s.fullMapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    s.fullMapper->SetInputData(s.full);
    s.actor = vtkSmartPointer<vtkActor>::New();
    s.actor->SetMapper(s.fullMapper);
    if (s.isCloud) {
        s.full->SetVerts(vertexCells(points.size(), 1));
        s.colours = vtkSmartPointer<vtkUnsignedCharArray>::New();
        s.colours->SetNumberOfComponents(4);
        s.colours->SetName("display colours");
        s.full->GetPointData()->SetScalars(s.colours);
        s.fullMapper->SetColorModeToDirectScalars();
        s.fullMapper->ScalarVisibilityOn();
        s.actor->GetProperty()->SetPointSize(scene_->pointSize);
        s.actor->ForceOpaqueOn();
        s.actor->GetShaderProperty()->AddFragmentShaderReplacement("//VTK::Light::Impl", true, kDiscardHidden, false);
    } else {
        const Mesh& mesh = *item.mesh();
        vtkNew<vtkCellArray> polys;
        polys->AllocateExact(static_cast<vtkIdType>(mesh.triangles.size()), static_cast<vtkIdType>(3 * mesh.triangles.size()));
        for (const auto& t : mesh.triangles) {
            const vtkIdType ids[3] = {t[0], t[1], t[2]};
            polys->InsertNextCell(3, ids);
        }
        s.full->SetPolys(polys);
        s.fullMapper->ScalarVisibilityOff();
        s.actor->GetProperty()->SetColor(0.85, 0.85, 0.8);
    }
    scene_->renderer->AddActor(s.actor);
    scene_->shown[item.id] = s;
    updateStride();
    refreshEntity(item);
}

void CloudView::refreshEntity(const Document::Item& item)
{
    const auto it = scene_->shown.find(item.id);
    if (it == scene_->shown.end())
        return;
    Shown& s = it->second;
    s.actor->SetVisibility(item.display.visible);
    if (s.isCloud) {
        std::vector<std::uint8_t> rgba;
        colourEntity(item.points(), item.display, rgba);
        // Same array object: VTK re-uploads the colours only, never the points.
        s.colours->SetNumberOfTuples(static_cast<vtkIdType>(s.pointCount));
        std::copy(rgba.begin(), rgba.end(), s.colours->GetPointer(0));
        s.colours->Modified();
    }
    render();
}

void CloudView::removeEntity(EntityId id)
{
    const auto it = scene_->shown.find(id);
    if (it == scene_->shown.end())
        return;
    scene_->renderer->RemoveActor(it->second.actor);
    scene_->shown.erase(it);
    if (scene_->shown.empty())
        scene_->sceneOrigin.reset();
    updateStride();
    render();
}

void CloudView::setLegend(const ColourLegend& legend)
{
    if (!legend.shown) {
        scene_->scalarBar->VisibilityOff();
        render();
        return;
    }
    constexpr int kColours = 256;
    scene_->scalarBarTable->SetNumberOfTableValues(kColours);
    for (int i = 0; i < kColours; ++i) {
        const auto c = legend.scale.colourAt(i / double(kColours - 1));
        scene_->scalarBarTable->SetTableValue(i, c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, 1.0);
    }
    scene_->scalarBarTable->SetTableRange(legend.min, legend.max);
    scene_->scalarBar->SetTitle(legend.title.c_str());
    scene_->scalarBar->VisibilityOn();
    render();
}

void CloudView::clear()
{
    for (auto& [id, s] : scene_->shown)
        scene_->renderer->RemoveActor(s.actor);
    scene_->shown.clear();
    scene_->sceneOrigin.reset();
    scene_->scalarBar->VisibilityOff();
    render();
}

void CloudView::resetCamera()
{
    scene_->renderer->ResetCamera();
    render();
}

void CloudView::zoomToEntity(EntityId id)
{
    const auto it = scene_->shown.find(id);
    if (it == scene_->shown.end())
        return;
    scene_->renderer->ResetCamera(it->second.actor->GetBounds());
    render();
}

void CloudView::setStandardView(StandardView view)
{
    // Direction from the focal point to the camera, and the up vector.
    Eigen::Vector3d eye, up(0, 0, 1);
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
    scene_->pointSize = size;
    for (auto& [id, s] : scene_->shown)
        if (s.isCloud)
            s.actor->GetProperty()->SetPointSize(size);
    render();
}

float CloudView::pointSize() const { return scene_->pointSize; }

void CloudView::setParallelProjection(bool parallel)
{
    scene_->renderer->GetActiveCamera()->SetParallelProjection(parallel);
    scene_->renderer->ResetCameraClippingRange();
    render();
}

bool CloudView::parallelProjection() const { return scene_->renderer->GetActiveCamera()->GetParallelProjection() != 0; }

CameraState CloudView::camera() const
{
    vtkCamera* c = scene_->renderer->GetActiveCamera();
    CameraState s;
    c->GetPosition(s.position.data());
    c->GetFocalPoint(s.focalPoint.data());
    c->GetViewUp(s.viewUp.data());
    s.viewAngle = c->GetViewAngle();
    s.parallel = c->GetParallelProjection() != 0;
    s.parallelScale = c->GetParallelScale();
    return s;
}

void CloudView::setCamera(const CameraState& s)
{
    vtkCamera* c = scene_->renderer->GetActiveCamera();
    c->SetPosition(s.position.data());
    c->SetFocalPoint(s.focalPoint.data());
    c->SetViewUp(s.viewUp.data());
    c->SetViewAngle(s.viewAngle);
    c->SetParallelProjection(s.parallel);
    c->SetParallelScale(s.parallelScale);
    scene_->renderer->ResetCameraClippingRange();
    render();
}

void CloudView::setInteractiveBudget(std::size_t points)
{
    scene_->budget = std::max<std::size_t>(points, 1);
    updateStride();
}

std::size_t CloudView::interactiveStride() const { return scene_->stride; }

void CloudView::updateStride()
{
    std::size_t total = 0;
    for (const auto& [id, s] : scene_->shown)
        if (s.isCloud)
            total += s.pointCount;
    scene_->stride = std::max<std::size_t>(1, (total + scene_->budget - 1) / scene_->budget);
}

void CloudView::setMoving(bool moving)
{
    scene_->moving = moving;
    for (auto& [id, s] : scene_->shown) {
        if (!s.isCloud)
            continue;
        const bool decimate = moving && scene_->stride > 1;
        if (decimate && s.decimatedStride != scene_->stride) {
            s.decimated = vtkSmartPointer<vtkPolyData>::New();
            s.decimated->SetPoints(s.full->GetPoints());
            s.decimated->GetPointData()->SetScalars(s.colours);
            s.decimated->SetVerts(vertexCells(s.pointCount, scene_->stride));
            s.decimatedMapper = vtkSmartPointer<vtkPolyDataMapper>::New();
            s.decimatedMapper->SetInputData(s.decimated);
            s.decimatedMapper->SetColorModeToDirectScalars();
            s.decimatedMapper->ScalarVisibilityOn();
            s.decimatedStride = scene_->stride;
        }
        s.actor->SetMapper(decimate ? s.decimatedMapper.Get() : s.fullMapper.Get());
    }
    if (!moving)
        render(); // full detail at rest
}

void CloudView::setPickMode(bool on)
{
    if (scene_->pickMode == on)
        return;
    scene_->pickMode = on;
    widget_->setCursor(on ? Qt::CrossCursor : Qt::ArrowCursor);
    emit pickModeChanged(on);
}

bool CloudView::pickMode() const { return scene_->pickMode; }

bool CloudView::pickAt(int x, int y)
{
    // VTK counts pixels from the bottom-left, in device pixels.
    const double ratio = widget_->devicePixelRatioF();
    const int height = scene_->window->GetSize()[1];
    return pickAtDevicePixel(static_cast<int>(x * ratio), static_cast<int>(height - 1 - y * ratio));
}

bool CloudView::pickAtDevicePixel(int x, int y)
{
    if (!scene_->picker->Pick(x, y, 0.0, scene_->renderer))
        return false;
    vtkActor* actor = scene_->picker->GetActor();
    const vtkIdType point = scene_->picker->GetPointId();
    for (const auto& [id, s] : scene_->shown)
        if (s.actor.Get() == actor && point >= 0) {
            emit pointPicked(id, static_cast<std::size_t>(point));
            return true;
        }
    return false;
}

void CloudView::render() { scene_->window->Render(); }

bool CloudView::saveScreenshot(const QString& path)
{
    scene_->window->Render();
    vtkNew<vtkWindowToImageFilter> grab;
    grab->SetInput(scene_->window);
    grab->ReadFrontBufferOff();
    grab->Update();
    vtkNew<vtkPNGWriter> writer;
    writer->SetFileName(path.toStdString().c_str());
    writer->SetInputConnection(grab->GetOutputPort());
    writer->Write();
    return writer->GetErrorCode() == 0;
}

} // namespace scandiff::gui
