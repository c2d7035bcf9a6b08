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
    return lastStatus_.of(key, [&](const TileKey& k) { return owned_.count(k) ? Owned : border_.count(k) ? Border : Far; });
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

namespace {

double largestFinite(const std::vector<double>& values, double floor)
{
    double largest = floor;
    for (const double v : values)
        if (std::isfinite(v))
            largest = std::max(largest, v);
    return largest;
}

} // namespace

ReachIndex::ReachIndex(std::vector<Eigen::Vector2d> centres, std::vector<double> halfSides, double minimumCell)
    : centres_(std::move(centres)), halfSides_(std::move(halfSides)),
      everywhere_(std::any_of(halfSides_.begin(), halfSides_.end(), [](double r) { return !std::isfinite(r); })),
      cells_(largestFinite(halfSides_, minimumCell))
{
    if (everywhere_)
        return;
    for (std::size_t m = 0; m < centres_.size(); ++m)
        byCell_[cells_.tileOf(centres_[m].x(), centres_[m].y())].push_back(m);
}

bool ReachIndex::touches(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) const
{
    if (everywhere_)
        return true;
    // A square reaches at most one cell beyond its own.
    const TileKey first = cells_.tileOf(lo.x(), lo.y()), last = cells_.tileOf(hi.x(), hi.y());
    for (std::int64_t x = first.x - 1; x <= last.x + 1; ++x)
        for (std::int64_t y = first.y - 1; y <= last.y + 1; ++y) {
            const auto found = byCell_.find({x, y});
            if (found == byCell_.end())
                continue;
            for (const std::size_t m : found->second) {
                const Eigen::Vector2d& c = centres_[m];
                const double r = halfSides_[m];
                if (lo.x() <= c.x() + r && hi.x() >= c.x() - r && lo.y() <= c.y() + r && hi.y() >= c.y() - r)
                    return true;
            }
        }
    return false;
}

} // namespace scandiff::mpi
