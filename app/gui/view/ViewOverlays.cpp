// SPDX-License-Identifier: GPL-3.0-or-later
// What the view draws over the clouds: the colour bar, the measurements and
// their labels, the scale bar (CloudView's members; see CloudView.cpp).
#include "view/CloudView.h"
#include "view/CloudViewScene.h"

#include <QString>

#include <vtkActor2D.h>
#include <vtkBillboardTextActor3D.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkCoordinate.h>
#include <vtkLookupTable.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkPolyDataMapper2D.h>
#include <vtkProperty.h>
#include <vtkProperty2D.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cmath>

namespace scandiff::gui {

void CloudView::setLegend(const ColourLegend& legend)
{
    legend_ = legend;
    if (!legend.shown) {
        scene_->scalarBar->VisibilityOff();
        renderSoon();
        return;
    }
    vtkLookupTable* table = scene_->scalarBarTable;
    table->ResetAnnotations();
    if (!legend.categories.empty()) {
        // Labels: one swatch per value present, named by the value.
        table->IndexedLookupOn();
        table->SetNumberOfTableValues(static_cast<vtkIdType>(legend.categories.size()));
        for (std::size_t i = 0; i < legend.categories.size(); ++i) {
            const auto& [value, c] = legend.categories[i];
            table->SetTableValue(static_cast<vtkIdType>(i), c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, 1.0);
            table->SetAnnotation(vtkVariant(value), std::to_string(value));
        }
        scene_->scalarBar->SetTitle(wrappedTitle(legend.title).c_str());
        scene_->scalarBar->VisibilityOn();
        renderSoon();
        return;
    }
    table->IndexedLookupOff();
    constexpr int kColours = 256;
    scene_->scalarBarTable->SetNumberOfTableValues(kColours);
    for (int i = 0; i < kColours; ++i) {
        const auto c = legend.scale.colourAt(i / double(kColours - 1));
        scene_->scalarBarTable->SetTableValue(i, c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, 1.0);
    }
    scene_->scalarBarTable->SetTableRange(legend.min, legend.max);
    scene_->scalarBar->SetTitle(wrappedTitle(legend.title).c_str());
    scene_->scalarBar->VisibilityOn();
    renderSoon();
}

void CloudView::setAnnotations(const std::vector<Annotation>& annotations)
{
    annotations_ = annotations; // kept global: redrawn if the scene's origin changes
    for (auto& label : scene_->labels)
        scene_->renderer->RemoveActor(label);
    scene_->labels.clear();
    annotationCount_ = annotations.size();
    const Eigen::Vector3d origin = scene_->sceneOrigin.value_or(Eigen::Vector3d::Zero());
    vtkNew<vtkPoints> points;
    vtkNew<vtkCellArray> lines, marks;
    for (const Annotation& a : annotations) {
        if (a.points.empty())
            continue;
        std::vector<vtkIdType> ids;
        for (const Eigen::Vector3d& p : a.points) {
            const Eigen::Vector3d local = p - origin; // in double, then small
            ids.push_back(points->InsertNextPoint(local.x(), local.y(), local.z()));
            marks->InsertNextCell(1, &ids.back());
        }
        if (a.closed && ids.size() > 2)
            ids.push_back(ids.front());
        if (ids.size() > 1)
            lines->InsertNextCell(static_cast<vtkIdType>(ids.size()), ids.data());
        if (!a.label.empty()) {
            auto label = vtkSmartPointer<vtkBillboardTextActor3D>::New();
            label->SetInput(a.label.c_str());
            const Eigen::Vector3d at = a.points.back() - origin;
            label->SetPosition(at.x(), at.y(), at.z());
            label->SetDisplayOffset(10, 10);
            label->GetTextProperty()->SetFontSize(14);
            label->GetTextProperty()->SetColor(1.0, 1.0, 0.6);
            label->GetTextProperty()->SetBackgroundColor(0.1, 0.1, 0.1);
            label->GetTextProperty()->SetBackgroundOpacity(0.7);
            label->PickableOff();
            scene_->renderer->AddActor(label);
            scene_->labels.push_back(label);
        }
    }
    scene_->annotations->SetPoints(points);
    scene_->annotations->SetLines(lines);
    scene_->annotations->SetVerts(marks);
    if (!scene_->annotationActor->GetMapper()) {
        vtkNew<vtkPolyDataMapper> mapper;
        mapper->SetInputData(scene_->annotations);
        // Drawn over the points they measure, not hidden among them.
        mapper->SetRelativeCoincidentTopologyLineOffsetParameters(0, -66000);
        mapper->SetRelativeCoincidentTopologyPointOffsetParameter(-66000);
        scene_->annotationActor->SetMapper(mapper);
        scene_->annotationActor->GetProperty()->SetColor(1.0, 0.2, 0.8);
        scene_->annotationActor->GetProperty()->SetLineWidth(2.5f);
        scene_->annotationActor->GetProperty()->SetPointSize(9.0f);
        scene_->annotationActor->GetProperty()->RenderPointsAsSpheresOn();
        scene_->annotationActor->PickableOff(); // a click on a measured point picks the cloud's point
        scene_->annotationActor->UseBoundsOff(); // nor does it count for "zoom to all"
        scene_->renderer->AddActor(scene_->annotationActor);
    }
    scene_->annotations->Modified();
    resetClippingRange();
    renderSoon();
}

void CloudView::setScaleBar(bool on)
{
    scene_->scaleBarShown = on;
    render();
}

bool CloudView::scaleBar() const { return scene_->scaleBarShown; }

double CloudView::metresPerPixel() const
{
    vtkCamera* camera = scene_->renderer->GetActiveCamera();
    const int* size = scene_->renderer->GetSize();
    const double height = std::max(1, size[1]);
    if (camera->GetParallelProjection())
        return 2.0 * camera->GetParallelScale() / height;
    const double halfAngle = camera->GetViewAngle() * 3.14159265358979323846 / 360.0;
    return 2.0 * camera->GetDistance() * std::tan(halfAngle) / height;
}

double CloudView::scaleBarLength() const
{
    // The round length nearest below a fifth of the view's width.
    const double target = metresPerPixel() * std::max(1, scene_->renderer->GetSize()[0]) / 5.0;
    if (!(target > 0) || !std::isfinite(target))
        return 0.0;
    const double decade = std::pow(10.0, std::floor(std::log10(target)));
    for (double step : {5.0, 2.0, 1.0})
        if (step * decade <= target)
            return step * decade;
    return decade;
}

void CloudView::updateScaleBar()
{
    const double length = scene_->scaleBarShown && !scene_->shown.empty() ? scaleBarLength() : 0.0;
    scene_->scaleBarActor->SetVisibility(length > 0);
    scene_->scaleBarText->SetVisibility(length > 0);
    if (!(length > 0))
        return;
    const double pixels = length / metresPerPixel();
    const int* size = scene_->renderer->GetSize();
    const double right = size[0] - 110.0, left = right - pixels, y = 18.0; // bottom right, clear of the colour bar
    vtkNew<vtkPoints> points;
    for (const auto& [x, dy] : std::vector<std::pair<double, double>>{{left, 5}, {left, 0}, {right, 0}, {right, 5}})
        points->InsertNextPoint(x, y + dy, 0);
    vtkNew<vtkCellArray> line;
    const vtkIdType ids[4] = {0, 1, 2, 3};
    line->InsertNextCell(4, ids);
    scene_->scaleBarLine->SetPoints(points);
    scene_->scaleBarLine->SetLines(line);
    const QString text = length >= 1000 ? QString("%1 km").arg(length / 1000) : length >= 1 ? QString("%1 m").arg(length)
                         : length >= 0.01                                      ? QString("%1 cm").arg(length * 100)
                                                                               : QString("%1 mm").arg(length * 1000);
    scene_->scaleBarText->SetInput(text.toUtf8().constData());
    scene_->scaleBarText->SetPosition((left + right) / 2, y + 8);
}

} // namespace scandiff::gui
