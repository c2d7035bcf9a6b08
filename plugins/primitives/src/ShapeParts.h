// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! After detection (internal to the plugin): the parts of one surface that
//! a detector returned apart brought together, and the points each shape
//! should hold given to it.
//!
//! A scan's shapes come out of RANSAC in pieces for reasons that are not in
//! the surface: a wall is cut by the shadow of a column standing in front of
//! it, a pipe by the tank it passes behind, a narrow strip of a thin pipe
//! fits a plane as well as its cylinder, and the points where two shapes
//! meet go to whichever shape was found first. Two parts are one surface
//! when their points lie on one shape and nothing separates them but what
//! no scanner saw: the space between them either holds points (they touch)
//! or lies behind something from every scanner (the cloud's sensor poses
//! say which). A gap a scanner looked through is real: two plates with the
//! floor seen between them stay two shapes.

#include <scandiff/core/PointCloud.h>
#include <scandiff/plugins/primitives/PrimitiveDetection.h>

#include <Eigen/Core>

#include <array>

#include <functional>
#include <string>
#include <vector>

namespace scandiff::plugins::detail {

//! What a scanner saw, as the nearest range in each direction (cells of
//! about its angular step, from every point of the cloud: a surface hides
//! what lies behind it from every scanner, whichever scan its points came
//! from). Unlike the visibility test's depth map, which finds the surface
//! through a direction, this keeps the nearest return only: a wall another
//! station saw behind a platform this one saw never counts as seen through
//! the platform.
class ScannerView
{
public:
    //! `step`: the scanner's angular step (rad, > 0).
    ScannerView(const PointCloud& cloud, const SensorPose& pose, double step);

    //! Whether the scanner looked past the point (global): at least 3 of its
    //! direction's cell and the 8 around it hold returns, and every return
    //! there lies farther than the point by more than `tolerance` (along the
    //! ray). False where next to nothing came back. `isAReturn`: the point
    //! is one of the cloud's, and its own return does not count.
    bool lookedPast(const Eigen::Vector3d& point, double tolerance, bool isAReturn = false) const;

    const Eigen::Vector3d& position() const { return position_; }

private:
    bool cellOf(const Eigen::Vector3d& point, int& u, int& v, double& range) const;

    Eigen::Vector3d position_;
    Eigen::Matrix3d worldToSensor_;
    double step_ = 0;
    int width_ = 0, height_ = 0;
    //! Per cell, the two nearest ranges (infinity: none): a return of the
    //! cloud asked about is told from what lies in front of or behind it.
    std::vector<std::array<float, 2>> nearest_;
};

//! What the steps read: the points relative to `centre` (the shapes'
//! primitives are global), their unit normals (zero: unknown; empty: none),
//! the tolerances, and the scanners' depth maps (empty: no sensor pose).
struct SurfaceEvidence
{
    SurfaceEvidence(const std::vector<Eigen::Vector3d>& points_, const std::vector<Eigen::Vector3f>& normals_)
        : points(points_), normals(normals_)
    {
    }

    const std::vector<Eigen::Vector3d>& points;
    const std::vector<Eigen::Vector3f>& normals;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    double epsilon = 0.01;        //!< a point on a surface lies within this (m)
    double linkDistance = 0.05;   //!< points closer than this are neighbours on a surface (m)
    double normalCosine = 0.9;    //!< a point's normal within this of its surface's (unoriented)
    double typeTolerance = 0.2;   //!< a union fits when its RMS is within this of its parts'
    double spacing = 0.01;        //!< the scan's median spacing, for the shapes' footprints (m)
    std::size_t minPoints = 200;  //!< a shape left with fewer is dropped
    std::vector<ScannerView> views; //!< one per scanner, built on every point of the cloud
    std::function<void()> checkCancel = [] {};
};

//! The views of the cloud's sensor poses (empty without any). A pose
//! without its angular step gets the scan's spacing over the points' median
//! range from it.
std::vector<ScannerView> scannerViews(const PointCloud& cloud, double spacing);

//! The shape's area, centroid and (cylinder, cone) length from its inliers.
void measureShape(DetectedPrimitive& shape, const SurfaceEvidence& evidence);

//! Merges pairs of shapes whose points lie on one of them and which touch
//! or are separated only by what no scanner saw; the union is refitted and
//! kept when it fits as well as its parts. A part of another type (a plane
//! strip of a pipe) joins a shape of more parameters that holds its points.
//! `mergeApart`: also across hidden gaps (false for regions grown on values,
//! which are apart by their values). Returns the merges, noted in `notes`.
std::size_t mergeSurfaceParts(std::vector<DetectedPrimitive>& shapes, const SurfaceEvidence& evidence, bool mergeApart,
                              std::vector<std::string>& notes);

//! Gives each point the shape whose surface it lies nearest to (within
//! epsilon, its normal agreeing), among the shapes holding points within
//! the link distance of it, repeated while shapes grow: the points a shape
//! left next to it join it, a point at the meeting of two shapes goes to
//! the one it lies on. Changed shapes are refitted; shapes left with fewer
//! than the minimum support are dropped. Returns the points that changed.
std::size_t claimPoints(std::vector<DetectedPrimitive>& shapes, const SurfaceEvidence& evidence, std::size_t cloudSize,
                        std::vector<std::string>& notes);

//! Leaves out of each shape the points no return of its surface can be: on
//! a sphere, a cylinder, a cone or a torus, a point where no scanner faces
//! the surface at less than 88 degrees of incidence (its back: the mixed
//! pixels just behind a pipe's silhouette; the inside of a sphere, a
//! cylinder or a cone faces the scanners standing in it); on any shape, a
//! point where a scanner facing the surface (below 80 degrees) looked past
//! it, its own return aside (a return on a face's plane beyond the face,
//! with the floor seen behind it). Shapes left with fewer than the minimum
//! support are dropped. Without sensor poses, nothing is left out. Returns
//! the points left out.
std::size_t dropUnseeable(std::vector<DetectedPrimitive>& shapes, const SurfaceEvidence& evidence, std::vector<std::string>& notes);

//! How much of a shape's residuals is a form rather than noise: over cells
//! of the link distance (4 points or more), the mean of n x (the cell's mean
//! residual)^2 over the residuals' variance. About 1 when the residuals are
//! independent noise; n when each cell's points lie off the shape together
//! (a lumpy bag fitted with a sphere, two walls' corner with a cylinder).
double residualStructure(const DetectedPrimitive& shape, const SurfaceEvidence& evidence);

//! Leaves out the shapes that are no surface of their type: residuals
//! wider than half epsilon (1.5 times the scan's noise, epsilon being 3
//! times it) and formed (residualStructure above 4). Returns how many.
std::size_t dropFormedResiduals(std::vector<DetectedPrimitive>& shapes, const SurfaceEvidence& evidence, std::vector<std::string>& notes);

} // namespace scandiff::plugins::detail
