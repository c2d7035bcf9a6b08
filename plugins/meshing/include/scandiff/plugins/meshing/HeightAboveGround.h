// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Height above ground: each point's height over the terrain its ground
//! points make (the classes given, ASPRS 2 by default, as `ground` writes
//! them), the terrain being their Delaunay triangulation in XY (a TIN, CGAL)
//! interpolated linearly in the triangle under the point; what PDAL's
//! filters.hag_delaunay gives and CloudCompare users compute for canopy
//! heights. A point beyond the TIN's outline gets its height over the
//! nearest ground point (in XY).

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>

#include <string>
#include <vector>

namespace scandiff::plugins {

struct HeightAboveGroundParams
{
    std::string classField = "classification";
    std::vector<int> groundClasses{2};
};

struct HeightAboveGroundResult
{
    std::vector<float> height;     //!< per point (m); NaN for a point without finite coordinates
    std::size_t groundPoints = 0;  //!< in the classes, with finite coordinates
    std::size_t outsideHull = 0;   //!< points beyond the TIN's outline (the nearest ground point's height)
};

//! Throws Error(InvalidArgument) without the class field or classes,
//! Error(InvalidData) when the ground points are fewer than 3 or all on a
//! line, Error(Cancelled).
HeightAboveGroundResult heightAboveGround(const PointCloud& cloud, const HeightAboveGroundParams& params,
                                          ProgressObserver* progress = nullptr);

} // namespace scandiff::plugins
