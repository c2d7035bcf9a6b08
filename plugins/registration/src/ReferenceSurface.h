// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The surface a moving cloud is registered on: a cloud (closest points by the
//! octree, normals from the cloud or fitted) or a mesh (closest points on the
//! triangles by the cloud-to-mesh search). Queries and answers are in double,
//! relative to a frame origin chosen by the caller (internal to the plugin).

#include <scandiff/core/Mesh.h>
#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/plugins/registration/Icp.h>
#include <scandiff/octree/Octree.h>

#include <Eigen/Core>

#include <limits>
#include <memory>
#include <vector>

namespace scandiff::plugins::detail {

struct ClosestPoints
{
    std::vector<Eigen::Vector3d> points;  //!< frame coordinates
    std::vector<Eigen::Vector3d> normals; //!< unit, zero where there is none
    std::vector<char> found;
    //! How rough the reference is where each closest point lies: its
    //! neighbours' RMS distance to their fitted plane (m). Empty when the
    //! surface does not know (a mesh, a cloud with its own normals).
    std::vector<double> spread;
};

class ReferenceSurface
{
public:
    virtual ~ReferenceSurface() = default;
    //! The closest point of the surface to each query (frame coordinates);
    //! with a finite `maxDistance`, only within it (the others not found),
    //! which makes queries far from the surface cheap.
    virtual void closest(const std::vector<Eigen::Vector3d>& queries, ClosestPoints& out,
                         double maxDistance = std::numeric_limits<double>::infinity()) const = 0;
    //! The frame's origin in global coordinates: the centre of the surface's box.
    const Eigen::Vector3d& frameOrigin() const { return origin_; }

protected:
    Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
};

//! A cloud: `needNormals` fits them when the cloud has none (a plane on
//! `normalNeighbours` points, turned towards +Z), each where a closest point
//! first lands. The cloud must outlive the surface.
std::unique_ptr<ReferenceSurface> cloudSurface(const PointCloud& cloud, bool needNormals, std::size_t normalNeighbours,
                                               const ProgressObserver* cancel = nullptr);
//! A mesh (triangle normals by vertex order). The mesh must outlive the surface.
std::unique_ptr<ReferenceSurface> meshSurface(const Mesh& mesh);

//! icpRegister on a surface built once (several registrations on one reference).
IcpResult icpOnSurface(const PointCloud& moving, const ReferenceSurface& surface, const IcpParams& params, ProgressObserver* progress);

} // namespace scandiff::plugins::detail
