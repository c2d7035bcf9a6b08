// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Point normals (thesis 000, annex A.2) and their orientation.
//!
//! A normal is fitted on each point's neighbourhood (its k nearest points, or
//! every point within a radius) by one of three local models:
//! - Plane: the least-squares plane, i.e. the smallest principal axis of the
//!   neighbourhood's covariance (method 1 of the annex);
//! - Quadric: a height function z = a u² + b uv + c v² + d u + e v + f over
//!   that plane, and the normal of that surface above the point (follows
//!   curvature better on rounded shapes);
//! - Triangulation: the 2D Delaunay triangulation of the neighbourhood
//!   projected on its plane, and the weighted mean of the normals of the
//!   triangles around the point (method 2 of the annex, computed per point's
//!   neighbourhood rather than per octree cell, so it has none of the cell-border
//!   artefacts the thesis reports; Max's weights rather than areas, exact on a
//!   sphere).
//! A fit gives a direction, not a side: orientation chooses the side, from a
//! direction, a sensor position, the centroid, or by propagation over a minimum
//! spanning tree of the neighbourhood graph (Hoppe et al. 1992) for closed or
//! concave objects.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/octree/Octree.h>

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace scandiff {

enum class NormalModel { Plane, Quadric, Triangulation };

struct NormalOrientation
{
    enum class Kind {
        None,                 //!< as fitted (the side is arbitrary)
        Direction,            //!< n . direction >= 0
        TowardsSensor,        //!< towards the scanner that saw the point
        AwayFromCentroid,     //!< outward, seen from the cloud's centroid
        TowardsCentroid,      //!< inward
        MinimumSpanningTree   //!< propagated along the neighbourhood graph's MST
    };
    Kind kind = Kind::Direction;
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ(); //!< Direction
    //! TowardsSensor: this position (global coordinates); absent: the cloud's
    //! sensor poses (each point towards the nearest one).
    std::optional<Eigen::Vector3d> sensor;
    //! Away/TowardsCentroid: this point, in the cloud's frame (its local
    //! coordinates); absent: the centroid of the cloud's points. For a cloud
    //! that is a part of a larger one (scandiff-mpi's tiles) whose centroid counts.
    std::optional<Eigen::Vector3d> centroid;
    //! MinimumSpanningTree: neighbours per point in the graph. Each connected
    //! part of the graph starts from its highest point, oriented upwards (+Z),
    //! where an outward normal of a closed surface points up.
    std::size_t mstNeighbours = 10;
};

struct NormalParams
{
    //! Neighbours within this radius (m, > 0); absent: the `knn` nearest.
    std::optional<double> radius;
    std::size_t knn = 12; //!< >= 3 (>= 6 for the quadric)
    //! With a radius, plane model: a point with fewer than this many points
    //! within the radius is fitted on this many nearest ones instead (0:
    //! never). A scan's spacing grows with range: a radius wide enough for
    //! the noise near the scanner holds one or two points on a far wall.
    std::size_t minNeighbours = 0;
    NormalModel model = NormalModel::Plane;
    NormalOrientation orientation;
    bool flip = false; //!< reverse every normal after orienting it
};

namespace fields {
//! Smallest eigenvalue of the neighbourhood's covariance over their sum: 0 on
//! a plane, 1/3 for an isotropic blob (Pauly et al. 2002, "surface variation").
inline constexpr const char* kSurfaceVariation = "surface_variation";
} // namespace fields

struct NormalResult
{
    //! Unit normals, one per point; (0, 0, 0) where the neighbourhood does not
    //! determine a plane (fewer than 3 points, or all on a line).
    std::vector<Eigen::Vector3f> normals;
    ScalarField surfaceVariation; //!< fields::kSurfaceVariation, NaN where no normal
    std::size_t unfitted = 0;     //!< points left without a normal
    std::size_t components = 0;   //!< MST orientation: connected parts of the graph
};

//! Normals of every point. Throws Error(InvalidArgument) for bad parameters or
//! a sensor orientation without any sensor, Error(InvalidData) for an empty
//! cloud or non-finite coordinates, Error(Cancelled).
NormalResult computeNormals(const PointCloud& cloud, const NormalParams& params, ProgressObserver* progress = nullptr);

//! Plane normals (the least-squares plane of the `knn` >= 3 nearest points)
//! of the points `indices` of `cloud` only, turned towards +Z, written to
//! their slots of `normals` (one per point of the cloud; a zero vector where
//! no plane fits): for a caller that needs some of them, in turns, and holds
//! the cloud's octree (`tree`, built on its positions). The same normals as
//! computeNormals with the same neighbours and orientation. With `spread`
//! (one slot per point too), each fitted point's neighbours' RMS distance to
//! their plane (m; 0 where no plane fits): how rough the surface is there.
void planeNormalsOf(const PointCloud& cloud, const octree::Octree& tree, const std::vector<std::uint32_t>& indices, std::size_t knn,
                    std::vector<Eigen::Vector3f>& normals, std::vector<float>* spread = nullptr);

//! Orients `normals` (one per point of `cloud`, zero vectors are left alone)
//! in place; returns the number of connected parts for the MST orientation
//! (else 0). Throws like computeNormals.
std::size_t orientNormals(const PointCloud& cloud, std::vector<Eigen::Vector3f>& normals, const NormalOrientation& orientation,
                          ProgressObserver* progress = nullptr);

//! "+z", "-x", "0.2,0,1" (a direction), "sensor", "sensor:X,Y,Z", "centroid"
//! (away from it), "-centroid" (towards it), "mst", "none". Throws
//! Error(InvalidArgument) naming the accepted forms.
NormalOrientation parseNormalOrientation(const std::string& text);

} // namespace scandiff
