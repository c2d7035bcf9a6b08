// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Subsampling (thesis 000 annex C: "octree decimation, resampling"): which
//! points to keep, as sorted indices, so that the kept cloud (PointCloud::subset)
//! has every field, colour and normal of the kept points, in input order.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>

#include <cstdint>
#include <vector>

namespace scandiff {

//! `count` points drawn uniformly without replacement (all of them when the
//! cloud has no more). The same seed gives the same points.
std::vector<std::size_t> randomSubsample(const PointCloud& cloud, std::size_t count, std::uint64_t seed = 0);

//! Points more than `minDistance` apart: each point is kept unless a point
//! kept before it lies within `minDistance`, the points visited cell by cell
//! of an octree level at least that wide, by parity class of the cells (the
//! cells of a class, at least a cell apart, are decided in parallel), in
//! Morton order within a cell. So no two kept points are within `minDistance`
//! of each other (their distance is larger), and every dropped point lies
//! within `minDistance` of a kept one, exactly (distances in float on the
//! local coordinates, as the octree's queries compute them). The same input
//! gives the same points whatever the number of threads.
//! Throws Error(InvalidArgument) for a distance that is not > 0,
//! Error(InvalidData) for non-finite coordinates, Error(Cancelled).
std::vector<std::size_t> spatialSubsample(const PointCloud& cloud, double minDistance, ProgressObserver* progress = nullptr);

//! One point per non-empty cell of the octree level (on the cube enclosing the
//! cloud): the one nearest to the cell's centre, the smaller index on a tie.
//! Throws Error(InvalidArgument) for a level outside [1, 21].
std::vector<std::size_t> octreeSubsample(const PointCloud& cloud, int level, ProgressObserver* progress = nullptr);

} // namespace scandiff
