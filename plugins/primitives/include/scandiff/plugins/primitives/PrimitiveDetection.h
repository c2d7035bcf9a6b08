// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Primitive extraction: planes, spheres, cylinders, cones and tori found in a
//! cloud by efficient RANSAC (Schnabel, Wahl and Klein 2007, through CGAL's
//! Shape_detection), or planes by region growing (CGAL's, on point sets),
//! then made what a user can trust:
//! - each shape's inliers one connected part (cluster epsilon): disjoint
//!   coplanar plates are separate shapes;
//! - the right type: the simplest type that fits the shape's points about as
//!   well as the best (a complexity penalty), with a radius within bounds
//!   tied to the extent of its points; a shape no type holds within epsilon
//!   leaves its points unassigned;
//! - every shape refitted by least squares on its inliers (geometric
//!   distances), with the standard uncertainty of its parameters;
//! - repeatable: the same seed gives the same shapes, whatever the threads.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/geometry/Primitives.h>

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace scandiff::plugins {

//! How shapes are found: efficient RANSAC (every type), planar regions
//! grown from the flattest points (planes only; no random draw), or the
//! sequential RANSAC of thesis 001 for façades (planes only, by classes of
//! orientation, each the largest connected region of its inliers).
enum class PrimitiveMethod { EfficientRansac, RegionGrowing, Sequential };

//! "efficient-ransac", "region-growing", "sequential"; throws Error(InvalidArgument) otherwise.
PrimitiveMethod parsePrimitiveMethod(const std::string& name);

//! What region growing grows on: planes (a point joins within epsilon of the
//! region's plane, its normal within the deviation); smooth surfaces (normals
//! of neighbours within the smoothness angle, edges stopping it: planes,
//! pipes, spheres); or a value such as intensity (thesis 003 §3.2: stones of
//! a wall, painted marks).
enum class GrowOn { Plane, Smoothness, Value };

//! "plane", "smoothness", "intensity"; throws Error(InvalidArgument) otherwise.
GrowOn parseGrowOn(const std::string& name);

struct PrimitiveDetectionParams
{
    PrimitiveMethod method = PrimitiveMethod::EfficientRansac;
    std::set<PrimitiveKind> kinds = {PrimitiveKind::Plane, PrimitiveKind::Sphere, PrimitiveKind::Cylinder, PrimitiveKind::Cone,
                                     PrimitiveKind::Torus};
    //! Largest distance of an inlier to its shape (m); absent: 3 x the noise
    //! estimated from the points' local plane fits.
    std::optional<double> epsilon;
    //! Largest gap inside one connected part (m); absent: 3 x the median spacing.
    std::optional<double> clusterEpsilon;
    double normalDeviationDegrees = 25; //!< largest angle between a point's normal and its shape's
    std::size_t minPoints = 200;        //!< smallest support of a shape (points)
    double probability = 0.01;          //!< RANSAC's chance of missing the largest shape in a round
    //! A shape's type is the simplest (plane, sphere, cylinder, cone, torus)
    //! whose least-squares RMS is within this fraction of the best type's.
    double typeTolerance = 0.2;
    //! Sequential: a plane's normal within this angle of its class's axis (thesis 001: 1°).
    double orientationToleranceDegrees = 1.0;
    //! Region growing: on what (see GrowOn).
    GrowOn growOn = GrowOn::Plane;
    //! Smoothness: largest angle between the normals of two neighbours in a region (deg).
    double smoothnessDegrees = 20;
    //! Smoothness: a point whose surface variation is above this stops the region
    //! (it joins, it does not spread it); absent: 2 x the median variation.
    std::optional<double> curvature;
    //! Value: the scalar field grown on, the largest variance of a region's
    //! values (absent: 4 x the median variance within the radius) and the
    //! radius a region grows by (absent: 2 x the median spacing, thesis 003).
    std::string valueField = "intensity";
    std::optional<double> valueTolerance;
    std::optional<double> valueRadius;
    std::uint64_t seed = 0;
};

struct DetectedPrimitive
{
    int id = 0;
    Primitive primitive;              //!< global coordinates
    std::vector<std::uint32_t> inliers; //!< indices into the input cloud, increasing
    double rms = 0;                   //!< of the inliers' distances
    double area = 0;                  //!< of the inliers' footprint on the surface (m², cells of the cluster epsilon)
    double length = 0;                //!< cylinder, cone: the inliers' extent along the axis (m)
    //! The inliers' centroid (global): where the shape is, whatever point of
    //! it `primitive` carries (a plane's or an axis's point may lie far off).
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    std::vector<std::pair<std::string, double>> uncertainty; //!< see refinePrimitive()
};

struct PrimitiveDetectionResult
{
    std::vector<DetectedPrimitive> primitives;
    std::vector<int> primitiveId;       //!< per input point, -1 when on no shape
    std::vector<float> distance;        //!< per input point, signed distance to its shape (NaN off every shape)
    double epsilon = 0, clusterEpsilon = 0; //!< the values used
    bool normalsComputed = false;       //!< the cloud had none: fitted within max(2.5 spacings, 10 x the noise)
    //! Sequential: the façade's horizontal normal (the thesis's y axis), global frame.
    std::optional<Eigen::Vector3d> facadeNormal;
    std::vector<std::string> notes;
};

//! Throws Error(InvalidArgument) for bad parameters, Error(InvalidData) for an
//! empty cloud or one with fewer points than the minimum support,
//! Error(Cancelled).
PrimitiveDetectionResult detectPrimitives(const PointCloud& cloud, const PrimitiveDetectionParams& params,
                                          ProgressObserver* progress = nullptr);

} // namespace scandiff::plugins
