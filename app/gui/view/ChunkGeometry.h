// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The VTK geometry of the view's chunks: views on a cloud's positions, vertex
//! cells, a gridded cloud's cells as quads, a drawing's polylines.

#include <scandiff/core/Drawing.h>
#include <scandiff/core/PointCloud.h>

#include <vtkSmartPointer.h>

#include <cstddef>
#include <cstdint>

class vtkCellArray;
class vtkPoints;
class vtkPolyData;
class vtkPolyDataMapper;

namespace scandiff::gui {

//! VTK points reading `count` xyz triples at `xyz` in place (no copy; VTK does not free them).
vtkSmartPointer<vtkPoints> pointsOver(const float* xyz, std::size_t count);

//! How many of `count` points every stride-th from `first` on takes: a
//! slice's or a decimated frame's share of a chunk.
std::size_t everyStride(std::size_t count, std::size_t stride, std::size_t first = 0);

//! Vertex cells for every stride-th point from `first` on, as two flat 32-bit
//! arrays (half the memory of VTK's default 64-bit ids; a cloud above 2^31
//! points is refused by the view before this). The `stride` sets of firsts
//! 0 .. stride - 1 hold every point once: the view's slices.
vtkSmartPointer<vtkCellArray> vertexCells(std::size_t count, std::size_t stride, std::size_t first = 0);

//! A chunk of a cloud as the view reads it: `count` points from these
//! addresses on (the cloud's positions and normals, the view's RGBA).
struct ChunkArrays
{
    const float* xyz = nullptr;
    const std::uint8_t* rgba = nullptr;
    const float* normals = nullptr; //!< null when the cloud has none
    std::size_t count = 0;
};

//! Every stride-th point of the chunk from `first` on, copied into `out`'s
//! own arrays (positions, colours, normals) with a vertex each: what a
//! decimated frame or a slice draws. OpenGL then holds these few points, not
//! the whole chunk (16 bytes a point in a software renderer's memory, for
//! the session, when the chunk's own arrays are drawn). The arrays are
//! reused from one call to the next.
void gatherPoints(vtkPolyData& out, const ChunkArrays& chunk, std::size_t stride, std::size_t first = 0);
//! The colours only again, after a recolouring (same stride and first).
void gatherColours(vtkPolyData& out, const ChunkArrays& chunk, std::size_t stride, std::size_t first = 0);

//! What the point picker reads for a chunk never drawn in full: all its
//! points (shared, no copy) and a vertex on each of the six extreme ones, so
//! that its bounds, which VTK takes from the cells, are the chunk's. Never
//! drawn: OpenGL holds nothing of it.
vtkSmartPointer<vtkPolyData> pickingGeometry(vtkPoints* points);

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
