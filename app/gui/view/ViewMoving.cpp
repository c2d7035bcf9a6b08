// SPDX-License-Identifier: GPL-3.0-or-later
// Move / rotate in the view (CloudView::startMovingEntities): a box widget
// around the entities, their actors drawn through its transform until the
// motion is applied to the data (by the transform tool) or dropped.
#include "view/CloudView.h"
#include "view/CloudViewScene.h"

#include <QVTKOpenGLNativeWidget.h>

#include <vtkCallbackCommand.h>
#include <vtkMatrix4x4.h>
#include <vtkTransform.h>
#include <vtkEvent.h>
#include <vtkWidgetEvent.h>
#include <vtkWidgetEventTranslator.h>

#include <algorithm>
#include <limits>

namespace scandiff::gui {

namespace {

// Global motion <-> the box's transform in the scene's frame (whose origin is
// `origin` in global coordinates): B = T(-origin) M T(origin).
Eigen::Matrix4d toScene(const Eigen::Matrix4d& global, const Eigen::Vector3d& origin)
{
    Eigen::Matrix4d shift = Eigen::Matrix4d::Identity(), back = Eigen::Matrix4d::Identity();
    shift.topRightCorner<3, 1>() = -origin;
    back.topRightCorner<3, 1>() = origin;
    return shift * global * back;
}

vtkSmartPointer<vtkMatrix4x4> vtkMatrixOf(const Eigen::Matrix4d& m)
{
    auto matrix = vtkSmartPointer<vtkMatrix4x4>::New();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            matrix->SetElement(r, c, m(r, c));
    return matrix;
}

} // namespace

void CloudView::startMovingEntities(const std::vector<EntityId>& ids)
{
    stopMovingEntities();
    const Eigen::Vector3d origin = scene_->sceneOrigin.value_or(Eigen::Vector3d::Zero());
    double bounds[6] = {std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
                        std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
                        std::numeric_limits<double>::max(), -std::numeric_limits<double>::max()};
    for (EntityId id : ids) {
        const auto it = scene_->shown.find(id);
        if (it == scene_->shown.end())
            continue;
        scene_->movingIds.push_back(id);
        for (const auto& chunk : it->second.chunks) {
            const double* b = chunk.actor->GetBounds(); // the scene's frame, its position included
            for (int a = 0; a < 3; ++a) {
                bounds[2 * a] = std::min(bounds[2 * a], b[2 * a]);
                bounds[2 * a + 1] = std::max(bounds[2 * a + 1], b[2 * a + 1]);
            }
        }
    }
    if (scene_->movingIds.empty() || !(bounds[0] <= bounds[1]))
        return;
    scene_->movingCentre = origin + Eigen::Vector3d((bounds[0] + bounds[1]) / 2, (bounds[2] + bounds[3]) / 2, (bounds[4] + bounds[5]) / 2);
    scene_->movedBy.setIdentity();
    if (!scene_->moveWidget->GetInteractor()) { // first use
        scene_->moveBox->SetPlaceFactor(1.0);
        scene_->moveBox->HandlesOff(); // no faces to pull: the box only moves and turns
        scene_->moveWidget->SetInteractor(widget_->interactor());
        scene_->moveWidget->SetDefaultRenderer(scene_->renderer);
        scene_->moveWidget->SetRepresentation(scene_->moveBox);
        scene_->moveWidget->ScalingEnabledOff();
        scene_->moveWidget->MoveFacesEnabledOff();
        // VTK moves the box with the middle button; Shift + left does too, for
        // a touchpad (a left drag on a face turns it).
        vtkWidgetEventTranslator* keys = scene_->moveWidget->GetEventTranslator();
        keys->SetTranslation(vtkCommand::LeftButtonPressEvent, vtkEvent::ShiftModifier, 0, 0, nullptr, vtkWidgetEvent::Translate);
        keys->SetTranslation(vtkCommand::LeftButtonReleaseEvent, vtkEvent::ShiftModifier, 0, 0, nullptr, vtkWidgetEvent::EndTranslate);
        auto moved = vtkSmartPointer<vtkCallbackCommand>::New();
        moved->SetClientData(this);
        moved->SetCallback([](vtkObject*, unsigned long, void* self, void*) {
            auto* view = static_cast<CloudView*>(self);
            vtkNew<vtkTransform> transform;
            view->scene_->moveBox->GetTransform(transform);
            Eigen::Matrix4d box;
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c)
                    box(r, c) = transform->GetMatrix()->GetElement(r, c);
            const Eigen::Vector3d origin = view->scene_->sceneOrigin.value_or(Eigen::Vector3d::Zero());
            view->scene_->movedBy = toScene(box, -origin); // back to global: T(origin) B T(-origin)
            view->applyMovingPreview();
            emit view->movedByChanged(view->scene_->movedBy);
        });
        scene_->moveWidget->AddObserver(vtkCommand::InteractionEvent, moved);
        auto dragged = vtkSmartPointer<vtkCallbackCommand>::New();
        dragged->SetClientData(this);
        dragged->SetCallback([](vtkObject*, unsigned long event, void* self, void*) {
            static_cast<CloudView*>(self)->setMoving(event == vtkCommand::StartInteractionEvent);
        });
        scene_->moveWidget->AddObserver(vtkCommand::StartInteractionEvent, dragged);
        scene_->moveWidget->AddObserver(vtkCommand::EndInteractionEvent, dragged);
    }
    scene_->moveBox->PlaceWidget(bounds);
    scene_->moveWidget->On();
    applyMovingPreview();
}

void CloudView::setMovedBy(const Eigen::Matrix4d& global)
{
    if (scene_->movingIds.empty())
        return;
    scene_->movedBy = global;
    const Eigen::Vector3d origin = scene_->sceneOrigin.value_or(Eigen::Vector3d::Zero());
    vtkNew<vtkTransform> transform;
    transform->SetMatrix(vtkMatrixOf(toScene(global, origin)));
    scene_->moveBox->SetTransform(transform);
    applyMovingPreview();
}

Eigen::Matrix4d CloudView::movedBy() const { return scene_->movedBy; }

Eigen::Vector3d CloudView::movingCentre() const { return scene_->movingCentre; }

bool CloudView::movingEntities() const { return !scene_->movingIds.empty(); }

void CloudView::stopMovingEntities()
{
    if (scene_->movingIds.empty())
        return;
    scene_->movedBy.setIdentity();
    applyMovingPreview();
    scene_->movingIds.clear();
    scene_->moveWidget->Off();
    renderSoon();
}

void CloudView::applyMovingPreview()
{
    // An actor draws UserMatrix x (its position + its points): the motion in
    // the scene's frame, composed in double before the one float matrix.
    const Eigen::Vector3d origin = scene_->sceneOrigin.value_or(Eigen::Vector3d::Zero());
    const bool none = scene_->movedBy.isIdentity(0.0);
    const vtkSmartPointer<vtkMatrix4x4> matrix = none ? nullptr : vtkMatrixOf(toScene(scene_->movedBy, origin));
    for (EntityId id : scene_->movingIds) {
        const auto it = scene_->shown.find(id);
        if (it == scene_->shown.end())
            continue;
        for (auto& chunk : it->second.chunks)
            chunk.actor->SetUserMatrix(matrix);
    }
    renderInteractively();
}

} // namespace scandiff::gui
