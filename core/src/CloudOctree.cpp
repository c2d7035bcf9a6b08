// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/CloudOctree.h>
#include <scandiff/core/Error.h>

#include <stdexcept>

namespace scandiff {

octree::Octree buildOctree(const PointCloud& cloud, std::optional<octree::CubicBox> box, const ProgressObserver* cancel)
{
    const std::function<void()> checkpoint = [cancel] {
        if (cancel->cancelRequested())
            throw Error(ErrorCode::Cancelled, "cancelled by the user");
    };
    try {
        return octree::Octree(cloud.positions().data(), cloud.size(), box, cancel ? checkpoint : std::function<void()>{});
    } catch (const std::invalid_argument& e) {
        throw Error(ErrorCode::InvalidData, "cloud '" + cloud.name + "': " + e.what());
    }
}

} // namespace scandiff
