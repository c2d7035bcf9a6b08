// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The VTK geometry of the view's chunks: views on a cloud's positions, vertex
//! cells, a gridded cloud's cells as quads, a drawing's polylines.

#include <scandiff/core/Drawing.h>
#include <scandiff/core/PointCloud.h>

#include <vtkSmartPointer.h>

#include <cstddef>

class vtkCellArray;
class vtkPoints;
class vtkPolyData;
class vtkPolyDataMapper;

namespace scandiff::gui {

//! VTK points reading `count` xyz triples at `xyz` in place (no copy; VTK does not free them).
vtkSmartPointer<vtkPoints> pointsOver(const float* xyz, std::size_t count);

//! Vertex cells for every stride-th point from `first` on, as two flat 32-bit
//! arrays (half the memory of VTK's default 64-bit ids; a cloud above 2^31
//! points is refused by the view before this). The `stride` sets of firsts
//! 0 .. stride - 1 hold every point once: the view's slices.
vtkSmartPointer<vtkCellArray> vertexCells(std::size_t count, std::size_t stride, std::size_t first = 0);

//! A mapper drawing a chunk's points in their RGBA colours. The points go to
//! OpenGL as they are: they are floats about the cloud's origin already (the
//! view's offset is the actor's), so VTK's shift and scale of the coordinates
//! adds no precision, and with it on (VTK turns it on for data wider than
//! about 32 m) VTK packs a copy of every chunk's points that it keeps after
//! the upload, 12 bytes a point for the session.
vtkSmartPointer<vtkPolyDataMapper> chunkMapper(vtkPolyData* chunk);

//! A gridded cloud's cells (DEM of difference, raster) as flat squares on
//! the ground plane at each cell's height: four corners per cell (float, about
//! the cloud's origin like its points), and a quad per cell.
void makeRasterGeometry(vtkPolyData& polyData, const PointCloud& cloud, std::size_t begin, std::size_t count, double cell);

//! A drawing's polylines as lines about `origin` (double points: UTM
//! coordinates keep their millimetres), each coloured by its layer (RGB cell
//! scalars, a bright palette that stands out over clouds). Null when the
//! drawing has no polyline of two points.
vtkSmartPointer<vtkPolyData> drawingLines(const Drawing& drawing, const Eigen::Vector3d& origin);

} // namespace scandiff::gui
