// SPDX-License-Identifier: GPL-3.0-or-later
#include "Tiling.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace scandiff::mpi {

TileKey TileGrid::tileOf(double x, double y) const
{
    return {static_cast<std::int64_t>(std::floor(x / size_)), static_cast<std::int64_t>(std::floor(y / size_))};
}

Eigen::Vector2d TileGrid::tileMin(const TileKey& key) const
{
    return {static_cast<double>(key.x) * size_, static_cast<double>(key.y) * size_};
}

Eigen::Vector2d TileGrid::tileMax(const TileKey& key) const
{
    return {static_cast<double>(key.x + 1) * size_, static_cast<double>(key.y + 1) * size_};
}

double TileGrid::depthInGrownTile(const TileKey& key, double halo, double x, double y) const
{
    const Eigen::Vector2d lo = tileMin(key), hi = tileMax(key);
    return std::min({x - (lo.x() - halo), (hi.x() + halo) - x, y - (lo.y() - halo), (hi.y() + halo) - y});
}

std::map<TileKey, int> assignTiles(const std::map<TileKey, std::uint64_t>& pointsPerTile, int ranks)
{
    std::vector<std::pair<TileKey, std::uint64_t>> tiles(pointsPerTile.begin(), pointsPerTile.end());
    std::stable_sort(tiles.begin(), tiles.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
    std::vector<std::uint64_t> load(static_cast<std::size_t>(std::max(ranks, 1)), 0);
    std::map<TileKey, int> owner;
    for (const auto& [key, count] : tiles) {
        const auto least = std::min_element(load.begin(), load.end()); // the first of equal loads: the lower rank
        *least += count;
        owner[key] = static_cast<int>(least - load.begin());
    }
    return owner;
}

HaloRegion::HaloRegion(const TileGrid& grid, const std::vector<TileKey>& tiles, double halo)
    : grid_(grid), owned_(tiles.begin(), tiles.end()), halo_(halo),
      reach_(static_cast<std::int64_t>(std::ceil(halo / grid.size())))
{
    for (const TileKey& key : tiles)
        for (std::int64_t dx = -reach_; dx <= reach_; ++dx)
            for (std::int64_t dy = -reach_; dy <= reach_; ++dy) {
                const TileKey near{key.x + dx, key.y + dy};
                if (owned_.count(near) == 0)
                    border_.insert(near);
            }
}

HaloRegion::Status HaloRegion::statusOf(const TileKey& key) const
{
    // Scans are coherent: consecutive points mostly share a tile.
    if (!(key == lastKey_)) {
        lastKey_ = key;
        lastStatus_ = owned_.count(key) ? Owned : border_.count(key) ? Border : Far;
    }
    return lastStatus_;
}

bool HaloRegion::contains(double x, double y) const
{
    const TileKey centre = grid_.tileOf(x, y);
    const Status status = statusOf(centre);
    if (status != Border)
        return status == Owned;
    for (std::int64_t dx = -reach_; dx <= reach_; ++dx)
        for (std::int64_t dy = -reach_; dy <= reach_; ++dy) {
            const TileKey key{centre.x + dx, centre.y + dy};
            if (owned_.count(key) == 0)
                continue;
            const Eigen::Vector2d lo = grid_.tileMin(key), hi = grid_.tileMax(key);
            if (x >= lo.x() - halo_ && x <= hi.x() + halo_ && y >= lo.y() - halo_ && y <= hi.y() + halo_)
                return true;
        }
    return false;
}

bool HaloRegion::intersects(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) const
{
    const auto overlaps = [&](const TileKey& key) {
        const Eigen::Vector2d tileLo = grid_.tileMin(key), tileHi = grid_.tileMax(key);
        return lo.x() <= tileHi.x() + halo_ && hi.x() >= tileLo.x() - halo_ && lo.y() <= tileHi.y() + halo_ &&
               hi.y() >= tileLo.y() - halo_;
    };
    const TileKey first = grid_.tileOf(lo.x() - halo_, lo.y() - halo_), last = grid_.tileOf(hi.x() + halo_, hi.y() + halo_);
    // A large box (a big triangle of a CAD model) looks at the owned tiles
    // instead of every tile it spans.
    const double spanned = (static_cast<double>(last.x - first.x) + 1) * (static_cast<double>(last.y - first.y) + 1);
    if (spanned > static_cast<double>(owned_.size()))
        return std::any_of(owned_.begin(), owned_.end(), overlaps);
    for (std::int64_t x = first.x; x <= last.x; ++x)
        for (std::int64_t y = first.y; y <= last.y; ++y)
            if (owned_.count({x, y}) && overlaps({x, y}))
                return true;
    return false;
}

} // namespace scandiff::mpi
