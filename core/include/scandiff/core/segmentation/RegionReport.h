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
//! edges; each edge is then moved onto the outermost point of its cell on that
//! side, so the outline runs through the extreme points instead of up to a
//! cell outside them, and simplified (collinear vertices dropped,
//! Douglas-Peucker at half a cell). `area` is that of the moved rings before
//! the simplification: a densely sampled rectangle gets its own area. A grid
//! outline is used rather than an alpha shape because it needs no
//! triangulation (core does not depend on CGAL), and its one parameter has a
//! plain meaning: the size of the smallest notch it follows. Throws
//! Error(InvalidArgument) for cellSize <= 0. Grids wider than 4096 cells use a
//! coarser cell (with a warning).
Outline2d concaveOutline(const std::vector<Eigen::Vector2d>& points, double cellSize);

//! The automatic outline cell of points: 1.5 times the median distance of the
//! points to their 4th nearest neighbour (one cell per point spacing and a
//! half, so the sampling leaves few holes); `bounds` sizes a fallback for a
//! lone point or duplicates.
double outlineCellFor(const std::vector<Eigen::Vector3f>& points, const BoundingBox& bounds);

struct RegionReportParams
{
    //! Field holding the region id of each point (NaN: no region).
    std::string regionField = "region_id";
    //! Field whose statistics are reported (the distances); empty: none.
    std::string distanceField;
    //! Each point's level of detection of those distances (m, a 95 % bound:
    //! M3C2's LoD95), for the volume along the distances and its uncertainty.
    //! Empty: m3c2_uncertainty when the distances are m3c2_distance and the
    //! cloud has it, else none.
    std::string uncertaintyField;
    //! Cell size of the outline grid (m), >= 0; 0 = automatic per region: 1.5
    //! times the median distance of its points to their 4th nearest neighbour
    //! (one cell per point spacing and a half, so the sampling leaves few holes).
    double outlineCellSize = 0.0;
    //! The other epoch, for the volume between the epochs; null: no volume.
    const PointCloud* reference = nullptr;
    //! Horizontal cell size (m) of the 2.5D volume grid, >= 0; 0: the region's outline cell size.
    double volumeCellSize = 0.0;
    //! Which epoch the region's cloud is: the later one (the compared cloud of
    //! a C2C, where appeared matter shows) or the earlier one (the reference of
    //! a both-ways C2C, where removed matter shows). The volume is always
    //! later minus earlier, so appearance counts positive, removal negative.
    bool regionInLaterEpoch = true;
    //! The height of each epoch in a column: the highest point (the surface seen
    //! from above, CloudCompare's "max"), the mean, or the lowest.
    enum class ColumnHeight { Highest, Mean, Lowest };
    ColumnHeight columnHeight = ColumnHeight::Highest;
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
    double outlineArea = 0.0;   //!< area inside that outline, in the best-fit plane (m^2): a wall's surface
    double footprintArea = 0.0; //!< area of the outline of the points seen from above, horizontal (m^2)
    //! The horizontal footprint's rings (global X, Y), largest first: the 2.5D volume is taken inside them.
    std::vector<Polygon2d> footprint;
    double outlineCellSize = 0.0;                //!< the grid cell used for the outlines (m)
    std::size_t distanceCount = 0;               //!< valid distance values
    double meanDistance = std::numeric_limits<double>::quiet_NaN();
    double maxDistance = std::numeric_limits<double>::quiet_NaN(); //!< the value of largest magnitude (sign kept)
    double rmsDistance = std::numeric_limits<double>::quiet_NaN();
    //! Volume between the epochs inside the footprint (m^3), later minus
    //! earlier: positive where matter appeared, negative where it went. On a
    //! horizontal grid, each column's height difference (ColumnHeight of each
    //! epoch's points in it: the region's own points, every point of the other
    //! epoch) times the area of the column inside the footprint, summed.
    //! Columns where the other epoch has no point are left out. Absent without
    //! the other epoch.
    std::optional<double> volume;
    double volumeAdded = 0.0;   //!< the sum over the columns that rose (m^3, >= 0)
    double volumeRemoved = 0.0; //!< the sum over the columns that sank (m^3, >= 0); volume = added - removed
    //! Fraction of the footprint's area where the other epoch had points.
    double volumeCoverage = 0.0;
    //! With an uncertainty field: the volume the distances sweep, the area
    //! inside the outline in the region's plane times the mean distance (m^3,
    //! signed: on a cliff, the rock fallen along the normals), and its
    //! uncertainty, that area times the mean level of detection. The levels of
    //! detection are added, not combined in quadrature: their largest part, the
    //! registration error, is the same for every point of the region, so the
    //! bound stays a 95 % one.
    std::optional<double> distanceVolume;
    std::optional<double> distanceVolumeUncertainty;
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
