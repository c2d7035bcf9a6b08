// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Fine registration: the iterative closest point method (Besl and McKay
//! 1992; point-to-plane after Chen and Medioni 1992) with what a comparison
//! of two epochs needs on top:
//! - exact closest points (the octree's batch queries; a mesh reference
//!   through the cloud-to-mesh search), in double in a frame centred on the
//!   reference, so UTM coordinates lose nothing;
//! - degrees of freedom constrained inside the solver (RigidMotion.h);
//! - a maximum correspondence distance, a trimmed overlap ratio, a robust
//!   kernel whose scale follows the residuals (1.4826 x their median absolute
//!   value), switched on once the plain iterations have converged (a scale
//!   taken while the clouds are still far apart would down-weight the far
//!   points that hold the rotation);
//! - the change-robust mode of thesis 000 §1.4: only the correspondences
//!   below a distance that shrinks from one iteration to the next count (here
//!   3 x the robust scale of the residuals, never below the median spacing of
//!   the correspondences, never growing), so a moved wall or a new object does
//!   not pull the result; what is finally left out is marked in the field
//!   registration_excluded.

#include <scandiff/core/Mesh.h>
#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/plugins/registration/RegistrationReport.h>
#include <scandiff/plugins/registration/RigidMotion.h>

#include <Eigen/Core>

#include <cstdint>
#include <optional>

namespace scandiff::plugins {

enum class IcpMethod { PointToPoint, PointToPlane };
enum class RobustKernel { None, Huber, Cauchy, GemanMcClure };

//! What the change-robust mode registers on, of the moving cloud. Either way
//! the ASPRS classes ground (2) and building (6) when the cloud has them.
enum class StableParts {
    //! Every planar part (12 neighbours near a plane): ground, walls, roofs,
    //! ceilings; what grows (vegetation) stays out, what is built or raised
    //! (a roof, a car) counts.
    Surfaces,
    //! The ground a morphological filter finds (GroundFilter.h) and the walls
    //! first; then, from there, the other planar parts too, for the
    //! horizontal position and the heading only: for epochs where roofs and
    //! objects may have been raised (on the real samp11 pair with every
    //! object raised 0.3-1.5 m: 4.6 cm instead of 8.8 cm), at the cost of
    //! what the filter misses of the ground (samp53: 8.6 cm instead of 1.6).
    Ground,
};

struct IcpParams
{
    IcpMethod method = IcpMethod::PointToPlane;
    DofConstraint constraint;
    //! Correspondences farther than this (m) are left out; absent: none.
    std::optional<double> maxDistance;
    //! The fraction of the correspondences kept, the closest (0 < f <= 1).
    double overlap = 1.0;
    RobustKernel kernel = RobustKernel::None;
    bool changeRobust = false;
    StableParts stableParts = StableParts::Surfaces;
    //! Moving points used: at most this many, drawn at random (all if 0).
    std::size_t sampleCount = 50000;
    std::uint64_t seed = 0;
    std::size_t maxIterations = 100;
    //! Converged when an iteration moves the points by less than this (m), or
    //! the RMS changes by less than this fraction.
    double moveTolerance = 1e-6;
    double rmsTolerance = 1e-7;
    //! Reference normals for point-to-plane (when the reference cloud has
    //! none): a plane fit on this many neighbours.
    std::size_t normalNeighbours = 12;
    //! The moving cloud's starting motion (global coordinates), identity by default.
    Eigen::Matrix4d initial = Eigen::Matrix4d::Identity();
    //! The report's residual statistics and the residual fields over every
    //! moving point (true), or the statistics over the iterations' sample
    //! only, with no field (false: a caller weighing many candidate motions,
    //! for which the pass over a 300 k-point station costs more than the
    //! iterations).
    bool residualOfEveryPoint = true;
};

namespace fields {
//! The signed residual of each moving point after registration: along the
//! reference normal for point-to-plane and a mesh, the distance for point-to-point.
inline constexpr const char* kRegistrationResidual = "registration_residual";
//! 1 for the points left out of the final correspondences (beyond the
//! distance, trimmed, or treated as change), 0 for those used.
inline constexpr const char* kRegistrationExcluded = "registration_excluded";
} // namespace fields

struct IcpResult
{
    RegistrationReport report;
    ScalarField residual; //!< fields::kRegistrationResidual, one per moving point
    ScalarField excluded; //!< fields::kRegistrationExcluded
};

//! Registers `moving` on a reference cloud or mesh (the other pointer null).
//! Throws Error(InvalidArgument) for bad parameters, Error(InvalidData) for an
//! empty cloud, too few correspondences, or a mesh without triangles;
//! Error(Cancelled).
IcpResult icpRegister(const PointCloud& moving, const PointCloud* referenceCloud, const Mesh* referenceMesh,
                      const IcpParams& params, ProgressObserver* progress = nullptr);

IcpMethod parseIcpMethod(const std::string& text);
RobustKernel parseRobustKernel(const std::string& text);

} // namespace scandiff::plugins
