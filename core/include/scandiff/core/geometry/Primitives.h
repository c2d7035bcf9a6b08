// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Geometric primitives (plane, sphere, cylinder, cone, torus): signed distances and
//! least-squares fits, in global coordinates. Used by the distance-to-primitive
//! and unrolling tools (thesis 000 annex C, "développement": a cooling tower
//! unrolled about its axis) and by primitive extraction.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/Table.h>

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace scandiff {

enum class PrimitiveKind { Plane, Sphere, Cylinder, Cone, Torus };

struct Primitive
{
    PrimitiveKind kind = PrimitiveKind::Plane;
    //! Plane: a point of it. Sphere, torus: the centre. Cylinder: a point of
    //! the axis (the foot of the points' centroid). Cone: the apex.
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
    //! Plane: the unit normal. Cylinder, torus: the unit axis. Cone: the unit
    //! axis from the apex into the cone. Sphere: unused.
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
    double radius = 0;      //!< sphere, cylinder; torus: the major radius (m)
    double halfAngle = 0;   //!< cone: between the axis and the surface (radians, in (0, pi/2))
    double minorRadius = 0; //!< torus: the tube's radius (m)
};

//! Signed distance from p (global) to the primitive's surface: on the normal's
//! side of a plane, outside a sphere, a cylinder, a cone or a torus's tube are
//! positive.
double signedDistance(const Primitive& primitive, const Eigen::Vector3d& p);

struct PrimitiveFit
{
    Primitive primitive;
    double rms = 0;           //!< of the signed distances of every point
    std::size_t points = 0;   //!< points the fit used
};

//! The least-squares primitive of `kind` through the cloud's points, minimising
//! the sum of squared distances to its surface: a plane by its principal axes
//! (closed form), a sphere from its algebraic fit, a cylinder and a cone from
//! their axes found from the point normals (computed when the cloud has none),
//! then refined by Levenberg-Marquardt (Eigen) on the geometric distances.
//! Clouds above 200,000 points are fitted on an even sample of them. Throws
//! Error(InvalidData) when the points do not determine the primitive (too
//! few, collinear, a fit that does not converge).
PrimitiveFit fitPrimitive(const PointCloud& cloud, PrimitiveKind kind, ProgressObserver* progress = nullptr);

//! The sphere of the algebraic fit (Kasa) through `points`, given relative to
//! `centre`; empty when they determine none. A start for refinePrimitive().
std::optional<Primitive> algebraicSphere(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& centre);

//! The cylinder whose axis is orthogonal to every normal (the smallest axis
//! of their second moments) and whose section is the algebraic circle of the
//! points across that axis: a start for refinePrimitive(). Points relative
//! to `centre` (the result is global); empty when they determine none.
std::optional<Primitive> cylinderFromNormals(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals,
                                             const Eigen::Vector3d& centre);

//! Kasa's algebraic circle through 2D points: its centre and radius; false
//! when they determine none. A start for a cylinder's section.
bool fitCircle(const std::vector<Eigen::Vector2d>& points, Eigen::Vector2d& centre, double& radius);

//! A refined primitive and the standard uncertainty of its parameters.
struct PrimitiveRefinement
{
    Primitive primitive;
    double rms = 0; //!< of the signed distances of the points
    //! Standard uncertainties (1 sigma, from the residuals' variance and the
    //! Jacobian at the solution), by name: "direction_deg" (the normal's or
    //! axis's angle), "offset" (plane), "centre"/"apex"/"axis_position" (m,
    //! the norm over the free directions), "radius", "minor_radius",
    //! "half_angle_deg".
    std::vector<std::pair<std::string, double>> uncertainty;
};

//! The least-squares primitive (geometric distances, Levenberg-Marquardt)
//! through `points`, given relative to `centre` (so no UTM magnitude reaches
//! the solver), started from `initial` (global). Every kind, the torus
//! included. Throws Error(InvalidData) with fewer points than parameters or
//! a diverging refinement.
PrimitiveRefinement refinePrimitive(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& centre,
                                    const Primitive& initial);

PrimitiveKind parsePrimitiveKind(const std::string& name);
const char* primitiveKindName(PrimitiveKind kind);

//! "plane:PX,PY,PZ,NX,NY,NZ", "sphere:CX,CY,CZ,R", "cylinder:PX,PY,PZ,DX,DY,DZ,R",
//! "cone:AX,AY,AZ,DX,DY,DZ,HALF_ANGLE_DEGREES", "torus:CX,CY,CZ,DX,DY,DZ,R,r": the text primitiveText() writes
//! and users paste. Directions are normalised. Throws Error(InvalidArgument).
Primitive parsePrimitive(const std::string& text);
//! The inverse of parsePrimitive, every double kept.
std::string primitiveText(const Primitive& primitive);

//! One row per parameter (name, value): what the tools give as a table.
Table primitiveTable(const Primitive& primitive, std::optional<double> rms = std::nullopt);

} // namespace scandiff
