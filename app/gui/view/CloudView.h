// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The 3D view: a QVTKOpenGLNativeWidget that shows clouds and meshes.
//! Conversion from scandiff's data model to VTK happens here and only here.

#include <scandiff/core/Mesh.h>
#include <scandiff/core/PointCloud.h>

#include <QWidget>

#include <memory>

class QVTKOpenGLNativeWidget;

namespace scandiff::gui {

class CloudView : public QWidget
{
    Q_OBJECT
public:
    explicit CloudView(QWidget* parent = nullptr);
    ~CloudView() override;

    //! Shows a cloud: its colours if it has some, else its first scalar field,
    //! else its height. Coordinates are drawn relative to the first entity's
    //! origin, so georeferenced data stays precise on the GPU.
    void addCloud(const PointCloud& cloud);
    void addMesh(const Mesh& mesh);
    void clear();
    void resetCamera();
    void setPointSize(float size);
    //! Renders now and saves the view to a PNG (used by --screenshot).
    bool saveScreenshot(const QString& path);

private:
    struct Scene;
    QVTKOpenGLNativeWidget* widget_;
    std::unique_ptr<Scene> scene_;
};

} // namespace scandiff::gui
