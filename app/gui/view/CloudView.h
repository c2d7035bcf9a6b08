// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The 3D view: a QVTKOpenGLNativeWidget that shows the document's clouds and
//! meshes. Conversion from scandiff's data model to VTK happens here and only
//! here. Thresholds and colour changes only rewrite the per-point colour array
//! (points outside the range get alpha 0 and are discarded by the fragment
//! shader); the geometry is uploaded once. While the camera moves, clouds above
//! the interactive budget are drawn decimated, in full at rest.

#include "document/Document.h"
#include "view/EntityColouring.h"

#include <scandiff/core/processing/CloudEditing.h>

#include <QSurfaceFormat>
#include <QColor>
#include <QImage>
#include <QWidget>

#include <array>
#include <memory>
#include <set>

class QTimer;
class QVTKOpenGLNativeWidget;

namespace scandiff::gui {

enum class StandardView { Top, Bottom, Front, Back, Left, Right, Iso };

//! Everything needed to put the camera back (sessions), in global coordinates.
struct CameraState
{
    std::array<double, 3> position{0, 0, 1}, focalPoint{0, 0, 0}, viewUp{0, 1, 0};
    double viewAngle = 30.0;
    bool parallel = false;
    double parallelScale = 1.0;
};

class CloudView : public QWidget
{
    Q_OBJECT
public:
    explicit CloudView(QWidget* parent = nullptr);
    ~CloudView() override;

    //! The OpenGL format the view needs; set as the default before QApplication exists.
    static QSurfaceFormat defaultSurfaceFormat();

    //! Shows a document entity (coordinates relative to the first entity's
    //! origin, so georeferenced data stays precise on the GPU).
    void addEntity(const Document::Item& item);
    void removeEntity(EntityId id);
    //! Re-reads visibility and colours of an entity from its display state.
    void refreshEntity(const Document::Item& item);
    //! Marks drawn over the clouds (measurements): each a path through its
    //! points (global coordinates), closed when asked, its points marked, and
    //! its label written beside its last point, facing the camera.
    struct Annotation
    {
        std::vector<Eigen::Vector3d> points;
        bool closed = false;
        std::string label;
    };
    void setAnnotations(const std::vector<Annotation>& annotations);
    std::size_t annotationCount() const { return annotationCount_; }
    //! The colour-scale bar (hidden when `legend.shown` is false).
    void setLegend(const ColourLegend& legend);
    const ColourLegend& legend() const { return legend_; }
    void clear();

    void resetCamera();
    void zoomToEntity(EntityId id);
    void setStandardView(StandardView view);
    void setPointSize(float size);
    //! The point size an entity is drawn with (its own, or the view's), 0 if not shown.
    float entityPointSize(EntityId id) const;
    //! One plain colour behind the clouds; an invalid colour: the default gradient.
    void setBackground(const QColor& colour);
    //! This view's own choice to hide an entity the tree shows (side-by-side
    //! views: an epoch on each side).
    void setShownHere(EntityId id, bool shown);
    //! Whether the entity is drawn in this view (ticked, and not hidden here).
    bool isShownHere(EntityId id) const;
    //! Whether some of the entity is within the view's frame (shown here, its
    //! chunks' boxes projected onto the widget): what the colour bar may describe.
    bool isOnScreen(EntityId id) const;
    //! How many texts of a drawing are labelled in the view (0: none, or not a drawing), and whether they are shown.
    std::size_t labelCount(EntityId id) const;
    bool labelsVisible(EntityId id) const;
    //! Shares `leader`'s camera: both views then move together.
    void followCamera(CloudView& leader);
    //! Eye-Dome Lighting (VTK's EDL pass): shades clouds without normals by
    //! their depth differences on screen, so a façade's reliefs read.
    void setEyeDomeLighting(bool on);
    bool eyeDomeLighting() const;
    //! A scale bar at the bottom of the view, its length labelled in metres.
    void setScaleBar(bool on);
    bool scaleBar() const;
    //! The length the scale bar shows now (m), 0 when hidden or nothing is shown.
    double scaleBarLength() const;
    //! The size of a screen pixel at the focal point's depth (m).
    double metresPerPixel() const;
    //! The plain background colour, invalid for the default gradient.
    QColor background() const;
    //! Whether an entity is drawn lit by its normals.
    bool isShaded(EntityId id) const;
    float pointSize() const;
    void setParallelProjection(bool parallel);
    bool parallelProjection() const;
    CameraState camera() const;
    void setCamera(const CameraState& state);

