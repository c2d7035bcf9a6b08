// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Builds the octree of a cloud's local positions, with the project's error
//! policy: an empty cloud or a non-finite coordinate is an Error(InvalidData)
//! naming the cloud. The cloud must outlive the octree and keep its points.
//! With an observer, Cancel is heard between the phases of the build (it is
//! linear, about 0.1 s per million points on 2 cores, too long to go unheard
//! on tens of millions): Error(Cancelled) is thrown.

#include <scandiff/core/PointCloud.h>
#include <scandiff/core/Progress.h>
#include <scandiff/octree/Octree.h>

#include <optional>

namespace scandiff {

octree::Octree buildOctree(const PointCloud& cloud, std::optional<octree::CubicBox> box = std::nullopt,
                           const ProgressObserver* cancel = nullptr);

} // namespace scandiff
