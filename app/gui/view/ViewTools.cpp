// SPDX-License-Identifier: GPL-3.0-or-later
// The tools that work in the view itself: the clipping box, the scissors'
// polygon and point picking (CloudView's members; the rest of the view is
// CloudView.cpp, its refinement ViewRefinement.cpp, moving entities ViewMoving.cpp).
#include "view/CloudView.h"
#include "view/ChunkGeometry.h"
#include "view/CloudViewScene.h"

#include <QVTKOpenGLNativeWidget.h>

#include <vtkActor2D.h>
#include <vtkBoxRepresentation.h>
#include <vtkBoxWidget2.h>
#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkCellPicker.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkMatrix4x4.h>
#include <vtkPlane.h>
#include <vtkPlaneCollection.h>
#include <vtkPlanes.h>
#include <vtkPointPicker.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkPolyDataMapper2D.h>
#include <vtkProperty2D.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkTransform.h>

#include <algorithm>
#include <limits>

namespace scandiff::gui {

void CloudView::setClippingBox(bool on)
{
    if (on == scene_->clipping)
        return;
    scene_->clipping = on;
    if (on) {
        if (!scene_->clipWidget->GetInteractor()) { // first use (GetRepresentation would make a default one)
            scene_->clipBox->SetPlaceFactor(1.0);
            scene_->clipBox->HandlesOn();
            scene_->clipWidget->SetInteractor(widget_->interactor());
            scene_->clipWidget->SetDefaultRenderer(scene_->renderer);
            scene_->clipWidget->SetRepresentation(scene_->clipBox);
            auto moved = vtkSmartPointer<vtkCallbackCommand>::New();
            moved->SetClientData(this);
            moved->SetCallback([](vtkObject*, unsigned long, void* self, void*) { static_cast<CloudView*>(self)->applyClipping(); });
            scene_->clipWidget->AddObserver(vtkCommand::InteractionEvent, moved);
            // Dragging the box is a move like the camera's: decimated while it
            // lasts, refined at rest (the widget's own frames draw what is set).
            auto dragged = vtkSmartPointer<vtkCallbackCommand>::New();
            dragged->SetClientData(this);
            dragged->SetCallback([](vtkObject*, unsigned long event, void* self, void*) {
                static_cast<CloudView*>(self)->setMoving(event == vtkCommand::StartInteractionEvent);
            });
            scene_->clipWidget->AddObserver(vtkCommand::StartInteractionEvent, dragged);
            scene_->clipWidget->AddObserver(vtkCommand::EndInteractionEvent, dragged);
        }
        // Around what is shown.
        double bounds[6];
        scene_->renderer->ComputeVisiblePropBounds(bounds);
        if (bounds[0] <= bounds[1])
            scene_->clipBox->PlaceWidget(bounds);
        scene_->clipWidget->On();
    } else {
        scene_->clipWidget->Off();
    }
    applyClipping();
    emit clippingBoxChanged(on);
}

bool CloudView::clippingBoxOn() const { return scene_->clipping; }

void CloudView::setClippingBox(const CropBox& box)
{
    // The representation is placed axis-aligned, then turned and moved by its transform.
    const Eigen::Vector3d origin = scene_->sceneOrigin.value_or(Eigen::Vector3d::Zero());
    const Eigen::Vector3d half = box.size / 2;
    double bounds[6] = {-half.x(), half.x(), -half.y(), half.y(), -half.z(), half.z()};
    scene_->clipBox->PlaceWidget(bounds);
    vtkNew<vtkTransform> transform;
    vtkNew<vtkMatrix4x4> matrix;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c)
            matrix->SetElement(r, c, box.rotation(r, c));
        matrix->SetElement(r, 3, box.centre[r] - origin[r]);
    }
    transform->SetMatrix(matrix);
    scene_->clipBox->SetTransform(transform);
    applyClipping();
}

