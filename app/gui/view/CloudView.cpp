// SPDX-License-Identifier: GPL-3.0-or-later
#include "view/CloudView.h"

#include <QVBoxLayout>
#include <QVTKOpenGLNativeWidget.h>

#include <vtkActor.h>
#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkIdTypeArray.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <optional>
#include <vector>

namespace scandiff::gui {

struct CloudView::Scene
{
    vtkNew<vtkGenericOpenGLRenderWindow> window;
    vtkNew<vtkRenderer> renderer;
    std::vector<vtkSmartPointer<vtkActor>> actors;
    std::optional<Eigen::Vector3d> sceneOrigin;
    float pointSize = 2.0f;
};

namespace {

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

//! Colours, else first scalar field, else height: what a user expects to see first.
void colourPoints(const PointCloud& cloud, vtkPolyData* data, vtkPolyDataMapper* mapper)
{
    if (cloud.hasColors()) {
        vtkNew<vtkUnsignedCharArray> colours;
        colours->SetNumberOfComponents(3);
        colours->SetNumberOfTuples(static_cast<vtkIdType>(cloud.size()));
        auto* raw = colours->GetPointer(0);
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            raw[3 * i] = cloud.colors()[i].r;
            raw[3 * i + 1] = cloud.colors()[i].g;
            raw[3 * i + 2] = cloud.colors()[i].b;
        }
        colours->SetName("rgb");
        data->GetPointData()->SetScalars(colours);
        mapper->SetColorModeToDirectScalars();
        mapper->ScalarVisibilityOn();
        return;
    }
    vtkNew<vtkFloatArray> values;
    values->SetNumberOfTuples(static_cast<vtkIdType>(cloud.size()));
    double lo = 0, hi = 1;
    if (!cloud.fields().empty()) {
        const ScalarField& field = cloud.fields().front();
        for (std::size_t i = 0; i < cloud.size(); ++i)
            values->SetValue(static_cast<vtkIdType>(i), field.values()[i]);
        const ValueRange r = field.range();
        if (r.validCount > 0) {
            lo = r.min - field.offset();
            hi = r.max - field.offset();
        }
        values->SetName(field.name().c_str());
    } else {
        float zmin = std::numeric_limits<float>::max(), zmax = -zmin;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            const float z = cloud.positions()[i].z();
            values->SetValue(static_cast<vtkIdType>(i), z);
            zmin = std::min(zmin, z);
            zmax = std::max(zmax, z);
        }
        if (zmin <= zmax) {
            lo = zmin;
            hi = zmax;
        }
        values->SetName("height");
    }
    data->GetPointData()->SetScalars(values);
    vtkNew<vtkLookupTable> table;
    table->SetHueRange(0.667, 0.0); // blue -> red, the usual distance scale
    table->SetNanColor(0.6, 0.6, 0.6, 1.0);
    table->Build();
    mapper->SetLookupTable(table);
    mapper->SetScalarRange(lo, hi > lo ? hi : lo + 1);
    mapper->ScalarVisibilityOn();
}

} // namespace

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
}

CloudView::~CloudView() = default;

void CloudView::addCloud(const PointCloud& cloud)
{
    if (!scene_->sceneOrigin)
        scene_->sceneOrigin = cloud.origin();
    vtkNew<vtkPolyData> data;
    data->SetPoints(toVtkPoints(cloud, *scene_->sceneOrigin));
    // One vertex cell per point, built as two flat arrays (no per-point InsertNextCell).
    const auto n = static_cast<vtkIdType>(cloud.size());
    vtkNew<vtkIdTypeArray> offsets;
    vtkNew<vtkIdTypeArray> connectivity;
    offsets->SetNumberOfValues(n + 1);
    connectivity->SetNumberOfValues(n);
    for (vtkIdType i = 0; i < n; ++i) {
        offsets->SetValue(i, i);
        connectivity->SetValue(i, i);
    }
    offsets->SetValue(n, n);
    vtkNew<vtkCellArray> vertices;
    vertices->SetData(offsets, connectivity);
    data->SetVerts(vertices);
    vtkNew<vtkPolyDataMapper> mapper;
    mapper->SetInputData(data);
    colourPoints(cloud, data, mapper);
    auto actor = vtkSmartPointer<vtkActor>::New();
    actor->SetMapper(mapper);
    actor->GetProperty()->SetPointSize(scene_->pointSize);
    scene_->renderer->AddActor(actor);
    scene_->actors.push_back(actor);
}

void CloudView::addMesh(const Mesh& mesh)
{
    if (!scene_->sceneOrigin)
        scene_->sceneOrigin = mesh.vertices.origin();
    vtkNew<vtkPolyData> data;
    data->SetPoints(toVtkPoints(mesh.vertices, *scene_->sceneOrigin));
    vtkNew<vtkCellArray> polys;
    for (const auto& t : mesh.triangles) {
        const vtkIdType ids[3] = {t[0], t[1], t[2]};
        polys->InsertNextCell(3, ids);
    }
    data->SetPolys(polys);
    vtkNew<vtkPolyDataMapper> mapper;
    mapper->SetInputData(data);
    mapper->ScalarVisibilityOff();
    auto actor = vtkSmartPointer<vtkActor>::New();
    actor->SetMapper(mapper);
    actor->GetProperty()->SetColor(0.85, 0.85, 0.8);
    scene_->renderer->AddActor(actor);
    scene_->actors.push_back(actor);
}

void CloudView::clear()
{
    for (auto& actor : scene_->actors)
        scene_->renderer->RemoveActor(actor);
    scene_->actors.clear();
    scene_->sceneOrigin.reset();
    scene_->window->Render();
}

void CloudView::resetCamera()
{
    scene_->renderer->ResetCamera();
    scene_->window->Render();
}

void CloudView::setPointSize(float size)
{
    scene_->pointSize = size;
    for (auto& actor : scene_->actors)
        actor->GetProperty()->SetPointSize(size);
    scene_->window->Render();
}

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
