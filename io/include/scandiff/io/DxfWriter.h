// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! DXF export for CAD: points, 2D/3D polylines (open or closed), 3DFACEs and
//! text, on named layers. Written as AutoCAD R12 (AC1009) ASCII DXF, the version
//! every CAD and GIS program imports: HEADER ($ACADVER, extents), TABLES (LTYPE
//! CONTINUOUS, LAYER, STYLE STANDARD), ENTITIES, EOF; ezdxf's audit accepts it
//! without errors. Coordinates are global (double), written with 6 decimals
//! (micrometres, even for UTM coordinates).
//!
//! Layer names are made valid R12 symbol names: letters, digits, '$', '-' and
//! '_' only (anything else becomes '_'), at most 31 characters; DXF compares
//! them without regard to case, so "Points" and "POINTS" are one layer.

#include <scandiff/core/Drawing.h>
#include <scandiff/core/PointCloud.h>
#include <scandiff/io/FileIO.h>

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace scandiff::io {

class DxfDrawing
{
public:
    //! Declares a layer with an AutoCAD colour index (1..255); a layer declared
    //! again keeps its first colour. Entities on an undeclared layer get it
    //! declared with colour 7 (white/black). Throws Error(InvalidArgument) for a
    //! colour outside 1..255.
    void addLayer(const std::string& name, int colorIndex = 7);
    //! The add* functions throw Error(InvalidArgument) for non-finite coordinates.
    void addPoint(const std::string& layer, const Eigen::Vector3d& p);
    //! A polyline of at least 2 vertices; `planar` writes a 2D POLYLINE at the
    //! first vertex's elevation (all z must be equal, else InvalidArgument),
    //! otherwise a 3D POLYLINE.
    void addPolyline(const std::string& layer, const std::vector<Eigen::Vector3d>& vertices, bool closed, bool planar = false);
    //! A polyline with arcs: a 2D POLYLINE in the object coordinate system of
    //! `normal`, each vertex with its bulge (see DrawingPolyline::bulges).
    //! Throws Error(InvalidArgument) unless there is one finite bulge per
    //! vertex and every vertex lies in one plane normal to `normal` (1 µm).
    void addArcPolyline(const std::string& layer, const std::vector<Eigen::Vector3d>& vertices, const std::vector<double>& bulges,
                        const Eigen::Vector3d& normal, bool closed);
    //! A triangle, written as a 3DFACE whose 4th corner repeats the 3rd.
    void add3dFace(const std::string& layer, const std::array<Eigen::Vector3d, 3>& corners);
    //! Single-line text (line breaks become spaces) of the given height (> 0),
    //! its baseline starting at `position`.
    void addText(const std::string& layer, const Eigen::Vector3d& position, double height, const std::string& text);

    //! Writes the drawing atomically. Throws Error(Io).
    void write(const std::filesystem::path& path) const;

    struct Layer { std::string name; int color; };
    struct Entity; // defined in DxfWriter.cpp
    ~DxfDrawing();
    DxfDrawing();
    DxfDrawing(DxfDrawing&&) noexcept;
    DxfDrawing& operator=(DxfDrawing&&) noexcept;

private:
    //! Index in layers_ of the (sanitised) layer, declaring it if needed.
    std::size_t layerIndex(const std::string& name, int colorIndex = 7);
    std::size_t addVertices(const Eigen::Vector3d* first, std::size_t count);

    std::vector<Layer> layers_;
    std::vector<Entity> entities_;
    //! The coordinates of every entity, in order: entities keep a range of it.
    std::vector<Eigen::Vector3d> vertices_;
};

//! Writes a tool's drawing as DXF (R12): each layer in turn one of the six
//! basic colours, its closed or open polylines as 3D polylines (those with
//! arcs as 2D polylines with bulges in their plane), its texts.
//! Polylines of fewer than 2 points are skipped. Throws Error(Io), or
//! Error(InvalidArgument) for non-finite coordinates.
void writeDrawingDxf(const Drawing& drawing, const std::filesystem::path& path);

} // namespace scandiff::io
