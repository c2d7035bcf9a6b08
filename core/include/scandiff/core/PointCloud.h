// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The point cloud of scandiff.
//!
//! Positions are float32 *local* coordinates; the cloud's `origin` (double) is
//! added to get the true (global) coordinates: global = origin + local. Keeping
//! the large part of georeferenced coordinates (UTM, Lambert: 10^5..10^7 m) in
//! the double origin keeps millimetre precision in 32-bit floats, as CloudCompare
//! does with its "global shift".
//!
//! A cloud is move-only: copying millions of points must be explicit (clone()).

#include <scandiff/core/ScalarField.h>
#include <scandiff/core/SensorPose.h>

#include <Eigen/Core>

#include <cstdint>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace scandiff {

struct Rgb8
{
    std::uint8_t r = 0, g = 0, b = 0;
    friend bool operator==(const Rgb8& a, const Rgb8& b) { return a.r == b.r && a.g == b.g && a.b == b.b; }
};

//! A transformation applied to a cloud's global coordinates (global' = M *
//! global, homogeneous), kept in the cloud's history so the user sees how it
//! got where it is and can undo a step with the inverse.
struct AppliedTransform
{
    Eigen::Matrix4d matrix = Eigen::Matrix4d::Identity();
    std::string description; //!< "rotate z 30 deg about 0,0,0", "matrix from T.txt"...
};

//! The integer grid a file stored the coordinates on (LAS: coordinate =
//! offset + scale * integer). Kept so that writing LAS again gives the same
//! integers; dropped by anything that moves the points off it.
struct CoordinateGrid
{
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    Eigen::Vector3d scale = Eigen::Vector3d::Ones();
    friend bool operator==(const CoordinateGrid& a, const CoordinateGrid& b) { return a.offset == b.offset && a.scale == b.scale; }
};

struct BoundingBox
{
    Eigen::Vector3d min = Eigen::Vector3d::Constant(0.0);
    Eigen::Vector3d max = Eigen::Vector3d::Constant(0.0);
    bool empty = true;
};

class PointCloud
{
public:
    PointCloud() = default;
    PointCloud(PointCloud&&) noexcept = default;
    PointCloud& operator=(PointCloud&&) noexcept = default;
    PointCloud(const PointCloud&) = delete;
    PointCloud& operator=(const PointCloud&) = delete;
    //! Explicit deep copy.
    PointCloud clone() const;

    std::string name;

    std::size_t size() const { return positions_.size(); }
    bool empty() const { return positions_.empty(); }

    //! Global coordinates = origin() + local position.
    const Eigen::Vector3d& origin() const { return origin_; }
    //! Changes the origin while keeping global coordinates (re-expresses positions).
    void shiftOrigin(const Eigen::Vector3d& newOrigin);
    //! Sets the origin without touching the local positions (readers use it).
    void setOrigin(const Eigen::Vector3d& origin) { origin_ = origin; }

    const std::vector<Eigen::Vector3f>& positions() const { return positions_; }
    std::vector<Eigen::Vector3f>& positions() { return positions_; }
    Eigen::Vector3d globalPosition(std::size_t i) const { return origin_ + positions_[i].cast<double>(); }

    //! What the float positions miss of the exact coordinates a file gave, per
    //! point: exact local = p + r on each axis, in double. Empty unless a
    //! reader keeps them, which it does only where a float cannot give the
    //! file's value back: a LAS grid finer than the float's step at that
    //! distance from the origin (laspy's 1_4_w_evlr.las: a scale of 1.2e-6
    //! ft, 2,000 ft from the origin where a float's step is 1.2e-4). Writers
    //! use exactLocalPosition(), so such a file goes back to the same
    //! integers. 12 bytes a point, only for such files. A residual counts only
    //! while it is below half the float's last digit (the float view is still
    //! the rounding of that value): a position changed since wins, and a
    //! transformation drops them.
    const std::vector<Eigen::Vector3f>& positionResiduals() const { return residuals_; }
    std::vector<Eigen::Vector3f>& positionResiduals() { return residuals_; }
    void dropPositionResiduals()
    {
        residuals_.clear();
        residuals_.shrink_to_fit();
    }
    //! The local position with its residual, in double (see positionResiduals()).
    Eigen::Vector3d exactLocalPosition(std::size_t i) const
    {
        Eigen::Vector3d p = positions_[i].cast<double>();
        if (i < residuals_.size())
            for (int a = 0; a < 3; ++a) {
                // Below half the float's last digit (inclusive: a tie rounds to even).
                const float f = positions_[i][a], r = residuals_[i][a];
                if (std::abs(r) <= 0.5f * (std::nextafter(std::abs(f), HUGE_VALF) - std::abs(f)))
                    p[a] += static_cast<double>(r);
            }
        return p;
    }
    Eigen::Vector3d exactGlobalPosition(std::size_t i) const { return origin_ + exactLocalPosition(i); }

