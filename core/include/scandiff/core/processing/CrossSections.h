// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Cross-sections, as CloudCompare's tool cuts them: slabs of a given
//! thickness across a cloud, perpendicular to a world axis, one every `step`;
//! each slab's points and the outline of their section in the slab's plane
//! (the concave outline of the points projected on it, as the region report
//! draws regions), ready for a drawing.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace scandiff {

struct CrossSectionParams
{
    int axis = 0;            //!< the slabs are perpendicular to x (0), y (1) or z (2)
    double thickness = 0.1;  //!< of each slab (m), > 0
    double step = 1.0;       //!< between the slabs' middles (m), > 0
    //! The first and last slab middles (global coordinate on `axis`); absent:
    //! from the cloud's extent, the first half a thickness inside it.
    std::optional<double> first, last;
    //! Cell of the outlines (m), >= 0; 0: from each slab's point spacing.
    double outlineCell = 0.0;
};

struct CrossSection
{
    double position = 0.0;            //!< the slab's middle on the axis (global)
    std::vector<std::size_t> indices; //!< its points, increasing
    //! The section's outline rings in the slab's middle plane, global, largest first.
    std::vector<std::vector<Eigen::Vector3d>> outlines;
    double area = 0.0; //!< inside the outlines (m^2)
};

//! Slabs holding no point are left out. Throws Error(InvalidArgument) for a
//! bad axis, thickness, step or range (more than 100,000 slabs), Error(Cancelled).
std::vector<CrossSection> crossSections(const PointCloud& cloud, const CrossSectionParams& params, ProgressObserver* progress = nullptr);

} // namespace scandiff