CropBox CloudView::clippingBox() const
{
    // The box's corners in the scene: an axis-aligned box turned and moved, so
    // its centre and edges give back the centre, the sizes and the rotation.
    vtkPolyData* outline = vtkPolyData::New();
    scene_->clipBox->GetPolyData(outline); // 8 corners first, then face centres and the middle
    auto corner = [&](int i) {
        double p[3];
        outline->GetPoint(i, p);
        return Eigen::Vector3d(p[0], p[1], p[2]);
    };
    // vtkBoxRepresentation numbers its corners as a hexahedron: 0-1 along x, 0-3 along y, 0-4 along z.
    const Eigen::Vector3d c0 = corner(0), ex = corner(1) - c0, ey = corner(3) - c0, ez = corner(4) - c0;
    outline->Delete();
    CropBox box;
    box.size = {ex.norm(), ey.norm(), ez.norm()};
    box.centre = c0 + (ex + ey + ez) / 2 + scene_->sceneOrigin.value_or(Eigen::Vector3d::Zero());
    for (int a = 0; a < 3; ++a) {
        const Eigen::Vector3d edge = a == 0 ? ex : a == 1 ? ey : ez;
        box.rotation.col(a) = edge.norm() > 0 ? Eigen::Vector3d(edge.normalized()) : Eigen::Vector3d::Unit(a);
    }
    return box;
}

void CloudView::applyClipping()
{
    vtkNew<vtkPlanes> planes;
    if (scene_->clipping)
        scene_->clipBox->GetPlanes(planes);
    for (auto& [id, s] : scene_->shown)
        for (auto& c : s.chunks)
            for (vtkPolyDataMapper* mapper : {c.fullMapper.Get(), c.decimatedMapper.Get()}) {
                if (!mapper)
                    continue;
                // The planes are in the scene's frame; a chunk's points sit at its actor's offset.
                mapper->RemoveAllClippingPlanes();
                if (!scene_->clipping)
                    continue;
                double offset[3];
                c.actor->GetPosition(offset);
                for (int k = 0; k < planes->GetNumberOfPlanes(); ++k) {
                    vtkPlane* plane = planes->GetPlane(k);
                    double origin[3], normal[3];
                    plane->GetOrigin(origin);
                    plane->GetNormal(normal);
                    vtkNew<vtkPlane> local;
                    local->SetOrigin(origin[0] - offset[0], origin[1] - offset[1], origin[2] - offset[2]);
                    // The box's faces face outwards; a mapper keeps the side a plane faces.
                    local->SetNormal(-normal[0], -normal[1], -normal[2]);
                    mapper->AddClippingPlane(local);
                }
            }
    render();
}

void CloudView::setScissorsMode(bool on)
{
    if (scene_->scissorsMode == on)
        return;
    scene_->scissorsMode = on;
    scene_->scissors.clear();
    addScissorsVertex(std::numeric_limits<double>::quiet_NaN(), 0); // redraws the (empty) outline
    if (on)
        setPickMode(false);
    widget_->setCursor(on ? Qt::CrossCursor : Qt::ArrowCursor);
    emit scissorsModeChanged(on);
}

bool CloudView::scissorsMode() const { return scene_->scissorsMode; }

void CloudView::addScissorsVertex(double x, double y)
{
    if (std::isfinite(x))
        scene_->scissors.emplace_back(x, y);
    // The outline in VTK's display pixels (device pixels from the bottom-left),
    // closed back to the first vertex so the user sees what will be cut.
    const double ratio = widget_->devicePixelRatioF();
    const int height = scene_->window->GetSize()[1];
    vtkNew<vtkPoints> points;
    vtkNew<vtkCellArray> lines;
    std::vector<vtkIdType> ids;
    for (const Eigen::Vector2d& v : scene_->scissors)
        ids.push_back(points->InsertNextPoint(v.x() * ratio, height - 1 - v.y() * ratio, 0));
    if (ids.size() > 2)
        ids.push_back(ids.front());
    if (ids.size() > 1)
        lines->InsertNextCell(static_cast<vtkIdType>(ids.size()), ids.data());
    scene_->scissorsOutline->SetPoints(points);
    scene_->scissorsOutline->SetLines(lines);
    scene_->scissorsOutline->Modified();
    renderSoon();
}

void CloudView::finishScissors()
{
    if (!scene_->scissorsMode)
        return;
    const std::vector<Eigen::Vector2d> polygon = scene_->scissors;
    setScissorsMode(false);
    if (polygon.size() >= 3)
        emit polygonDrawn(polygon, globalToWidgetPixels());
}

