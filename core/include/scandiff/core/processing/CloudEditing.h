// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Merging, transforming and cropping clouds (thesis 000 annex C:
//! "translation; scaling; merge"). Every computation on coordinates is done
//! in double on the global coordinates (origin + local), so clouds of
//! different global shifts meet without losing their millimetres.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>

#include <Eigen/Core>

#include <string>
#include <vector>

namespace scandiff {

namespace fields {
//! Which input a merged point comes from: 0 for the first cloud, 1 for the next...
inline constexpr const char* kSourceIndex = "source_index";
} // namespace fields

//! One cloud holding every point of `clouds`, in their order, with the field
//! fields::kSourceIndex. The origin is the clouds' common one, or when they
//! differ the one suggestOrigin() picks for all of them together. Fields are
//! matched by name (NaN where a cloud lacks one); points of a cloud without
//! colours get white and without normals (0, 0, 0) when others have them;
//! sensor poses are all kept; the transformation history starts anew.
//! Throws Error(InvalidArgument) when `clouds` is empty.
PointCloud mergeClouds(const std::vector<const PointCloud*>& clouds, ProgressObserver* progress = nullptr);

//! The cloud moved by `matrix` (global' = matrix * global, homogeneous; its
//! last row must be 0 0 0 1): positions in double, normals by the inverse
//! transpose of the linear part (renormalised), sensor poses moved and turned;
//! a new origin chosen for the moved points (suggestOrigin), and the step added
//! to the transformation history with `description`. Throws
//! Error(InvalidArgument) for a non-finite, singular or projective matrix.
PointCloud transformCloud(const PointCloud& cloud, const Eigen::Matrix4d& matrix, const std::string& description,
                          ProgressObserver* progress = nullptr);

//! The cloud moved back by the inverse of the last transformation of its
//! history, which then no longer holds it: positions to the float step of the
//! local coordinates (0.06 mm within a kilometre of the cloud's origin). Throws
//! Error(InvalidArgument) when the history is empty.
PointCloud undoLastTransform(const PointCloud& cloud, ProgressObserver* progress = nullptr);

//! A rotation about an axis through `centre` (right hand, degrees), a uniform
//! scale about `centre`, a translation: the matrices transformCloud applies.
Eigen::Matrix4d rotationAbout(const Eigen::Vector3d& axis, double degrees, const Eigen::Vector3d& centre);
Eigen::Matrix4d scaleAbout(double factor, const Eigen::Vector3d& centre);
Eigen::Matrix4d translation(const Eigen::Vector3d& offset);

//! Rz(heading) Ry(pitch) Rx(roll), angles in degrees: how oriented boxes,
//! sensor poses and typed motions turn (as a quaternion and as a matrix);
//! and back (pitch in [-90, 90]).
Eigen::Quaterniond orientationFromHeadingPitchRoll(double heading, double pitch, double roll);
Eigen::Matrix3d rotationFromHeadingPitchRoll(double heading, double pitch, double roll);
Eigen::Vector3d headingPitchRollOf(const Eigen::Matrix3d& rotation);

//! A rigid motion as a user types it or drags it: turned about a centre by
//! heading, pitch and roll (degrees), then moved by `offset` (metres).
struct RigidMotion
{
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    double heading = 0, pitch = 0, roll = 0;
};
//! The matrix of x' = R (x - centre) + centre + offset, R as above.
Eigen::Matrix4d rigidMotionMatrix(const RigidMotion& motion, const Eigen::Vector3d& centre);
//! The motion a rigid matrix makes about `centre` (its rotation part must be a rotation).
RigidMotion rigidMotionOf(const Eigen::Matrix4d& matrix, const Eigen::Vector3d& centre);

//! A box in global coordinates: centre, full side lengths along its own axes,
//! and the rotation from its axes to the world's (identity: axis-aligned).
struct CropBox
{
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    Eigen::Vector3d size = Eigen::Vector3d::Zero();
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
};

//! A polygon drawn looking along `axis` (0 x, 1 y, 2 z): its vertices are the
//! two other global coordinates in cyclic order (y z for x, z x for y, x y for z).
struct CropPolygon
{
    std::vector<Eigen::Vector2d> vertices; //!< at least 3; closed implicitly
    int axis = 2;
};

//! A box from text "CX,CY,CZ,SX,SY,SZ[,HEADING[,PITCH,ROLL]]": centre and side
//! lengths (m), then degrees about Z, Y and X in turn (as sensor poses).
//! Throws Error(InvalidArgument).
CropBox parseOrientedBox(const std::string& text);
//! The text parseOrientedBox reads back as the same box (to 0.1 mm and 1e-6 degree).
std::string orientedBoxText(const CropBox& box);

//! Indices (increasing) of the points inside the box, faces included.
std::vector<std::size_t> pointsInBox(const PointCloud& cloud, const CropBox& box);
//! Indices (increasing) of the points whose projection lies inside the polygon
//! (even-odd rule, so a self-crossing polygon keeps what a fill would).
//! Throws Error(InvalidArgument) for fewer than 3 vertices or an axis outside 0..2.
std::vector<std::size_t> pointsInPolygon(const PointCloud& cloud, const CropPolygon& polygon);
//! Indices (increasing) of the points that a view shows inside a polygon
//! drawn on the screen (the scissors): `globalToScreen` takes global
//! coordinates (homogeneous) to the screen's, before the division by w; the
//! polygon's vertices are in the same screen units. Points behind the eye
//! (w <= 0) are outside. Even-odd rule. Throws Error(InvalidArgument) for fewer
//! than 3 vertices or non-finite ones.
std::vector<std::size_t> pointsInScreenPolygon(const PointCloud& cloud, const Eigen::Matrix4d& globalToScreen,
                                               const std::vector<Eigen::Vector2d>& polygon);
//! The complement of a sorted index list among `count` points.
std::vector<std::size_t> complementOf(const std::vector<std::size_t>& sorted, std::size_t count);

} // namespace scandiff
