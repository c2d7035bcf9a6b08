// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! 3D connected components on the octree grid (thesis 000 §3.2.4): the selected
//! points are projected into the cells of one octree level, adjacent occupied
//! cells are merged, and each connected set of cells becomes a region.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/core/ScalarField.h>
#include <scandiff/octree/Octree.h>

#include <cstdint>
#include <vector>

namespace scandiff {

struct ConnectedComponentsParams
{
    //! Octree level of the grid, in [1, 21], on the cube enclosing the *whole*
    //! cloud (so the cell size does not depend on which points are selected):
    //! cell size = cube side / 2^level. 0 = automatic: the shallowest level
    //! whose cells hold at most 10 points of the whole cloud on average, i.e.
    //! cells a few point spacings wide, so a sampled surface stays connected.
    int level = 0;
    //! Adjacency of cells: faces (6), faces + edges (18), or all 26 neighbours.
    octree::Connectivity connectivity = octree::Connectivity::Corners26;
    //! Components with fewer points are dropped (their points get no region), >= 1.
    std::size_t minPoints = 1;
};

struct ConnectedComponentsResult
{
    //! "region_id": 1..regionCount, ordered by decreasing point count (ties: by
    //! position along the Morton curve); NaN for unselected and dropped points.
    ScalarField regionId;
    std::size_t regionCount = 0;
    std::vector<std::size_t> regionSizes; //!< points of region id r at index r-1
    std::size_t droppedComponents = 0;    //!< smaller than minPoints
    std::size_t droppedPoints = 0;
    int level = 0;                        //!< the level used
    double cellSize = 0.0;                //!< its cell size (m)
};

//! Components of the points with selected[i] != 0 (e.g. selectionFromLabels()
//! of the `changed` field). Throws Error(InvalidArgument) if `selected` is not
//! one entry per point or a parameter is out of range, Error(InvalidData) for
//! an empty cloud or a non-finite coordinate, Error(Cancelled).
ConnectedComponentsResult connectedComponents(const PointCloud& cloud, const std::vector<std::uint8_t>& selected,
                                              const ConnectedComponentsParams& params = {},
                                              ProgressObserver* progress = nullptr);

//! "6", "18", "26"; throws Error(InvalidArgument) otherwise.
octree::Connectivity parseConnectivity(int value);

} // namespace scandiff