Eigen::Matrix4d CloudView::globalToWidgetPixels() const
{
    vtkCamera* camera = scene_->renderer->GetActiveCamera();
    const double width = std::max(1, widget_->width()), height = std::max(1, widget_->height());
    vtkMatrix4x4* clip = camera->GetCompositeProjectionTransformMatrix(width / height, -1, 1);
    Eigen::Matrix4d sceneToClip;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            sceneToClip(r, c) = clip->GetElement(r, c);
    // Clip coordinates to pixels, still homogeneous: x from -1..1 to 0..width,
    // y from 1..-1 (up) to 0..height (down).
    Eigen::Matrix4d toPixels = Eigen::Matrix4d::Identity();
    toPixels(0, 0) = width / 2, toPixels(0, 3) = width / 2;
    toPixels(1, 1) = -height / 2, toPixels(1, 3) = height / 2;
    Eigen::Matrix4d fromGlobal = Eigen::Matrix4d::Identity();
    fromGlobal.block<3, 1>(0, 3) = -scene_->sceneOrigin.value_or(Eigen::Vector3d::Zero());
    return toPixels * sceneToClip * fromGlobal;
}

bool CloudView::isPointShown(EntityId id, std::size_t index) const
{
    const auto it = scene_->shown.find(id);
    if (it == scene_->shown.end() || !it->second.isCloud || index >= it->second.pointCount)
        return false;
    it->second.settleColours();
    return it->second.rgba[4 * index + 3] != 0;
}

void CloudView::setPickMode(bool on)
{
    if (on)
        setScissorsMode(false); // one use of the left click at a time
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
    // Points by the point picker; a grid's cells (drawn as quads, whose
    // vertices are corners shared by four cells) by the cell picker, when the
    // point picker finds nothing else.
    Shown* pickedEntity = nullptr;
    EntityId pickedId = kNoEntity;
    std::size_t index = 0;
    auto chunkOf = [&](vtkActor* actor, bool& raster, std::size_t& begin) {
        for (auto& [id, s] : scene_->shown)
            for (const auto& c : s.chunks)
                if (c.actor.Get() == actor) {
                    pickedEntity = &s;
                    pickedId = id;
                    raster = c.raster;
                    begin = c.begin;
                    return true;
                }
        return false;
    };
    bool raster = false;
    std::size_t begin = 0;
    // Among every point of a chunk, not the few its decimated copy draws:
    // the picker reads the points of the actor's mapper.
    std::vector<std::pair<vtkActor*, vtkMapper*>> drawing;
    for (auto& [id, s] : scene_->shown)
        for (auto& c : s.chunks)
            if (s.isCloud && !c.raster && c.actor->GetMapper() != c.fullMapper.Get()) {
                if (!c.pickMapper) {
                    c.pickMapper = vtkSmartPointer<vtkPolyDataMapper>::New();
                    c.pickMapper->SetInputData(pickingGeometry(c.full->GetPoints()));
                }
                drawing.emplace_back(c.actor.Get(), c.actor->GetMapper());
                c.actor->SetMapper(c.pickMapper);
            }
    const bool pointHit = scene_->picker->Pick(x, y, 0.0, scene_->renderer) && scene_->picker->GetPointId() >= 0 &&
                          chunkOf(scene_->picker->GetActor(), raster, begin) && !raster;
    for (auto& [actor, mapper] : drawing)
        actor->SetMapper(mapper);
    if (pointHit) {
        index = begin + static_cast<std::size_t>(scene_->picker->GetPointId());
    } else {
        if (!scene_->cellPicker->Pick(x, y, 0.0, scene_->renderer) || scene_->cellPicker->GetCellId() < 0 ||
            !chunkOf(scene_->cellPicker->GetActor(), raster, begin) || !raster)
            return false;
        index = begin + static_cast<std::size_t>(scene_->cellPicker->GetCellId());
    }
    // The picker sees every point; one hidden by the thresholds is not an answer.
    if (pickedEntity->isCloud)
        pickedEntity->settleColours();
    if (pickedEntity->isCloud && pickedEntity->rgba[4 * index + 3] == 0)
        return false;
    emit pointPicked(pickedId, index);
    return true;
}

} // namespace scandiff::gui
