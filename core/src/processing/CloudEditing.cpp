// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/processing/CloudEditing.h>
#include <scandiff/core/geometry/PlanarRings.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/core/TextLists.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <limits>

namespace scandiff {

namespace {

constexpr double kPi = 3.14159265358979323846;

template <typename Body>
void forEachPoint(std::size_t n, Body&& body)
{
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
            body(i);
    });
}

BoundingBox unionOf(const BoundingBox& a, const BoundingBox& b)
{
    if (a.empty)
        return b;
    if (b.empty)
        return a;
    BoundingBox u;
    u.empty = false;
    u.min = a.min.cwiseMin(b.min);
    u.max = a.max.cwiseMax(b.max);
    return u;
}

} // namespace

PointCloud mergeClouds(const std::vector<const PointCloud*>& clouds, ProgressObserver* progress)
{
    if (clouds.empty())
        throw Error(ErrorCode::InvalidArgument, "merge: no cloud to merge");
    bool sameOrigin = true;
    BoundingBox bounds;
    std::size_t total = 0;
    bool colours = false, normals = false;
    std::vector<std::string> fieldNames;
    std::vector<double> fieldOffsets;
    std::vector<bool> fieldIsDouble;
    for (const PointCloud* c : clouds) {
        sameOrigin = sameOrigin && c->origin() == clouds.front()->origin();
        bounds = unionOf(bounds, c->bounds());
        total += c->size();
        colours = colours || c->hasColors();
        normals = normals || c->hasNormals();
        for (const auto& f : c->fields()) {
            const auto known = std::find(fieldNames.begin(), fieldNames.end(), f.name());
            if (known == fieldNames.end()) {
                fieldNames.push_back(f.name());
                fieldOffsets.push_back(f.offset());
                fieldIsDouble.push_back(f.isDouble());
            } else if (f.isDouble()) {
                fieldIsDouble[static_cast<std::size_t>(known - fieldNames.begin())] = true;
            }
        }
    }
    PointCloud merged;
    merged.name = "merged";
    merged.setOrigin(sameOrigin ? clouds.front()->origin() : suggestOrigin(bounds));
    // Clouds read from one survey's files share their grid: the merge keeps it.
    bool sameGrid = true;
    for (const PointCloud* c : clouds)
        sameGrid = sameGrid && c->sourceGrid() == clouds.front()->sourceGrid();
    if (sameGrid)
        merged.setSourceGrid(clouds.front()->sourceGrid());
    // One system for all, or none: merging clouds of different systems gives
    // coordinates in no system at all (with a warning).
    bool sameCrs = true;
    for (const PointCloud* c : clouds)
        sameCrs = sameCrs && c->crsWkt() == clouds.front()->crsWkt();
    if (sameCrs)
        merged.setCrsWkt(clouds.front()->crsWkt());
    else
        logWarning("merge: the clouds are in different coordinate reference systems; the merged cloud has none");
    bool exact = false; // a cloud keeps its file's exact coordinates: the merge keeps them all
    for (const PointCloud* c : clouds)
        exact = exact || !c->positionResiduals().empty();
    merged.resize(total);
    if (exact)
        merged.positionResiduals().assign(total, Eigen::Vector3f::Zero());
    if (colours)
        merged.enableColors();
    if (normals)
        merged.enableNormals();
    for (std::size_t f = 0; f < fieldNames.size(); ++f) {
        ScalarField& field = merged.addField(fieldNames[f]);
        field.setOffset(fieldOffsets[f]);
        if (fieldIsDouble[f])
            field.keepDoubles();
    }
    ScalarField& source = merged.addField(fields::kSourceIndex);
    ProgressTicker ticker(progress, "Merging", total);
    std::size_t at = 0;
    for (std::size_t k = 0; k < clouds.size(); ++k) {
        const PointCloud& c = *clouds[k];
        const Eigen::Vector3d shift = c.origin() - merged.origin();
        const std::size_t n = c.size();
        forEachPoint(n, [&](std::size_t i) {
            const Eigen::Vector3d local = (exact ? c.exactLocalPosition(i) : c.positions()[i].cast<double>()) + shift;
            merged.positions()[at + i] = local.cast<float>();
            if (exact)
                merged.positionResiduals()[at + i] = (local - merged.positions()[at + i].cast<double>()).cast<float>();
            source.values()[at + i] = static_cast<float>(k);
        });
        if (colours)
            std::fill_n(merged.enableColors().begin() + static_cast<std::ptrdiff_t>(at), n, Rgb8{255, 255, 255});
        if (c.hasColors())
            std::copy(c.colors().begin(), c.colors().end(), merged.enableColors().begin() + static_cast<std::ptrdiff_t>(at));
        if (c.hasNormals())
            std::copy(c.normals().begin(), c.normals().end(), merged.enableNormals().begin() + static_cast<std::ptrdiff_t>(at));
        for (const auto& f : c.fields()) {
            if (f.name() == fields::kSourceIndex)
                continue; // an earlier merge's: this merge's own replaces it
            ScalarField& target = *merged.field(f.name());
            // Re-expressed around the merged field's offset, in double.
            const double delta = f.offset() - target.offset();
            if (target.isDouble())
                forEachPoint(n, [&](std::size_t i) { target.setValue(at + i, f.value(i)); });
            else
                forEachPoint(n, [&](std::size_t i) {
                    target.values()[at + i] = static_cast<float>(static_cast<double>(f.values()[i]) + delta);
                });
        }
        for (const auto& pose : c.sensors())
            merged.sensors().push_back(pose);
        at += n;
        ticker.step(n);
    }
    // Exact forms were gathered as doubles: the smallest that holds them all.
    for (std::size_t f = 0; f < fieldNames.size(); ++f)
        if (fieldIsDouble[f])
            merged.field(fieldNames[f])->compact(true);
    return merged;
}

