// SPDX-License-Identifier: GPL-3.0-or-later
#include "view/ChunkGeometry.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkOpenGLPolyDataMapper.h>
#include <vtkOpenGLVertexBufferObject.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkTypeInt32Array.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <array>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace scandiff::gui {

//! VTK points reading `count` xyz triples at `xyz` in place (no copy; VTK does not free them).
vtkSmartPointer<vtkPoints> pointsOver(const float* xyz, std::size_t count)
{
    auto points = vtkSmartPointer<vtkPoints>::New();
    points->SetDataTypeToFloat();
    vtkFloatArray::SafeDownCast(points->GetData())
        ->SetArray(const_cast<float*>(xyz), static_cast<vtkIdType>(3 * count), /*save: VTK does not free*/ 1);
    return points;
}

std::size_t everyStride(std::size_t count, std::size_t stride, std::size_t first)
{
    return first < count ? (count - first + stride - 1) / stride : 0;
}

vtkSmartPointer<vtkCellArray> vertexCells(std::size_t count, std::size_t stride, std::size_t first)
{
    const auto n = static_cast<vtkIdType>(everyStride(count, stride, first));
    vtkNew<vtkTypeInt32Array> offsets;
    vtkNew<vtkTypeInt32Array> connectivity;
    offsets->SetNumberOfValues(n + 1);
    connectivity->SetNumberOfValues(n);
    for (vtkIdType i = 0; i < n; ++i) {
        offsets->SetValue(i, static_cast<std::int32_t>(i));
        connectivity->SetValue(i, static_cast<std::int32_t>(static_cast<vtkIdType>(first) + i * static_cast<vtkIdType>(stride)));
    }
    offsets->SetValue(n, static_cast<std::int32_t>(n));
    auto cells = vtkSmartPointer<vtkCellArray>::New();
    cells->SetData(offsets, connectivity);
    return cells;
}

namespace {

//! `out`'s array named `name` with `components` per point, made when absent.
template <typename Array>
Array* ownArray(vtkDataSetAttributes& attributes, const char* name, int components)
{
    auto* array = Array::SafeDownCast(attributes.GetArray(name));
    if (!array) {
        auto made = vtkSmartPointer<Array>::New();
        made->SetName(name);
        made->SetNumberOfComponents(components);
        attributes.AddArray(made);
        array = made;
    }
    return array;
}

} // namespace

void gatherPoints(vtkPolyData& out, const ChunkArrays& chunk, std::size_t stride, std::size_t first)
{
    const std::size_t m = everyStride(chunk.count, stride, first);
    if (!out.GetPoints() || !vtkFloatArray::SafeDownCast(out.GetPoints()->GetData())) {
        auto points = vtkSmartPointer<vtkPoints>::New();
        points->SetDataTypeToFloat();
        out.SetPoints(points);
    }
    auto* positions = vtkFloatArray::SafeDownCast(out.GetPoints()->GetData());
    positions->SetNumberOfComponents(3);
    positions->SetNumberOfTuples(static_cast<vtkIdType>(m));
    float* p = positions->GetPointer(0);
    for (std::size_t k = 0; k < m; ++k)
        std::copy_n(chunk.xyz + 3 * (first + k * stride), 3, p + 3 * k);
    positions->Modified();
    out.GetPoints()->Modified();
    if (chunk.normals) {
        auto* normals = ownArray<vtkFloatArray>(*out.GetPointData(), "normals", 3);
        normals->SetNumberOfTuples(static_cast<vtkIdType>(m));
        float* n = normals->GetPointer(0);
        for (std::size_t k = 0; k < m; ++k)
            std::copy_n(chunk.normals + 3 * (first + k * stride), 3, n + 3 * k);
        normals->Modified();
        out.GetPointData()->SetNormals(normals);
    }
    gatherColours(out, chunk, stride, first);
    out.SetVerts(vertexCells(m, 1));
}

void gatherColours(vtkPolyData& out, const ChunkArrays& chunk, std::size_t stride, std::size_t first)
{
    const std::size_t m = everyStride(chunk.count, stride, first);
    auto* colours = ownArray<vtkUnsignedCharArray>(*out.GetPointData(), "display colours", 4);
    colours->SetNumberOfTuples(static_cast<vtkIdType>(m));
    std::uint8_t* c = colours->GetPointer(0);
    for (std::size_t k = 0; k < m; ++k)
        std::copy_n(chunk.rgba + 4 * (first + k * stride), 4, c + 4 * k);
    colours->Modified();
    out.GetPointData()->SetScalars(colours);
}