    //! Points drawn in one frame: while the camera moves or a threshold is
    //! dragged, clouds are decimated by one common stride so their total stays
    //! below it; at rest, the full picture is drawn in slices of that size (see
    //! Refinement). By default it adapts to the machine (what it draws in 1/20
    //! s, measured on each frame); setting it turns the adaptation off.
    void setInteractiveBudget(std::size_t points);
    std::size_t interactiveBudget() const;
    //! The stride used while moving (1 = no decimation); for tests.
    std::size_t interactiveStride() const;
    //! Where an entity's own frame sits in the scene (its actors' position, in
    //! double) and the first float position its actors draw: for tests of the
    //! precision of mixed frames. False if the entity is not shown.
    bool shownFrame(EntityId id, Eigen::Vector3d& offset, Eigen::Vector3f& firstPosition) const;
    //! Switches the decimated drawing on or off as a camera move would.
    void setMoving(bool moving);
    //! The picture at rest when the clouds hold more points than one frame's
    //! budget: the decimated frame first (slice 0: every stride-th point),
    //! then slices 1 .. stride - 1 (every stride-th point from the slice's
    //! number on) drawn over it one per event-loop turn, without clearing, so
    //! that no frame on the GUI thread draws more than the budget and menus,
    //! clicks and camera moves are served between slices. A move, a colour or
    //! threshold change stops it; the next rest starts again from slice 0.
    struct Refinement
    {
        std::size_t slices = 0;       //!< in the picture being refined (its stride)
        std::size_t slicesDrawn = 0;  //!< slice 0 included
        std::size_t pointsDrawn = 0;  //!< by those slices
        std::size_t largestSlice = 0; //!< points of the largest slice drawn
        std::size_t starts = 0;       //!< refinements started since the view was made
        bool refining = false;        //!< slices remain and are scheduled
    };
    const Refinement& refinement() const;
    //! Whether a decimated frame asked for by a colour or threshold change
    //! is still to be drawn (it is, when the event loop next turns).
    bool frameScheduled() const;
    //! Points whose coordinates OpenGL holds for the shown clouds (the vertex
    //! buffers of the chunks' mappers): a stride-th of the clouds while they
    //! are refined in slices, every point once a frame drew them all.
    std::size_t pointsGivenToOpenGl() const;
    //! Bytes the view holds per shown cloud besides OpenGL: its RGBA colours
    //! and the copies a decimated frame and a slice draw.
    std::size_t heldBytes() const;
    //! Points whose colours wait for the slice that draws them (a display
    //! change on a cloud refined in slices colours the decimated frame's only).
    std::size_t pointsAwaitingColour() const;

    //! Scissors: left clicks draw a polygon on the screen, a right click (or
    //! finishScissors) closes it and emits polygonDrawn; turning the mode off
    //! drops an unfinished polygon.
    void setScissorsMode(bool on);
    bool scissorsMode() const;
    //! A vertex at widget pixel (x, y from the top-left), as a click in scissors mode adds.
    void addScissorsVertex(double x, double y);
    void finishScissors();
    //! Global coordinates (homogeneous) to widget pixels (x right, y down),
    //! before the division by w: what the camera shows where.
    Eigen::Matrix4d globalToWidgetPixels() const;
    //! The clipping box (CloudCompare's): a box with handles to move, turn and
    //! resize, drawn around the shown clouds when switched on; only what is
    //! inside it is drawn. Its place, in global coordinates, is what
    //! "Extract inside" cuts with.
    void setClippingBox(bool on);
    bool clippingBoxOn() const;
    void setClippingBox(const CropBox& box);
    CropBox clippingBox() const;
    //! Move / rotate (CloudCompare's Translate/Rotate): a box
    //! around `ids` (drag inside it to move them, on a face to turn them about
    //! its centre); they are drawn moved as it goes, their data untouched
    //! until the caller applies the motion. movedBy() is the motion so far, in
    //! global coordinates (global' = M global); movingCentre() the centre of
    //! their bounds when it started (global).
    void startMovingEntities(const std::vector<EntityId>& ids);
    //! Moves the box and the drawing to a typed motion.
    void setMovedBy(const Eigen::Matrix4d& global);
    Eigen::Matrix4d movedBy() const;
    Eigen::Vector3d movingCentre() const;
    bool movingEntities() const;
    //! The entities drawn where their data is again; the box goes.
    void stopMovingEntities();
    //! Whether a point of a shown cloud is drawn (not hidden by its thresholds).
    bool isPointShown(EntityId id, std::size_t index) const;

