// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! One group of points per stone, from the points classified stone or joint.
//! A joint two or three points wide has gaps where a few of its points were
//! classified stone, and stone points chained through such a gap join two
//! stones into one region (the "stone-to-stone junctions" thesis 003 §III.2.1
//! removes by hand before meshing). Here the joints are found as lines of
//! parting points (joint class, or set back from the faces), gaps included;
//! every stone point on a joint or closer than one and a half spacings to one
//! is set aside, the rest (the stones' cores) are grouped, and the stone
//! points set aside go back to the nearest core through stone points (those
//! on a joint line too: a stone's side seen in its groove is the stone's). Internal to the contours plugin; extractStones() calls it.

#include <scandiff/core/Progress.h>
#include <scandiff/octree/Octree.h>

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace scandiff::plugins {

struct StoneRegionParams
{
    //! A stone point with fewer other stone points than `cleaningNeighbours`
    //! within `cleaningRadius` is isolated (thesis 003 §III.1.2.1.1); radius 0:
    //! twice the spacing where the point lies.
    double cleaningRadius = 0.0;
    int cleaningNeighbours = 3;
};

struct StoneRegions
{
    std::vector<std::int32_t> label; //!< per point: its stone region, -1 for none
    std::vector<std::uint8_t> joint; //!< per point: 1 on a joint line (parting points lined up, gaps included)
    std::vector<std::uint8_t> parting; //!< per point: 1 for a joint-class or recessed point
    std::vector<float> spacing;      //!< per point: the spacing where it lies (its 8th neighbour's distance / sqrt 2: a square grid's step)
    std::size_t isolatedRemoved = 0; //!< stone points left out as isolated
    std::size_t setAside = 0;        //!< stone points near a joint, given back to the nearest core
};

//! `planar`: the points in the wall's plane (z = 0), the octree built on them;
//! `stone`: 1 for a stone point; `known`: 0 for a point without a value (in
//! neither class); `recessed`: 1 for a point set back from the faces (it
//! parts stones as a joint point does, whatever its class; empty: none).
StoneRegions separateStones(const octree::Octree& tree, const std::vector<Eigen::Vector3f>& planar, const std::vector<std::uint8_t>& stone,
                            const std::vector<std::uint8_t>& known, const std::vector<std::uint8_t>& recessed, const StoneRegionParams& params,
                            ProgressTicker& ticker);

} // namespace scandiff::plugins
