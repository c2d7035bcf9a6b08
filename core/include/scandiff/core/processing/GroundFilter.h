// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Ground filtering: which points lie on the bare terrain, and the terrain
//! model they give.
//!
//! The method is the Simple Morphological Filter (SMRF; Pingel, Clarke and
//! McBride 2013, ISPRS J. 77: 21-30), with the published defaults PDAL's
//! `filters.smrf` also uses: on a grid of `cell` the lowest point of each cell
//! (empty cells filled from their neighbours) is opened morphologically by
//! windows growing one cell at a time up to `window`; a cell the opening lowers
//! by more than `slope` x the window's radius is an object (a building, a
//! tree). The cells left give a terrain model (objects' cells filled from the
//! ground around them), and a point is ground when it lies within `threshold`
//! + `scalar` x the model's local slope of it. Published mean total error on
//! the 15 ISPRS filter-test samples: 2.97 % (with per-sample tuning of the
//! authors; 4-5 % with defaults).
//!
//! Windows are squares (the paper opens by disks): a square's corners reach
//! 1.4 times further, so an object is removed by a slightly smaller window.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>

#include <cstdint>
#include <vector>

namespace scandiff {

struct GroundFilterParams
{
    double cell = 1.0;       //!< m, grid cell (about the ground's point spacing or more)
    double slope = 0.15;     //!< rise over run the terrain may have without being an object
    double window = 18.0;    //!< m, largest window: wider than the largest building
    double threshold = 0.5;  //!< m, height from the terrain model within which a point is ground
    double scalar = 1.25;    //!< m per unit of the model's slope added to the threshold on slopes
};

//! A terrain model on a regular grid: heights at the cells' centres.
struct TerrainGrid
{
    double originX = 0, originY = 0; //!< local coordinates of cell (0, 0)'s lower corner
    double cell = 1.0;
    std::size_t columns = 0, rows = 0;
    std::vector<double> heights;     //!< row-major, local z; every cell has one
    std::vector<double> slopes;      //!< rise over run at each cell (central differences)
    //! Height at a local (x, y), interpolated bilinearly between cell centres.
    double heightAt(double x, double y) const;
    double slopeAt(double x, double y) const;
};

struct GroundFilterResult
{
    std::vector<std::uint8_t> ground; //!< per point: 1 ground, 0 not (0 for non-finite points)
    std::size_t groundCount = 0;
    std::size_t objectCells = 0;      //!< grid cells with points the opening marked as objects
    TerrainGrid terrain;
};

//! SMRF over the cloud's local coordinates. Throws Error(InvalidArgument) for
//! a parameter out of range, Error(InvalidData) for a cloud without finite
//! points or whose grid would pass 200 million cells (give a larger cell),
//! Error(Cancelled).
GroundFilterResult filterGround(const PointCloud& cloud, const GroundFilterParams& params = {},
                                ProgressObserver* progress = nullptr);

} // namespace scandiff