    //! In pick mode a left click picks the nearest point instead of rotating.
    void setPickMode(bool on);
    bool pickMode() const;
    //! Picks at widget pixel (x, y from the top-left); emits pointPicked on success.
    bool pickAt(int x, int y);

    //! Renders now and saves the view to a PNG.
    bool saveScreenshot(const QString& path);
    //! The picture on screen now, as drawn so far (nothing drawn again): for
    //! tests of what the slices add up to.
    QImage shownPicture() const;
    //! Renders now (in full at rest).
    void render();
    //! One render at the next event-loop turn, however many changes ask for it.
    void renderSoon();
    //! Renders at once decimated, then in full after 250 ms without changes.
    void renderInteractively();

signals:
    void pointPicked(EntityId id, std::size_t index);
    void pickModeChanged(bool on);
    void scissorsModeChanged(bool on);
    void clippingBoxChanged(bool on);
    //! A closed polygon in widget pixels and the projection it was drawn with.
    void polygonDrawn(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Matrix4d& globalToPixels);
    //! The view changed these itself (a session restored them): menus follow.
    void pointSizeChanged(float size);
    void projectionChanged(bool parallel);
    //! The camera moved (a drag, a zoom, a standard view, a restored session).
    void cameraChanged();
    //! The move box was dragged: the motion so far (global coordinates).
    void movedByChanged(const Eigen::Matrix4d& global);

private:
    class PickCommand;
    struct Shown;
    static constexpr std::size_t kChunkPoints = 1u << 18;
    //! addEntity's kinds: a drawing's lines and texts; a cloud's or a mesh's
    //! actors (false when it has nothing to show), as one mesh piece or as
    //! chunks of a cloud's points.
    void addDrawing(const Document::Item& item);
    bool addData(const Document::Item& item);
    void addMeshPiece(Shown& shown, const Mesh& mesh, const Eigen::Vector3d& offset);
    void addCloudChunks(Shown& shown, const PointCloud& points, const Eigen::Vector3d& offset);
    void updateStride();
    void updateScaleBar();
    //! Clips every chunk's mappers to the box's six faces (or none).
    void applyClipping();
    //! The entities being moved drawn by the move box's transform.
    void applyMovingPreview();
    void setDecimated(Shown& shown, bool moving);
    //! The near and far planes around what is shown and the measurements.
    void resetClippingRange();
    //! Whether the clouds at rest are drawn in slices (more points than the
    //! budget; Eye-Dome Lighting's passes redraw the whole frame, so not then).
    bool refinesInSlices() const;
    void startRefinement();
    void drawNextSlice();
    void stopRefinement();
    //! One frame, timed: the budget follows what the machine draws in 1/20 s.
    void timedRender(std::size_t points);
    void resizeEvent(QResizeEvent* event) override;
    QTimer* settleTimer_ = nullptr;
    QTimer* sliceTimer_ = nullptr;
    bool pickAtDevicePixel(int x, int y);
    struct Scene;
    QVTKOpenGLNativeWidget* widget_;
    std::unique_ptr<Scene> scene_;
    ColourLegend legend_;
    std::size_t annotationCount_ = 0;
    std::vector<Annotation> annotations_; //!< as given (global coordinates)
    std::set<EntityId> hiddenHere_;        //!< hidden in this view only
};

} // namespace scandiff::gui