PointCloud undoLastTransform(const PointCloud& cloud, ProgressObserver* progress)
{
    if (cloud.transformHistory().empty())
        throw Error(ErrorCode::InvalidArgument, "undo: '" + cloud.name + "' has no transformation to undo");
    const AppliedTransform last = cloud.transformHistory().back();
    PointCloud out = transformCloud(cloud, last.matrix.inverse(), "undo", progress);
    // Neither the undone step nor its undoing stays in the history.
    out.transformHistory().pop_back();
    out.transformHistory().pop_back();
    return out;
}

Eigen::Matrix4d rotationAbout(const Eigen::Vector3d& axis, double degrees, const Eigen::Vector3d& centre)
{
    if (!(axis.norm() > 0) || !axis.allFinite() || !std::isfinite(degrees))
        throw Error(ErrorCode::InvalidArgument, "rotation: the axis must be a non-zero vector and the angle finite");
    const Eigen::Matrix3d r = Eigen::AngleAxisd(degrees * kPi / 180.0, axis.normalized()).toRotationMatrix();
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = r;
    m.topRightCorner<3, 1>() = centre - r * centre;
    return m;
}

Eigen::Matrix4d scaleAbout(double factor, const Eigen::Vector3d& centre)
{
    if (!(factor > 0) || !std::isfinite(factor))
        throw Error(ErrorCode::InvalidArgument, "scale: the factor must be > 0");
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() *= factor;
    m.topRightCorner<3, 1>() = centre * (1 - factor);
    return m;
}

Eigen::Matrix4d translation(const Eigen::Vector3d& offset)
{
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topRightCorner<3, 1>() = offset;
    return m;
}

