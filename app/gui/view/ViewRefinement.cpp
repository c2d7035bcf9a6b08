// SPDX-License-Identifier: GPL-3.0-or-later
// The picture at rest drawn in slices of the frame budget (CloudView::Refinement),
// and the timed frames that measure the budget.
#include "view/ChunkGeometry.h"
#include "view/CloudView.h"
#include "view/CloudViewScene.h"

#include <QElapsedTimer>
#include <QTimer>

#include <vtkCellArray.h>
#include <vtkOpenGLPolyDataMapper.h>
#include <vtkOpenGLVertexBufferObject.h>
#include <vtkOpenGLVertexBufferObjectGroup.h>
#include <vtkPointData.h>
#include <vtkPlaneCollection.h>

#include <algorithm>

namespace scandiff::gui {

void CloudView::timedRender(std::size_t points)
{
    // Frames tell how many points this machine draws per second; a frame is
    // sized to stay near 20 per second (a GPU draws tens of millions of
    // points in that time, Mesa's software renderer about a hundred
    // thousand). The budget grows at most fourfold a frame: a frame of few
    // points measures the frame's fixed costs more than the points.
    QElapsedTimer clock;
    clock.start();
    scene_->window->Render();
    const double seconds = clock.nsecsElapsed() / 1e9;
    if (scene_->adaptiveBudget && points >= 50'000 && seconds > 0.005) {
        constexpr double kFrameSeconds = 0.05;
        const auto budget = static_cast<std::size_t>(points / seconds * kFrameSeconds);
        scene_->budget = std::clamp<std::size_t>(budget, 100'000, 4 * scene_->budget);
        updateStride();
    }
}

bool CloudView::frameScheduled() const { return scene_->interactiveRenderPending; }

std::size_t CloudView::pointsGivenToOpenGl() const
{
    std::size_t points = 0;
    for (const auto& [id, s] : scene_->shown)
        for (const auto& c : s.chunks)
            for (vtkPolyDataMapper* mapper : {c.fullMapper.Get(), c.decimatedMapper.Get(), c.sliceMapper.Get()}) {
                auto* openGl = vtkOpenGLPolyDataMapper::SafeDownCast(mapper);
                vtkOpenGLVertexBufferObject* vertices = openGl ? openGl->GetVBOs()->GetVBO("vertexMC") : nullptr;
                if (s.isCloud && !c.raster && vertices)
                    points += vertices->GetNumberOfTuples();
            }
    return points;
}

std::size_t CloudView::heldBytes() const
{
    std::size_t bytes = 0;
    for (const auto& [id, s] : scene_->shown) {
        bytes += s.rgba.capacity();
        for (const auto& c : s.chunks)
            for (vtkPolyData* copy : {c.decimated.Get(), c.slice.Get()})
                if (copy)
                    bytes += 1024 * copy->GetActualMemorySize(); // kibibytes
    }
    return bytes;
}

std::size_t CloudView::pointsAwaitingColour() const
{
    std::size_t points = 0;
    for (const auto& [id, s] : scene_->shown)
        if (s.pendingColours)
            points += s.pointCount;
    return points;
}

bool CloudView::refinesInSlices() const { return scene_->stride > 1 && !scene_->eyeDomeLighting; }

const CloudView::Refinement& CloudView::refinement() const { return scene_->refinement; }

void CloudView::stopRefinement()
{
    sliceTimer_->stop();
    scene_->refinement.refining = false;
}

void CloudView::startRefinement()
{
    stopRefinement();
    Refinement& r = scene_->refinement;
    r.slices = scene_->stride;
    r.slicesDrawn = 1;
    r.pointsDrawn = 0;
    ++r.starts;
    // Slice 0 is the decimated picture, drawn in full (background and all).
    for (auto& [id, s] : scene_->shown) {
        setDecimated(s, true);
        if (!s.isCloud)
            continue;
        for (const auto& c : s.chunks)
            if (c.actor->GetVisibility())
                r.pointsDrawn += c.raster ? c.count : everyStride(c.count, r.slices);
    }
    r.largestSlice = r.pointsDrawn;
    timedRender(r.pointsDrawn);
    r.refining = r.slices > 1;
    if (r.refining)
        sliceTimer_->start();
}

void CloudView::drawNextSlice()
{
    Refinement& r = scene_->refinement;
    if (!r.refining || scene_->moving)
        return;
    const std::size_t slice = r.slicesDrawn;
    const bool last = slice + 1 >= r.slices;
    // Only the slice's points are drawn over the picture: what else it shows
    // (meshes, grids, drawings, labels, the clipping box) is on it already,
    // and is drawn once more over the last slice, so that what stands in
    // front of the points (labels, the box) stays in front.
    std::vector<vtkProp*> resting;
    const auto rest = [&](vtkProp* prop) {
        if (!last && prop->GetVisibility()) {
            prop->VisibilityOff();
            resting.push_back(prop);
        }
    };
    std::size_t points = 0;
    for (auto& [id, s] : scene_->shown) {
        for (auto& c : s.chunks) {
            if (!c.actor->GetVisibility())
                continue;
            if (!s.isCloud || c.raster) {
                rest(c.actor);
                continue;
            }
            if (!c.slice) {
                c.slice = vtkSmartPointer<vtkPolyData>::New();
                c.sliceMapper = chunkMapper(c.slice);
            }
            c.sliceMapper->SetClippingPlanes(c.fullMapper->GetClippingPlanes());
            s.colourForGather(c, r.slices, slice);
            gatherPoints(*c.slice, c.arrays(s), r.slices, slice);
            points += everyStride(c.count, r.slices, slice);
            c.actor->SetMapper(c.sliceMapper);
        }
        if (s.labels)
            rest(s.labels);
    }
    rest(scene_->annotationActor);
    for (const auto& label : scene_->labels)
        rest(label);
    if (scene_->clipping)
        rest(scene_->clipBox);
    // The overlays (colour and scale bars) once more over the last slice only:
    // drawn over themselves at each slice, their texts would thicken.
    scene_->overlay->SetDraw(last);
    scene_->renderer->PreserveColorBufferOn();
    scene_->renderer->PreserveDepthBufferOn();
    timedRender(points);
    scene_->renderer->PreserveColorBufferOff();
    scene_->renderer->PreserveDepthBufferOff();
    scene_->overlay->SetDraw(true);
    for (vtkProp* prop : resting)
        prop->VisibilityOn();
    for (auto& [id, s] : scene_->shown)
        for (auto& c : s.chunks)
            if (s.isCloud && !c.raster && c.decimatedMapper)
                c.actor->SetMapper(c.decimatedMapper);
    r.slicesDrawn = slice + 1;
    r.pointsDrawn += points;
    r.largestSlice = std::max(r.largestSlice, points);
    r.refining = !last;
    if (last) // every slice coloured its points: the colours are whole, but a hidden chunk's
        for (auto& [id, s] : scene_->shown) {
            if (!s.pendingColours)
                continue;
            for (const auto& c : s.chunks)
                if (!c.actor->GetVisibility())
                    s.colourForGather(c, 1);
            s.coloursComplete();
        }
    if (r.refining)
        sliceTimer_->start();
    else if (!refinesInSlices())
        renderSoon(); // the budget grew past the scene meanwhile: one full frame now
}

} // namespace scandiff::gui
