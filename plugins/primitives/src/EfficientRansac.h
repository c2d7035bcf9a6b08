// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The call into CGAL's efficient RANSAC (internal to the plugin): CGAL's
//! headers stay in EfficientRansac.cpp, the slowest file of the plugin to build.

#include <scandiff/core/geometry/Primitives.h>

#include <Eigen/Core>

#include <cstdint>
#include <set>
#include <vector>

namespace scandiff::plugins::detail {

struct RansacSettings
{
    std::set<PrimitiveKind> kinds;
    double epsilon = 0.01;
    double clusterEpsilon = 0.1;
    double normalCosine = 0.9;
    std::size_t minPoints = 200;
    double probability = 0.01;
    std::uint64_t seed = 0;
};

struct RansacShape
{
    Primitive primitive;                //!< in the frame of the points given
    std::vector<std::uint32_t> members; //!< positions in the vectors given
};

//! Shapes found among `points` (local coordinates, unit `normals`), in the
//! order CGAL found them. Deterministic for a seed and an input order.
std::vector<RansacShape> efficientRansac(const std::vector<Eigen::Vector3d>& points, std::vector<Eigen::Vector3d> normals,
                                         const RansacSettings& settings, const std::function<bool(double)>& keepGoing);

} // namespace scandiff::plugins::detail