    //! Resizes positions and every attribute present (new entries: 0 / NaN).
    void resize(std::size_t n);
    void reserve(std::size_t n);

    bool hasColors() const { return !colors_.empty(); }
    const std::vector<Rgb8>& colors() const { return colors_; }
    //! Enables colours (size() black entries) if absent and returns them.
    std::vector<Rgb8>& enableColors();
    void removeColors() { colors_.clear(); colors_.shrink_to_fit(); }

    bool hasNormals() const { return !normals_.empty(); }
    const std::vector<Eigen::Vector3f>& normals() const { return normals_; }
    std::vector<Eigen::Vector3f>& enableNormals();
    void removeNormals() { normals_.clear(); normals_.shrink_to_fit(); }

    const std::vector<ScalarField>& fields() const { return fields_; }
    //! Null if there is no field of that name.
    const ScalarField* field(const std::string& name) const;
    ScalarField* field(const std::string& name);
    //! Returns the named field, creating it (all NaN) if absent.
    ScalarField& addField(const std::string& name);
    //! Adds a field built elsewhere; its size must equal size(). Replaces a field of the same name.
    ScalarField& addField(ScalarField field);
    //! The same, the new field placed before the field at `position` (at the
    //! end past the last): readers keep a file's order of attributes.
    ScalarField& addField(ScalarField field, std::size_t position);
    bool removeField(const std::string& name);

    //! Scanner poses this cloud was acquired from (visibility needs them).
    std::vector<SensorPose>& sensors() { return sensors_; }
    const std::vector<SensorPose>& sensors() const { return sensors_; }

    //! The transformations applied to this cloud, oldest first (clone() and
    //! subset() keep them; readers start with none).
    std::vector<AppliedTransform>& transformHistory() { return history_; }
    const std::vector<AppliedTransform>& transformHistory() const { return history_; }

    //! The grid of the file the points came from (LAS), if any: clone() and
    //! subset() keep it, a transformation drops it.
    const std::optional<CoordinateGrid>& sourceGrid() const { return grid_; }
    void setSourceGrid(std::optional<CoordinateGrid> grid) { grid_ = std::move(grid); }

    //! The coordinate reference system of the global coordinates, as OGC WKT
    //! (empty: unknown). Readers set it from the file (LAS), writers that can
    //! hold it write it back, and a GeoTIFF made from the cloud is
    //! georeferenced with it. clone(), subset() and a rigid transformation
    //! keep it: the coordinates stay in the same system.
    const std::string& crsWkt() const { return crs_; }
    void setCrsWkt(std::string wkt) { crs_ = std::move(wkt); }

    //! Bytes its per-point arrays hold (capacities: positions and their
    //! exact residuals, colours, normals, every field): what the cloud costs
    //! in memory, the view's and the tools' own buffers apart.
    std::size_t heldBytes() const;

    //! Bounding box of the global coordinates, ignoring non-finite positions.
    BoundingBox bounds() const;

    //! A new cloud made of the listed points, in that order, with every attribute.
    PointCloud subset(const std::vector<std::size_t>& indices) const;

    //! Drops the points whose position is NaN or infinite (with their attributes);
    //! returns how many were dropped. Readers call it and log a warning: the
    //! documented policy for non-finite coordinates in point clouds.
    std::size_t removeNonFinitePoints();

    //! Throws Error(InvalidData) if the attribute arrays disagree with the point count.
    void checkConsistency() const;

private:
    Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3f> positions_;
    std::vector<Eigen::Vector3f> residuals_; //!< see positionResiduals()
    std::vector<Rgb8> colors_;
    std::vector<Eigen::Vector3f> normals_;
    std::vector<ScalarField> fields_;
    std::vector<SensorPose> sensors_;
    std::vector<AppliedTransform> history_;
    std::optional<CoordinateGrid> grid_;
    std::string crs_;
};

//! Chooses an origin for global coordinates spanning `bounds`: zero when float32
//! keeps sub-millimetre precision (all |coordinates| < 1e4 m), otherwise the box
//! minimum rounded down to a multiple of 1000 m, as a survey user would expect.
Eigen::Vector3d suggestOrigin(const BoundingBox& bounds);

} // namespace scandiff
