// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Measurements of segmented change regions, for reports and CAD export: point
//! count, bounding box, centroid, best-fit plane, concave outline and footprint
//! area, distance statistics, and the volume between the two epochs (2.5D).

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>

#include <Eigen/Core>

#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace scandiff {

//! A closed polygon (the last vertex is not repeated).
using Polygon2d = std::vector<Eigen::Vector2d>;

struct Outline2d
{
    std::vector<Polygon2d> rings; //!< outer boundaries, counter-clockwise, largest first
    double area = 0.0;            //!< area inside them (holes filled)
};

//! A concave outline of 2D points. The points are rasterised on a grid of
//! `cellSize`, one-cell gaps are closed (dilation then erosion), and the outer
//! boundary of every 4-connected piece of occupied cells is traced along cell
//! edges, then simplified (collinear vertices dropped, Douglas-Peucker at half a
//! cell). A grid outline is used rather than an alpha shape because it needs no
//! triangulation (core does not depend on CGAL), cannot self-intersect before
//! simplification, and its one parameter has a plain meaning: the size of the
//! smallest notch it follows. Throws Error(InvalidArgument) for cellSize <= 0.
//! Grids wider than 4096 cells use a coarser cell (with a warning).
Outline2d concaveOutline(const std::vector<Eigen::Vector2d>& points, double cellSize);

struct RegionReportParams
{
    //! Field holding the region id of each point (NaN: no region).
    std::string regionField = "region_id";
    //! Field whose statistics are reported (the distances); empty: none.
    std::string distanceField;
    //! Cell size of the outline grid (m), >= 0; 0 = automatic per region: 1.5
    //! times the median distance of its points to their 4th nearest neighbour
    //! (one cell per point spacing and a half, so the sampling leaves few holes).
    double outlineCellSize = 0.0;
    //! The other epoch, for the volume between the epochs; null: no volume.
    const PointCloud* reference = nullptr;
    //! Horizontal cell size (m) of the 2.5D volume grid, >= 0; 0: the region's outline cell size.
    double volumeCellSize = 0.0;
};

struct RegionStatistics
{
    int id = 0;
    std::size_t pointCount = 0;
    BoundingBox bounds;                          //!< global coordinates
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero(); //!< global
    Eigen::Vector3d planeNormal = Eigen::Vector3d::UnitZ(); //!< of the best-fit (least-squares) plane
    //! Outline in the best-fit plane, lifted back to 3D (global), closed rings, largest first.
    std::vector<std::vector<Eigen::Vector3d>> outlines;
    double footprintArea = 0.0;                  //!< area inside the outline, in the plane (m^2)
    double outlineCellSize = 0.0;                //!< the grid cell used for the outline (m)
    std::size_t distanceCount = 0;               //!< valid distance values
    double meanDistance = std::numeric_limits<double>::quiet_NaN();
    double maxDistance = std::numeric_limits<double>::quiet_NaN(); //!< the value of largest magnitude (sign kept)
    double rmsDistance = std::numeric_limits<double>::quiet_NaN();
    //! Volume between the epochs over the region (m^3): per vertical column of
    //! the 2.5D grid, (mean Z of the region's points - mean Z of the reference's
    //! points) times the cell area, summed; positive where matter appeared.
    //! Columns where the reference has no point are left out. Absent without a reference.
    std::optional<double> volume;
    //! Fraction of the region's columns where the reference had points.
    double volumeCoverage = 0.0;
};

//! The point indices of each region, by region id (values rounded to the
//! nearest integer; NaN, no region, skipped), in input order.
std::map<int, std::vector<std::size_t>> pointsByRegion(const ScalarField& regionIds);

//! One entry per region id present, in increasing id order. Points with a
//! non-finite position are ignored. Throws Error(InvalidArgument) for a missing
//! field or negative sizes, Error(InvalidData) for a region id that is not a
//! positive integer, Error(Cancelled).
std::vector<RegionStatistics> regionReport(const PointCloud& cloud, const RegionReportParams& params = {},
                                           ProgressObserver* progress = nullptr);

} // namespace scandiff
