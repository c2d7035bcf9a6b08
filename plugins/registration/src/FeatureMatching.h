// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Local shape descriptors and their matching, for the global alignment:
//! Fast Point Feature Histograms (Rusu, Blodow and Beetz 2009,
//! Descriptors.cpp), and nearest neighbours in descriptor space (FLANN's
//! kd-tree through PCL, in FeatureMatching.cpp only: its headers are slow to
//! compile and never reach another file).

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <utility>
#include <vector>

namespace scandiff::plugins::detail {

using Descriptor = std::array<float, 33>;

//! The FPFH of every point (positions and unit normals, float, one frame),
//! from its neighbours within `radius`: three histograms of 11 bins, each
//! summing to 100. `valid[i]` is false where the point had no neighbour.
void fpfhDescriptors(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& normals, double radius,
                     std::vector<Descriptor>& descriptors, std::vector<char>& valid);

//! Pairs (a, b) of descriptors each other's nearest neighbour (mutual); when
//! fewer than `minimumMutual` are mutual, every a's nearest b instead.
std::vector<std::pair<std::size_t, std::size_t>> matchDescriptors(const std::vector<Descriptor>& a, const std::vector<Descriptor>& b,
                                                                  std::size_t minimumMutual);

} // namespace scandiff::plugins::detail