vtkSmartPointer<vtkPolyData> pickingGeometry(vtkPoints* points)
{
    auto geometry = vtkSmartPointer<vtkPolyData>::New();
    geometry->SetPoints(points);
    const vtkIdType n = points->GetNumberOfPoints();
    std::array<vtkIdType, 6> extreme{};
    double low[3], high[3];
    for (int axis = 0; axis < 3; ++axis) {
        low[axis] = std::numeric_limits<double>::infinity();
        high[axis] = -low[axis];
    }
    for (vtkIdType i = 0; i < n; ++i) {
        double p[3];
        points->GetPoint(i, p);
        for (int axis = 0; axis < 3; ++axis) {
            if (p[axis] < low[axis]) {
                low[axis] = p[axis];
                extreme[2 * axis] = i;
            }
            if (p[axis] > high[axis]) {
                high[axis] = p[axis];
                extreme[2 * axis + 1] = i;
            }
        }
    }
    auto cells = vtkSmartPointer<vtkCellArray>::New();
    if (n > 0)
        for (vtkIdType i : extreme)
            cells->InsertNextCell(1, &i);
    geometry->SetVerts(cells);
    return geometry;
}

vtkSmartPointer<vtkPolyDataMapper> chunkMapper(vtkPolyData* chunk)
{
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputData(chunk);
    mapper->SetColorModeToDirectScalars();
    mapper->ScalarVisibilityOn();
    if (auto* openGl = vtkOpenGLPolyDataMapper::SafeDownCast(mapper))
        openGl->SetVBOShiftScaleMethod(vtkOpenGLVertexBufferObject::DISABLE_SHIFT_SCALE);
    return mapper;
}

//! A gridded cloud's cells (DEM of difference, raster) as flat squares on
//! the ground plane at each cell's height: four corners per cell (float, about
//! the cloud's origin like its points), and a quad per cell.
void makeRasterGeometry(vtkPolyData& polyData, const PointCloud& cloud, std::size_t begin, std::size_t count, double cell)
{
    vtkNew<vtkPoints> corners;
    corners->SetDataTypeToFloat();
    corners->SetNumberOfPoints(static_cast<vtkIdType>(4 * count));
    const double half = 0.5 * cell;
    const double dx[4] = {-half, half, half, -half}, dy[4] = {-half, -half, half, half};
    for (std::size_t i = 0; i < count; ++i) {
        const Eigen::Vector3f& p = cloud.positions()[begin + i];
        for (int k = 0; k < 4; ++k)
            corners->SetPoint(static_cast<vtkIdType>(4 * i + k), p.x() + dx[k], p.y() + dy[k], p.z());
    }
    vtkNew<vtkCellArray> quads;
    quads->AllocateExact(static_cast<vtkIdType>(count), static_cast<vtkIdType>(4 * count));
    for (std::size_t i = 0; i < count; ++i) {
        const vtkIdType ids[4] = {static_cast<vtkIdType>(4 * i), static_cast<vtkIdType>(4 * i + 1), static_cast<vtkIdType>(4 * i + 2),
                                  static_cast<vtkIdType>(4 * i + 3)};
        quads->InsertNextCell(4, ids);
    }
    polyData.SetPoints(corners);
    polyData.SetPolys(quads);
}

vtkSmartPointer<vtkPolyData> drawingLines(const Drawing& drawing, const Eigen::Vector3d& origin)
{
    static const unsigned char palette[][3] = {{255, 60, 170}, {60, 210, 255}, {255, 225, 0}, {110, 255, 90}, {255, 140, 0}, {190, 120, 255}};
    vtkNew<vtkPoints> points;
    points->SetDataTypeToDouble();
    vtkNew<vtkCellArray> lines;
    vtkNew<vtkUnsignedCharArray> colours;
    colours->SetNumberOfComponents(3);
    colours->SetName("layer colours");
    std::map<std::string, std::size_t> layers;
    std::vector<vtkIdType> ids;
    for (const DrawingPolyline& polyline : drawing.polylines) {
        if (polyline.points.size() < 2)
            continue;
        const std::size_t layer = layers.emplace(polyline.layer, layers.size()).first->second;
        ids.clear();
        for (const Eigen::Vector3d& v : polylineVertices(polyline)) { // arcs as points along them
            const Eigen::Vector3d local = v - origin;
            ids.push_back(points->InsertNextPoint(local.x(), local.y(), local.z()));
        }
        if (polyline.closed)
            ids.push_back(ids.front());
        lines->InsertNextCell(static_cast<vtkIdType>(ids.size()), ids.data());
        colours->InsertNextTypedTuple(palette[layer % (sizeof palette / sizeof palette[0])]);
    }
    if (lines->GetNumberOfCells() == 0)
        return nullptr;
    auto polyData = vtkSmartPointer<vtkPolyData>::New();
    polyData->SetPoints(points);
    polyData->SetLines(lines);
    polyData->GetCellData()->SetScalars(colours);
    return polyData;
}

} // namespace scandiff::gui
