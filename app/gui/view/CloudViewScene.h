// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! What a CloudView holds (private to view/): its VTK scene and, per shown
//! entity, its chunks. Shared by CloudView.cpp and ViewRefinement.cpp.

#include "view/ChunkGeometry.h"
#include "view/EntityColouring.h"
#include "view/CloudView.h"

#include <vtkActor.h>
#include <vtkActor2D.h>
#include <vtkBillboardTextActor3D.h>
#include <vtkBoxRepresentation.h>
#include <vtkBoxWidget2.h>
#include <vtkCellPicker.h>
#include <vtkEDLShading.h>
#include <vtkFloatArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPointPicker.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkSmartPointer.h>
#include <vtkTextActor.h>
#include <vtkUnsignedCharArray.h>

#include <cstdint>
#include <map>
#include <optional>
#include <vector>

namespace scandiff::gui {

//! One shown entity, drawn as chunks of at most kChunkPoints points, one
//! actor each: a renderer (software ones above all) then works on bounded
//! buffers, as CloudCompare draws its clouds chunk by chunk. A chunk's VTK
//! arrays are views on the entity's positions and RGBA colours (no copies),
//! drawn only when every point is (a screenshot, Eye-Dome Lighting, a cloud
//! within the frame budget). Its decimated twin holds copies of every
//! stride-th point only, and its slice (the picture refined at rest) of the
//! slice being drawn: what OpenGL is given stays a stride-th of the cloud.
struct CloudView::Shown
{
    struct Chunk
    {
        std::size_t begin = 0, count = 0;
        vtkSmartPointer<vtkPolyData> full, decimated, slice;
        vtkSmartPointer<vtkFloatArray> normals; //!< a view on the cloud's normals, when it has some
        vtkSmartPointer<vtkPolyDataMapper> fullMapper, decimatedMapper, sliceMapper;
        vtkSmartPointer<vtkPolyDataMapper> pickMapper; //!< over pickingGeometry, made at the first pick
        vtkSmartPointer<vtkUnsignedCharArray> colours;
        vtkSmartPointer<vtkActor> actor;
        std::size_t decimatedStride = 0;
        //! A gridded cloud's chunk: four corners per point (its cell), colours
        //! copied from the entity's RGBA at each refresh, never decimated.
        bool raster = false;
        //! Its points as the gathering reads them (see gatherPoints).
        ChunkArrays arrays(const Shown& shown) const
        {
            return {vtkFloatArray::SafeDownCast(full->GetPoints()->GetData())->GetPointer(0), shown.rgba.data() + 4 * begin,
                    normals ? normals->GetPointer(0) : nullptr, count};
        }
    };
    bool isCloud = true;
    std::size_t pointCount = 0;
    float ownPointSize = 0; //!< the entity's own point size; 0: the view's
    bool documentVisible = true; //!< its tick in the tree; the view may still hide it (setShownHere)
    std::vector<std::uint8_t> rgba; //!< 4 bytes per point, what the chunks' colour arrays show
    //! A display change on a cloud refined in slices colours only the points
    //! the next frame draws (a threshold drag on 60 M points then recolours a
    //! few hundred thousand at each step); each slice colours its own before
    //! it is gathered, and what reads every point settles the rest first.
    std::optional<EntityColourer> pendingColours;
    std::vector<Chunk> chunks;

    //! A chunk's every stride-th point from `first`, coloured if colours are pending.
    void colourForGather(const Chunk& c, std::size_t stride, std::size_t first = 0)
    {
        if (pendingColours)
            pendingColours->colour(rgba.data(), c.begin, c.begin + c.count, stride, first);
    }
    //! Every point's colour, for what reads them all (a full frame, picking, the scissors).
    void settleColours()
    {
        if (pendingColours) {
            pendingColours->colourAll(rgba.data());
            coloursComplete();
        }
    }
    //! Every point coloured since the last display change: nothing pending,
    //! and the chunks' colour arrays (views on rgba) marked changed, so that
    //! a full frame uploads them again (one may have been drawn, stale, while
    //! a camera drag held the cloud undecimated).
    void coloursComplete()
    {
        pendingColours.reset();
        for (Chunk& c : chunks)
            if (c.colours)
                c.colours->Modified();
    }
    //! A drawing's texts (stone ids), placed so that they never overlap: as
    //! many as the view has room for, more as one zooms in.
    vtkSmartPointer<vtkActor2D> labels;
};

struct CloudView::Scene
{
    vtkNew<vtkGenericOpenGLRenderWindow> window;
    vtkNew<vtkRenderer> renderer;
    //! The flat overlays (colour bar, scale bar, scissors) on a layer of their
    //! own, drawn after the clouds: the Eye-Dome Lighting pass of the main
    //! layer must not shade them.
    vtkNew<vtkRenderer> overlay;
    vtkNew<vtkScalarBarActor> scalarBar;
    vtkNew<vtkLookupTable> scalarBarTable;
    vtkNew<vtkPointPicker> picker;
    //! For gridded clouds: a click inside a cell picks the cell, whatever its size on screen.
    vtkNew<vtkCellPicker> cellPicker;
    std::map<EntityId, Shown> shown;
    std::optional<Eigen::Vector3d> sceneOrigin;
    float pointSize = 2.0f;
    //! A start a software renderer (Mesa's, on a machine without a GPU) draws
    //! in about a quarter of a second; the first frames measure the machine.
    std::size_t budget = 300'000;
    bool adaptiveBudget = true;
    std::size_t stride = 1;
    bool moving = false;
    bool settling = false; //!< decimated after a colour change, until the settle timer fires
    bool renderPending = false;
    bool interactiveRenderPending = false; //!< a decimated frame scheduled by renderInteractively
    Refinement refinement;
    bool pickMode = false;
    // Measurements: one polydata of paths and marks, and a label per measurement.
    vtkNew<vtkPolyData> annotations;
    vtkNew<vtkActor> annotationActor;
    std::vector<vtkSmartPointer<vtkBillboardTextActor3D>> labels;
    bool eyeDomeLighting = false;
    vtkSmartPointer<vtkEDLShading> edl;
    vtkNew<vtkBoxWidget2> clipWidget;
    vtkNew<vtkBoxRepresentation> clipBox;
    bool clipping = false;
    // The scale bar: a line of a round length (1, 2 or 5 x 10^k m) about a
    // fifth of the view wide, its length written above it, sized before each
    // frame from the camera (at the focal point's depth in perspective).
    bool scaleBarShown = true;
    vtkNew<vtkPolyData> scaleBarLine;
    vtkNew<vtkActor2D> scaleBarActor;
    vtkNew<vtkTextActor> scaleBarText;
    // Move / rotate: the box around the entities being moved, their ids, the
    // centre of their bounds (global) and the motion so far (global).
    vtkNew<vtkBoxWidget2> moveWidget;
    vtkNew<vtkBoxRepresentation> moveBox;
    std::vector<EntityId> movingIds;
    Eigen::Vector3d movingCentre = Eigen::Vector3d::Zero();
    Eigen::Matrix4d movedBy = Eigen::Matrix4d::Identity();
    // Scissors: the polygon being drawn, in widget pixels, and its outline on screen.
    bool scissorsMode = false;
    std::vector<Eigen::Vector2d> scissors;
    vtkNew<vtkPolyData> scissorsOutline;
    vtkNew<vtkActor2D> scissorsActor;
};

} // namespace scandiff::gui