PointCloud transformCloud(const PointCloud& cloud, const Eigen::Matrix4d& matrix, const std::string& description,
                          ProgressObserver* progress)
{
    if (!matrix.allFinite() || matrix.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
        throw Error(ErrorCode::InvalidArgument, "transform: the matrix must be finite with a last row of 0 0 0 1");
    const Eigen::Matrix3d linear = matrix.topLeftCorner<3, 3>();
    const Eigen::Vector3d offset = matrix.topRightCorner<3, 1>();
    const double determinant = linear.determinant();
    if (!(std::abs(determinant) > 1e-12))
        throw Error(ErrorCode::InvalidArgument, "transform: the matrix is singular (it would flatten the cloud)");
    PointCloud out = cloud.clone();
    out.setSourceGrid(std::nullopt); // moved points leave the file's grid
    out.dropPositionResiduals();     // and the file's exact coordinates
    // The moved cloud's bounds from the moved corners of its box, for its origin.
    BoundingBox moved;
    const BoundingBox box = cloud.bounds();
    if (!box.empty) {
        for (int corner = 0; corner < 8; ++corner) {
            const Eigen::Vector3d p((corner & 1) ? box.max.x() : box.min.x(), (corner & 2) ? box.max.y() : box.min.y(),
                                    (corner & 4) ? box.max.z() : box.min.z());
            BoundingBox one;
            one.empty = false;
            one.min = one.max = linear * p + offset;
            moved = unionOf(moved, one);
        }
    }
    const Eigen::Vector3d newOrigin = suggestOrigin(moved);
    out.setOrigin(newOrigin);
    // global' - origin' = L (origin + local) + t - origin', with the constant
    // part summed once in double.
    const Eigen::Vector3d constant = linear * cloud.origin() + offset - newOrigin;
    ProgressTicker ticker(progress, "Transforming", cloud.size());
    forEachPoint(cloud.size(), [&](std::size_t i) {
        out.positions()[i] = (linear * cloud.positions()[i].cast<double>() + constant).cast<float>();
    });
    if (cloud.hasNormals()) {
        const Eigen::Matrix3d normalMatrix = linear.inverse().transpose();
        forEachPoint(cloud.size(), [&](std::size_t i) {
            const Eigen::Vector3d n = normalMatrix * cloud.normals()[i].cast<double>();
            const double length = n.norm();
            out.enableNormals()[i] = length > 0 ? Eigen::Vector3f((n / length).cast<float>()) : Eigen::Vector3f::Zero();
        });
    }
    ticker.step(cloud.size());
    // A sensor keeps its pose relative to the points: moved, and turned by the
    // rotation nearest to the linear part (its polar factor).
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(linear, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d rotation = svd.matrixU() * svd.matrixV().transpose();
    if (rotation.determinant() < 0)
        rotation = -rotation;
    for (auto& pose : out.sensors()) {
        pose.position = linear * pose.position + offset;
        pose.orientation = Eigen::Quaterniond(rotation * pose.orientation.toRotationMatrix()).normalized();
    }
    out.transformHistory().push_back({matrix, description});
    return out;
}

CropBox parseOrientedBox(const std::string& text)
{
    const std::vector<double> v = parseNumberList(text, "the oriented box");
    if (v.size() != 6 && v.size() != 7 && v.size() != 9)
        throw Error(ErrorCode::InvalidArgument, "an oriented box is CX,CY,CZ,SX,SY,SZ[,HEADING[,PITCH,ROLL]] (sizes in m, angles in degrees)");
    CropBox box;
    box.centre = Eigen::Vector3d(v[0], v[1], v[2]);
    box.size = Eigen::Vector3d(v[3], v[4], v[5]);
    const double heading = v.size() > 6 ? v[6] : 0, pitch = v.size() > 7 ? v[7] : 0, roll = v.size() > 8 ? v[8] : 0;
    box.rotation = rotationFromHeadingPitchRoll(heading, pitch, roll);
    return box;
}

Eigen::Quaterniond orientationFromHeadingPitchRoll(double heading, double pitch, double roll)
{
    // Heading about Z, then pitch about Y, then roll about X.
    constexpr double kPi = 3.14159265358979323846;
    return Eigen::AngleAxisd(heading * kPi / 180, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch * kPi / 180, Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(roll * kPi / 180, Eigen::Vector3d::UnitX());
}

Eigen::Matrix3d rotationFromHeadingPitchRoll(double heading, double pitch, double roll)
{
    return orientationFromHeadingPitchRoll(heading, pitch, roll).toRotationMatrix();
}

Eigen::Vector3d headingPitchRollOf(const Eigen::Matrix3d& r)
{
    // The inverse of Rz(heading) Ry(pitch) Rx(roll).
    const double degrees = 180.0 / 3.14159265358979323846;
    return {std::atan2(r(1, 0), r(0, 0)) * degrees, std::asin(std::clamp(-r(2, 0), -1.0, 1.0)) * degrees,
            std::atan2(r(2, 1), r(2, 2)) * degrees};
}

Eigen::Matrix4d rigidMotionMatrix(const RigidMotion& motion, const Eigen::Vector3d& centre)
{
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    const Eigen::Matrix3d r = rotationFromHeadingPitchRoll(motion.heading, motion.pitch, motion.roll);
    m.topLeftCorner<3, 3>() = r;
    m.topRightCorner<3, 1>() = centre + motion.offset - r * centre;
    return m;
}

RigidMotion rigidMotionOf(const Eigen::Matrix4d& matrix, const Eigen::Vector3d& centre)
{
    const Eigen::Matrix3d r = matrix.topLeftCorner<3, 3>();
    const Eigen::Vector3d angles = headingPitchRollOf(r);
    RigidMotion motion;
    motion.heading = angles.x();
    motion.pitch = angles.y();
    motion.roll = angles.z();
    motion.offset = matrix.topRightCorner<3, 1>() - centre + r * centre;
    return motion;
}

std::string orientedBoxText(const CropBox& box)
{
    const Eigen::Vector3d angles = headingPitchRollOf(box.rotation);
    const double heading = angles.x(), pitch = angles.y(), roll = angles.z();
    char text[256];
    std::snprintf(text, sizeof text, "%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.6g,%.6g,%.6g", box.centre.x(), box.centre.y(), box.centre.z(),
                  box.size.x(), box.size.y(), box.size.z(), heading, pitch, roll);
    return text;
}

std::vector<std::size_t> pointsInBox(const PointCloud& cloud, const CropBox& box)
{
    if (!box.size.allFinite() || (box.size.array() < 0).any() || !box.centre.allFinite() || !box.rotation.allFinite())
        throw Error(ErrorCode::InvalidArgument, "crop: the box must have finite, non-negative sizes");
    // In the box's frame, relative to its centre: global - centre = origin - centre + local.
    const Eigen::Matrix3d toBox = box.rotation.transpose();
    const Eigen::Vector3d shift = toBox * (cloud.origin() - box.centre);
    const Eigen::Vector3d half = box.size / 2;
    std::vector<std::size_t> inside;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d p = toBox * cloud.positions()[i].cast<double>() + shift;
        if ((p.array().abs() <= half.array()).all())
            inside.push_back(i);
    }
    return inside;
}

std::vector<std::size_t> pointsInPolygon(const PointCloud& cloud, const CropPolygon& polygon)
{
    if (polygon.vertices.size() < 3)
        throw Error(ErrorCode::InvalidArgument, "crop: a polygon needs at least 3 vertices");
    if (polygon.axis < 0 || polygon.axis > 2)
        throw Error(ErrorCode::InvalidArgument, "crop: the polygon's axis must be x, y or z");
    for (const auto& v : polygon.vertices)
        if (!v.allFinite())
            throw Error(ErrorCode::InvalidArgument, "crop: the polygon's vertices must be finite");
    const int a = (polygon.axis + 1) % 3, b = (polygon.axis + 2) % 3;
    const Eigen::Vector2d origin(cloud.origin()[a], cloud.origin()[b]);
    // The vertices relative to the cloud's origin, so the test works on local
    // magnitudes (a double's rounding stays far below a millimetre).
    std::vector<Eigen::Vector2d> v;
    for (const auto& p : polygon.vertices)
        v.push_back(p - origin);
    const std::size_t m = v.size();
    std::vector<char> inside(cloud.size(), 0);
    forEachPoint(cloud.size(), [&](std::size_t i) {
        const double x = cloud.positions()[i][a], y = cloud.positions()[i][b];
        bool in = false;
        for (std::size_t j = 0, k = m - 1; j < m; k = j++) {
            // Crossing number: an edge counts when it straddles the point's
            // horizontal line (half-open, so a vertex on it counts once).
            if ((v[j].y() > y) != (v[k].y() > y)) {
                const double cross = v[k].x() + (y - v[k].y()) * (v[j].x() - v[k].x()) / (v[j].y() - v[k].y());
                if (x < cross)
                    in = !in;
            }
        }
        inside[i] = in;
    });
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (inside[i])
            out.push_back(i);
    return out;
}

std::vector<std::size_t> pointsInScreenPolygon(const PointCloud& cloud, const Eigen::Matrix4d& globalToScreen,
                                               const std::vector<Eigen::Vector2d>& polygon)
{
    if (polygon.size() < 3)
        throw Error(ErrorCode::InvalidArgument, "segment by polygon: a polygon needs at least 3 vertices");
    for (const auto& v : polygon)
        if (!v.allFinite())
            throw Error(ErrorCode::InvalidArgument, "segment by polygon: the polygon's vertices must be finite");
    // The cloud's origin folded into the matrix, in double: each point is then
    // projected from its small local coordinates.
    Eigen::Matrix4d toOrigin = Eigen::Matrix4d::Identity();
    toOrigin.block<3, 1>(0, 3) = cloud.origin();
    const Eigen::Matrix4d localToScreen = globalToScreen * toOrigin;
    std::vector<char> inside(cloud.size(), 0);
    forEachPoint(cloud.size(), [&](std::size_t i) {
        const Eigen::Vector4d h = localToScreen * cloud.positions()[i].cast<double>().homogeneous();
        if (!(h.w() > 0) || !h.allFinite())
            return; // behind the eye, or not a point
        inside[i] = containsPoint(polygon, Eigen::Vector2d(h.x() / h.w(), h.y() / h.w()));
    });
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (inside[i])
            out.push_back(i);
    return out;
}

std::vector<std::size_t> complementOf(const std::vector<std::size_t>& sorted, std::size_t count)
{
    std::vector<std::size_t> out;
    out.reserve(count - std::min(count, sorted.size()));
    std::size_t j = 0;
    for (std::size_t i = 0; i < count; ++i) {
        if (j < sorted.size() && sorted[j] == i) {
            ++j;
            continue;
        }
        out.push_back(i);
    }
    return out;
}

} // namespace scandiff
